"""KKTFactor: LAPACK's band LU on a narrow ordered band, SuperLU on a wide one.

Oracles: the dense matrix (eigenvalues' signs and product, numpy's solve and the
solve's residual).
"""

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import with_rank_one_terms

from supercoil.solvers.errors import SingularMatrixError
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.lu import BandLU, OrderedLU
from supercoil.solvers.problem import HessianParts


def banded_kkt(rng, n, m, rank_one=0, dense_rows=0, width=3):
    """A chain-like KKT problem: ``H`` of half-bandwidth ``width`` (indefinite),
    ``m`` constraints on neighbouring unknowns, ``dense_rows`` rows on every unknown
    (integral phase conditions) and ``rank_one`` dense symmetric rank-one terms."""
    H = np.zeros((n, n))
    for k in range(width + 1):
        d = rng.standard_normal(n - k)
        H += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
    H += np.diag(rng.uniform(-1.0, 3.0, n))
    J = np.zeros((m + dense_rows, n))
    for j in range(m):
        start = int(rng.integers(0, n - 3))
        J[j, start:start + 3] = rng.standard_normal(3)
    J[m:] = rng.standard_normal((dense_rows, n))
    return with_rank_one_terms(rng, H, J, rank_one)


@pytest.mark.parametrize("seed", range(8))
def test_band_factor_equals_the_dense_matrix(seed):
    rng = np.random.default_rng(900 + seed)
    n, m = int(rng.integers(60, 160)), int(rng.integers(1, 12))
    H, J = banded_kkt(rng, n, m, rank_one=int(rng.integers(0, 3)),
                      dense_rows=int(seed % 3 == 2))
    shift, mass = (0.0, None) if seed % 2 else (-0.3, rng.uniform(0.5, 2.0, n))
    band = KKTFactor(H, J, shift=shift, mass=mass)
    assert isinstance(band._lu, BandLU)
    k = J.shape[0]
    Hd = H.dense() - shift * np.diag(mass if mass is not None else np.ones(n))
    K = np.block([[Hd, J.toarray().T], [J.toarray(), np.zeros((k, k))]])
    _assert_dense(band, K, rng.standard_normal((n + k, 2)))


def _assert_dense(factor, K, rhs):
    """The factor's inertia, determinant sign and solves are those of the dense ``K``
    (solves relative to its condition)."""
    ev = np.linalg.eigvalsh(K)
    assert factor.negative_count == np.sum(ev < 0)
    assert factor.determinant_sign == int(np.prod(np.sign(ev)))
    z, exact = factor.solve(rhs), np.linalg.solve(K, rhs)
    cond = np.linalg.cond(K)
    assert np.max(np.abs(z - exact)) <= 1e-13 * cond * np.max(np.abs(exact))
    assert np.max(np.abs(K @ z - rhs)) <= 1e-12 * cond * np.max(np.abs(rhs))


def test_band_determinant_sign_counts_row_swaps():
    """Matrices whose LU needs row swaps (zero diagonal): the sign from U's diagonal
    and the pivots equals the sign of the determinant, either parity of swaps."""
    rng = np.random.default_rng(7)
    for trial in range(20):
        n = 40
        A = np.zeros((n, n))
        for k in range(3):
            d = rng.standard_normal(n - k)
            A += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
        A[np.arange(0, n, 3), np.arange(0, n, 3)] = 0.0  # forces pivoting
        coo = sp.coo_matrix(A)
        lu = BandLU.of(n, coo.row, coo.col, coo.data, np.arange(n))
        assert np.any(lu._piv != np.arange(n))
        assert lu.determinant_sign() == int(np.sign(np.linalg.det(A)))


def test_wide_bands_go_to_superlu_and_singular_matrices_are_reported():
    rng = np.random.default_rng(3)
    # a band wider than a quarter of the matrix: SuperLU, the dense matrix's results
    A = rng.standard_normal((20, 20))
    A = A + A.T
    wide = KKTFactor(HessianParts(sp.csr_matrix(A)))
    assert isinstance(wide._lu, OrderedLU)
    _assert_dense(wide, A, rng.standard_normal(20))
    J = sp.csr_matrix(rng.standard_normal((3, 20)))
    wide = KKTFactor(HessianParts(sp.csr_matrix(A)), J)
    assert isinstance(wide._lu, OrderedLU)
    K = np.block([[A, J.toarray().T], [J.toarray(), np.zeros((3, 3))]])
    _assert_dense(wide, K, rng.standard_normal(23))
    # an exactly singular banded matrix (band LU) or a singular wide one (SuperLU)
    H = np.diag(np.r_[np.ones(30), 0.0, np.ones(29)])
    with pytest.raises(SingularMatrixError):
        KKTFactor(HessianParts(sp.csr_matrix(H)))
    A[:, 0] = A[0, :] = 0.0
    with pytest.raises(SingularMatrixError):
        KKTFactor(HessianParts(sp.csr_matrix(A)))


