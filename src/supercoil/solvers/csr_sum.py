"""Sums of CSR matrices and of dense element blocks, as scipy makes them, compiled.

Along a branch the Hessian is assembled many times per point on the same few
sparsity patterns (rod + contact + constraint curvature). scipy.sparse spends
most of such a sum on checks and index-dtype bookkeeping (measured at N = 100:
60 µs per sum for microseconds of arithmetic). These functions return the same
matrices, entry for entry and in the same stored order, by compiled passes:

* :func:`csr_add` is ``A + B`` of scipy for canonical CSR operands (sorted,
  no duplicates): the union pattern, ``a + b`` where both are stored, ``a``
  or ``b`` alone elsewhere, and every entry that comes out zero dropped (as
  scipy's merge does), one compiled merge of the rows;
  :func:`csr_add_blocks` adds dense element blocks to ``A`` the same way, and
  optionally a third matrix after them;
* :func:`block_csr` assembles dense element blocks (a contact Hessian's pair
  blocks) into canonical CSR in one compiled pass: the pattern of scipy's
  ``csr_matrix((data, (rows, cols)))``, duplicates summed in the input order.

Anything else (other formats, unsorted or duplicate indices) goes to scipy.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.solvers.csr import CSRArrays, csr_from_arrays


def csr_add(A: sp.csr_matrix, B: sp.spmatrix) -> sp.csr_matrix:
    """``(A + B).tocsr()`` (see module doc): :func:`add_arrays` of canonical float64
    operands of one shape, else scipy's sum."""
    a, b = CSRArrays.of(A), CSRArrays.of(B)
    if a is None or b is None or not (a.canonical and b.canonical) or A.shape != B.shape:
        return (A + B).tocsr()
    return add_arrays(a, b).tocsr()


def add_arrays(A: CSRArrays, B: CSRArrays) -> CSRArrays:
    """The arrays of scipy's ``A + B`` for canonical float64 CSR arrays of one shape.

    Merged row by row in one compiled pass (:func:`merge_kernel`): ``a + b`` where both
    store an entry, ``a`` or ``0.0 + b`` where one does (the sums of the former
    per-pattern maps, which started from zeros), entries equal to zero dropped; the
    index dtypes of ``A`` (see :func:`canonical_arrays`). The former path (a memo of
    index maps keyed by both patterns' bytes) spent most of a call on the key: 68 µs
    per hit at N = 200 (9000 + 12 800 entries), and a sort and two binary searches on
    every new contact pattern.
    """
    indptr, indices, data = merge_kernel(A.indptr, A.indices, A.data, B.indptr, B.indices,
                                          B.data, A.shape[0])
    return canonical_arrays(data, indices, indptr, A.shape, A.indices.dtype, A.indptr.dtype)


def csr_add_blocks(A: sp.csr_matrix, dofs: np.ndarray, blocks: np.ndarray,
                   then: sp.spmatrix | None = None) -> sp.csr_matrix:
    """``csr_add(A, block_csr(dofs, blocks, n))``, and with ``then`` ``csr_add`` of that
    and ``then``, without the intermediate matrices: the same entries, bit for bit
    (:func:`add_blocks_arrays` of canonical float64 operands, else those sums)."""
    a = CSRArrays.of(A)
    c = None if then is None else CSRArrays.of(then)
    out = None
    if a is not None and a.canonical and (then is None or (c is not None and c.canonical)):
        out = add_blocks_arrays(a, dofs, blocks, c)
    if out is None:
        out = csr_add(A, block_csr(dofs, blocks, A.shape[0]))
        return out if then is None else csr_add(out, then)
    return out.tocsr()


