"""Sums and restrictions of CSR matrices whose patterns repeat, without scipy's overhead.

Along a branch the Hessian is assembled many times per point on the same few
sparsity patterns (rod + contact + constraint curvature, restricted to the
free DOFs). scipy.sparse spends most of such a call on checks and index-dtype
bookkeeping (measured at N = 100: 60 µs per sum and 80 µs per restriction for
microseconds of arithmetic). These functions return the same matrices, entry
for entry and in the same stored order, by compiled passes or from index maps
computed once per pattern:

* :func:`csr_add` is ``A + B`` of scipy for canonical CSR operands (sorted,
  no duplicates): the union pattern, ``a + b`` where both are stored, ``a``
  or ``b`` alone elsewhere, and every entry that comes out zero dropped (as
  scipy's merge does), one compiled merge of the rows;
  :func:`csr_add_blocks` adds dense element blocks to ``A`` the same way, and
  optionally a third matrix after them;
* :func:`csr_restrict` is ``A[keep][:, keep]`` for sorted unique ``keep``:
  the kept entries of each kept row in their stored order, explicit zeros
  included, one compiled pass; :func:`csr_columns` is ``A[:, keep]`` likewise,
  from index maps computed once per pattern.

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
            total = 0
            for part in item:
                total += PatternMemo._size(part)
            return total
        if isinstance(item, bytes):
            return len(item)
        nbytes = getattr(item, "nbytes", None)
        return 8 if nbytes is None else int(nbytes)

    def get(self, key: tuple):
        return self._items.get(key)

    def put(self, key: tuple, value: tuple) -> None:
        size = self._size(key) + self._size(value)
        if size > self.max_bytes:
            return
        if key in self._items:  # replaced: its size no longer counts
            del self._items[key]
            self._total -= self._sizes.pop(key)
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


def pattern_words(A: sp.csr_matrix, B: sp.csr_matrix, u: np.ndarray, v: np.ndarray
                  ) -> tuple[np.ndarray, int]:
    """What a per-pattern memo needs to know of two CSR matrices and two vectors, as one
    int64 array, and a 64-bit hash of it: ``(words, hash)``.

    The words are the lengths of the six arrays, ``A.indptr``, ``2 A.indices + (A.data
    != 0)``, the same of ``B``, then ``u != 0`` and ``v != 0``: equal words, equal stored
    patterns, zeros and shapes' rows (the caller keys the columns). A memo keys on
    ``(hash, shapes)`` and compares the words of a hit (:func:`same_words`): exact, a
    collision is a miss. Made in one compiled pass (with four interleaved polynomial
    hashes): 11 µs for the 12 200 words of a contact state at N = 100 (10 400 entries
    of ``S``), and 7 µs for the comparison, where Python's hash of ``S.indices``' bytes
    alone took 25 µs (and the bordered factor's memos hashed them twice, ``J``'s
    three times)."""
    return _pattern_words(A.indptr, A.indices, A.data, B.indptr, B.indices, B.data,
                          np.asarray(u), np.asarray(v))


@njit()
def _pattern_words(a_ptr, a_idx, a_data, b_ptr, b_idx, b_data, u, v):
    words = np.empty(6 + a_ptr.size + a_idx.size + b_ptr.size + b_idx.size + u.size
                     + v.size, dtype=np.int64)
    words[0], words[1], words[2] = a_ptr.size, a_idx.size, b_ptr.size
    words[3], words[4], words[5] = b_idx.size, u.size, v.size
    w = 6
    for i in range(a_ptr.size):
        words[w] = a_ptr[i]
        w += 1
    for i in range(a_idx.size):
        words[w] = 2 * np.int64(a_idx[i]) + (a_data[i] != 0.0)
        w += 1
    for i in range(b_ptr.size):
        words[w] = b_ptr[i]
        w += 1
    for i in range(b_idx.size):
        words[w] = 2 * np.int64(b_idx[i]) + (b_data[i] != 0.0)
        w += 1
    for i in range(u.size):
        words[w] = u[i] != 0.0
        w += 1
    for i in range(v.size):
        words[w] = v[i] != 0.0
        w += 1
    # four polynomial hashes (base an odd 64-bit constant, wrapping) over the words
    # interleaved, so that the multiplications do not wait on each other
    base = np.int64(-7046029254386353131)  # 0x9E3779B97F4A7C15
    h0, h1, h2, h3 = np.int64(1), np.int64(2), np.int64(3), np.int64(4)
    quads = words.size // 4
    for q in range(quads):
        h0 = h0 * base + words[4 * q]
        h1 = h1 * base + words[4 * q + 1]
        h2 = h2 * base + words[4 * q + 2]
        h3 = h3 * base + words[4 * q + 3]
    for w in range(4 * quads, words.size):
        h0 = h0 * base + words[w]
    h = ((h0 * base + h1) * base + h2) * base + h3
    return words, h ^ (h >> 29)


@njit()
def same_words(a, b) -> bool:
    """``np.array_equal`` of two int64 arrays, compiled (no temporaries)."""
    if a.size != b.size:
        return False
    for i in range(a.size):
        if a[i] != b[i]:
            return False
    return True


def _pattern_key(A: sp.csr_matrix) -> tuple:
    return (A.shape, A.indptr.tobytes(), A.indices.tobytes())


def _is_canonical_csr(A) -> bool:
    return getattr(A, "format", None) == "csr" and A.has_canonical_format


def csr_from_arrays(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray,
                    shape: tuple[int, int], canonical: bool = False) -> sp.csr_matrix:
    """``scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)`` without copying the
    arrays; ``canonical``: the caller guarantees sorted indices without duplicates, and
    the matrix says so (``has_canonical_format``) without scipy checking every row."""
    out = sp.csr_matrix((data, indices, indptr), shape=shape, copy=False)
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


def csr_add_blocks(A: sp.csr_matrix, dofs: np.ndarray, blocks: np.ndarray,
                   then: sp.spmatrix | None = None) -> sp.csr_matrix:
    """``csr_add(A, block_csr(dofs, blocks, n))``, and with ``then`` ``csr_add`` of that
    and ``then``, without the intermediate matrices: the same entries, bit for bit.
    ``A`` and ``then`` square ``(n, n)``.

    One compiled pass over the rows (:func:`_add_blocks_kernel`): a row's block entries
    summed in the blocks' order (as :func:`_block_csr_kernel`), its columns sorted,
    merged into ``A``'s row and then into ``then``'s as :func:`_merge_kernel` merges,
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
    if dofs.ndim != 2 or not _is_canonical_csr(A) or A.dtype != np.float64 or \
            A.shape[1] != n or (c is not None and (not _is_canonical_csr(c) or c.dtype != np.float64
                               or c.shape != A.shape)):
        out = csr_add(A, block_csr(dofs, blocks, n))
        return out if c is None else csr_add(out, c)
    blocks = np.ascontiguousarray(np.asarray(blocks, dtype=float)[:p])
    if p and (dofs.min() < 0 or dofs.max() >= n
              or blocks.shape != (p, dofs.shape[1], dofs.shape[1])):
        raise ValueError("csr_add_blocks: DOFs outside [0, n) or blocks of the wrong shape")
    if c is None:
        c = _EMPTY_ROWS
        c_ptr = np.zeros(n + 1, dtype=np.int32)
    else:
        c_ptr = c.indptr
    upper = int(A.indptr[n]) - int(A.indptr[0]) + blocks.size + int(c_ptr[n]) - int(c_ptr[0])
    index_dtype, indptr_dtype = A.indices.dtype, A.indptr.dtype
    if max(int(upper), n) > np.iinfo(indptr_dtype).max:
        index_dtype = indptr_dtype = np.int64  # as scipy upcasts (see _canonical_csr)
    indptr, indices, data = _add_blocks_kernel(
        A.indptr, A.indices, A.data, dofs, blocks, c_ptr, c.indices, c.data, n,
        np.empty(0, dtype=index_dtype), np.empty(0, dtype=indptr_dtype))
    return csr_from_arrays(data, indices, indptr, A.shape, canonical=True)


