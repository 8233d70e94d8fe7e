"""The bordered factor's per-pattern memo and its compiled kernels against the former code.

Oracles: a factor made with every pattern memo cleared (the memo's hit must give the
same arrays, bit for bit, as the path that computes everything: the band LU, the
refinement matrix, ``K^-1 C``, ``max |B|`` and the solves), also as values, stored
zeros, the border's zeros, cancellations in ``J^T J`` and patterns change between
calls; and the former numpy formulas, restated here, for the compiled kernels (the
layout's argsort, the multipliers' stable sort, the band offsets, the ordering's
certificate, the refinement residual, the one-border Schur test).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from test_corrector_fast_paths import contact_like_kkt
from test_kkt_band import banded_kkt

from supercoil.continuation import band_bordered, bordered, bordered_matrix
from supercoil.continuation.band_bordered import BandBordered
from supercoil.continuation.bordered import BorderedFactor
from supercoil.solvers import band, csr, kkt_matrix, ordering, patterns, pinned_rows
from supercoil.solvers.problem import HessianParts


def clear_memos():
    for memo in (bordered._PATTERNS, bordered_matrix._LAYOUTS, ordering._ORDER_MEMO, ordering._GRAM_MEMO,
                 kkt_matrix._BAND_MEMO, pinned_rows._CUT_MEMO):
        memo.clear()


def factor_arrays(factor):
    """Everything a factor holds that its solves use."""
    lu = factor._lu
    out = [factor.order, factor.kkt_order, np.float64(factor.row_scale)]
    if isinstance(lu, BandBordered):
        out += [lu._lub, lu._piv, lu._B.data, lu._B.indices, lu._B.indptr, lu._C, lu._R,
                lu._D, lu._KC, np.float64(lu._b_max), np.asarray(lu._schur[0])]
        # max |B| as the former __init__ took it
        assert lu._b_max == float(np.max(np.abs(lu._B.data), initial=0.0)) \
            or (np.isnan(lu._b_max) and np.isnan(np.max(np.abs(lu._B.data))))
    if len(factor._w):
        out += [factor._BV, factor._small]
    return out


def assert_same_factor(mine, fresh, rhs):
    assert type(mine._lu) is type(fresh._lu)
    for a, b in zip(factor_arrays(mine), factor_arrays(fresh), strict=True):
        assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    assert np.array_equal(mine.solve(rhs), fresh.solve(rhs))
    assert np.array_equal(mine.solve(rhs, refine=False), fresh.solve(rhs, refine=False))


def problems():
    """A sequence of bordered problems on a rod-like pattern: the same pattern with
    other values, a stored zero in S and in J made nonzero and back, zeros in the
    border, an exactly cancelling entry of J^T J, another pattern, a rank-one term,
    dense rows (pinned: not remembered), and the first pattern again."""
    rng = np.random.default_rng(17)
    S, J = contact_like_kkt(rng, 30, 2, zero_rows=1)
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1

    def border(zeros=()):
        column, row = rng.standard_normal(size - 1), rng.standard_normal(size)
        column[list(zeros)] = 0.0
        row[list(zeros)] = -0.0
        return column, row

    out = [(HessianParts(S), J, *border())]
    out.append((HessianParts(S * 1.3), J * 0.7, *border()))
    filled = S.copy()
    filled.data[np.flatnonzero(S.data == 0.0)[:2]] = 0.5  # a stored zero becomes nonzero
    out.append((HessianParts(filled), J, *border()))
    out.append((HessianParts(S), J, *border()))
    J_zero = J.copy()
    J_zero.data[np.flatnonzero(J.data)[3]] = 0.0  # a stored entry of J becomes zero
    out.append((HessianParts(S), J_zero, *border()))
    out.append((HessianParts(S), J, *border(zeros=(0, 5, size - 2))))
    out.append((HessianParts(S), J, *border(zeros=(0, 5, size - 2))))
    # two rows of J on the same two DOFs: (J^T J)_ab = J_0a J_0b + J_1a J_1b = 0 exactly
    J_cancel = J.tolil()
    J_cancel[0, :] = 0.0
    J_cancel[1, :] = 0.0
    J_cancel[0, 3], J_cancel[0, 40] = 1.0, 2.0
    J_cancel[1, 3], J_cancel[1, 40] = 1.0, -2.0
    J_cancel = sp.csr_matrix(J_cancel)
    out.append((HessianParts(S), J_cancel, *border()))
    J_near = J_cancel.copy()
    J_near.data[J_near.data == -2.0] = -1.5  # the same pattern, no cancellation
    out.append((HessianParts(S), J_near, *border()))
    out.append((HessianParts(S), J_cancel, *border()))
    S2, J2 = contact_like_kkt(np.random.default_rng(3), 30, 2)
    vectors = rng.standard_normal((1, n))
    out.append((HessianParts(S2, vectors, np.array([0.7])), J2, *border()))
    out.append((HessianParts(S2 * 0.9, vectors, np.array([-0.4])), J2, *border()))
    H3, J3 = banded_kkt(np.random.default_rng(4), n, 6, dense_rows=1)
    size3 = n + J3.shape[0] + 1
    for _ in range(2):
        out.append((H3, J3, rng.standard_normal(size3 - 1), rng.standard_normal(size3)))
    out.append((HessianParts(S), J, *border()))
    return out


def test_remembered_patterns_give_the_factor_of_the_memo_free_path_bit_for_bit(monkeypatch):
    clear_memos()
    rng = np.random.default_rng(2)
    ordered = []  # a miss of the pattern memo orders the pattern (or asks kkt_order's memo)
    remembered_order = bordered.remembered_order
    monkeypatch.setattr(bordered, "remembered_order",
                        lambda S, J: ordered.append(1) or remembered_order(S, J))
    hits = []
    for k, (hessian, J, column, row) in enumerate(problems()):
        before = len(ordered)
        mine = BorderedFactor(hessian, J, column, row)
        if len(ordered) == before:
            hits.append(k)
        state = [dict(memo._items) for memo in (bordered._PATTERNS, bordered_matrix._LAYOUTS,
                 ordering._ORDER_MEMO, ordering._GRAM_MEMO, kkt_matrix._BAND_MEMO, pinned_rows._CUT_MEMO)]
        clear_memos()
        fresh = BorderedFactor(hessian, J, column, row)
        for memo, items in zip((bordered._PATTERNS, bordered_matrix._LAYOUTS, ordering._ORDER_MEMO,
                                ordering._GRAM_MEMO, kkt_matrix._BAND_MEMO, pinned_rows._CUT_MEMO), state,
                               strict=True):
            memo.clear()
            for key, value in items.items():
                memo.put(key, value)
        assert_same_factor(mine, fresh, rng.standard_normal(J.shape[0] + hessian.sparse.shape[0] + 1))
        # and the former constructor's arithmetic: the same order given explicitly
        # (not remembered) gives the same factor too
        given = BorderedFactor(hessian, J, column, row, order=mine.kkt_order)
        assert_same_factor(given, fresh, rng.standard_normal(J.shape[0] + hessian.sparse.shape[0] + 1))
    # the repeated patterns (same words, certified) were hits: not a pattern whose zeros
    # changed, nor a cancellation that changed (7 -> 8 -> 9), nor dense rows (12, 13)
    assert hits == [1, 3, 6, 11, 14]


def test_a_failed_certificate_is_not_a_hit():
    """Same words, but an entry of J^T J of three terms cancels (the certificate fails):
    the factor orders the pattern anew, as the memo-free path does."""
    clear_memos()
    rng = np.random.default_rng(9)
    S, J = contact_like_kkt(rng, 20, 1)
    J = J.tolil()
    for k, values in enumerate(([1.0, 1.0], [1.0, 1.0], [1.0, -1.5])):
        J[k, :] = 0.0
        J[k, 4], J[k, 30] = values  # (J^T J)_{4, 30} = 1 + 1 - 1.5, three terms
    J = sp.csr_matrix(J)
    size = S.shape[0] + J.shape[0] + 1
    column, row = rng.standard_normal(size - 1), rng.standard_normal(size)
    factor = BorderedFactor(HessianParts(S), J, column, row)
    ((pattern,),) = bordered._PATTERNS.values()
    assert pattern.order_memo.certifies(J)
    J_bad = J.copy()
    J_bad.data[J_bad.data == -1.5] = -2.0 + 1e-12  # the sum ~1e-12: below 1e-8 of |terms|
    assert not pattern.order_memo.certifies(J_bad)
    mine = BorderedFactor(HessianParts(S), J_bad, column, row)
    clear_memos()
    fresh = BorderedFactor(HessianParts(S), J_bad, column, row)
    assert_same_factor(mine, fresh, rng.standard_normal(size))
    assert np.array_equal(factor.order, BorderedFactor(HessianParts(S), J, column, row).order)


def test_pattern_words_differ_exactly_when_the_patterns_or_zeros_do():
    rng = np.random.default_rng(1)
    S, J = contact_like_kkt(rng, 15, 1)
    column, row = rng.standard_normal(S.shape[0] + J.shape[0]), rng.standard_normal(10)
    words, key = patterns.pattern_words(S, J, column, row)
    same, same_key = patterns.pattern_words(S * 2.0, J * -1.0, column * 3.0, row)
    assert same_key == key and patterns.same_words(words, same)
    variants = []
    zero_s = S.copy()
    zero_s.data[7] = 0.0
    variants.append((zero_s, J, column, row))
    zero_j = J.copy()
    zero_j.data[2] = 0.0
    variants.append((S, zero_j, column, row))
    zero_column = column.copy()
    zero_column[4] = 0.0
    variants.append((S, J, zero_column, row))
    zero_row = row.copy()
    zero_row[-1] = 0.0
    variants.append((S, J, column, zero_row))
    variants.append((S, J, column, row[:-1]))  # a shorter row
    variants.append((S, J[:-1], column, row))  # one constraint fewer
    for variant in variants:
        other, _key = patterns.pattern_words(*variant)
        assert not patterns.same_words(words, other)
    assert patterns.same_words(words, patterns.pattern_words(S, J, column, row)[0])


def former_bordered_layout(S, J, col_at, row_at, has_corner, order):
    """bordered_matrix.bordered_layout as it was (numpy: row-major keys sorted by argsort)."""
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1
    s_rows = np.repeat(np.arange(n), np.diff(S.indptr))
    j_rows = np.repeat(np.arange(m), np.diff(J.indptr)) + n
    last = np.full(int(has_corner), size - 1)
    rows = np.concatenate([s_rows, J.indices, j_rows, col_at, np.full(row_at.size, size - 1),
                           last])
    cols = np.concatenate([S.indices, j_rows, J.indices, np.full(col_at.size, size - 1), row_at,
                           last])
    position = np.empty(size, dtype=np.int64)
    position[order] = np.arange(size)
    prow, pcol = position[rows], position[cols]
    by_row = np.argsort(prow.astype(np.int64) * size + pcol)
    prow, pcol = prow[by_row], pcol[by_row]
    indptr = np.zeros(size + 1, dtype=np.int64)
    np.cumsum(np.bincount(prow, minlength=size), out=indptr[1:])
    inner = np.flatnonzero((prow < size - 1) & (pcol < size - 1))
    index = np.int32 if max(size, pcol.size) < 2**31 - 1 else np.int64
    return by_row, pcol.astype(index), indptr.astype(index), inner, prow[inner], pcol[inner]


@pytest.mark.parametrize("seed", range(6))
def test_sorted_layout_equals_the_former_argsort(seed):
    rng = np.random.default_rng(70 + seed)
    S, J = contact_like_kkt(rng, int(rng.integers(5, 40)), int(rng.integers(0, 3)))
    if seed == 5:
        J = sp.csr_matrix((0, S.shape[0]))
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1
    col_at = np.sort(rng.choice(n + m, size=int(rng.integers(0, n + m)), replace=False))
    row_at = np.sort(rng.choice(n + m, size=int(rng.integers(0, n + m)), replace=False))
    order = rng.permutation(size) if seed % 2 else np.concatenate(
        [ordering.kkt_order(S, J), [size - 1]])
    for has_corner in (True, False):
        mine = bordered_matrix.bordered_layout(S, J, col_at, row_at, has_corner, order)
        former = former_bordered_layout(S, J, col_at, row_at, has_corner, order)
        for a, b in zip(mine, former, strict=True):
            assert a.dtype == b.dtype and np.array_equal(a, b)


@pytest.mark.parametrize("seed", range(5))
def test_placed_multipliers_equal_the_former_stable_sort(seed):
    rng = np.random.default_rng(80 + seed)
    n, m = int(rng.integers(1, 60)), int(rng.integers(0, 20))
    x_order = rng.permutation(n)
    k = int(rng.integers(0, 4 * m + 1))
    rows, columns = rng.integers(0, max(m, 1), k), rng.integers(0, n, k)
    if m == 0:
        rows = columns = np.zeros(0, dtype=np.int64)
    position = np.empty(n, dtype=np.int64)
    position[x_order] = np.arange(n)
    first = np.full(m, n, dtype=np.int64)
    np.minimum.at(first, rows, position[columns])
    keys = np.concatenate([2 * np.arange(n), 2 * first + 1])
    items = np.concatenate([x_order, n + np.arange(m)])
    former = items[np.argsort(keys, kind="stable")]
    mine = ordering._place_multipliers(x_order, rows, columns, n, m)
    assert mine.dtype == former.dtype and np.array_equal(mine, former)


@pytest.mark.parametrize("seed", range(4))
def test_band_layout_offsets_equal_numpys(seed):
    rng = np.random.default_rng(90 + seed)
    size = int(rng.integers(2, 200))
    k = int(rng.integers(1, 400))
    rows, cols = rng.integers(0, size, k), rng.integers(0, size, k)
    if seed == 0:
        rows = cols = np.arange(size)  # diagonal: kl = ku = 0
    kl = int(max(0, np.max(rows - cols)))
    ku = int(max(0, np.max(cols - rows)))
    layout = band.band_layout(size, rows.astype(np.int32), cols, 3.0)
    assert (layout.kl, layout.ku) == (kl, ku)
    # a band just wider than the fraction allows is refused, one just narrower is not
    assert band.band_layout(size, rows, cols, (kl + ku + 1) / size * 0.999) is None
    assert band.band_layout(size, rows, cols, (kl + ku + 1) / size * 1.001) is not None
    assert np.array_equal(layout.positions, cols * (2 * kl + ku + 1) + (kl + ku + rows - cols))
    assert layout.storage_size == (2 * kl + ku + 1) * size
    with pytest.raises(ValueError):
        band.band_layout(size, rows[:0], cols[:0])


def former_certifies(memo, J):
    total, size = ordering._pair_sums(J.data, memo._first, memo._second, memo._group,
                                 memo._n_groups)
    nonzero = np.abs(total) > 1e-8 * size
    if memo._cancelled is None:
        return bool(np.all(nonzero))
    cancelled = memo._two_terms & (total == 0.0)
    return bool(np.all(nonzero | memo._two_terms) and np.array_equal(cancelled, memo._cancelled))


def test_compiled_certificate_equals_the_former_one():
    rng = np.random.default_rng(12)
    n = 30
    J = np.zeros((6, n))
    J[0, [2, 9]] = 1.0, 1.0
    J[1, [2, 9]] = 1.0, -1.0  # (2, 9) of J^T J: two terms, cancel
    J[2, [4, 7, 11]] = 1.0, 2.0, 3.0
    J[3, [4, 7]] = 1.0, 1.0
    J[4, [4, 7]] = 1.0, 1.0  # (4, 7): three terms
    J[5, [20, 21]] = 0.5, 0.25
    J = sp.csr_matrix(J)
    order = np.arange(n + 6)
    memo = ordering.OrderMemo.of(J, order)
    trials = [J]
    for _ in range(30):
        other = J.copy()
        other.data = other.data * rng.choice([1.0, -1.0, 0.5, 1e-9], other.data.size)
        trials.append(other)
    other = J.copy()
    other.data[other.data == -1.0] = -1.0 + 1e-13  # two terms, not cancelling
    trials.append(other)
    other = J.copy()
    other.data[np.flatnonzero(other.data == 2.0)] = -2.0  # (4, 7): -2 + 1 + 1, three terms
    trials.append(other)
    seen = set()
    for J_trial in trials:
        for cancelled in (memo._cancelled, None):
            memo._cancelled = cancelled
            expected = former_certifies(memo, J_trial)
            assert memo.certifies(J_trial) == expected
            seen.add(expected)
        memo._cancelled = ordering.OrderMemo.of(J, order)._cancelled
    assert seen == {True, False}


@pytest.mark.parametrize("p", [None, 1, 3])
def test_refinement_residual_equals_the_sparse_product(p):
    rng = np.random.default_rng(30 + (p or 0))
    A = sp.random(50, 50, density=0.2, format="csr", random_state=p or 0)
    A.data = rng.standard_normal(A.data.size) * 10.0 ** rng.uniform(-5, 5, A.data.size)
    shape = (50,) if p is None else (50, p)
    rhs, z = rng.standard_normal(shape), rng.standard_normal(shape)
    res, norm, z_max, rhs_max = band_bordered._refinement_residual(A.indptr, A.indices, A.data,
                                                              rhs, z)
    former = rhs - csr.csr_matvec(A.indptr, A.indices, A.data, z, 50)
    assert np.array_equal(res, former) and res.shape == former.shape
    assert norm == float(np.max(np.abs(former), initial=0.0))
    assert z_max == float(np.max(np.abs(z))) and rhs_max == float(np.max(np.abs(rhs)))
    z[7] = np.nan
    _res, norm, z_max, _ = band_bordered._refinement_residual(A.indptr, A.indices, A.data, rhs, z)
    assert np.isnan(z_max) and np.isnan(norm) == np.isnan(np.max(np.abs(
        rhs - csr.csr_matvec(A.indptr, A.indices, A.data, z, 50))))


def former_schur_test(D, R, KC, schur):
    """BandBordered._from_factor's test of Sigma as it was (arrays): kept or not."""
    if not np.all(np.isfinite(schur)):
        return False
    bound = np.abs(D) + np.outer(np.linalg.norm(R, axis=0), np.linalg.norm(KC, axis=0))
    rows = np.max(bound, axis=1)
    rows[rows == 0.0] = 1.0
    columns = np.max(bound / rows[:, None], axis=0)
    columns[columns == 0.0] = 1.0
    scaled = schur / rows[:, None] / columns[None, :]
    return not abs(scaled[0, 0]) <= 1e-13


