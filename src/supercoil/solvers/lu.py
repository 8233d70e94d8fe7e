"""LU factors with partial pivoting of a symmetrically reordered sparse matrix.

Two back ends with one interface (``solve``, ``determinant_sign``, ``order``):
LAPACK's band LU (:class:`BandLU`) where the reordered band is narrow, SuperLU
(:class:`OrderedLU`) where it is wide. A symmetric reordering keeps the
determinant, so its sign is the product of the signs of ``U``'s diagonal and
the parities of the row (and column) interchanges.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.linalg import splu

from supercoil.solvers.band import BandLayout, band_factor, band_layout
from supercoil.solvers.errors import SingularMatrixError


def permutation_parity(perm: np.ndarray) -> int:
    """+1 for an even permutation, -1 for an odd one: ``(-1)^(n - cycles)``.

    Cycles are counted by pointer jumping (each index learns the smallest
    index of its cycle in ``log2 n`` vectorised rounds); a loop over the
    indices took 0.17 ms per call at n = 400, twice per inertia count.
    """
    perm = np.asarray(perm, dtype=np.int64)
    n = perm.size
    smallest = np.arange(n)
    jump = perm.copy()
    covered = 1  # each index has seen the next `covered` indices of its cycle
    while covered < n:
        np.minimum(smallest, smallest[jump], out=smallest)
        jump = jump[jump]
        covered *= 2
    cycles = int(np.count_nonzero(smallest == np.arange(n)))
    return -1 if (n - cycles) % 2 else 1
class OrderedLU:
    """SuperLU with partial pivoting of a symmetrically reordered matrix.

    Built from the matrix's entries: the permuted matrix is formed directly in
    the canonical CSC form (sorted, as splu makes it) that ``K[order][:,
    order]`` gave, so SuperLU factorises the same arrays.
    """

    def __init__(self, size: int, rows: np.ndarray, cols: np.ndarray, values: np.ndarray,
                 order: np.ndarray):
        self.order = order
        position = np.empty(size, dtype=np.int64)
        position[order] = np.arange(size)
        prow, pcol = position[rows], position[cols]
        by_column = np.lexsort((prow, pcol))
        indptr = np.zeros(size + 1, dtype=np.int64)
        np.cumsum(np.bincount(pcol, minlength=size), out=indptr[1:])
        Kp = sp.csc_matrix((values[by_column], prow[by_column], indptr), shape=(size, size))
        self.lu = splu(Kp, permc_spec="NATURAL")
        self.perm_r = self.lu.perm_r
        self.perm_c = self.lu.perm_c

    @property
    def U(self):
        return self.lu.U

    def determinant_sign(self) -> int:
        """Sign of the determinant (a symmetric reordering keeps it) from the pivoted LU."""
        sign = int(np.prod(np.sign(self.lu.U.diagonal())))
        return sign * permutation_parity(self.perm_r) * permutation_parity(self.perm_c)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        sol = self.lu.solve(np.ascontiguousarray(rhs[self.order]))
        out = np.empty_like(sol)
        out[self.order] = sol
        return out


class BandLU:
    """LAPACK's band LU with partial pivoting (``dgbtrf``) of a symmetrically reordered
    matrix, from its entries (no duplicates): the interface of :class:`OrderedLU`.

    On the banded KKT ordering the two are the same elimination, rows pivoted
    within the band; solves agree to round-off (relative to the condition
    number), not bit for bit. The band LU is 2 to 10 times faster on the captured
    KKT matrices of the N = 200 ring, with and without contact
    (``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_kkt_factor.py``). :meth:`from_layout` and :meth:`of` return
    None (the caller takes SuperLU) when the band is wider than a quarter of the
    matrix, as :class:`~supercoil.continuation.bordered.BorderedFactor` does.
    """

    def __init__(self, order, lub, piv, kl, ku):
        self.order = order
        self._lub, self._piv, self._kl, self._ku = lub, piv, kl, ku

    @classmethod
    def of(cls, size: int, rows: np.ndarray, cols: np.ndarray, values: np.ndarray,
           order: np.ndarray) -> BandLU | None:
        if size < 2 or values.size == 0:
            return None
        position = np.empty(size, dtype=np.int64)
        position[order] = np.arange(size)
        return cls.from_layout(order, band_layout(size, position[rows], position[cols]), values)

    @classmethod
    def from_layout(cls, order: np.ndarray, layout: BandLayout | None, values: np.ndarray
                    ) -> BandLU | None:
        """:meth:`of` with the band layout of the reordered entries already made
        (:func:`~supercoil.solvers.kkt_matrix.kkt_band_layout`); None for a ``layout`` of None (band too wide)."""
        if layout is None or layout.size < 2 or values.size == 0:
            return None
        lub, piv, kl, ku, info = band_factor(layout, values)
        if info > 0:  # U(info, info) is exactly zero, as SuperLU's "exactly singular"
            raise SingularMatrixError("KKT matrix is singular (a zero pivot in the band LU)")
        if info < 0:
            return None
        return cls(order, lub, piv, kl, ku)

    def determinant_sign(self) -> int:
        """Sign of the determinant of the reordered matrix (that of the matrix itself:
        a symmetric permutation keeps it): ``prod sign(U_ii)`` times the row swaps' parity."""
        diag = self._lub[self._kl + self._ku]
        swaps = int(np.count_nonzero(self._piv != np.arange(self._piv.size)))
        return int(np.prod(np.sign(diag))) * (-1 if swaps % 2 else 1)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        sol, _info = lapack.dgbtrs(self._lub, self._kl, self._ku,
                                   np.ascontiguousarray(rhs[self.order]), self._piv)
        out = np.empty_like(sol)
        out[self.order] = sol
        return out
