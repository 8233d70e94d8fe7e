"""CSR matrices held as their arrays: construction, restriction, column selection, products.

scipy.sparse spends most of a call on small matrices on checks and index-dtype
bookkeeping (measured at N = 100: 80 µs per restriction for microseconds of
arithmetic). These functions return the same matrices, entry for entry and in
the same stored order, by compiled passes or from index maps computed once per
pattern:

* :func:`csr_restrict` is ``A[keep][:, keep]`` for sorted unique ``keep``:
  the kept entries of each kept row in their stored order, explicit zeros
  included, one compiled pass; :func:`csr_columns` is ``A[:, keep]`` likewise,
  from index maps computed once per pattern;
* :func:`csr_matvec`, :func:`csr_rmatvec` and :class:`CSRArrays` are the products
  ``A @ x`` and ``A.T @ x`` with scipy's sums, without a ``scipy.sparse`` object;
* :func:`csr_vstack` stacks CSR blocks by concatenating their arrays.

Sums of CSR matrices and of dense element blocks are in
:mod:`supercoil.solvers.csr_sum`. Anything else (other formats, unsorted or
duplicate indices) goes to scipy.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.solvers.patterns import PatternMemo


def _pattern_key(A: sp.csr_matrix) -> tuple:
    return (A.shape, A.indptr.tobytes(), A.indices.tobytes())


def is_canonical_float(A) -> bool:
    """Whether ``A`` is a canonical CSR matrix of float64 entries, or the
    :class:`CSRArrays` of one."""
    if isinstance(A, CSRArrays):
        return A.canonical and A.data.dtype == np.float64
    return getattr(A, "format", None) == "csr" and A.dtype == np.float64 \
        and A.has_canonical_format


def csr_from_arrays(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray,
                    shape: tuple[int, int], canonical: bool = False) -> sp.csr_matrix:
    """``scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)`` without copying the
    arrays; ``canonical``: the caller guarantees sorted indices without duplicates, and
    the matrix says so (``has_canonical_format``) without scipy checking every row."""
    out = sp.csr_matrix((data, indices, indptr), shape=shape, copy=False)
    if canonical:
        out.has_canonical_format = True
    return out

def csr_restrict(A: sp.csr_matrix, keep: np.ndarray) -> sp.csr_matrix:
    """``A[keep][:, keep]`` as CSR (see module doc): :func:`restrict_arrays` of a square
    float64 CSR ``A``, else scipy's slicing."""
    arrays = CSRArrays.of(A, check_canonical=False)
    out = None if arrays is None else restrict_arrays(arrays, keep)
    if out is None:
        return A[keep][:, keep].tocsr()
    # the restriction of a canonical matrix is canonical (flagged so, the sums that
    # take it skip scipy's check)
    out.canonical = A.has_canonical_format
    return out.tocsr()


def restrict_arrays(A: CSRArrays, keep: np.ndarray) -> CSRArrays | None:
    """``A[keep][:, keep]`` for the arrays of a square CSR matrix and sorted unique ``keep``
    (None for anything else): one compiled pass (:func:`_restrict_kernel`) copies the
    kept entries of the kept rows in stored order, explicit zeros included; canonical
    if ``A`` is.

    It replaced a memo of index maps per pattern: on the tweezers' contact branch
    (N = 100) the Hessian's pattern changes with the contact pairs, and a quarter of
    the calls missed the memo (0.14-0.20 ms each, 0.03-0.04 ms a hit; the kernel takes
    about 0.01 ms).
    """
    keep = np.asarray(keep)
    if keep.ndim != 1 or keep.dtype.kind not in "iu" or A.shape[0] != A.shape[1] \
            or A.data.dtype != np.float64 or A.indices.dtype.kind != "i" \
            or A.indptr.dtype.kind != "i":
        return None
    out = _restrict_kernel(A.indptr, A.indices, A.data, keep.astype(np.int64, copy=False),
                           A.shape[0])
    if out is None:
        return None
    indptr, indices, data = out
    return CSRArrays(data, indices, indptr, (keep.size, keep.size), A.canonical)


@njit()
def _restrict_kernel(indptr, indices, data, keep, n):
    """Arrays of ``A[keep][:, keep]`` for the square CSR ``A`` ``(n, n)``, index dtypes
    kept; None unless ``keep`` is strictly increasing within ``[0, n)``. One pass into
    arrays sized for the kept rows, returned as views of their filled part (a count
    pass first made the call 1.5 times slower)."""
    m = keep.size
    new = np.full(n, -1, dtype=np.int64)
    upper = 0
    for t in range(m):
        r = keep[t]
        if r < 0 or r >= n or (t > 0 and r <= keep[t - 1]):
            return None
        new[r] = t
        upper += indptr[r + 1] - indptr[r]
    out_ptr = np.zeros(m + 1, dtype=indptr.dtype)
    out_indices = np.empty(upper, dtype=indices.dtype)
    out_data = np.empty(upper)
    k = 0
    for t in range(m):
        r = keep[t]
        for e in range(indptr[r], indptr[r + 1]):
            c = new[indices[e]]
            if c >= 0:
                out_indices[k] = c
                out_data[k] = data[e]
                k += 1
        out_ptr[t + 1] = k
    return out_ptr, out_indices[:k], out_data[:k]


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


