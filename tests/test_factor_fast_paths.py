"""The bordered and KKT factorisations against direct constructions of their inputs.

Oracles: LAPACK's band LU of a C-ordered ``ab`` filled by fancy indexing,
``permuted_bordered``'s entries of the pinned block, scipy's sums, differences,
stacks and COO conversion: the same arrays bit for bit, also when the pattern
changes between calls (the per-pattern memos must not hand out a stale layout);
and dense solves of the bordered matrix for the solutions.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.linalg import lapack
from test_kkt_band import banded_kkt

from supercoil.continuation.band_bordered import BandBordered
from supercoil.continuation.bordered import BorderedFactor
from supercoil.continuation.bordered_matrix import permuted_bordered
from supercoil.solvers import kkt, kkt_matrix, ordering, pinned_rows
from supercoil.solvers.band import band_factor, band_layout, band_lu
from supercoil.solvers.csr import CSRArrays, csr_matvec, csr_rmatvec, csr_vstack
from supercoil.solvers.csr_sum import csr_add
from supercoil.solvers.problem import HessianParts


def reference_band_lu(size, rows, cols, values):
    """LAPACK's band LU of a C-ordered ``ab`` filled by 2-D fancy indexing."""
    kl = int(max(0, np.max(rows - cols)))
    ku = int(max(0, np.max(cols - rows)))
    ab = np.zeros((2 * kl + ku + 1, size))
    ab[kl + ku + rows - cols, cols] = values
    lub, piv, info = lapack.dgbtrf(ab, kl, ku)
    return lub, piv, kl, ku, info


def random_band(rng, n, lower, upper, density=0.6):
    A = np.zeros((n, n))
    for k in range(-lower, upper + 1):
        d = rng.standard_normal(n - abs(k)) * (rng.random(n - abs(k)) < density)
        A += np.diag(d, k)
    A += np.diag(rng.uniform(-3.0, 3.0, n))
    return sp.coo_matrix(A)


@pytest.mark.parametrize("seed", range(4))
def test_band_lu_equals_the_reference_band_lu_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(20, 120))
    A = random_band(rng, n, int(rng.integers(0, 6)), int(rng.integers(0, 6)))
    mine, reference = band_lu(n, A.row, A.col, A.data, 1.0), reference_band_lu(n, A.row, A.col, A.data)
    assert mine[2:] == reference[2:]
    assert np.array_equal(mine[0], reference[0]) and np.array_equal(mine[1], reference[1])
    # the layout of the pattern, filled with other values, factorises those
    layout = band_layout(n, A.row, A.col, 1.0)
    other = rng.standard_normal(A.data.size)
    refilled, fresh = band_factor(layout, other), reference_band_lu(n, A.row, A.col, other)
    assert np.array_equal(refilled[0], fresh[0]) and np.array_equal(refilled[1], fresh[1])
    assert band_layout(n, A.row, A.col, max_fraction=0.01) is None


def reference_band_entries(S, J, column, border_row, corner, order):
    """The band block's entries: those of the pinned (or plain) KKT block from
    permuted_bordered without the matrix."""
    pinned = pinned_rows.PinnedRows.of(J) if J.shape[0] else None
    J_banded = J if pinned is None else pinned.sparse
    _, entries = permuted_bordered(S, J_banded, column, border_row, corner, order,
                                    matrix=False)
    return entries


def check_bordered(factor, hessian, J, column, row, rng):
    """The factor's band LU is the reference one bit for bit; its refinement matrix is
    permuted_bordered's scipy matrix; its solves are those of the dense matrix."""
    S = kkt_matrix.canonical(hessian.sparse.tocsr())
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1
    border_row = factor.row_scale * row[:-1]
    corner = row[-1] * factor.row_scale
    entries = reference_band_entries(S, kkt_matrix.canonical(J), column, border_row, corner,
                                  factor.order)
    lub, piv, kl, ku, _info = reference_band_lu(size - 1, *entries)
    assert isinstance(factor._lu, BandBordered)
    assert (factor._lu._kl, factor._lu._ku) == (kl, ku)
    assert np.array_equal(factor._lu._lub, lub) and np.array_equal(factor._lu._piv, piv)
    B_reference, _ = permuted_bordered(S, kkt_matrix.canonical(J), column, border_row, corner,
                                     factor.order)
    B_mine = factor._lu._B
    assert isinstance(B_mine, CSRArrays)
    for name in ("data", "indices", "indptr"):
        assert np.array_equal(getattr(B_mine, name), getattr(B_reference, name))
    B = np.zeros((size, size))
    B[:n, :n] = hessian.dense()
    B[:n, n:-1] = J.toarray().T
    B[n:-1, :n] = J.toarray()
    B[:-1, -1] = column
    B[-1] = row
    rhs = rng.standard_normal(size)
    exact = np.linalg.solve(B, rhs)
    scale = np.linalg.cond(B) * np.max(np.abs(exact))
    assert np.max(np.abs(factor.solve(rhs) - exact)) <= 1e-13 * scale
    refined = factor.refined_solve(hessian, J, column, row, rhs)
    assert refined is not None and np.max(np.abs(refined - exact)) <= 1e-13 * scale


