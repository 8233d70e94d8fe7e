"""Sparse symmetric KKT factorisation with inertia.

The saddle-point matrix of an energy ``E`` with constraints ``c`` is

    K = [[H, J^T], [J, 0]],   H = S + U diag(w) U^T,

with ``S`` sparse (banded for a rod) and a few dense rank-one terms
(treated with the Woodbury identity in both parts below).

Solves use an LU with partial pivoting on ``K`` in a banded ordering (stable for
saddle points): LAPACK's band LU where the ordered band is narrow, SuperLU
where it is wider than a quarter of the matrix (see :class:`KKTFactor`).

Inertia. ``L D L^T`` without pivoting breaks down on saddle-point matrices
(element growth; measured wrong counts on a ring), and an augmented Hessian
``H + rho J^T J`` mis-signs eigenvalues of size ``O(1/rho)`` (measured: the
count flickers near Michell's threshold). The count is exact instead: block
elimination with look-ahead on the banded ordering and Haynsworth's inertia
additivity (:mod:`supercoil.solvers.band`). Since
``neg(K) = neg(Z^T H Z) + m`` (Gould 1985) for ``m`` independent constraints,
at least ``m`` must be found (checked).
With the rank-one terms, from the two Schur complements of
``[[K_S, U], [U^T, -W^-1]]`` (Haynsworth's inertia additivity, both ways):
``neg(K_S + U W U^T) = neg(K_S) + neg(-W^-1 - U^T K_S^-1 U) - neg(-W^-1)``.

Dense constraint rows (:func:`dense_rows`: Doedel's integral phase condition
``<M g, q - q_0> = 0``, whose row is a whole symmetry mode) would make the
banded ordering as wide as the matrix. Each is replaced in the factorised
matrix by a *pin*, its own entry on one DOF (:func:`pin_dense_rows`), which
keeps ``K_pin`` banded and as regular as with a node gauge; the rest of the
row and of its column is the symmetric rank-``2r`` term
``K = K_pin + E Delta^T + Delta E^T = K_pin + U W U^T``, ``U = [E, Delta]``,
``W = [[0, I], [I, 0]]`` (``E`` the unit columns of the pinned rows'
multipliers, ``Delta`` the dense rows less their pins), taken by the formula
above like the rank-one terms of ``H``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.sparse.linalg import splu

from supercoil._numba import njit
from supercoil.solvers.band import (
    BandLayout,
    band_factor,
    band_layout,
    band_layout_of_nonzeros,
    bandwidth_order,
    symmetric_inertia,
)
from supercoil.solvers.patterns import PatternMemo, _merge_kernel, csr_add, csr_from_arrays
from supercoil.solvers.problem import HessianParts


class SingularMatrixError(RuntimeError):
    """The KKT matrix is (numerically) singular."""


class InertiaError(RuntimeError):
    """The inertia could not be certified."""


def _permutation_parity(perm: np.ndarray) -> int:
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


def _woodbury_negatives(solve, U: np.ndarray, w_inverse: np.ndarray, w_negatives: int):
    """Return (H^-1 U, small, correction) for ``H + U W U^T``, ``w_inverse = W^-1``
    symmetric ``(k, k)`` with ``w_negatives = neg(-W^-1)``: ``small = W^-1 + U^T H^-1 U``
    and the correction ``neg(-small) - neg(-W^-1)`` of the negative count (module doc)."""
    HU = solve(U)
    small = w_inverse + U.T @ HU
    correction = int(np.sum(np.linalg.eigvalsh(-small) < 0)) - w_negatives
    return HU, small, correction


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


def kkt_negative_count(K: sp.spmatrix, n_constraints: int = 0,
                       order: np.ndarray | None = None) -> int:
    """Number of negative eigenvalues of a sparse symmetric (KKT) matrix.

    At least ``n_constraints`` must be found when the constraints are independent.
    """
    neg, zero, _ = symmetric_inertia(K, order)
    if zero or neg < n_constraints:
        raise InertiaError(
            f"the KKT matrix has {neg} negative and {zero} zero eigenvalues with "
            f"{n_constraints} constraints: it is singular or the constraints are dependent")
    return neg


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
    entries (:class:`_OrderMemo`). Forming the pattern of ``S + J^T J`` with
    scipy.sparse cost 0.6 ms of a 2 ms bordered factorisation at N = 100. A new
    pattern (the integral contact's pairs change: 200 of the tweezers' 1098 orderings
    at N = 100) is ordered from a compiled merge of the patterns
    (:func:`_kkt_order_merged`).
    """
    return remembered_order(S, J)[0]