def csr_columns_map(A: sp.csr_matrix | CSRArrays, keep: np.ndarray):
    """``(selected, indices, indptr)`` with ``A[:, keep]`` equal to
    ``csr_from_arrays(A.data[selected], indices, indptr, (A.shape[0], keep.size))`` for
    every CSR matrix of ``A``'s pattern (what :func:`csr_columns` does), or None when
    ``A`` is not CSR (a scipy matrix or :class:`CSRArrays`) or ``keep`` is not sorted
    unique column indices (scipy's case). Callers must not modify the arrays."""
    keep = np.asarray(keep)
    is_csr = isinstance(A, CSRArrays) or getattr(A, "format", None) == "csr"
    if not is_csr or keep.ndim != 1 or keep.dtype.kind not in "iu" \
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


class CSRArrays:
    """A square or rectangular CSR matrix held as its arrays: for the products of
    refinement loops (``A @ x``, ``x`` ``(n,)`` or ``(n, k)``, by :func:`csr_matvec`,
    without a ``scipy.sparse`` object: its construction and operator dispatch cost 30 µs
    per factor and 20 µs per product at N = 100), and for the sums and restrictions
    of a Hessian's assembly, whose intermediate matrices nobody reads
    (:class:`~supercoil.solvers.problem.HessianParts`). ``canonical``: the indices of
    each row are sorted, without duplicates. ``tocsr``/``tocsc`` give the scipy matrix,
    which owns copies of the index arrays (the arrays may be a pattern's, shared)."""

    __slots__ = ("canonical", "data", "indices", "indptr", "shape")

    def __init__(self, data: np.ndarray, indices: np.ndarray, indptr: np.ndarray,
                 shape: tuple[int, int], canonical: bool = False):
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, shape
        self.canonical = canonical

    @classmethod
    def of(cls, A, check_canonical: bool = True) -> CSRArrays | None:
        """The arrays of a float64 ``scipy.sparse`` CSR matrix with integer indices (shared,
        not copied), None for anything else; ``canonical`` as ``A.has_canonical_format``
        (scipy checks the rows of a matrix not flagged either way), False without
        ``check_canonical``."""
        if getattr(A, "format", None) != "csr" or A.dtype != np.float64 \
                or A.indices.dtype.kind != "i" or A.indptr.dtype.kind != "i":
            return None
        return cls(A.data, A.indices, A.indptr, A.shape,
                   bool(A.has_canonical_format) if check_canonical else False)

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        return csr_matvec(self.indptr, self.indices, self.data, x, self.shape[1])

    def tocsr(self) -> sp.csr_matrix:
        return csr_from_arrays(self.data, self.indices.copy(), self.indptr.copy(), self.shape,
                               canonical=self.canonical)

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


def transpose_matvec(A, x: np.ndarray) -> np.ndarray:
    """``A.T @ x`` for a sparse ``A`` ``(m, n)`` and ``x`` ``(m,)``: for a float64 CSR ``A``
    by :func:`csr_rmatvec` (scipy's sums, without the transpose object), else scipy's."""
    if getattr(A, "format", None) == "csr" and A.dtype == np.float64:
        return csr_rmatvec(A.indptr, A.indices, A.data, x, A.shape[1])
    return A.T @ x


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
    same number of columns: their arrays concatenated (:func:`csr_stack_arrays`, what
    scipy's own fast path for CSR blocks does, without its checks and dispatch: 0.25 ms
    at N = 200 made 0.03 ms); anything else goes to scipy."""
    if not blocks or any(getattr(b, "format", None) != "csr" or b.dtype != np.float64
                         or b.shape[1] != blocks[0].shape[1] for b in blocks):
        return sp.vstack(blocks, format="csr")
    return csr_stack_arrays([(b.data, b.indices, b.indptr, b.shape[0]) for b in blocks],
                            blocks[0].shape[1])


def csr_stack_arrays(blocks: list, n_cols: int) -> sp.csr_matrix:
    """One CSR matrix of the row blocks ``(data, indices, indptr, n_rows)`` (CSR arrays of
    float64 blocks of ``n_cols`` columns) stacked in order: the matrix of
    :func:`stack_arrays`."""
    out = stack_arrays(blocks, n_cols)
    return csr_from_arrays(out.data, out.indices, out.indptr, out.shape)


def stack_arrays(blocks: list, n_cols: int, canonical: bool = False) -> CSRArrays:
    """The arrays of the row blocks ``(data, indices, indptr, n_rows)`` (CSR arrays of
    float64 blocks of ``n_cols`` columns) stacked in order: those of
    ``scipy.sparse.vstack`` of their matrices, built once, without a matrix per block
    (int32 indices where they fit, as scipy). ``canonical``: the caller knows every
    block to be canonical, and so is the stack."""
    n_rows = sum(int(rows) for _, _, _, rows in blocks)
    nnz = sum(int(indptr[rows] - indptr[0]) for _, _, indptr, rows in blocks)
    index = np.int32 if max(nnz, n_rows, n_cols) < 2**31 - 1 else np.int64
    indptr = np.empty(n_rows + 1, dtype=index)
    indptr[0] = 0
    row = offset = 0
    for _, _, b_ptr, rows in blocks:
        indptr[row + 1:row + rows + 1] = b_ptr[1:rows + 1] - b_ptr[0] + offset
        row += rows
        offset += int(b_ptr[rows] - b_ptr[0])
    indices = np.concatenate([b_idx[b_ptr[0]:b_ptr[rows]] for _, b_idx, b_ptr, rows in blocks]
                             ).astype(index, copy=False)
    data = np.concatenate([b_data[b_ptr[0]:b_ptr[rows]] for b_data, _, b_ptr, rows in blocks])
    return CSRArrays(data, indices, indptr, (n_rows, n_cols), canonical)
