"""Sums and restrictions of CSR matrices whose patterns repeat, without scipy's overhead.

Along a branch the Hessian is assembled many times per point on the same few
sparsity patterns (rod + contact + constraint curvature, restricted to the
free DOFs). scipy.sparse spends most of such a call on checks and index-dtype
bookkeeping (measured at N = 100: 60 µs per sum and 80 µs per restriction for
microseconds of arithmetic). These functions return the same matrices, entry
for entry and in the same stored order, by compiled merges or from index maps
computed once per pattern:

* :func:`csr_add` is ``A + B`` of scipy for canonical CSR operands (sorted,
  no duplicates): the union pattern, ``a + b`` where both are stored, ``a``
  or ``b`` alone elsewhere, and every entry that comes out zero dropped (as
  scipy's merge does), one compiled merge of the rows;
  :func:`csr_add_blocks` adds dense element blocks to ``A`` the same way;
* :func:`csr_restrict` is ``A[keep][:, keep]`` for sorted unique ``keep``:
  the kept entries of each kept row in their stored order, explicit zeros
  included; :func:`csr_columns` is ``A[:, keep]`` likewise.

:func:`block_csr` assembles dense element blocks (a contact Hessian's pair
blocks) into canonical CSR in one compiled pass: the pattern of scipy's
``csr_matrix((data, (rows, cols)))``, duplicates summed in the input order.

Anything else (other formats, unsorted or duplicate indices) goes to scipy.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit


class PatternMemo:
    """A small first-in-first-out memo of per-pattern index maps, bounded in size.

    Keys and values are tuples of bytes, arrays and numbers; the oldest entries
    are dropped beyond ``max_entries`` or ``max_bytes`` (keys and values
    together), so that large problems (N = 10 000: tens of MB per pattern) keep
    one or two patterns rather than exhausting memory.
    """

    def __init__(self, max_entries: int = 16, max_bytes: int = 64 * 2**20):
        self.max_entries, self.max_bytes = max_entries, max_bytes
        self._items: dict[tuple, tuple] = {}
        self._sizes: dict[tuple, int] = {}
        self._total = 0

    @staticmethod
    def _size(item) -> int:
        if isinstance(item, tuple):
            return sum(PatternMemo._size(part) for part in item)
        return int(getattr(item, "nbytes", len(item) if isinstance(item, bytes) else 8))

    def get(self, key: tuple):
        return self._items.get(key)

    def put(self, key: tuple, value: tuple) -> None:
        size = self._size(key) + self._size(value)
        if size > self.max_bytes:
            return
        while self._items and (len(self._items) >= self.max_entries
                               or self._total + size > self.max_bytes):
            oldest = next(iter(self._items))
            del self._items[oldest]
            self._total -= self._sizes.pop(oldest)
        self._items[key] = value
        self._sizes[key] = size
        self._total += size

    def clear(self) -> None:
        self._items.clear()
        self._sizes.clear()
        self._total = 0

    def __len__(self) -> int:
        return len(self._items)

    def values(self):
        return self._items.values()


_RESTRICT_MEMO = PatternMemo()


def _pattern_key(A: sp.csr_matrix) -> tuple:
    return (A.shape, A.indptr.tobytes(), A.indices.tobytes())


def _is_canonical_csr(A) -> bool:
    return getattr(A, "format", None) == "csr" and A.has_canonical_format


# The attributes scipy's csr_matrix sets from (data, indices, indptr) besides the arrays,
# the shape and the (lazily computed) format flags; see csr_from_arrays.
_CSR_ATTRIBUTES = {"data", "indices", "indptr", "_shape", "maxprint", "_has_canonical_format",
                   "_has_sorted_indices"}
_CSR_FLAGS = ("_has_canonical_format", "_has_sorted_indices")


def _csr_template() -> dict | None:
    """The attributes (beyond arrays, shape and flags) of a csr_matrix scipy made, or None
    when scipy sets any attribute this module does not know (then scipy builds them)."""
    made = sp.csr_matrix((np.zeros(1), np.zeros(1, dtype=np.int32),
                          np.array([0, 1], dtype=np.int32)), shape=(1, 1))
    if type(made) is not sp.csr_matrix or not set(vars(made)) <= _CSR_ATTRIBUTES:
        return None
    return {k: v for k, v in vars(made).items()
            if k not in ("data", "indices", "indptr", "_shape") + _CSR_FLAGS}


_TEMPLATE = _csr_template()


def csr_from_arrays(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray,
                    shape: tuple[int, int], canonical: bool = False) -> sp.csr_matrix:
    """``scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)`` for arrays this
    module (or a caller holding a fixed layout) guarantees to be valid CSR: float64
    ``data``, int32 ``indices`` and ``indptr`` (the dtype scipy keeps; int64 ones, which
    scipy narrows when they fit, go to scipy), ``indptr`` non-decreasing from 0 to
    ``data.size``, indices in ``[0, shape[1])``. The object gets the attributes scipy gives it, without scipy's
    index-dtype and format checks (9 µs a construction at N = 200, of which 7 µs are
    the checks; some 10 000 constructions in the ring's diagram at N = 200). The
    arrays are not copied (as scipy's ``copy=False``). ``canonical``: set the
    canonical-format flag (sorted, no duplicates); otherwise scipy works it out when
    asked, as for a matrix it made. Anything else goes to scipy's constructor."""
    if _TEMPLATE is None or data.dtype != np.float64 or indices.dtype != np.int32 \
            or indptr.dtype != np.int32 or indices.ndim != 1 \
            or indptr.shape != (shape[0] + 1,) or max(shape) >= 2**31 - 1:
        out = sp.csr_matrix((data, indices, indptr), shape=shape)
    else:
        out = sp.csr_matrix.__new__(sp.csr_matrix)
        vars(out).update(_TEMPLATE)
        out.data, out.indices, out.indptr = data, indices, indptr
        out._shape = (int(shape[0]), int(shape[1]))
    if canonical:
        out.has_canonical_format = True
    return out


def csr_add(A: sp.csr_matrix, B: sp.spmatrix) -> sp.csr_matrix:
    """``(A + B).tocsr()`` (see module doc).

    Canonical float64 operands are merged row by row in one compiled pass
    (:func:`_merge_kernel`): ``a + b`` where both store an entry, ``a`` or
    ``0.0 + b`` where one does (the sums of the former per-pattern maps, which
    started from zeros), entries equal to zero dropped. The former path (a
    memo of index maps keyed by both patterns' bytes) spent most of a call on
    the key: 68 µs per hit at N = 200 (9000 + 12 800 entries), and a sort and
    two binary searches on every new contact pattern.
    """
    if not (_is_canonical_csr(A) and _is_canonical_csr(B)) or A.shape != B.shape \
            or A.dtype != np.float64 or B.dtype != np.float64:
        return (A + B).tocsr()
    indptr, indices, data = _merge_kernel(A.indptr, A.indices, A.data, B.indptr, B.indices,
                                          B.data, A.shape[0])
    return _canonical_csr(data, indices, indptr, A.shape, A.indices.dtype, A.indptr.dtype)


def csr_add_blocks(A: sp.csr_matrix, dofs: np.ndarray, blocks: np.ndarray) -> sp.csr_matrix:
    """``csr_add(A, block_csr(dofs, blocks, n))`` without the intermediate matrix: the
    same entries, bit for bit (the blocks' sums of :func:`_block_csr_kernel`, merged
    into ``A`` by :func:`_merge_kernel`). ``A`` square ``(n, n)``."""
    n = A.shape[0]
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    p = dofs.shape[0]
    if p == 0 or not _is_canonical_csr(A) or A.dtype != np.float64 or A.shape[1] != n:
        return csr_add(A, block_csr(dofs, blocks, n))
    blocks = np.ascontiguousarray(np.asarray(blocks, dtype=float)[:p])
    if dofs.min() < 0 or dofs.max() >= n or blocks.shape != (p, dofs.shape[1], dofs.shape[1]):
        raise ValueError("csr_add_blocks: DOFs outside [0, n) or blocks of the wrong shape")
    b_ptr, b_idx, b_data = _block_csr_kernel(dofs, blocks, n)
    indptr, indices, data = _merge_kernel(A.indptr, A.indices, A.data, b_ptr, b_idx, b_data, n)
    return _canonical_csr(data, indices, indptr, A.shape, A.indices.dtype, A.indptr.dtype)


def _canonical_csr(data, indices, indptr, shape, index_dtype, indptr_dtype) -> sp.csr_matrix:
    """The merged arrays as a canonical csr_matrix with the operands' index dtypes, wider
    (int64, as scipy would upcast) where those cannot hold the entry count or shape."""
    widest = np.iinfo(np.dtype(indptr_dtype)).max
    if max(int(indptr[-1]) if indptr.size else 0, *shape) > widest:
        index_dtype = indptr_dtype = np.int64
    return csr_from_arrays(data, indices.astype(index_dtype), indptr.astype(indptr_dtype), shape,
                           canonical=True)


@njit()
def _merge_kernel(a_ptr, a_idx, a_data, b_ptr, b_idx, b_data, n):
    """Arrays of ``A + B`` for canonical CSR ``A``, ``B`` with ``n`` rows: per row the
    sorted union of the columns, ``a + b`` where both store the column, ``a`` or
    ``0.0 + b`` where one does; entries equal to zero (either sign) dropped."""
    nnz_max = a_ptr[n] - a_ptr[0] + b_ptr[n] - b_ptr[0]
    indptr = np.zeros(n + 1, dtype=np.int64)
    indices = np.empty(nnz_max, dtype=np.int64)
    data = np.empty(nnz_max)
    nnz = 0
    for r in range(n):
        ia, ea = a_ptr[r], a_ptr[r + 1]
        ib, eb = b_ptr[r], b_ptr[r + 1]
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
        indptr[r + 1] = nnz
    return indptr, indices[:nnz].copy(), data[:nnz].copy()


def csr_restrict(A: sp.csr_matrix, keep: np.ndarray) -> sp.csr_matrix:
    """``A[keep][:, keep]`` as CSR (see module doc)."""
    keep = np.asarray(keep)
    if getattr(A, "format", None) != "csr" or keep.ndim != 1 or keep.dtype.kind not in "iu" or A.shape[0] != A.shape[1] \
            or (keep.size > 1 and not np.all(np.diff(keep) > 0)) \
            or (keep.size and (keep[0] < 0 or keep[-1] >= A.shape[0])):
        return A[keep][:, keep].tocsr()
    key = (_pattern_key(A), keep.tobytes())
    maps = _RESTRICT_MEMO.get(key)
    if maps is None:
        n = A.shape[0]
        new = np.full(n, -1, dtype=np.int64)
        new[keep] = np.arange(keep.size)
        rows = np.repeat(np.arange(n), np.diff(A.indptr))
        selected = np.flatnonzero((new[rows] >= 0) & (new[A.indices] >= 0))
        indptr = np.zeros(keep.size + 1, dtype=A.indptr.dtype)
        np.cumsum(np.bincount(new[rows[selected]], minlength=keep.size), out=indptr[1:])
        maps = (selected, new[A.indices[selected]].astype(A.indices.dtype), indptr)
        _RESTRICT_MEMO.put(key, maps)
    selected, indices, indptr = maps
    return csr_from_arrays(A.data[selected], indices.copy(), indptr.copy(),
                           (keep.size, keep.size))


_COLUMNS_MEMO = PatternMemo()


def csr_columns(A: sp.csr_matrix, keep: np.ndarray) -> sp.csr_matrix:
    """``A[:, keep]`` as CSR for sorted unique ``keep`` (explicit zeros kept, the stored
    order of each row unchanged); anything else goes to scipy."""
    keep = np.asarray(keep)
    maps = csr_columns_map(A, keep)
    if maps is None:
        return A[:, keep].tocsr()
    selected, indices, indptr = maps
    return csr_from_arrays(A.data[selected], indices.copy(), indptr.copy(),
                           (A.shape[0], keep.size))


def csr_columns_map(A: sp.csr_matrix, keep: np.ndarray):
    """``(selected, indices, indptr)`` with ``A[:, keep]`` equal to
    ``csr_from_arrays(A.data[selected], indices, indptr, (A.shape[0], keep.size))`` for
    every CSR matrix of ``A``'s pattern (what :func:`csr_columns` does), or None when
    ``A`` is not CSR or ``keep`` is not sorted unique column indices (scipy's case).
    Callers must not modify the arrays."""
    keep = np.asarray(keep)
    if getattr(A, "format", None) != "csr" or keep.ndim != 1 or keep.dtype.kind not in "iu" \
            or (keep.size > 1 and not np.all(np.diff(keep) > 0)) \
            or (keep.size and (keep[0] < 0 or keep[-1] >= A.shape[1])):
        return None
    key = (_pattern_key(A), keep.tobytes())
    maps = _COLUMNS_MEMO.get(key)
    if maps is None:
        new = np.full(A.shape[1], -1, dtype=np.int64)
        new[keep] = np.arange(keep.size)
        selected = np.flatnonzero(new[A.indices] >= 0)
        rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))[selected]
        indptr = np.zeros(A.shape[0] + 1, dtype=A.indptr.dtype)
        np.cumsum(np.bincount(rows, minlength=A.shape[0]), out=indptr[1:])
        maps = (selected, new[A.indices[selected]].astype(A.indices.dtype), indptr)
        _COLUMNS_MEMO.put(key, maps)
    return maps


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
    p, w = dofs.shape
    # the blocks' rows touching each DOF (CSR of the incidence), in block order
    start = np.zeros(n + 1, dtype=np.int64)
    for k in range(p):
        for i in range(w):
            start[dofs[k, i] + 1] += 1
    for r in range(n):
        start[r + 1] += start[r]
    which = np.empty(start[n], dtype=np.int64)  # k * w + i
    fill = start[:n].copy()
    for k in range(p):
        for i in range(w):
            r = dofs[k, i]
            which[fill[r]] = k * w + i
            fill[r] += 1
    slot = np.full(n, -1, dtype=np.int64)  # column -> position in the row being built
    indptr = np.zeros(n + 1, dtype=np.int64)
    indices = np.empty(start[n] * w, dtype=np.int64)
    data = np.empty(start[n] * w)
    values = np.empty(n)
    nnz = 0
    for r in range(n):
        first = nnz
        for e in range(start[r], start[r + 1]):
            k = which[e] // w
            i = which[e] - k * w
            for j in range(w):  # duplicates summed in the blocks' order
                c = dofs[k, j]
                if slot[c] < 0:
                    slot[c] = nnz
                    indices[nnz] = c
                    values[c] = blocks[k, i, j]
                    nnz += 1
                else:
                    values[c] += blocks[k, i, j]
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