def remembered_order(S: sp.spmatrix, J: sp.spmatrix) -> tuple[np.ndarray, _OrderMemo | None]:
    """:func:`kkt_order` and the :class:`_OrderMemo` that certifies it for other values
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
    memo = _OrderMemo.of(J, order, pairs) if pairs is not None else None
    if memo is not None and memo.certifies(J):
        _ORDER_MEMO.put(key, (memo, memo.order, memo._first, memo._second, memo._group,
                              memo._two_terms, memo._cancelled))
        return order, memo
    return order, None


class _OrderMemo:
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
    """:meth:`_OrderMemo.certifies` on :func:`_pair_sums`' sums: every entry of ``J^T J``
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
    dense rows (more than ``_OrderMemo.MAX_TERMS_PER_ENTRY`` terms per nonzero entry)."""
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
    if stored.size and int(np.sum(counts**2)) > _OrderMemo.MAX_TERMS_PER_ENTRY * stored.size:
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
    one compiled merge (:func:`~supercoil.solvers.patterns._merge_kernel`) of ``|S|``
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
    if not (_is_canonical_float(S) and _is_canonical_float(J)) or S.shape[0] != S.shape[1] \
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
    indptr, indices, _data = _merge_kernel(
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


def _is_canonical_float(A) -> bool:
    return getattr(A, "format", None) == "csr" and A.dtype == np.float64 \
        and A.has_canonical_format


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


def canonical(M: sp.csr_matrix) -> sp.csr_matrix:
    """``M``, or a copy with sorted indices and duplicates summed (as bmat would)."""
    if M.has_canonical_format:
        return M
    M = M.copy()
    M.sum_duplicates()
    return M


def _kkt_entries(S: sp.csr_matrix, J: sp.csr_matrix, values: bool = True):
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
            _kkt_values(S, J) if values else None)


def _kkt_values(S: sp.csr_matrix, J: sp.csr_matrix) -> np.ndarray:
    """The values of :func:`_kkt_entries` (canonical ``S``, ``J``): ``[S, J, J]``."""
    return np.concatenate([S.data, J.data, J.data]) if J.shape[0] else S.data


_BAND_MEMO = PatternMemo()


def kkt_band_layout(S: sp.csr_matrix, J: sp.csr_matrix, order: np.ndarray,
                    s_bytes: tuple[bytes, bytes] | None = None, max_fraction: float = 0.25,
                    values: np.ndarray | None = None) -> BandLayout | None:
    """:func:`~supercoil.solvers.band.band_layout` of ``[[S, J^T], [J, 0]]`` (canonical
    CSR ``S``, ``J``) reordered by ``order`` (row ``order[k]`` at ``k``): where the
    values :func:`_kkt_values` go in the band storage of the reordered matrix, or None
    when its band is wider than ``max_fraction`` of it. Remembered per pattern (and
    order): the factorisations of a corrector share it, and the entries' reordering and
    band offsets (0.1 ms at N = 200) are not redone. ``s_bytes``: ``S``'s ``(indptr,
    indices)`` bytes if already made. ``values``: the :func:`_kkt_values` of this
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
        S_c, J_c = canonical(S), canonical(J)  # as _kkt_entries
        rows, cols = _permuted_kkt_entries(S_c.indptr, S_c.indices, J_c.indptr, J_c.indices,
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
def _permuted_kkt_entries(s_ptr, s_idx, j_ptr, j_idx, position):
    """The places ``(position[rows], position[columns])`` of :func:`_kkt_entries`'
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
    of ``scipy.sparse.csr_matrix((values, (rows, cols)))`` of :func:`_kkt_entries`
    (each row's columns sorted, explicit zeros kept), from a gather remembered per
    pattern rather than a COO conversion and sort at every inertia count."""
    n, m = S.shape[0], J.shape[0]
    size = n + m
    key = (n, m, S.indptr.tobytes(), S.indices.tobytes(), J.indptr.tobytes(),
           J.indices.tobytes())
    found = _CSR_MEMO.get(key)
    if found is None:
        rows, cols, _values = _kkt_entries(S, J, values=False)
        by_row = np.argsort(rows.astype(np.int64) * size + cols)  # distinct entries
        indptr = np.zeros(size + 1, dtype=np.int64)
        np.cumsum(np.bincount(rows, minlength=size), out=indptr[1:])
        index = np.int32 if max(size, rows.size) < 2**31 - 1 else np.int64
        found = (by_row, cols[by_row].astype(index), indptr.astype(index))
        _CSR_MEMO.put(key, found)
    by_row, indices, indptr = found
    K = sp.csr_matrix((_kkt_values(S, J)[by_row], indices.copy(), indptr.copy()),
                      shape=(size, size))
    K.has_canonical_format = True
    return K


def _shifted(S: sp.csr_matrix, shift: float, mass: np.ndarray) -> sp.csr_matrix:
    """``(S - shift * diags(mass)).tocsr()`` of scipy, entry for entry: ``S + D`` with
    ``D`` the CSR of ``-(shift * mass)`` (zeros dropped, as scipy's conversion of the
    diagonal does), summed by :func:`~supercoil.solvers.patterns.csr_add` (``a - b``
    is ``a + (-b)`` exactly; zeros of the sum dropped as scipy's subtraction does)."""
    n = S.shape[0]
    diagonal = -(shift * np.asarray(mass, dtype=float))
    at = np.flatnonzero(diagonal != 0.0)
    index = S.indices.dtype if S.indices.dtype == S.indptr.dtype else np.int64
    indptr = np.zeros(n + 1, dtype=index)
    indptr[at + 1] = 1
    np.cumsum(indptr, out=indptr)
    D = sp.csr_matrix((diagonal[at], at.astype(index), indptr), shape=(n, n))
    D.has_canonical_format = True
    return csr_add(S, D)


class _OrderedLU:
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
        return sign * _permutation_parity(self.perm_r) * _permutation_parity(self.perm_c)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        sol = self.lu.solve(np.ascontiguousarray(rhs[self.order]))
        out = np.empty_like(sol)
        out[self.order] = sol
        return out


class _BandLU:
    """LAPACK's band LU with partial pivoting (``dgbtrf``) of a symmetrically reordered
    matrix, from its entries (no duplicates): the interface of :class:`_OrderedLU`.

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
           order: np.ndarray) -> _BandLU | None:
        if size < 2 or values.size == 0:
            return None
        position = np.empty(size, dtype=np.int64)
        position[order] = np.arange(size)
        return cls.from_layout(order, band_layout(size, position[rows], position[cols]), values)

    @classmethod
    def from_layout(cls, order: np.ndarray, layout: BandLayout | None, values: np.ndarray
                    ) -> _BandLU | None:
        """:meth:`of` with the band layout of the reordered entries already made
        (:func:`kkt_band_layout`); None for a ``layout`` of None (band too wide)."""
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


class KKTFactor:
    """Factorisation of ``[[H - shift*M, J^T], [J, 0]]`` with its inertia.

    ``hessian`` holds the sparse part and rank-one terms of ``H`` on the free
    unknowns, ``jacobian`` is ``(m, n)``; ``shift`` and ``mass`` (diagonal,
    ``(n,)``) are for shift-invert eigenvalue computations; ``order`` reuses
    the :func:`kkt_order` of an earlier factor of the same pattern
    (:attr:`order`). The matrix is factorised by LAPACK's band LU (:class:`_BandLU`)
    when the ordered band is narrow, else by SuperLU (:class:`_OrderedLU`). The inertia is
    computed on first use of :attr:`reduced_negative_count`, from the matrices given
    (referenced, not copied: a caller must not change their entries in place while
    it uses the factor; none in the package does). Dense rows of
    ``J`` are pinned and their remainder taken by Woodbury's identity
    (module doc), so the sparse factorisation and the banded inertia see
    ``K_pin``; :attr:`order` is then :func:`kkt_order` of ``K_pin``'s pattern.
    Where ``K_pin`` is singular but ``K`` is not (the mode a dense row removes
    vanishes on its pinned DOF), ``K`` itself is factorised, as without pins.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix | None = None,
                 shift: float = 0.0, mass: np.ndarray | None = None,
                 order: np.ndarray | None = None):
        S = hessian.sparse.tocsr()
        n = S.shape[0]
        if shift != 0.0:
            S = _shifted(S, shift, mass if mass is not None else np.ones(n))
        J = sp.csr_matrix((0, n)) if jacobian is None else sp.csr_matrix(jacobian)
        self.n = n
        self.m = J.shape[0]
        self._S = S
        self._J = J
        self._hessian = hessian
        pinned = PinnedRows.of(J) if self.m else None
        if pinned is not None:
            try:
                self._factor(pinned, order)
                if np.all(np.isfinite(self._small)):
                    return
            except SingularMatrixError:
                pass
            order = None  # an order of the pinned pattern
        self._factor(None, order)

    def _factor(self, pinned: PinnedRows | None, order: np.ndarray | None) -> None:
        """Factorise ``K_pin`` (or ``K`` when ``pinned`` is None) and the low-rank terms."""
        S, J, hessian = self._S, self._J, self._hessian
        n, size = self.n, self.n + self.m
        self._pinned = pinned is not None
        J_factored = J if pinned is None else pinned.sparse
        # A banded ordering keeps the partial-pivoting LU within twice the band.
        self._order = kkt_order(S, J_factored) if order is None else order
        S, J_factored = canonical(S), canonical(J_factored)
        self._factored = (S, J_factored)
        # with the values: a straight rod stores zeros that couple far unknowns, whose
        # stored band is too wide (SuperLU then) where its nonzero band is narrow
        values = _kkt_values(S, J_factored)
        layout = kkt_band_layout(S, J_factored, self._order, values=values)
        self._lu = _BandLU.from_layout(self._order, layout, values)
        if self._lu is None:
            try:
                self._lu = _OrderedLU(size, *_kkt_entries(S, J_factored), self._order)
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularMatrixError(f"KKT matrix is singular ({exc})") from None
        r = len(hessian.coefficients)
        w = np.asarray(hessian.coefficients, dtype=float)
        columns = [np.zeros((size, r))]
        if r:
            columns[0][:n] = hessian.vectors.T
        w_inverse = np.diag(1.0 / w) if r else np.zeros((0, 0))
        w_negatives = int(np.sum(-1.0 / w < 0)) if r else 0
        # sign of det W (module doc): prod sign(w), times (-1)^k for [[0, I], [I, 0]]
        self._w_sign = int(np.prod(np.sign(w))) if r else 1
        if pinned is not None:
            E, Delta, gamma = pinned.low_rank(n, size)
            root = np.sqrt(gamma)
            columns += [E * root, Delta / root]  # balanced: E D^T = (E root)(D / root)^T
            k = pinned.rows.size
            swap = np.block([[np.zeros((k, k)), np.eye(k)], [np.eye(k), np.zeros((k, k))]])
            w_inverse = np.block([[w_inverse, np.zeros((r, 2 * k))],
                                  [np.zeros((2 * k, r)), swap]])
            self._w_sign *= (-1) ** k
            w_negatives += k  # -[[0, I], [I, 0]] has k eigenvalues -1 and k eigenvalues 1
        self._U = np.hstack(columns) if len(columns) > 1 else columns[0]
        self._has_low_rank = self._U.shape[1] > 0
        if self._has_low_rank:
            self._KU, self._small, self._woodbury_correction = _woodbury_negatives(
                self._lu.solve, self._U, w_inverse, w_negatives)
        self._reduced_neg: int | None = None

    @property
    def order(self) -> np.ndarray:
        return self._order

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``K z = rhs`` for the full matrix (rank-one terms included)."""
        z = self._lu.solve(np.asarray(rhs, dtype=float))
        if self._has_low_rank:
            z = z - self._KU @ np.linalg.solve(self._small, self._U.T @ z)
        return z

    @property
    def reduced_negative_count(self) -> int:
        """Negative eigenvalues of ``H`` restricted to ``ker J`` (exact inertia)."""
        if self._reduced_neg is None:
            K = kkt_csr(*self._factored)
            try:
                neg = kkt_negative_count(K, self.m, self._order)
            except InertiaError:
                if not self._pinned:
                    raise
                self._factor(None, None)
                return self.reduced_negative_count
            if self._has_low_rank:
                neg += self._woodbury_correction
            self._reduced_neg = neg - self.m
        return self._reduced_neg

    @property
    def negative_count(self) -> int:
        """Negative eigenvalues of the full KKT matrix (``reduced + m``)."""
        return self.reduced_negative_count + self.m

    @property
    def determinant_sign(self) -> int:
        """Sign of ``det K`` from the pivoted LU (permutation parities included)."""
        sign = self._lu.determinant_sign()
        if self._has_low_rank:
            # det(K_S + U W U^T) = det(K_S) det(W) det(W^-1 + U^T K_S^-1 U)
            sign *= self._w_sign * int(np.sign(np.linalg.det(self._small)))
        return sign

