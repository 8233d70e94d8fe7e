"""The banded ordering of a KKT matrix that keeps its leading blocks regular.

:func:`kkt_order` orders ``[[S, J^T], [J, 0]]`` by reverse Cuthill–McKee on the
pattern of ``|S| + |J^T J|``, each multiplier right after the first unknown its
constraint touches. Along a branch the same few patterns come back at every
corrector iteration: orderings are remembered per pattern, with a certificate
(:class:`OrderMemo`) that the pattern of ``J^T J`` is the remembered one for
other values of ``J``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from supercoil._numba import njit
from supercoil.solvers.band import bandwidth_order
from supercoil.solvers.csr import csr_from_arrays, is_canonical_float
from supercoil.solvers.csr_sum import merge_kernel
from supercoil.solvers.patterns import PatternMemo


def kkt_order(S: sp.spmatrix, J: sp.spmatrix) -> np.ndarray:
    """Banded ordering of ``[[S, J^T], [J, 0]]`` that keeps leading blocks regular.

    Reverse Cuthill–McKee on the pattern of ``S + J^T J``; each multiplier is
    placed right after the first unknown its constraint touches. Every leading
    principal submatrix is then the KKT matrix of a piece of the rod whose
    boundary edges are constrained too; placing multipliers after their last
    unknown instead leaves the boundary edges free to stretch, a near-null
    mode of the angle-based bending energy that ruined the inertia count
    (measured at N = 400 near Michell's mode-3 threshold).

    The ordering depends on the nonzero pattern only, and along a branch the
    same few patterns come back at every corrector iteration: orderings are
    remembered by the stored patterns of ``S`` and ``J`` and their zero
    entries (:class:`OrderMemo`). Forming the pattern of ``S + J^T J`` with
    scipy.sparse cost 0.6 ms of a 2 ms bordered factorisation at N = 100. A new
    pattern (the integral contact's pairs change: 200 of the tweezers' 1098 orderings
    at N = 100) is ordered from a compiled merge of the patterns
    (:func:`_kkt_order_merged`).
    """
    return remembered_order(S, J)[0]


def remembered_order(S: sp.spmatrix, J: sp.spmatrix) -> tuple[np.ndarray, OrderMemo | None]:
    """:func:`kkt_order` and the :class:`OrderMemo` that certifies it for other values
    of ``J`` of the same stored patterns and zeros (None: not remembered), for a caller
    that remembers more per pattern (:class:`~supercoil.continuation.bordered.
    BorderedFactor`)."""
    J = J if isinstance(J, sp.csr_matrix) else sp.csr_matrix(J)  # read only here
    if getattr(S, "format", None) != "csr" or not J.has_canonical_format:
        return _kkt_order(S, J), None
    j_key = (J.shape, J.indptr.tobytes(), J.indices.tobytes(),
             np.packbits(J.data != 0).tobytes())
    key = (S.shape, S.indptr.tobytes(), S.indices.tobytes(),
           np.packbits(S.data != 0).tobytes(), *j_key)
    memo = _ORDER_MEMO.get(key)
    if memo is not None and memo[0].certifies(J):
        return memo[0].order.copy(), memo[0]
    pairs = _gram_pattern(J, j_key)
    order = _kkt_order(S, J, pairs)
    memo = OrderMemo.of(J, order, pairs) if pairs is not None else None
    if memo is not None and memo.certifies(J):
        _ORDER_MEMO.put(key, (memo, memo.order, memo._first, memo._second, memo._group,
                              memo._two_terms, memo._cancelled))
        return order, memo
    return order, None


class OrderMemo:
    """A :func:`kkt_order` with what makes it valid for other values of ``J``.

    Same stored patterns and zeros of ``S`` and ``J`` give the same pattern
    of ``|S| + |J^T J|`` unless an entry of ``J^T J`` is an exact zero
    through cancellation (scipy's product drops those). :meth:`certifies`
    checks that every entry of ``J^T J`` (``t`` terms ``J_ka J_kb``) has
    ``|sum| > 1e-8 sum |terms|``: then its floating-point sum, in any order,
    is not zero, and the pattern, hence the ordering, is the remembered one.
    An entry with exactly two terms has the same sum in either order, so scipy's
    product stores it exactly when that sum is not 0: such an entry certifies
    when it is stored or dropped as in the ``J`` the order was computed with,
    however small (an exactly symmetric state, where the two edges at a node on
    a mirror axis cancel to 0 or to round-off; under the 1e-8 rule alone every
    such state missed the memo: 1542 of 1552 orderings recomputed on the ring's
    alpha branch, N = 200).
    """

    MAX_TERMS_PER_ENTRY = 64  # dense rows (a phase condition) are not remembered

    def __init__(self, order, first, second, group, n_groups, two_terms=None, cancelled=None):
        self.order = order
        self._first, self._second, self._group, self._n_groups = first, second, group, n_groups
        # entries of J^T J with exactly two terms, and those of them that cancelled
        # exactly in the J the order was computed with (None: no exact cancellation
        # allowed, the former rule)
        self._two_terms, self._cancelled = two_terms, cancelled

    @classmethod
    def of(cls, J: sp.csr_matrix, order: np.ndarray, pairs: _GramPattern | None = None):
        """The memo of ``order`` for ``J`` (``pairs``: :func:`_gram_pattern` of ``J`` if
        known), or None when ``J`` has dense rows."""
        pairs = _gram_pattern(J) if pairs is None else pairs
        if pairs is None:
            return None
        memo = cls(order, pairs.first, pairs.second, pairs.group, pairs.n_groups,
                   pairs.two_terms)
        memo._cancelled = memo._exactly_cancelled(J)
        return memo

    def _exactly_cancelled(self, J: sp.csr_matrix) -> np.ndarray:
        """Entries of J^T J with two terms that sum to exactly 0 (a sum of two numbers
        is the same in either order, so scipy's product drops exactly these)."""
        total, _size = _pair_sums(J.data, self._first, self._second, self._group,
                                  self._n_groups)
        return self._two_terms & (total == 0.0)

    def certifies(self, J: sp.csr_matrix) -> bool:
        """Whether the order is that of ``J``'s values (class doc), in one compiled pass
        (:func:`_certified`: the numpy version's sums and tests took 35 µs a call at
        N = 100)."""
        if self._cancelled is None:
            none = np.zeros(0, dtype=bool)
            return bool(_certified(J.data, self._first, self._second, self._group,
                                   self._n_groups, none, none, True))
        return bool(_certified(J.data, self._first, self._second, self._group,
                               self._n_groups, self._two_terms, self._cancelled, False))


@njit()
def _certified(data, first, second, group, n_groups, two_terms, cancelled, strict):
    """:meth:`OrderMemo.certifies` on :func:`_pair_sums`' sums: every entry of ``J^T J``
    has ``|sum| > 1e-8 sum |terms|`` (``strict``), or, else, every entry of more than
    two terms has, and each entry of two terms cancels exactly (sum 0) where
    ``cancelled`` says and only there (an entry of two terms is present exactly when
    its sum is not 0: either order gives the same sum)."""
    total, size = _pair_sums(data, first, second, group, n_groups)
    for k in range(n_groups):
        nonzero = abs(total[k]) > 1e-8 * size[k]
        if strict:
            if not nonzero:
                return False
        elif not (nonzero or two_terms[k]) \
                or (two_terms[k] and total[k] == 0.0) != cancelled[k]:
            return False
    return True


@njit()
def _pair_sums(data, first, second, group, n_groups):
    """Per entry of ``J^T J``: the sum of its terms ``t = data[first] * data[second]`` and
    of their magnitudes, added in the terms' order: ``np.bincount(group, t)`` and
    ``np.bincount(group, |t|)`` (the same sums; one pass, no temporaries: 0.05 ms of a
    memo hit at N = 100 before)."""
    total = np.zeros(n_groups)
    size = np.zeros(n_groups)
    for i in range(group.size):
        t = data[first[i]] * data[second[i]]
        total[group[i]] += t
        size[group[i]] += abs(t)
    return total, size


# values (memo, its arrays): the arrays only count towards the memory bound
_ORDER_MEMO = PatternMemo(max_entries=32)


class _GramPattern:
    """The entries of ``J^T J`` as sums of products of ``J``'s nonzero entries, per
    pattern of ``J`` (stored entries and which of them are zero).

    ``first``, ``second`` index ``J.data``: every ordered pair of nonzero entries of
    one row, term ``J_ka J_kb`` of the entry ``(a, b)``; ``group`` numbers the
    entries (``n_groups`` of them) in the row-major order of their ``(a, b)``;
    ``two_terms`` marks those with exactly two terms, ``one_term`` those with one.
    ``slots`` are the entries of ``J^T J + I`` (row-major keys ``a n + b``, sorted),
    ``slot_of_group`` each entry's slot and ``diagonal`` the slots on the diagonal.
    ``rows``, ``columns`` are the nonzero entries of ``J`` (the multipliers'
    places in :func:`kkt_order`).
    """

    __slots__ = ("columns", "diagonal", "first", "group", "n_groups", "one_term", "rows",
                 "second", "slot_of_group", "slots", "two_terms")

    @property
    def nbytes(self) -> int:  # for PatternMemo's memory bound
        return sum(int(getattr(self, name).nbytes) for name in self.__slots__
                   if name != "n_groups")


def _gram_pattern(J: sp.csr_matrix, key: tuple | None = None) -> _GramPattern | None:
    """:class:`_GramPattern` of canonical CSR ``J`` (remembered per pattern; ``key``: its
    ``(shape, indptr, indices, nonzero bits)`` bytes if made), or None when ``J`` has
    dense rows (more than ``OrderMemo.MAX_TERMS_PER_ENTRY`` terms per nonzero entry)."""
    if key is None:
        key = (J.shape, J.indptr.tobytes(), J.indices.tobytes(),
               np.packbits(J.data != 0).tobytes())
    found = _GRAM_MEMO.get(key)
    if found is not None:
        return found[0]
    m, n = J.shape
    stored = np.flatnonzero(J.data != 0)
    row = np.repeat(np.arange(m), np.diff(J.indptr))[stored]
    counts = np.bincount(row, minlength=m)
    if stored.size and int(np.sum(counts**2)) > OrderMemo.MAX_TERMS_PER_ENTRY * stored.size:
        _GRAM_MEMO.put(key, (None,))
        return None
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    # all pairs (e1, e2) of stored entries of one row: e1 = starts[k] + u, e2 = starts[k] + v
    pair_row = np.repeat(np.arange(m), counts**2)
    within = np.arange(pair_row.size) - np.repeat(np.cumsum(counts**2) - counts**2, counts**2)
    width = counts[pair_row]
    out = _GramPattern()
    out.first = stored[starts[pair_row] + within // np.maximum(width, 1)]
    out.second = stored[starts[pair_row] + within % np.maximum(width, 1)]
    entry = J.indices[out.first].astype(np.int64) * n + J.indices[out.second]
    keys, group = np.unique(entry, return_inverse=True)
    out.group = group.ravel()
    out.n_groups = keys.size
    terms = np.bincount(out.group, minlength=keys.size)
    out.two_terms, out.one_term = terms == 2, terms == 1
    out.slots = np.union1d(keys, np.arange(n, dtype=np.int64) * (n + 1))
    out.slot_of_group = np.searchsorted(out.slots, keys)
    out.diagonal = np.zeros(out.slots.size, dtype=bool)
    out.diagonal[np.searchsorted(out.slots, np.arange(n, dtype=np.int64) * (n + 1))] = True
    out.rows, out.columns = row, J.indices[stored].astype(np.int64)
    _GRAM_MEMO.put(key, (out,))
    return out


_GRAM_MEMO = PatternMemo()


def _kkt_order(S: sp.spmatrix, J: sp.spmatrix, pairs: _GramPattern | None = None
               ) -> np.ndarray:
    """:func:`kkt_order` computed (not remembered): :func:`_kkt_order_merged` where it
    applies, else :func:`_kkt_order_scipy` (the same ordering)."""
    order = _kkt_order_merged(S, J, pairs)
    return order if order is not None else _kkt_order_scipy(S, J)


def _kkt_order_merged(S: sp.spmatrix, J: sp.spmatrix, pairs: _GramPattern | None = None
                      ) -> np.ndarray | None:
    """:func:`_kkt_order_scipy`'s ordering, the pattern of ``|S| + |J^T J| + I`` made by
    one compiled merge (:func:`~supercoil.solvers.csr_sum.merge_kernel`) of ``|S|``
    with the pattern of ``J^T J + I`` (:func:`_gram_pattern`), or None (then scipy's
    path) for operands it does not take or a ``J^T J`` whose pattern it cannot certify.

    The pattern is scipy's, so reverse Cuthill-McKee gets the same arrays: sorted rows
    (scipy's sums of canonical matrices are sorted), every nonzero of ``S``, the
    diagonal, and each entry of ``J^T J`` that scipy's product keeps, an entry whose sum
    is not exactly zero. An entry of one or two terms has the same sum in any order
    (``0 + t1 + t2``): kept exactly when that is not 0. An entry of more terms must
    have ``|sum| > 1e-8 sum |terms|`` (then no order of summation gives 0), else None.
    The merge is 3 to 4 times faster than scipy's sums and products on the captured
    KKT matrices of the N = 200 ring (``OPENBLAS_NUM_THREADS=1 python
    benchmarks/bench_kkt_factor.py``), which spend most of their time forming that
    pattern; it orders the tweezers' new contact patterns (about one factorisation in
    five). :func:`_kkt_order_scipy` orders what the merge does not take.
    """
    if not (is_canonical_float(S) and is_canonical_float(J)) or S.shape[0] != S.shape[1] \
            or J.shape[1] != S.shape[0] or S.shape[0] >= 2**31 - 1:
        return None
    n, m = S.shape[0], J.shape[0]
    if pairs is None:
        pairs = _gram_pattern(J)
        if pairs is None:
            return None
    total, size = _pair_sums(J.data, pairs.first, pairs.second, pairs.group, pairs.n_groups)
    exact = pairs.one_term | pairs.two_terms
    if not np.all(exact | (np.abs(total) > 1e-8 * size)):
        return None
    present = pairs.diagonal.copy()
    present[pairs.slot_of_group[(total != 0.0) | ~exact]] = True
    keys = pairs.slots[present]
    gram_indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(keys // n, minlength=n), out=gram_indptr[1:])
    # the index dtypes of S (as csr_add's operands): one compiled specialisation
    indptr, indices, _data = merge_kernel(
        S.indptr, S.indices, np.abs(S.data), gram_indptr.astype(S.indptr.dtype),
        (keys % n).astype(S.indices.dtype), np.ones(keys.size), n)
    pattern = csr_from_arrays(np.ones(indices.size), indices.astype(np.int32),
                              indptr.astype(np.int32), (n, n), canonical=True)
    x_order = np.asarray(reverse_cuthill_mckee(pattern, symmetric_mode=True), dtype=np.int64)
    if m == 0:
        return x_order
    return _place_multipliers(x_order, pairs.rows, pairs.columns, n, m)


def _place_multipliers(x_order: np.ndarray, rows: np.ndarray, columns: np.ndarray, n: int,
                       m: int) -> np.ndarray:
    """``x_order`` with each multiplier right after the first unknown its constraint
    touches (``rows``, ``columns``: the nonzero entries of ``J``; see :func:`kkt_order`)."""
    return _place_multipliers_kernel(np.asarray(x_order, dtype=np.int64),
                                     np.asarray(rows, dtype=np.int64),
                                     np.asarray(columns, dtype=np.int64), n, m)


@njit()
def _place_multipliers_kernel(x_order, rows, columns, n, m):
    """:func:`_place_multipliers` compiled: the multipliers bucketed by the place of their
    first unknown (in index order within a bucket, as numpy's stable sort of the keys
    ``2 place + 1`` among the unknowns' ``2 k`` did; 50 µs of it at N = 100)."""
    position = np.empty(n, dtype=np.int64)
    for k in range(n):
        position[x_order[k]] = k
    first = np.full(m, n, dtype=np.int64)
    for e in range(rows.size):
        first[rows[e]] = min(first[rows[e]], position[columns[e]])
    start = np.zeros(n + 2, dtype=np.int64)
    for j in range(m):
        start[first[j] + 1] += 1
    for k in range(n + 1):
        start[k + 1] += start[k]
    bucket = np.empty(m, dtype=np.int64)
    fill = start.copy()
    for j in range(m):
        bucket[fill[first[j]]] = j
        fill[first[j]] += 1
    out = np.empty(n + m, dtype=np.int64)
    e = 0
    for k in range(n + 1):
        if k < n:
            out[e] = x_order[k]
            e += 1
        for t in range(start[k], start[k + 1]):
            out[e] = n + bucket[t]
            e += 1
    return out


def _kkt_order_scipy(S: sp.spmatrix, J: sp.spmatrix) -> np.ndarray:
    """:func:`kkt_order` computed with scipy.sparse (the reference of the merged path)."""
    n, m = S.shape[0], J.shape[0]
    J = sp.csr_matrix(J, copy=True)
    J.eliminate_zeros()  # a straight rod's constraints do not touch its lateral DOFs
    x_order = bandwidth_order(abs(S) + abs(J.T @ J))
    if m == 0:
        return x_order
    row_of_entry = np.repeat(np.arange(m), np.diff(J.indptr))
    return _place_multipliers(x_order, row_of_entry, J.indices, n, m)