class CSRArrays:
    """A square or rectangular CSR matrix held as its arrays, for the products of
    refinement loops: ``A @ x`` (``x`` ``(n,)`` or ``(n, k)``) by :func:`csr_matvec`,
    without a ``scipy.sparse`` object (its construction and operator dispatch cost
    30 µs per factor and 20 µs per product at N = 100). ``tocsr``/``tocsc`` give
    the scipy matrix (a sparse LU fallback)."""

    __slots__ = ("data", "indices", "indptr", "shape")

    def __init__(self, data: np.ndarray, indices: np.ndarray, indptr: np.ndarray,
                 shape: tuple[int, int]):
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, shape

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        return csr_matvec(self.indptr, self.indices, self.data, x, self.shape[1])

    def tocsr(self) -> sp.csr_matrix:
        return sp.csr_matrix((self.data, self.indices.copy(), self.indptr.copy()),
                             shape=self.shape)

    def tocsc(self) -> sp.csc_matrix:
        return self.tocsr().tocsc()


def csr_matvec(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray,
               x: np.ndarray, n_cols: int) -> np.ndarray:
    """``A @ x`` for the CSR arrays of ``A`` ``(m, n_cols)`` and ``x`` ``(n_cols,)`` or
    ``(n_cols, k)``: each row's products summed in stored order from 0, the loop of
    scipy's ``csr_matvec`` and ``csr_matvecs`` (the same sums; the tests compare them
    bit for bit). A wrong length raises ValueError, as scipy's "dimension mismatch"
    (the compiled loops do not check their indices)."""
    x = np.asarray(x, dtype=float)
    if x.shape[0] != n_cols:
        raise ValueError(f"dimension mismatch: a matrix of {n_cols} columns times a vector "
                         f"of {x.shape[0]} entries")
    if x.ndim == 1:
        return _csr_matvec(indptr, indices, data, x)
    return _csr_matvecs(indptr, indices, data, np.ascontiguousarray(x))