_EMPTY_ROWS = sp.csr_matrix((1, 1))  # the indices and data of no entries


@njit()
def _add_blocks_kernel(a_ptr, a_idx, a_data, dofs, blocks, c_ptr, c_idx, c_data, n,
                       index_like, indptr_like):
    """Arrays of ``(A + block sum) + C`` (see :func:`csr_add_blocks`) with the dtypes of
    ``index_like`` and ``indptr_like``; ``C`` of no entries adds nothing."""
    p, w = dofs.shape
    # the blocks' rows touching each DOF, in block order (as _block_csr_kernel)
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
        nb = 0
        for e in range(start[r], start[r + 1]):
            k = which[e] // w
            i = which[e] - k * w
            for j in range(w):  # duplicates summed in the blocks' order
                col = dofs[k, j]
                if slot[col] < 0:
                    slot[col] = nb
                    b_cols[nb] = col
                    values[col] = blocks[k, i, j]
                    nb += 1
                else:
                    values[col] += blocks[k, i, j]
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
        # A's row + the block row, then that row + C's, as _merge_kernel
        nm = _merge_rows(a_idx, a_data, a_ptr[r], a_ptr[r + 1], b_cols, b_vals, 0, nb,
                         m_cols, m_vals, 0)
        nnz = _merge_rows(m_cols, m_vals, 0, nm, c_idx, c_data, c_ptr[r], c_ptr[r + 1],
                          indices, data, nnz)
        indptr[r + 1] = nnz
    # copies: the arrays were sized for every block entry (five times the sum's
    # entries at 79 pairs), which the matrix would otherwise hold
    return indptr, indices[:nnz].copy(), data[:nnz].copy()


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


def csr_restrict(A: sp.csr_matrix, keep: np.ndarray) -> sp.csr_matrix:
    """``A[keep][:, keep]`` as CSR (see module doc).

    For sorted unique ``keep``, one compiled pass (:func:`_restrict_kernel`) copies the
    kept entries of the kept rows in stored order. It replaced a memo of index maps per
    pattern: on the tweezers' contact branch (N = 100) the Hessian's pattern changes
    with the contact pairs, and a quarter of the calls missed the memo (0.14-0.20 ms
    each, 0.03-0.04 ms a hit; the kernel takes about 0.01 ms).
    """
    keep = np.asarray(keep)
    if getattr(A, "format", None) == "csr" and keep.ndim == 1 and keep.dtype.kind in "iu" \
            and A.shape[0] == A.shape[1] and A.dtype == np.float64 \
            and A.indices.dtype.kind == "i" and A.indptr.dtype.kind == "i":
        out = _restrict_kernel(A.indptr, A.indices, A.data, keep.astype(np.int64, copy=False),
                               A.shape[0])
        if out is not None:
            indptr, indices, data = out
            # the restriction of a canonical matrix is canonical (flagged so, the sums
            # that take it skip scipy's check)
            return csr_from_arrays(data, indices, indptr, (keep.size, keep.size),
                                   canonical=A.has_canonical_format)
    return A[keep][:, keep].tocsr()


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
