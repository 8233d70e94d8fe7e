"""Dense constraint rows and their pins: keeping the KKT matrix banded.

A dense row of the constraint Jacobian (Doedel's integral phase condition
``<M g, q - q_0> = 0``, whose row is a whole symmetry mode) would make the
banded ordering of the KKT matrix as wide as the matrix. :func:`dense_rows`
finds them; :class:`PinnedRows` replaces each by a *pin*, its own entry on one
DOF, which keeps the factorised matrix banded, and keeps the rest of the rows
as a low-rank term (:mod:`supercoil.solvers.kkt`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.solvers.kkt_matrix import canonical
from supercoil.solvers.patterns import PatternMemo

# A constraint row is dense when it stores more than max(DENSE_ROW_MIN_ENTRIES,
# DENSE_ROW_FRACTION * n) nonzeros: an integral phase condition (all of a mode's
# DOFs) is, a contact constraint (12 DOFs) or a node gauge (1 DOF) is not.
DENSE_ROW_MIN_ENTRIES = 32
DENSE_ROW_FRACTION = 0.1


def dense_rows(J: sp.spmatrix) -> np.ndarray:
    """Indices of the dense rows of the constraint Jacobian ``J`` ``(m, n)`` (rule above)."""
    J = J if isinstance(J, sp.csr_matrix) else sp.csr_matrix(J)
    if not has_long_rows(J):
        return np.zeros(0, dtype=np.int64)
    limit = max(DENSE_ROW_MIN_ENTRIES, DENSE_ROW_FRACTION * J.shape[1])
    # only rows storing more than the limit can hold more nonzeros: count theirs
    candidates = np.flatnonzero(np.diff(J.indptr) > limit)
    counts = [np.count_nonzero(J.data[J.indptr[k]:J.indptr[k + 1]]) for k in candidates]
    return candidates[np.asarray(counts, dtype=np.int64) > limit] if candidates.size \
        else np.zeros(0, dtype=np.int64)


def has_long_rows(J: sp.csr_matrix) -> bool:
    """Whether the CSR matrix ``J`` stores a row of more entries than a dense row has
    nonzeros (:func:`dense_rows` looks only at those: without them ``J`` has no dense
    rows), by a compiled pass over ``J.indptr`` (numpy's took 30 µs at N = 100)."""
    limit = max(DENSE_ROW_MIN_ENTRIES, DENSE_ROW_FRACTION * J.shape[1])
    return J.shape[0] > 0 and _longest_row(J.indptr) > limit


@njit()
def _longest_row(indptr):
    longest = 0
    for k in range(indptr.size - 1):
        longest = max(longest, indptr[k + 1] - indptr[k])
    return longest


class PinnedRows:
    """Dense rows of ``J`` split into pins and the rest (see module doc).

    ``rows`` ``(r,)`` are the dense rows, ``pins`` ``(r,)`` the DOF pinned by
    each, chosen by Gaussian elimination with partial pivoting on the dense
    rows (each pin the largest remaining entry of its row), so that the
    ``(r, r)`` block ``J[rows][:, pins]`` is regular and pinning those DOFs
    removes the modes the rows hold. ``sparse`` is ``J`` with each dense row
    replaced by its entry at its pin (CSR, canonical); ``delta`` ``(r, n)``
    the dense rows with that entry zeroed, so ``J = sparse + I[:, rows] delta``.
    """

    def __init__(self, sparse: sp.csr_matrix, rows: np.ndarray, pins: np.ndarray,
                 delta: np.ndarray):
        self.sparse, self.rows, self.pins, self.delta = sparse, rows, pins, delta

    @classmethod
    def of(cls, J: sp.spmatrix) -> PinnedRows | None:
        """The split of ``J``, or None when it has no dense rows (or they are dependent)."""
        J = J if isinstance(J, sp.csr_matrix) else sp.csr_matrix(J)
        rows = dense_rows(J)
        if rows.size == 0:
            return None
        if not J.has_canonical_format:
            J = canonical(J)
            rows = dense_rows(J)
            if rows.size == 0:
                return None
        r, n = rows.size, J.shape[1]
        dense = np.zeros((r, n))
        for j, row in enumerate(rows):
            a, b = J.indptr[row], J.indptr[row + 1]
            dense[j, J.indices[a:b]] = J.data[a:b]
        work = dense.copy()
        pins = np.zeros(r, dtype=np.int64)
        for j in range(r):
            pins[j] = int(np.argmax(np.abs(work[j])))
            pivot = work[j, pins[j]]
            if pivot == 0.0 or abs(pivot) <= 1e-12 * np.max(np.abs(dense[j])):
                return None
            work[j + 1:] -= np.outer(work[j + 1:, pins[j]] / pivot, work[j])
        values = dense[np.arange(r), pins]
        delta = dense.copy()
        delta[np.arange(r), pins] = 0.0
        # the CSR arrays of J with each dense row cut to its pin (canonical: one entry);
        # where the kept entries go depends on the pattern only (remembered)
        key = (J.shape, J.indptr.tobytes(), J.indices.tobytes(), rows.tobytes())
        layout = _CUT_MEMO.get(key)
        if layout is None:
            counts = np.diff(J.indptr)
            new_counts = counts.copy()
            new_counts[rows] = 1
            indptr = np.zeros(J.shape[0] + 1, dtype=J.indptr.dtype)
            np.cumsum(new_counts, out=indptr[1:])
            row_of = np.repeat(np.arange(J.shape[0]), counts)
            kept = np.ones(J.shape[0], dtype=bool)
            kept[rows] = False
            kept = kept[row_of]
            entries = np.flatnonzero(kept)
            at = indptr[row_of[entries]] + entries - J.indptr[row_of[entries]]
            indices = np.empty(indptr[-1], dtype=J.indices.dtype)
            indices[at] = J.indices[entries]
            layout = (indptr, at, entries, indices)
            _CUT_MEMO.put(key, layout)
        indptr, at, entries, indices = layout
        indptr, indices = indptr.copy(), indices.copy()
        data = np.empty(indptr[-1])
        data[at] = J.data[entries]
        indices[indptr[rows]], data[indptr[rows]] = pins, values
        sparse = sp.csr_matrix((data, indices, indptr), shape=J.shape)
        sparse.has_canonical_format = True
        return cls(sparse, rows, pins, delta)

    def low_rank(self, n: int, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(E, Delta, gamma)`` of ``K = K_pin + E Delta^T + Delta E^T`` on a KKT matrix of
        ``size`` unknowns with ``n`` DOFs first: ``E`` ``(size, r)`` unit columns at the
        pinned rows' multipliers, ``Delta`` ``(size, r)`` the rest of the rows on the DOFs,
        ``gamma`` ``(r,)`` their largest entries (for balancing)."""
        r = self.rows.size
        E = np.zeros((size, r))
        E[n + self.rows, np.arange(r)] = 1.0
        Delta = np.zeros((size, r))
        Delta[:self.delta.shape[1]] = self.delta.T
        gamma = np.max(np.abs(self.delta), axis=1)
        gamma[gamma == 0.0] = 1.0
        return E, Delta, gamma


_CUT_MEMO = PatternMemo()
