"""The tweezers command run with two source trees, and their outputs compared.

Run: ``python benchmarks/compare_tweezers_trees.py OLD_SRC NEW_SRC`` (each the ``src``
folder of a tree, e.g. ``OLD_SRC=/tmp/old/src`` from ``git archive <commit> src`` and
``NEW_SRC=src``). Runs ``supercoil tweezers --twist-ratio 4/3 --length-over-diameter 33
--tension 75 --turns 0:5 --nodes 100`` with each tree on ``PYTHONPATH`` and prints
whether ``branch.json``'s points and special points and every stored array of
``result.h5`` (both trees writing result files) are identical bit for bit, else the largest differences. A change
meant to cut overhead only must print ``IDENTICAL``. About 10 s with
warm numba caches (a minute or two when a tree compiles its kernels first).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ARGS = ["tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "33", "--tension", "75",
        "--turns", "0:5", "--nodes", "100", "--quiet"]


def run(src: str, out: str) -> dict:
    env = dict(os.environ, PYTHONPATH=src, OPENBLAS_NUM_THREADS="1")
    result = subprocess.run([sys.executable, "-c", "from supercoil.cli.main import main; main()",
                             *ARGS, "--out", out], env=env, capture_output=True, text=True,
                            check=False)
    if result.returncode != 0:
        print(f"{src}: exit {result.returncode}\n{result.stderr[-2000:]}")
    with open(os.path.join(out, "branch.json")) as f:
        return json.load(f)


def compare_lists(key: str, old: list, new: list) -> bool:
    if len(old) != len(new):
        print(f"{key}: {len(old)} against {len(new)} entries")
        return False
    same, worst = True, 0.0
    for a, b in zip(old, new, strict=True):
        for name, value in a.items():
            other = b.get(name)
            numbers = isinstance(value, (int, float)) and isinstance(other, (int, float))
            if numbers and value != other:
                same, worst = False, max(worst, abs(value - other))
            elif not numbers and value != other:
                same = False
                if not isinstance(value, list):
                    print(f"{key}: {name}: {value!r} against {other!r}")
    print(f"{key}: {len(old)} entries, largest numeric difference {worst:.3e}")
    return same


def main() -> int:
    old_src, new_src = sys.argv[1:3]
    folder = tempfile.mkdtemp()
    old = run(old_src, os.path.join(folder, "old"))
    new = run(new_src, os.path.join(folder, "new"))
    # both lists compared (and their differences printed) before any verdict
    verdicts = [compare_lists(key, old[key], new[key]) for key in ("points", "special_points")]
    same = all(verdicts)
    from supercoil import load

    stored_old = load(os.path.join(folder, "old"))
    stored_new = load(os.path.join(folder, "new"))
    for name, a_branch in stored_old.branches.items():
        b_branch = stored_new.branches.get(name)
        for key in ("parameter_values", "states", "multipliers", "tangents", "arclength"):
            a = np.asarray(getattr(a_branch, key))
            b = None if b_branch is None else np.asarray(getattr(b_branch, key))
            if b is None or a.shape != b.shape:
                print(f"{name}:{key}: shapes {a.shape} against "
                      f"{None if b is None else b.shape}")
                same = False
            elif not np.array_equal(a, b, equal_nan=True):
                print(f"{name}:{key}: largest difference {np.nanmax(np.abs(a - b)):.3e}")
                same = False
    print("IDENTICAL bit for bit" if same else "DIFFERENT (see above)")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
