"""The cached kernels looked up before numba's set-up (``supercoil._numba``): the same
machine code as numba's own lookup, without numba's target refresh.

Each check runs in fresh interpreters (the lookup happens once per process and kernel):
one to make sure the kernels are in the cache, one with numba's own lookup
(``SUPERCOIL_NUMBA_PLAIN_CACHE=1``) and one with ours. Oracles: the results of the two
lookups are identical bit for bit (the rod's gradient and Hessian values through
several kernels, the contact integral's, and the parallel writhe kernel, whose cached
code needs numba's threading layer started when it is loaded); our lookup never runs
numba's refresh, numba's own does; the writhe of a closed curve also matches the
pure-numpy reference. Our loading leaves the kernels' bitcode unparsed (Linux, ELF
machine code): the symbols read from the machine code include every symbol numba lists
from the parsed bitcode, and a function compiled later against a kernel so loaded (numba
links the kernel's module in, parsed then) gives the same results as under numba's own
loading.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPT = r"""
import json, sys
import numpy as np
import numba.core.base as base

calls = []
original = base.BaseContext.refresh
def counted(self):
    calls.append(1)
    original(self)
base.BaseContext.refresh = counted

from supercoil import _numba

symbols = {}  # library name -> the symbols read from its machine code at its load
original_unserialize = _numba._unserialize_lazily
def recording(codegen, state):
    if state[1] == "object":
        symbols[state[0]] = _numba.elf_defined_symbols(state[2][0])
    return original_unserialize(codegen, state)
_numba._unserialize_lazily = recording
from supercoil.problems.tweezers import TweezersOptions, clamped_problem
from supercoil.contact.problem import ContactOptions, ContactProblem
from supercoil.rod import kernels
from supercoil.topology.writhe import writhe, writhe_reference

sys.path.insert(0, sys.argv[2])
from contact_toys import stadium_ring

options = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=33, tension=75,
                          turns=(0, 5), n_nodes=40)
rod, q0 = clamped_problem(options)
rng = np.random.default_rng(3)
q = q0 + 1e-3 * rng.standard_normal(q0.shape)
gradient = rod.gradient(q)
hessian = rod.hessian(q).sparse
t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
trefoil = np.column_stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t),
                           -np.sin(3 * t)])
wr = writhe(trefoil)
wr_reference = writhe_reference(trefoil)
# a stadium whose straight sides are 1.05 D apart: the barrier integral's terms
D = 0.02
ring, x = stadium_ring(80, 0.525 * D)
contact = ContactProblem(ring, ContactOptions(diameter=D, barrier_activation=0.1,
                                             formulation="integral"))  # reach 1.1 D
contact_gradient = contact.gradient(x.ravel()) - ring.gradient(x.ravel())
refresh_calls = len(calls)

# the libraries as loaded: which still hold their bitcode unparsed, and whether the
# symbols read from their machine code include every one numba lists from the bitcode
from supercoil.continuation import bordered
from supercoil.solvers import kkt

indptr = np.array([0, 2, 7, 8], dtype=np.int64)
longest = int(kkt._longest_row(indptr))
loaded = [kernels._gradient_kernel, bordered._bordered_values, kkt._longest_row]
libraries = [c.library for d in loaded for c in d.overloads.values()]
pending = ["_supercoil_bitcode" in lib.__dict__ for lib in libraries]
missing = []
for lib in libraries:
    names = symbols.get(lib.name)
    module = lib._shared_module  # parses the bitcode if it was pending
    listed = {g.name for gs in (module.functions, module.global_variables) for g in gs
              if not g.is_declaration}
    missing.append(sorted(listed - (names or set())))

# a function compiled now, calling a cached kernel: numba links the kernel's module in
import numba
from supercoil.solvers import patterns

words = np.array([3, 1, 4], dtype=np.int64)
same = bool(patterns.same_words(words, words.copy()))
callee = next(iter(patterns.same_words.overloads.values())).library
callee_pending = "_supercoil_bitcode" in callee.__dict__

@numba.njit(cache=False)
def both_same(a, b, c):
    return patterns.same_words(a, b) and patterns.same_words(a, c)

linked = [bool(both_same(words, words.copy(), words.copy())),
          bool(both_same(words, words.copy(), words[::-1].copy()))]
out = {
    "refresh_calls": refresh_calls,
    "lazy": [isinstance(lib, _numba._LazyLinking) for lib in libraries],
    "pending": pending,
    "missing_symbols": missing,
    "longest": longest,
    "same": same,
    "linked": linked,
    "callee_pending": callee_pending,
    "callee_parsed": "_supercoil_bitcode" not in callee.__dict__,
    "cached_first": type(kernels._gradient_kernel._cache).__name__ == "_CachedFirst",
    "gradient": gradient.tolist(),
    "hessian": hessian.data.tolist(),
    "contact_gradient": contact_gradient.tolist(),
    "writhe": wr,
    "writhe_reference": wr_reference,
}
json.dump(out, open(sys.argv[1], "w"))
"""


def run(tmp_path, name: str, plain: bool) -> dict:
    env = dict(os.environ)
    env.pop("SUPERCOIL_NUMBA_PLAIN_CACHE", None)
    if plain:
        env["SUPERCOIL_NUMBA_PLAIN_CACHE"] = "1"
    path = tmp_path / f"{name}.json"
    subprocess.run([sys.executable, "-c", SCRIPT, str(path), str(Path(__file__).parent)],
                   check=True, env=env, timeout=600)
    with open(path) as f:
        return json.load(f)


def test_cached_kernels_skip_numba_refresh_and_match_numba_lookup(tmp_path):
    run(tmp_path, "warm", plain=True)  # compiles (and caches) whatever is not cached yet
    plain = run(tmp_path, "plain", plain=True)
    quick = run(tmp_path, "quick", plain=False)
    if not quick["cached_first"]:
        pytest.skip("no usable numba cache here (or a numba without FunctionCache)")
    assert not plain["cached_first"]
    assert plain["refresh_calls"] > 0
    assert quick["refresh_calls"] == 0
    for key in ("gradient", "hessian", "contact_gradient", "writhe"):
        assert quick[key] == plain[key], key  # bit for bit (JSON floats round-trip)
    assert quick["writhe"] == pytest.approx(quick["writhe_reference"], abs=1e-12)
    # loaded without parsing the bitcode, the symbols from the machine code (Linux: ELF)
    if sys.platform.startswith("linux"):
        assert all(quick["lazy"]) and all(quick["pending"])
        assert not any(plain["lazy"])
        assert quick["missing_symbols"] == [[]] * len(quick["lazy"])
    # compiled against a lazily loaded kernel: its module parsed then, the same result
    assert quick["longest"] == plain["longest"] == 5
    assert quick["same"] and plain["same"]
    assert quick["linked"] == plain["linked"] == [True, False]
    if sys.platform.startswith("linux"):
        assert quick["callee_pending"]
    assert quick["callee_parsed"]
    assert np.isfinite(quick["gradient"]).all()
    assert np.count_nonzero(quick["contact_gradient"]) > 0  # the sides do touch


def test_elf_symbols_of_something_else_are_none():
    from supercoil._numba import elf_defined_symbols

    assert elf_defined_symbols(b"MZ\x90\x00 not an ELF object") is None
    assert elf_defined_symbols(b"\x7fELF\x02\x01\x01") is None  # truncated header
    assert elf_defined_symbols(b"\x7fELF\x01\x01" + bytes(64)) is None  # 32-bit