def test_one_border_schur_test_equals_the_array_formula():
    rng = np.random.default_rng(44)
    cases = []
    for _ in range(200):
        n = int(rng.integers(1, 30))
        R, KC = rng.standard_normal((n, 1)), rng.standard_normal((n, 1))
        D = rng.standard_normal((1, 1)) * rng.choice([0.0, 1.0])
        bound = abs(D[0, 0]) + np.linalg.norm(R) * np.linalg.norm(KC)
        schur = np.array([[bound * 10.0 ** rng.uniform(-16, -10) * rng.choice([-1, 1])]])
        cases.append((D, R, KC, schur))
    zero = np.zeros((3, 1))
    cases += [(np.zeros((1, 1)), zero, zero, np.array([[0.0]])),
              (np.zeros((1, 1)), zero, zero, np.array([[1e-300]])),
              (np.ones((1, 1)), zero, zero, np.array([[np.inf]])),
              (np.ones((1, 1)), zero, zero, np.array([[np.nan]])),
              (np.full((1, 1), np.inf), zero, zero, np.array([[1.0]]))]
    kept = []
    for D, R, KC, schur in cases:
        factor = BandBordered.__new__(BandBordered)
        factor._D, factor._R, factor._KC = D, R, KC
        mine = factor._one_border(schur) is not None
        with np.errstate(invalid="ignore"):  # inf / inf: the former arrays warned
            assert mine == former_schur_test(D, R, KC, schur)
        kept.append(mine)
    assert any(kept) and not all(kept)