@njit()
def _csr_matvec(indptr, indices, data, x):
    n = indptr.size - 1
    y = np.empty(n)
    for i in range(n):
        total = 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            total += data[jj] * x[indices[jj]]
        y[i] = total
    return y


@njit()
def _csr_matvecs(indptr, indices, data, x):
    n, k = indptr.size - 1, x.shape[1]
    y = np.zeros((n, k))
    for i in range(n):
        for jj in range(indptr[i], indptr[i + 1]):
            a = data[jj]
            j = indices[jj]
            for c in range(k):
                y[i, c] += a * x[j, c]
    return y


def csr_rmatvec(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, x: np.ndarray,
                n_cols: int) -> np.ndarray:
    """``A.T @ x`` for the CSR arrays of ``A`` ``(m, n_cols)`` and ``x`` ``(m,)``: row ``k``'s
    entries times ``x[k]`` added to their columns, rows in order, the loop of scipy's
    ``csc_matvec`` on ``A.T`` (the same sums) without making the transpose (a new
    ``csc_matrix`` each time, 15 µs at N = 200). A wrong length of ``x`` raises
    ValueError, as scipy's "dimension mismatch"."""
    x = np.asarray(x, dtype=float)
    if x.shape != (indptr.size - 1,):
        raise ValueError(f"dimension mismatch: the transpose of a matrix of "
                         f"{indptr.size - 1} rows times a vector of shape {x.shape}")
    return _csr_rmatvec(indptr, indices, data, x, n_cols)


