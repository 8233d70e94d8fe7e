"""The stored entries of a KKT matrix ``[[S, J^T], [J, 0]]``, without forming it by bmat.

The entries ``scipy.sparse.bmat`` would store (explicit zeros of ``S`` and ``J``
included, duplicates summed), as arrays (:func:`kkt_entries`), as canonical
CSR (:func:`kkt_csr`) or poured into LAPACK's band storage of the reordered
matrix (:func:`kkt_band_layout`), each from index maps remembered per pattern.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.solvers.band import BandLayout, band_layout, band_layout_of_nonzeros
from supercoil.solvers.csr import CSRArrays
from supercoil.solvers.csr_sum import add_arrays, csr_add
from supercoil.solvers.patterns import PatternMemo


def canonical(M: sp.csr_matrix) -> sp.csr_matrix:
    """``M``, or a copy with sorted indices and duplicates summed (as bmat would)."""
    if M.has_canonical_format:
        return M
    M = M.copy()
    M.sum_duplicates()
    return M


def kkt_entries(S: sp.csr_matrix, J: sp.csr_matrix, values: bool = True):
    """Stored entries ``(rows, columns, values)`` of ``[[S, J^T], [J, 0]]``.

    The entries ``scipy.sparse.bmat`` stores (explicit zeros of ``S`` and
    ``J`` included, duplicates summed), without building it; ``values=False``:
    None for the values (the pattern only).
    """
    S, J = canonical(S), canonical(J)
    n, m = S.shape[0], J.shape[0]
    s_rows = np.repeat(np.arange(n), np.diff(S.indptr))
    if not m:
        return s_rows, S.indices.astype(np.int64), S.data if values else None
    j_rows = np.repeat(np.arange(m), np.diff(J.indptr)) + n
    return (np.concatenate([s_rows, J.indices, j_rows]),
            np.concatenate([S.indices, j_rows, J.indices]),
            kkt_values(S, J) if values else None)


def kkt_values(S: sp.csr_matrix, J: sp.csr_matrix) -> np.ndarray:
    """The values of :func:`kkt_entries` (canonical ``S``, ``J``): ``[S, J, J]``."""
    return np.concatenate([S.data, J.data, J.data]) if J.shape[0] else S.data


_BAND_MEMO = PatternMemo()


def kkt_band_layout(S: sp.csr_matrix, J: sp.csr_matrix, order: np.ndarray,
                    s_bytes: tuple[bytes, bytes] | None = None, max_fraction: float = 0.25,
                    values: np.ndarray | None = None) -> BandLayout | None:
    """:func:`~supercoil.solvers.band.band_layout` of ``[[S, J^T], [J, 0]]`` (canonical
    CSR ``S``, ``J``) reordered by ``order`` (row ``order[k]`` at ``k``): where the
    values :func:`kkt_values` go in the band storage of the reordered matrix, or None
    when its band is wider than ``max_fraction`` of it. Remembered per pattern (and
    order): the factorisations of a corrector share it, and the entries' reordering and
    band offsets (0.1 ms at N = 200) are not redone. ``s_bytes``: ``S``'s ``(indptr,
    indices)`` bytes if already made. ``values``: the :func:`kkt_values` of this
    matrix; with them, a stored band too wide is narrowed to the band of the nonzero
    entries (:func:`~supercoil.solvers.band.band_layout_of_nonzeros`; the ordering sees
    nonzeros only), and a layout that drops stored entries is returned only for values
    that are zero there (else None)."""
    n, m = S.shape[0], J.shape[0]
    if s_bytes is None:
        s_bytes = (S.indptr.tobytes(), S.indices.tobytes())
    order = np.asarray(order)
    key = (n, m, *s_bytes, J.indptr.tobytes(), J.indices.tobytes(), order.tobytes(),
           float(max_fraction), values is not None)
    found = _BAND_MEMO.get(key)
    if found is None:
        size = n + m
        position = np.empty(size, dtype=np.int64)
        position[order] = np.arange(size)
        S_c, J_c = canonical(S), canonical(J)  # as kkt_entries
        rows, cols = permuted_kkt_entries(S_c.indptr, S_c.indices, J_c.indptr, J_c.indices,
                                           position)
        layout = band_layout(size, rows, cols, max_fraction) if rows.size else None
        if layout is None and values is not None and rows.size:
            layout = band_layout_of_nonzeros(size, rows, cols, values, max_fraction)
        found = (layout,)
        _BAND_MEMO.put(key, found)
    layout = found[0]
    if layout is not None and layout.dropped is not None \
            and (values is None or not layout.holds(values)):
        return None
    return layout


@njit()
def permuted_kkt_entries(s_ptr, s_idx, j_ptr, j_idx, position):
    """The places ``(position[rows], position[columns])`` of :func:`kkt_entries`'
    entries of canonical ``S``, ``J`` (int64), without its concatenations and gathers
    (the larger half of a new pattern's band layout at N = 100)."""
    n, m = s_ptr.size - 1, j_ptr.size - 1
    total = s_idx.size + 2 * j_idx.size
    rows = np.empty(total, dtype=np.int64)
    cols = np.empty(total, dtype=np.int64)
    e = 0
    for i in range(n):
        for p in range(s_ptr[i], s_ptr[i + 1]):
            rows[e], cols[e] = position[i], position[s_idx[p]]
            e += 1
    for k in range(m):
        for p in range(j_ptr[k], j_ptr[k + 1]):
            rows[e], cols[e] = position[j_idx[p]], position[n + k]
            e += 1
    for k in range(m):
        for p in range(j_ptr[k], j_ptr[k + 1]):
            rows[e], cols[e] = position[n + k], position[j_idx[p]]
            e += 1
    return rows, cols


_CSR_MEMO = PatternMemo()


def kkt_csr(S: sp.csr_matrix, J: sp.csr_matrix) -> sp.csr_matrix:
    """``[[S, J^T], [J, 0]]`` (canonical CSR ``S``, ``J``) as canonical CSR: the arrays
    of ``scipy.sparse.csr_matrix((values, (rows, cols)))`` of :func:`kkt_entries`
    (each row's columns sorted, explicit zeros kept), from a gather remembered per
    pattern rather than a COO conversion and sort at every inertia count."""
    n, m = S.shape[0], J.shape[0]
    size = n + m
    key = (n, m, S.indptr.tobytes(), S.indices.tobytes(), J.indptr.tobytes(),
           J.indices.tobytes())
    found = _CSR_MEMO.get(key)
    if found is None:
        rows, cols, _values = kkt_entries(S, J, values=False)
        by_row = np.argsort(rows.astype(np.int64) * size + cols)  # distinct entries
        indptr = np.zeros(size + 1, dtype=np.int64)
        np.cumsum(np.bincount(rows, minlength=size), out=indptr[1:])
        index = np.int32 if max(size, rows.size) < 2**31 - 1 else np.int64
        found = (by_row, cols[by_row].astype(index), indptr.astype(index))
        _CSR_MEMO.put(key, found)
    by_row, indices, indptr = found
    K = sp.csr_matrix((kkt_values(S, J)[by_row], indices.copy(), indptr.copy()),
                      shape=(size, size))
    K.has_canonical_format = True
    return K


def shifted(S, shift: float, mass: np.ndarray) -> sp.csr_matrix:
    """``(S - shift * diags(mass)).tocsr()`` of scipy, entry for entry (``S`` a scipy
    matrix or the :class:`~supercoil.solvers.csr.CSRArrays` of one): ``S + D`` with
    ``D`` the CSR arrays of ``-(shift * mass)`` (zeros dropped, as scipy's conversion of
    the diagonal does), summed by :func:`~supercoil.solvers.csr_sum.add_arrays` (``a - b``
    is ``a + (-b)`` exactly; zeros of the sum dropped as scipy's subtraction does),
    one matrix made."""
    n = S.shape[0]
    diagonal = -(shift * np.asarray(mass, dtype=float))
    at = np.flatnonzero(diagonal != 0.0)
    index = S.indices.dtype if S.indices.dtype == S.indptr.dtype else np.int64
    indptr = np.zeros(n + 1, dtype=index)
    indptr[at + 1] = 1
    np.cumsum(indptr, out=indptr)
    D = CSRArrays(diagonal[at], at.astype(index), indptr, (n, n), canonical=True)
    arrays = S if isinstance(S, CSRArrays) else CSRArrays.of(S)
    if arrays is None or not arrays.canonical:
        return csr_add(S.tocsr(), D.tocsr())
    return add_arrays(arrays, D).tocsr()