def test_bordered_factor_equals_the_reference_as_the_pattern_changes():
    """Toy KKT matrices: one pattern, the same pattern with other values, other
    patterns of the same sizes (constraints elsewhere; an entry added to ``S`` that
    widens the band), others (more constraints, a dense phase row), then the first
    again: every factor is the reference one (the memos are keyed on the pattern,
    not reused across patterns)."""
    rng = np.random.default_rng(5)
    n = 70
    problems = []
    for seed, m, dense, rank_one in ((1, 6, 0, 0), (1, 6, 0, 0), (2, 6, 0, 0), (2, 6, 0, 0),
                                     (3, 9, 1, 1), (1, 6, 0, 0)):
        H, J = banded_kkt(np.random.default_rng(seed), n, m, rank_one=rank_one,
                          dense_rows=dense)  # the same pattern for the same seed
        problems.append((H, J))
    problems[1] = (HessianParts(problems[1][0].sparse * 1.7, problems[1][0].vectors,
                                problems[1][0].coefficients), problems[1][1] * 0.5)
    wider = problems[3][0].sparse.tolil()
    wider[0, 9] = wider[9, 0] = 0.25
    problems[3] = (HessianParts(wider.tocsr()), problems[3][1])
    for H, J in problems:
        size = n + J.shape[0] + 1
        column, row = rng.standard_normal(size - 1), rng.standard_normal(size)
        check_bordered(BorderedFactor(H, J, column, row), H, J, column, row, rng)


def test_bordered_factor_on_ring_states_equals_the_reference():
    """A bent ring with its integral phase condition (a pinned dense row) at two
    nearby states: the same band LU and refinement matrix as the reference."""
    from test_factor_refinement import nearby_state
    from test_point_stability_paths import contact_ring_system

    system, x = contact_ring_system(excess_link=2.5)
    rng = np.random.default_rng(8)
    row = system.weights * np.linspace(1.0, 2.0, system.size)
    for y in (x, nearby_state(system, x, 1e-4)):
        H, J, column = system.hessian(y), system.jacobian(y), system.parameter_derivative(y)
        assert pinned_rows.dense_rows(J).size == 1
        check_bordered(BorderedFactor(H, J, column, row), H, J, column, row, rng)


@pytest.mark.parametrize("seed", range(3))
def test_kkt_factor_band_and_inertia_inputs_equal_the_reference(seed):
    """KKTFactor: its band LU is the reference band LU of the reordered KKT
    entries and the matrix handed to the inertia count is scipy's COO conversion of
    them, bit for bit; with a shift, the shifted Hessian is scipy's difference."""
    rng = np.random.default_rng(40 + seed)
    n = 90
    H, J = banded_kkt(rng, n, 8, rank_one=seed % 2, dense_rows=int(seed == 2))
    shift, mass = (0.0, None) if seed == 0 else (-0.4, rng.uniform(0.5, 2.0, n))
    factor = kkt.KKTFactor(H, J, shift=shift, mass=mass)
    S = H.sparse.tocsr()
    if shift != 0.0:
        S = (S - shift * sp.diags(mass)).tocsr()
    S_mine, J_mine = factor._factored
    for name in ("data", "indices", "indptr"):
        assert np.array_equal(getattr(S_mine, name), getattr(S, name))
    rows, cols, values = kkt_matrix.kkt_entries(S, J_mine)
    size = n + J.shape[0]
    position = np.empty(size, dtype=np.int64)
    position[factor.order] = np.arange(size)
    lub, piv, *_ = reference_band_lu(size, position[rows], position[cols], values)
    assert np.array_equal(factor._lu._lub, lub) and np.array_equal(factor._lu._piv, piv)
    K_reference = sp.csr_matrix((values, (rows, cols)), shape=(size, size))
    K_mine = kkt_matrix.kkt_csr(S_mine, J_mine)
    for name in ("data", "indices", "indptr"):
        assert np.array_equal(getattr(K_mine, name), getattr(K_reference, name))
    dense = np.block([[H.dense() - shift * np.diag(mass if mass is not None else np.ones(n)),
                       J.toarray().T], [J.toarray(), np.zeros((J.shape[0],) * 2)]])
    assert factor.negative_count == np.sum(np.linalg.eigvalsh(dense) < 0)


