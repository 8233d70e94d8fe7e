"""supercoil._lazy_numpy: scipy's copy of numpy's namespace, with and without the hook.

Oracle: the same namespace (every name, and what each resolves to) in a fresh process
without the hook; the hook's only effect is that numpy's unused lazy submodules stay
unimported. Fresh processes: the hook acts on a module's first import.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

pytest.importorskip("scipy.sparse")

PROBE = r"""
import json, sys, types
hook = sys.argv[1] == "hook"
import numpy
if hook:
    from supercoil import _lazy_numpy
    _lazy_numpy.install()
    hidden = sorted(_lazy_numpy.lazy_submodules())
else:
    hidden = []
import scipy.sparse
import scipy._lib.array_api_compat.numpy as compat
imported_after_scipy = sorted(n for n in getattr(numpy, "__numpy_submodules__", ())
                              if f"numpy.{n}" in sys.modules)
names = sorted(dir(compat))

def describe(value):
    if isinstance(value, types.ModuleType):
        return "module " + value.__name__
    return type(value).__module__ + "." + type(value).__qualname__ + " " + repr(
        getattr(value, "__name__", None))

# every name resolved (lazy ones imported now), described; and, for each of numpy's
# lazy submodules, whether the name is numpy's very object (compat has its own linalg
# and fft)
described = {n: describe(getattr(compat, n)) for n in names}
same = {n: getattr(compat, n) is getattr(numpy, n)
        for n in sorted(getattr(numpy, "__numpy_submodules__", ())) if n in names}
star = {}
exec("from scipy._lib.array_api_compat.numpy import *", star)
print(json.dumps({"hidden": hidden, "imported_after_scipy": imported_after_scipy,
                  "names": names, "described": described, "same": same,
                  "star": sorted(k for k in star if k != "__builtins__"),
                  "all": sorted(compat.__all__)}))
"""


def _probe(mode: str) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE, mode], check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout)


def test_the_namespace_is_the_same_and_unused_submodules_stay_unimported():
    plain, hooked = _probe("plain"), _probe("hook")
    if not hooked["hidden"]:
        pytest.skip("this numpy declares no lazy submodules (__numpy_submodules__)")
    assert hooked["names"] == plain["names"]
    assert hooked["all"] == plain["all"]
    assert hooked["star"] == plain["star"]
    assert hooked["described"] == plain["described"]
    assert hooked["same"] == plain["same"]
    assert hooked["same"]["testing"] and not hooked["same"]["fft"]
    # what the hook is for: the copy no longer imports them (plain: it does)
    for name in ("f2py", "testing", "ma"):
        assert name in plain["imported_after_scipy"]
        assert name in hooked["hidden"]
        assert name not in hooked["imported_after_scipy"]


def test_the_hook_fires_once_and_only_for_its_module():
    code = r"""
import sys
from supercoil import _lazy_numpy
_lazy_numpy.install()
_lazy_numpy.install()
assert sum(f is _lazy_numpy._hook for f in sys.meta_path) == 1
import json  # another module: the hook stays
assert _lazy_numpy._hook in sys.meta_path
import scipy.sparse
assert _lazy_numpy._hook not in sys.meta_path  # fired and removed itself
_lazy_numpy.install()  # the module is imported: nothing registered
assert _lazy_numpy._hook not in sys.meta_path
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True)
    assert out.stdout.strip() == "ok"