@njit()
def _csr_rmatvec(indptr, indices, data, x, n_cols):
    y = np.zeros(n_cols)
    for k in range(indptr.size - 1):
        xk = x[k]
        for jj in range(indptr[k], indptr[k + 1]):
            y[indices[jj]] += data[jj] * xk
    return y


def csr_vstack(blocks: list) -> sp.csr_matrix:
    """``scipy.sparse.vstack(blocks, format="csr")`` for CSR blocks of float64 with the
    same number of columns: their arrays concatenated (what scipy's own fast path for
    CSR blocks does, without its checks and dispatch: 0.25 ms at N = 200 made 0.03 ms);
    anything else goes to scipy."""
    if not blocks or any(getattr(b, "format", None) != "csr" or b.dtype != np.float64
                         or b.shape[1] != blocks[0].shape[1] for b in blocks):
        return sp.vstack(blocks, format="csr")
    n_rows = sum(b.shape[0] for b in blocks)
    nnz = sum(int(b.indptr[-1]) for b in blocks)
    index = np.int32 if max(nnz, n_rows, blocks[0].shape[1]) < 2**31 - 1 else np.int64
    indptr = np.empty(n_rows + 1, dtype=index)
    indptr[0] = 0
    row = offset = 0
    for b in blocks:
        indptr[row + 1:row + b.shape[0] + 1] = b.indptr[1:b.shape[0] + 1] - b.indptr[0] + offset
        row += b.shape[0]
        offset += int(b.indptr[b.shape[0]] - b.indptr[0])
    indices = np.concatenate([b.indices[b.indptr[0]:b.indptr[-1]] for b in blocks]).astype(
        index, copy=False)
    data = np.concatenate([b.data[b.indptr[0]:b.indptr[-1]] for b in blocks])
    return csr_from_arrays(data, indices, indptr, (n_rows, blocks[0].shape[1]))