def test_shifted_hessian_with_zeros_and_cancellation_equals_scipys_difference():
    """Explicit zeros in S, zero masses (not stored by scipy's diagonal) and a diagonal
    entry that cancels exactly (dropped by both)."""
    S = sp.csr_matrix(np.array([[2.0, 1.0, 0.0], [1.0, 0.5, 0.0], [0.0, 0.0, 3.0]]))
    S.data[S.data == 1.0] = 0.0  # explicit zeros off the diagonal
    mass = np.array([1.0, 0.0, 1.5])
    for shift in (2.0, -0.5, 1e-300):
        mine = kkt_matrix.shifted(S, shift, mass)
        scipys = (S - shift * sp.diags(mass)).tocsr()
        for name in ("data", "indices", "indptr"):
            assert np.array_equal(getattr(mine, name), getattr(scipys, name)), (shift, name)


def test_products_and_stacks_equal_scipys_bit_for_bit():
    rng = np.random.default_rng(11)
    for trial in range(6):
        A = sp.random(60, 45, density=0.15, format="csr", random_state=trial)
        A.data = rng.standard_normal(A.data.size) * 10.0 ** rng.uniform(-6, 6, A.data.size)
        x, X, u = rng.standard_normal(45), rng.standard_normal((45, 3)), rng.standard_normal(60)
        assert np.array_equal(csr_matvec(A.indptr, A.indices, A.data, x, 45), A @ x)
        assert np.array_equal(CSRArrays(A.data, A.indices, A.indptr, A.shape) @ X, A @ X)
        assert np.array_equal(csr_rmatvec(A.indptr, A.indices, A.data, u, 45), A.T @ u)
        B = sp.csr_matrix(rng.standard_normal((2, 45)))
        for blocks in ([A, B], [A], [A[5:17], B, A]):
            mine, scipys = csr_vstack(blocks), sp.vstack(blocks, format="csr")
            for name in ("data", "indices", "indptr"):
                assert np.array_equal(getattr(mine, name), getattr(scipys, name))
    # a wrong length is refused, as scipy's "dimension mismatch" (the compiled loops
    # would read and write out of bounds)
    with pytest.raises(ValueError, match="dimension mismatch"):
        csr_matvec(A.indptr, A.indices, A.data, x[:40], 45)
    with pytest.raises(ValueError, match="dimension mismatch"):
        CSRArrays(A.data, A.indices, A.indptr, A.shape) @ X[:40]
    with pytest.raises(ValueError, match="dimension mismatch"):
        csr_rmatvec(A.indptr, A.indices, A.data, u[:50], 45)
    H = HessianParts(sp.random(30, 30, density=0.2, format="csr", random_state=1),
                     rng.standard_normal((2, 30)), np.array([0.5, -2.0]))
    x = rng.standard_normal(30)
    assert np.allclose(H.matvec(x), H.dense() @ x, rtol=1e-14, atol=1e-14)


def test_csr_add_with_and_without_cancellation_on_one_pattern():
    """The same patterns twice: first nothing cancels (the union pattern as it is),
    then an entry cancels exactly (dropped): both as scipy's sum."""
    A = sp.csr_matrix(np.array([[1.0, 2.0, 0.0], [0.0, 3.0, 4.0], [5.0, 0.0, 6.0]]))
    B = sp.csr_matrix(np.array([[1.0, 0.0, 7.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    for a_values in (A.data, np.array([1.0, 2.0, -1.0, 4.0, 5.0, 6.0])):
        A2 = sp.csr_matrix((a_values, A.indices, A.indptr), shape=A.shape)
        mine, scipys = csr_add(A2, B), (A2 + B).tocsr()
        for name in ("data", "indices", "indptr"):
            assert np.array_equal(getattr(mine, name), getattr(scipys, name))


def test_order_memo_sums_and_dense_rows_equal_numpys_counts():
    rng = np.random.default_rng(3)
    _H, J = banded_kkt(rng, 120, 15, dense_rows=2)
    J = sp.csr_matrix(J)
    J.data[::7] = 0.0  # stored zeros do not count towards a dense row
    J.data[J.indptr[-2]:J.indptr[-1]][:100] = 0.0  # the last dense row falls below the limit
    row_of = np.repeat(np.arange(J.shape[0]), np.diff(J.indptr))
    counts = np.bincount(row_of[J.data != 0], minlength=J.shape[0])
    limit = max(pinned_rows.DENSE_ROW_MIN_ENTRIES, pinned_rows.DENSE_ROW_FRACTION * J.shape[1])
    assert np.array_equal(pinned_rows.dense_rows(J), np.flatnonzero(counts > limit))
    _H, J = banded_kkt(rng, 120, 15)
    J = sp.csr_matrix(J)
    memo = ordering.OrderMemo.of(J, np.arange(135))
    terms = J.data[memo._first] * J.data[memo._second]
    total, size = ordering._pair_sums(J.data, memo._first, memo._second, memo._group,
                                 memo._n_groups)
    assert np.array_equal(total, np.bincount(memo._group, terms, minlength=memo._n_groups))
    assert np.array_equal(size, np.bincount(memo._group, np.abs(terms),
                                            minlength=memo._n_groups))