def add_blocks_arrays(A: CSRArrays, dofs: np.ndarray, blocks: np.ndarray,
                      then: CSRArrays | None = None) -> CSRArrays | None:
    """The arrays of ``csr_add(A, block_csr(dofs, blocks, n))``, and with ``then`` of
    ``csr_add`` of that and ``then``, for canonical float64 CSR arrays ``A`` and ``then``
    ``(n, n)``; None when ``A`` or ``then`` is not such or ``dofs`` is not ``(p, w)``.

    One compiled pass over the rows (:func:`_add_blocks_kernel`): a row's block entries
    summed in the blocks' order (as :func:`_block_csr_kernel`), its columns sorted,
    merged into ``A``'s row and then into ``then``'s as :func:`merge_kernel` merges,
    zero sums dropped at each merge. Measured at two states of the tweezers' contact
    branch (N = 100, 13 and 79 pairs of 24-DOF blocks): 0.08 -> 0.05 ms and 0.21 ->
    0.17 ms against the block matrix and one :func:`csr_add` per operand (the block
    matrix's two transposes, and each call's checks and conversions, saved). A
    layout of the sum kept per pattern (the pair list was the previous call's in 526
    of 651 calls) cost 0.09 ms a hit and 0.46 ms a miss at 79 pairs; taking rows and
    columns by nodes gained 15 %: neither kept.
    """
    n = A.shape[0]
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    p = dofs.shape[0]
    c = then
    if dofs.ndim != 2 or not A.canonical or A.data.dtype != np.float64 or A.shape[1] != n \
            or (c is not None and (not c.canonical or c.data.dtype != np.float64
                                   or c.shape != A.shape)):
        return None
    blocks = np.ascontiguousarray(np.asarray(blocks, dtype=float)[:p])
    if p and (dofs.min() < 0 or dofs.max() >= n
              or blocks.shape != (p, dofs.shape[1], dofs.shape[1])):
        raise ValueError("csr_add_blocks: DOFs outside [0, n) or blocks of the wrong shape")
    if c is None:
        c_ptr, c_idx, c_data = np.zeros(n + 1, dtype=np.int32), _NO_INDICES, _NO_VALUES
    else:
        c_ptr, c_idx, c_data = c.indptr, c.indices, c.data
    upper = int(A.indptr[n]) - int(A.indptr[0]) + blocks.size + int(c_ptr[n]) - int(c_ptr[0])
    index_dtype, indptr_dtype = A.indices.dtype, A.indptr.dtype
    if max(int(upper), n) > np.iinfo(indptr_dtype).max:
        index_dtype = indptr_dtype = np.int64  # as scipy upcasts (see canonical_arrays)
    indptr, indices, data = _add_blocks_kernel(
        A.indptr, A.indices, A.data, dofs, blocks, c_ptr, c_idx, c_data, n,
        np.empty(0, dtype=index_dtype), np.empty(0, dtype=indptr_dtype))
    return CSRArrays(data, indices, indptr, A.shape, canonical=True)


_NO_INDICES = np.zeros(0, dtype=np.int32)  # the indices and values of no entries
_NO_VALUES = np.zeros(0)


@njit()
def _block_rows(dofs, n):
    """The blocks' rows touching each DOF (the CSR of the incidence), in block order:
    ``(start, which)``, DOF ``r``'s rows ``which[start[r]:start[r + 1]]`` as ``k * w + i``
    (row ``i`` of block ``k``, ``w`` rows a block)."""
    p, w = dofs.shape
    start = np.zeros(n + 1, dtype=np.int64)
    for k in range(p):
        for i in range(w):
            start[dofs[k, i] + 1] += 1
    for r in range(n):
        start[r + 1] += start[r]
    which = np.empty(start[n], dtype=np.int64)
    fill = start[:n].copy()
    for k in range(p):
        for i in range(w):
            r = dofs[k, i]
            which[fill[r]] = k * w + i
            fill[r] += 1
    return start, which


@njit(inline="always")
def _sum_block_row(r, start, which, dofs, blocks, slot, values, cols, count):
    """Row ``r`` of the block sum (rows from :func:`_block_rows`): each column met for the
    first time is marked in ``slot`` and appended to ``cols`` at ``count``, its value
    summed into ``values[column]`` in the blocks' order; returns the new ``count``."""
    w = dofs.shape[1]
    for e in range(start[r], start[r + 1]):
        k = which[e] // w
        i = which[e] - k * w
        for j in range(w):  # duplicates summed in the blocks' order
            col = dofs[k, j]
            if slot[col] < 0:
                slot[col] = count
                cols[count] = col
                values[col] = blocks[k, i, j]
                count += 1
            else:
                values[col] += blocks[k, i, j]
    return count


