"""The two paths of the KKT factorisation and of the KKT ordering, on captured matrices.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_kkt_factor.py [--calls K]``

On the KKT matrices of the N = 200 ring captured in ``tests/data/kkt_ring200_*.npz``
(with and without contact; ``S`` the leading ``n x n`` block, ``J`` the rows below):

* the factorisation of ``[[S, J^T], [J, 0]]`` in its banded ordering by LAPACK's band
  LU (``supercoil.solvers.lu.BandLU``) and by SuperLU (``OrderedLU``);
* the banded ordering of a new pattern (``kkt_order`` without its memo) from the
  compiled merge of the patterns (``_kkt_order_merged``) and from scipy's sums and
  products (``_kkt_order_scipy``; the two give the same ordering, checked here).

Prints the smallest and the median milliseconds per call of each and their ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from supercoil.solvers import kkt_matrix, lu, ordering

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


def _blocks(path: Path) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
    z = np.load(path)
    n = int(z["n"])
    size = z["indptr"].size - 1
    K = sp.csr_matrix((z["data"], z["indices"], z["indptr"]), shape=(size, size))
    S = kkt_matrix.canonical(sp.csr_matrix(K[:n, :n]))
    J = kkt_matrix.canonical(sp.csr_matrix(K[n:, :n]))
    return S, J, ordering._kkt_order(S, J)


def _timed(function, calls: int, rounds: int = 7) -> list[float]:
    function()  # warm: compiled kernels loaded, memos of the layouts filled
    out = []
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(calls):
            function()
        out.append((time.perf_counter() - start) / calls * 1e3)
    return out


def _line(label: str, fast: list[float], slow: list[float], names: tuple[str, str]) -> str:
    a, b = statistics.median(fast), statistics.median(slow)
    return (f"{label}: {names[0]} min {min(fast):.3f} median {a:.3f} ms, {names[1]} min "
            f"{min(slow):.3f} median {b:.3f} ms, ratio of medians {b / a:.1f}")


def measure(path: Path, calls: int) -> None:
    S, J, order = _blocks(path)
    size = S.shape[0] + J.shape[0]
    values = kkt_matrix.kkt_values(S, J)
    layout = kkt_matrix.kkt_band_layout(S, J, order, values=values)
    entries = kkt_matrix.kkt_entries(S, J)
    band = _timed(lambda: lu.BandLU.from_layout(order, layout, values), calls)
    superlu = _timed(lambda: lu.OrderedLU(size, *entries, order), calls)
    print(_line(f"{path.stem} factor", band, superlu, ("band LU", "SuperLU")))
    assert np.array_equal(ordering._kkt_order_merged(S, J), ordering._kkt_order_scipy(S, J))
    merged = _timed(lambda: ordering._kkt_order_merged(S, J), calls)
    scipys = _timed(lambda: ordering._kkt_order_scipy(S, J), calls)
    print(_line(f"{path.stem} ordering", merged, scipys, ("merged", "scipy")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=50, metavar="K")
    args = parser.parse_args()
    for path in sorted(DATA.glob("kkt_ring200_*.npz")):
        measure(path, args.calls)


if __name__ == "__main__":
    main()