@pytest.mark.parametrize("seed", range(3))
def test_permuted_kkt_entries_equal_the_gathered_entries(seed):
    """kkt_band_layout's places of the KKT entries against kkt_entries gathered by the
    positions (the former code), also without constraints."""
    rng = np.random.default_rng(120 + seed)
    S, J = contact_like_kkt(rng, int(rng.integers(4, 30)), int(rng.integers(0, 3)))
    if seed == 2:
        J = sp.csr_matrix((0, S.shape[0]))
    size = S.shape[0] + J.shape[0]
    position = rng.permutation(size)
    rows, cols, _values = kkt_matrix.kkt_entries(S, J, values=False)
    mine = kkt_matrix.permuted_kkt_entries(S.indptr, S.indices, J.indptr, J.indices, position)
    for a, b in zip(mine, (position[rows], position[cols]), strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_dense_rows_with_the_long_row_check_follow_the_rule():
    """dense_rows (its early exit on no long rows included) against the rule itself:
    rows of more than max(32, 0.1 n) nonzeros, stored zeros not counted; a matrix
    without long rows has none."""
    rng = np.random.default_rng(130)
    n = 500
    for trial in range(6):
        lengths = rng.integers(0, 80, 5)
        J = np.zeros((5, n))
        for k, length in enumerate(lengths):
            J[k, rng.choice(n, size=length, replace=False)] = rng.standard_normal(length)
        J = sp.csr_matrix(J)
        if trial % 2:
            J.data[::3] = 0.0  # stored zeros: long rows of few nonzeros
        limit = max(pinned_rows.DENSE_ROW_MIN_ENTRIES, pinned_rows.DENSE_ROW_FRACTION * n)
        rule = [k for k in range(5) if np.count_nonzero(J[k].data) > limit]
        assert pinned_rows.dense_rows(J).tolist() == rule
        assert pinned_rows.has_long_rows(J) == bool(np.max(np.diff(J.indptr)) > limit)
        assert not rule or pinned_rows.has_long_rows(J)
    assert not pinned_rows.has_long_rows(sp.csr_matrix((0, n)))


def test_pattern_memo_counts_the_layouts_it_keeps():
    """The memo's memory bound sees the layouts a remembered pattern keeps alive."""
    clear_memos()
    rng = np.random.default_rng(140)
    S, J = contact_like_kkt(rng, 25, 1)
    size = S.shape[0] + J.shape[0] + 1
    BorderedFactor(HessianParts(S), J, rng.standard_normal(size - 1), rng.standard_normal(size))
    ((pattern,),) = bordered._PATTERNS.values()
    held = sum(a.nbytes for a in pattern.layout) + pattern.band.positions.nbytes \
        + pattern.words.nbytes
    assert pattern.nbytes >= held
    assert bordered._PATTERNS._total >= held