@njit()
def _add_blocks_kernel(a_ptr, a_idx, a_data, dofs, blocks, c_ptr, c_idx, c_data, n,
                       index_like, indptr_like):
    """Arrays of ``(A + block sum) + C`` (see :func:`csr_add_blocks`) with the dtypes of
    ``index_like`` and ``indptr_like``; ``C`` of no entries adds nothing."""
    p, w = dofs.shape
    start, which = _block_rows(dofs, n)
    upper = a_ptr[n] - a_ptr[0] + p * w * w + c_ptr[n] - c_ptr[0]
    indptr = np.zeros(n + 1, dtype=indptr_like.dtype)
    indices = np.empty(upper, dtype=index_like.dtype)
    data = np.empty(upper)
    slot = np.full(n, -1, dtype=np.int64)  # column -> position in the row's block columns
    values = np.empty(n)  # the row's block sums, by column
    b_cols = np.empty(n, dtype=np.int64)
    b_vals = np.empty(n)  # the block sums in the order of b_cols
    m_cols = np.empty(n, dtype=np.int64)  # the row of A + blocks
    m_vals = np.empty(n)
    nnz = 0
    for r in range(n):
        nb = _sum_block_row(r, start, which, dofs, blocks, slot, values, b_cols, 0)
        for t in range(1, nb):  # insertion sort: the blocks' columns come in sorted runs
            col = b_cols[t]
            u = t - 1
            while u >= 0 and b_cols[u] > col:
                b_cols[u + 1] = b_cols[u]
                u -= 1
            b_cols[u + 1] = col
        for t in range(nb):
            b_vals[t] = values[b_cols[t]]
            slot[b_cols[t]] = -1
        # A's row + the block row, then that row + C's, as merge_kernel
        nm = _merge_rows(a_idx, a_data, a_ptr[r], a_ptr[r + 1], b_cols, b_vals, 0, nb,
                         m_cols, m_vals, 0)
        nnz = _merge_rows(m_cols, m_vals, 0, nm, c_idx, c_data, c_ptr[r], c_ptr[r + 1],
                          indices, data, nnz)
        indptr[r + 1] = nnz
    # copies: the arrays were sized for every block entry (five times the sum's
    # entries at 79 pairs), which the matrix would otherwise hold
    return indptr, indices[:nnz].copy(), data[:nnz].copy()


def canonical_arrays(data, indices, indptr, shape, index_dtype, indptr_dtype) -> CSRArrays:
    """The merged arrays as canonical CSR arrays with the operands' index dtypes, wider
    (int64, as scipy would upcast) where those cannot hold the entry count or shape."""
    widest = np.iinfo(np.dtype(indptr_dtype)).max
    if max(int(indptr[-1]) if indptr.size else 0, *shape) > widest:
        index_dtype = indptr_dtype = np.int64
    return CSRArrays(data, indices.astype(index_dtype), indptr.astype(indptr_dtype), shape,
                     canonical=True)


@njit()
def merge_kernel(a_ptr, a_idx, a_data, b_ptr, b_idx, b_data, n):
    """Arrays of ``A + B`` for canonical CSR ``A``, ``B`` with ``n`` rows: per row the
    sorted union of the columns, ``a + b`` where both store the column, ``a`` or
    ``0.0 + b`` where one does; entries equal to zero (either sign) dropped."""
    nnz_max = a_ptr[n] - a_ptr[0] + b_ptr[n] - b_ptr[0]
    indptr = np.zeros(n + 1, dtype=np.int64)
    indices = np.empty(nnz_max, dtype=np.int64)
    data = np.empty(nnz_max)
    nnz = 0
    for r in range(n):
        nnz = _merge_rows(a_idx, a_data, a_ptr[r], a_ptr[r + 1], b_idx, b_data, b_ptr[r],
                          b_ptr[r + 1], indices, data, nnz)
        indptr[r + 1] = nnz
    return indptr, indices[:nnz].copy(), data[:nnz].copy()


