"""Benchmark: the exact inertia count of a KKT matrix (``solvers.inertia``), per call.

Run from the repository root:

    python benchmarks/bench_inertia.py MATRIX.pkl [MATRIX.pkl ...]
        [--against SRC] [--rounds 7] [--calls 50]

Each ``MATRIX.pkl`` holds ``(A, order)`` (a sparse symmetric matrix and its
bandwidth-reducing order, as ``kkt_negative_count`` passes them); a ``.npz``
holds ``n``, csr ``indptr``, ``indices``, ``data`` and ``order`` (the two of
``tests/data/kkt_ring200_*.npz``, captured from the N = 200 ring). Times
``inertia._symmetric_inertia(A, order)`` warm, ``--calls`` calls per round; with
``--against SRC`` (a ``src`` folder, e.g. ``git archive main src | tar -x -C
/tmp/old``) the ``solvers/inertia.py`` of that tree (its ``solvers/band.py`` in
a tree that had no ``inertia.py``) is loaded beside this one and
the two are timed in alternating rounds (the host's speed drifts). Prints the
counts of both (they must agree), the smallest and median milliseconds per call,
and their ratios.
"""

from __future__ import annotations

import argparse
import importlib.util
import pickle
import statistics
import time
from pathlib import Path

from threadpoolctl import threadpool_limits


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _matrix(path: str):
    if path.endswith(".npz"):
        import numpy as np
        import scipy.sparse as sp

        f = np.load(path)
        n = int(f["n"])
        return sp.csr_matrix((f["data"], f["indices"], f["indptr"]), shape=(n, n)), f["order"]
    with open(path, "rb") as handle:
        return pickle.load(handle)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("matrices", nargs="+")
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--calls", type=int, default=50)
    args = parser.parse_args(argv)

    from supercoil.solvers import inertia

    versions = {"this": inertia}
    if args.against:
        solvers = Path(args.against) / "supercoil" / "solvers"
        module = solvers / "inertia.py"
        versions["against"] = _load(module if module.exists() else solvers / "band.py",
                                    "inertia_against")
    with threadpool_limits(limits=1, user_api="blas"):
        for path in args.matrices:
            A, order = _matrix(path)
            counts = {k: v._symmetric_inertia(A, order) for k, v in versions.items()}
            times: dict[str, list[float]] = {k: [] for k in versions}
            for _ in range(args.rounds):
                for key, module in versions.items():
                    start = time.perf_counter()
                    for _ in range(args.calls):
                        module._symmetric_inertia(A, order)
                    times[key].append(1e3 * (time.perf_counter() - start) / args.calls)
            print(f"{path}: n = {A.shape[0]}, counts {counts}")
            for key, t in times.items():
                print(f"  {key}: min {min(t):.3f} ms, median {statistics.median(t):.3f} ms")
            if args.against:
                this, other = times["this"], times["against"]
                print(f"  against / this: min {min(other) / min(this):.2f}, "
                      f"median {statistics.median(other) / statistics.median(this):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