def test_pinned_rows_from_the_remembered_layout_rebuild_the_jacobian():
    """PinnedRows.of remembers where the kept entries go per pattern: with other values
    on the same pattern (the second call) the split still satisfies
    J = sparse + I[:, rows] delta, each dense row cut to its pin."""
    from supercoil.solvers.pinned_rows import PinnedRows

    rng = np.random.default_rng(11)
    _, J = banded_kkt(rng, 120, 10, dense_rows=2)
    J = J.tocsr()
    for trial in range(3):
        J = sp.csr_matrix((rng.standard_normal(J.nnz), J.indices, J.indptr), shape=J.shape)
        split = PinnedRows.of(J)
        assert split is not None and np.array_equal(split.rows, [10, 11])
        rebuilt = split.sparse.toarray()
        rebuilt[split.rows] += split.delta
        assert np.array_equal(rebuilt, J.toarray())
        for j, row in enumerate(split.rows):
            cut = split.sparse[row]
            assert cut.nnz == 1 and cut.indices[0] == split.pins[j]


def test_permuted_bordered_entries_without_the_matrix_are_the_same():
    """BorderedFactor asks permuted_bordered for the pinned K's entries only
    (matrix=False): the same entries as with the matrix built, bit for bit."""
    from supercoil.continuation.bordered_matrix import permuted_bordered
    from supercoil.solvers.ordering import kkt_order

    rng = np.random.default_rng(21)
    H, J = banded_kkt(rng, 80, 9)
    S = H.sparse.tocsr()
    n, m = 80, J.shape[0]
    column, row = rng.standard_normal(n + m), rng.standard_normal(n + m)
    order = np.concatenate([kkt_order(S, J), [n + m]])
    B, with_matrix = permuted_bordered(S, J, column, row, 1.5, order)
    none, entries = permuted_bordered(S, J, column, row, 1.5, order, matrix=False,
                                       s_bytes=(S.indptr.tobytes(), S.indices.tobytes()))
    assert B is not None and none is None
    for a, b in zip(with_matrix, entries):
        assert np.array_equal(a, b)


def test_remembered_kkt_order_with_two_term_entries_that_cancel_or_nearly():
    """An entry of J^T J with two terms is stored by scipy exactly when their sum is
    not 0 (the same in either order), however small: the memo certifies it when it
    is stored or dropped as when the ordering was computed (exactly symmetric
    states), and only then. Oracle: the computed ordering, every time."""
    from supercoil.solvers import ordering

    rng = np.random.default_rng(8)
    n = 40
    base = np.zeros((n, n))
    for k in range(2):
        d = rng.standard_normal(n - k)
        base += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
    S = sp.csr_matrix(base + 4.0 * np.eye(n))
    rows = [(a, int(rng.choice(np.arange(2, n))), rng.standard_normal())
            for a in rng.choice(np.arange(2, n), size=10)]

    def jacobian(second, scale=1.0):
        J = np.zeros((len(rows) + 2, n))
        J[0, 0], J[0, 30], J[1, 0], J[1, 30] = 1.0, 1.0, 1.0, second  # (0, 30): 1 + second
        for k, (a, b, u) in enumerate(rows):
            J[k + 2, a], J[k + 2, b] = scale * u, 1.0
        return sp.csr_matrix(J)

    tiny = -(1.0 - 2.0**-52)  # 1 + tiny = 2^-52: stored, far below the 1e-8 bound
    for first, others in ((-1.0, (-1.0, tiny, 0.3)), (tiny, (-(1.0 - 2.0**-51), -1.0))):
        ordering._ORDER_MEMO.clear()
        computed = ordering.kkt_order(S, jacobian(first))
        assert np.array_equal(computed, ordering._kkt_order(S, jacobian(first)))
        assert len(ordering._ORDER_MEMO) == 1  # remembered despite the (near) cancellation
        ((memo, *_arrays),) = ordering._ORDER_MEMO.values()
        for second in others:
            J = jacobian(second, scale=1.3)
            same = (1.0 + second == 0.0) == (1.0 + first == 0.0)
            assert memo.certifies(J) == same
            assert np.array_equal(ordering.kkt_order(S, J), ordering._kkt_order(S, J))


def test_straight_rod_stored_zeros_take_the_band_of_the_nonzeros():
    """The clamped straight rod's Hessian and Jacobian store zeros that couple far
    unknowns (its lateral DOFs at rest): the stored band of its KKT matrix is wider than
    a quarter of it, its nonzero band narrow. The factor takes the band LU of the
    nonzeros (SuperLU took 2 ms a factorisation against 0.1-0.3 ms at N = 100), and
    agrees with the dense matrix (inertia, determinant sign, solves)."""
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.problems.tweezers import TweezersOptions, clamped_problem
    from supercoil.solvers.kkt_matrix import kkt_band_layout
    from supercoil.solvers.ordering import kkt_order

    options = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=33, tension=75,
                              turns=(0, 5), n_nodes=40)
    rod, q0 = clamped_problem(options)
    system = ExtendedSystem(rod, "turns", q0, None, q0, 1.0, 1e-7)
    rod.turns = 2.9  # beyond the first buckling: an indefinite Hessian
    x = system.pack(q0, np.zeros(rod.n_constraints), 2.9)
    H = system.hessian(x)
    J = system.jacobian(x)
    S, Jc = H.sparse.tocsr(), sp.csr_matrix(J)
    assert np.count_nonzero(Jc.data) < Jc.nnz  # stored zeros
    assert kkt_band_layout(S, Jc, kkt_order(S, Jc)) is None  # stored band too wide
    band = KKTFactor(H, J)
    assert isinstance(band._lu, BandLU)
    assert band.reduced_negative_count > 0
    k = J.shape[0]
    K = np.block([[H.dense(), J.toarray().T], [J.toarray(), np.zeros((k, k))]])
    _assert_dense(band, K, np.random.default_rng(4).standard_normal(K.shape[0]))