@njit(inline="always")
def _merge_rows(a_idx, a_data, ia, ea, b_idx, b_data, ib, eb, indices, data, nnz):
    """One row of ``A + B``: the sorted entries ``ia:ea`` of ``a_idx``/``a_data`` and
    ``ib:eb`` of ``b_idx``/``b_data`` merged into ``indices``/``data`` from ``nnz`` on,
    ``a + b`` where both store the column, ``a`` or ``0.0 + b`` where one does, entries
    equal to zero (either sign) dropped; returns the new ``nnz``."""
    while ia < ea or ib < eb:
        if ib >= eb or (ia < ea and a_idx[ia] < b_idx[ib]):
            c = a_idx[ia]
            value = a_data[ia]
            ia += 1
        elif ia >= ea or b_idx[ib] < a_idx[ia]:
            c = b_idx[ib]
            value = 0.0 + b_data[ib]
            ib += 1
        else:
            c = a_idx[ia]
            value = a_data[ia] + b_data[ib]
            ia += 1
            ib += 1
        if value != 0.0:
            indices[nnz] = c
            data[nnz] = value
            nnz += 1
    return nnz


def block_csr(dofs: np.ndarray, blocks: np.ndarray, n: int) -> sp.csr_matrix:
    """``sum_k`` of the dense ``blocks[k]`` ``(w, w)`` at rows and columns ``dofs[k]``
    ``(w,)``, as an ``(n, n)`` canonical CSR matrix (``dofs`` ``(p, w)``, entries in
    ``[0, n)``; ``blocks`` ``(>= p, w, w)``, the first ``p`` used).

    The pattern, explicit zeros included, and the stored order are those of
    ``scipy.sparse.csr_matrix((blocks.ravel(), (rows, cols)))`` with ``rows``,
    ``cols`` the blocks' DOFs; duplicates are summed in the order the blocks
    come (a stable sort of each row), scipy sums them in the order of its
    unstable sort: equal to round-off. Measured on the ring's contact branch
    at N = 200 (57 pair blocks of 24 DOFs): 0.05 ms against 0.63 ms.
    """
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    p = dofs.shape[0]
    blocks = np.ascontiguousarray(np.asarray(blocks, dtype=float)[:p])
    if p == 0:
        return sp.csr_matrix((n, n))
    if dofs.min() < 0 or dofs.max() >= n or blocks.shape != (p, dofs.shape[1], dofs.shape[1]):
        raise ValueError("block_csr: DOFs outside [0, n) or blocks of the wrong shape")
    indptr, indices, data = _block_csr_kernel(dofs, blocks, n)
    index = np.int32 if max(n, indices.size) < 2**31 - 1 else np.int64
    return csr_from_arrays(data, indices.astype(index), indptr.astype(index), (n, n),
                           canonical=True)


@njit()
def _block_csr_kernel(dofs, blocks, n):
    w = dofs.shape[1]
    start, which = _block_rows(dofs, n)
    slot = np.full(n, -1, dtype=np.int64)  # column -> position in the row being built
    indptr = np.zeros(n + 1, dtype=np.int64)
    indices = np.empty(start[n] * w, dtype=np.int64)
    data = np.empty(start[n] * w)
    values = np.empty(n)
    nnz = 0
    for r in range(n):
        first = nnz
        nnz = _sum_block_row(r, start, which, dofs, blocks, slot, values, indices, nnz)
        for t in range(first, nnz):
            c = indices[t]
            data[t] = values[c]
            slot[c] = -1
        indptr[r + 1] = nnz
    # the columns of each row sorted by transposing twice (a counting sort each time;
    # numba's sort of every row's slice took 20 times longer)
    t_indptr, t_indices, t_data = _transpose(indptr, indices[:nnz], data[:nnz], n)
    return _transpose(t_indptr, t_indices, t_data, n)


@njit()
def _transpose(indptr, indices, data, n):
    """CSR of the transpose of the square CSR ``(indptr, indices, data)``: each row's
    entries sorted by column, whatever the order of the input's."""
    nnz = indptr[n]
    out_ptr = np.zeros(n + 1, dtype=np.int64)
    for e in range(nnz):
        out_ptr[indices[e] + 1] += 1
    for r in range(n):
        out_ptr[r + 1] += out_ptr[r]
    fill = out_ptr[:n].copy()
    out_indices = np.empty(nnz, dtype=np.int64)
    out_data = np.empty(nnz)
    for r in range(n):
        for e in range(indptr[r], indptr[r + 1]):
            c = indices[e]
            out_indices[fill[c]] = r
            out_data[fill[c]] = data[e]
            fill[c] += 1
    return out_ptr, out_indices, out_data
