"""Linear algebra (inertia, solves) and Newton against exact answers and dense oracles."""

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import smooth_closed_curve, split_into_halves, with_rank_one_terms

from supercoil.problems.ring import twisted_circle_problem
from supercoil.solvers.inertia import symmetric_inertia
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.newton import NewtonOptions, Status, newton
from supercoil.solvers.problem import HessianParts


def random_band(rng, n, b):
    A = np.zeros((n, n))
    for k in range(b + 1):
        d = rng.standard_normal(n - k)
        A += np.diag(d, k) + (np.diag(d, -k) if k else 0)
    return A


@pytest.mark.parametrize("seed", range(12))
def test_block_inertia_equals_dense_eigenvalues(seed):
    rng = np.random.default_rng(seed)
    n, b = int(rng.integers(20, 250)), int(rng.integers(1, 10))
    A = random_band(rng, n, b)
    perm = rng.permutation(n)  # hide the band: the ordering must find it again
    Ap = A[perm][:, perm]
    neg, zero, pos = symmetric_inertia(sp.csr_matrix(Ap))
    ev = np.linalg.eigvalsh(A)
    assert (neg, zero, pos) == (np.sum(ev < 0), 0, np.sum(ev > 0))


def random_kkt(rng, n, m, rank_one):
    H = random_band(rng, n, 3) + 2.0 * np.eye(n)
    J = np.zeros((m, n))
    for j in range(m):
        cols = rng.choice(n, size=3, replace=False)
        J[j, cols] = rng.standard_normal(3)
    return with_rank_one_terms(rng, H, J, rank_one)


@pytest.mark.parametrize("seed", range(10))
def test_kkt_inertia_determinant_and_solve_match_dense(seed):
    rng = np.random.default_rng(100 + seed)
    n, m = int(rng.integers(20, 120)), int(rng.integers(1, 15))
    H, J = random_kkt(rng, n, m, rank_one=int(rng.integers(0, 3)))
    factor = KKTFactor(H, J)
    K = np.block([[H.dense(), J.toarray().T], [J.toarray(), np.zeros((m, m))]])
    ev = np.linalg.eigvalsh(K)
    assert factor.negative_count == np.sum(ev < 0)
    assert factor.reduced_negative_count == np.sum(ev < 0) - m
    assert factor.determinant_sign == int(np.prod(np.sign(ev)))
    rhs = rng.standard_normal(n + m)
    assert np.allclose(K @ factor.solve(rhs), rhs, atol=1e-9 * np.abs(rhs).max() * np.linalg.cond(K))


@pytest.mark.parametrize("seed", range(6))
def test_equilibrated_entries_equal_the_sparse_products_bit_for_bit(seed):
    """The Ruiz scaling on entry arrays (fast path) against diag(d) @ A @ diag(d) of
    scipy.sparse (the previous code), permuted: the same entries, the same bits."""
    from band_reference import equilibrated_entries

    from supercoil.solvers.ordering import kkt_order

    rng = np.random.default_rng(300 + seed)
    n, m = int(rng.integers(20, 120)), int(rng.integers(1, 15))
    H, J = random_kkt(rng, n, m, rank_one=0)
    S = H.sparse.multiply(10.0 ** rng.uniform(-4, 4, n)[:, None]).tocsr()
    S = (S + S.T).tocsr()  # rows of very different sizes, as bending against constraints
    K = sp.bmat([[S, J.T], [J, None]], format="csr")
    K.eliminate_zeros()
    order = kkt_order(S, J)
    rows, cols, values = equilibrated_entries(K, order)
    d = np.ones(n + m)
    for _ in range(8):
        scaled = sp.diags(d) @ K @ sp.diags(d)
        row_max = abs(scaled).max(axis=1).toarray().ravel()
        d = d / np.sqrt(np.where(row_max > 0, row_max, 1.0))
    reference = (sp.diags(d) @ K @ sp.diags(d)).tocsr()[order][:, order].tocoo()
    mine = sp.coo_matrix((values, (rows, cols)), shape=K.shape).tocsr()
    reference = reference.tocsr()
    assert np.array_equal(mine.indptr, reference.indptr)
    assert np.array_equal(mine.indices, reference.indices)
    assert np.array_equal(mine.data, reference.data)


def test_remembered_kkt_order_equals_the_computed_one_and_sees_cancellation():
    """kkt_order remembers orderings by pattern; _kkt_order_scipy computes them with
    scipy.sparse (the reference). Same pattern with other values: the same ordering; an
    entry of J^T J that cancels exactly (scipy drops it, the pattern changes): the memo
    must not be used."""
    from supercoil.solvers import ordering

    rng = np.random.default_rng(5)
    n = 40
    S = sp.csr_matrix(random_band(rng, n, 1) + 4.0 * np.eye(n))
    rows = [(0, 25, 1.0, 1.0), (1, 25, 1.0, -1.0)]  # J^T J entry (0, 25) cancels for (+, -)
    for k in range(2, 12):
        a, b = rng.choice(np.arange(2, n), size=2, replace=False)
        rows.append((a, b, rng.standard_normal(), rng.standard_normal()))

    def jacobian(sign):
        J = np.zeros((len(rows), n))
        for k, (a, b, u, v) in enumerate(rows):
            J[k, a], J[k, b] = u, v
        J[0, 0] = J[1, 0] = 1.0
        J[0, 25], J[1, 25] = 1.0, sign  # sign = -1: the (0, 25) entry of J^T J is 0
        return sp.csr_matrix(J)

    ordering._ORDER_MEMO.clear()
    plain = ordering.kkt_order(S, jacobian(0.5))
    assert np.array_equal(plain, ordering._kkt_order_scipy(S, jacobian(0.5)))
    assert len(ordering._ORDER_MEMO) == 1
    again = ordering.kkt_order(S, jacobian(0.7))  # same pattern, remembered
    assert np.array_equal(again, ordering._kkt_order_scipy(S, jacobian(0.7)))
    ((memo, *_arrays),) = ordering._ORDER_MEMO.values()
    assert memo.certifies(jacobian(0.7)) and not memo.certifies(jacobian(-1.0))
    cancelled = ordering.kkt_order(S, jacobian(-1.0))
    assert np.array_equal(cancelled, ordering._kkt_order_scipy(S, jacobian(-1.0)))
    for seed in range(5):  # random KKT patterns, each asked twice
        H, J = random_kkt(np.random.default_rng(400 + seed), 60, 8, rank_one=0)
        for _ in range(2):
            assert np.array_equal(ordering.kkt_order(H.sparse, J), ordering._kkt_order_scipy(H.sparse, J))


@pytest.mark.parametrize("seed", range(4))
def test_superlu_factor_from_entries_equals_superlu_of_bmat(seed):
    """The SuperLU factor of KKTFactor (wide bands) forms the permuted KKT matrix from
    entry arrays; the reference factorises bmat(...)[order][:, order]: same LU, same
    solves, bit for bit (explicit zeros of H and J kept)."""
    from scipy.sparse.linalg import splu

    from supercoil.solvers.kkt_matrix import canonical, kkt_entries
    from supercoil.solvers.lu import OrderedLU
    from supercoil.solvers.ordering import kkt_order

    rng = np.random.default_rng(500 + seed)
    n, m = int(rng.integers(30, 90)), int(rng.integers(1, 12))
    H, J = random_kkt(rng, n, m, rank_one=0)
    S = H.sparse.tocsr()
    S.data[::9] = 0.0
    J = J.tocsr()
    J.data[::4] = 0.0
    if seed == 3:  # every entry stored as two halves (not canonical): bmat sums them
        S = split_into_halves(S)
    order = kkt_order(S, J)
    factor = OrderedLU(n + m, *kkt_entries(canonical(S), canonical(J)), order)
    lu = splu(sp.bmat([[S, J.T], [J, None]], format="csr")[order][:, order].tocsc(),
              permc_spec="NATURAL")
    rhs = rng.standard_normal(n + m)
    reference = np.empty(n + m)
    reference[order] = lu.solve(rhs[order])
    assert np.array_equal(factor.solve(rhs), reference)
    assert np.array_equal(factor.U.diagonal(), lu.U.diagonal())
    assert np.array_equal(factor.perm_r, lu.perm_r)


def _same_csr(mine, reference):
    reference = reference.tocsr()
    return (mine.shape == reference.shape and np.array_equal(mine.indptr, reference.indptr)
            and np.array_equal(mine.indices, reference.indices)
            and np.array_equal(mine.data, reference.data)
            and np.array_equal(np.signbit(mine.data), np.signbit(reference.data)))


@pytest.mark.parametrize("seed", range(6))
def test_pattern_sums_and_restrictions_equal_scipy_bit_for_bit(seed):
    """solvers.csr and solvers.csr_sum (index maps remembered per pattern) against scipy's A + B and
    A[keep][:, keep]: cancelling entries dropped, explicit zeros and -0.0 as scipy has
    them, the same stored order; every call twice (the second from the memo)."""
    from supercoil.solvers.csr import csr_columns, csr_restrict
    from supercoil.solvers.csr_sum import csr_add

    rng = np.random.default_rng(600 + seed)
    n = int(rng.integers(5, 80))
    A = sp.random(n, n, density=0.15, random_state=seed, format="csr")
    B = sp.random(n, n, density=0.1, random_state=seed + 50, format="csr")
    A.data[::6] = 0.0
    B.data[1::7] = -0.0
    both = A.multiply(B != 0).tocsr()  # entries of B that cancel entries of A exactly
    C = (B - both).tocsr()
    C.sort_indices()
    for first, second in ((A, B), (A, C), (B, A), (A, sp.csr_matrix((n, n)))):
        for _ in range(2):
            assert _same_csr(csr_add(first, second), first + second)
    keep = np.flatnonzero(rng.random(n) < 0.7)
    for matrix in (A, B, A + B):
        for _ in range(2):
            assert _same_csr(csr_restrict(matrix.tocsr(), keep), matrix.tocsr()[keep][:, keep])
    shuffled = rng.permutation(keep)  # not sorted: scipy's own path
    assert _same_csr(csr_restrict(A, shuffled), A[shuffled][:, shuffled])
    wide = sp.random(n // 2 + 1, n, density=0.2, random_state=seed + 9, format="csr")
    wide.data[::5] = 0.0
    for matrix in (wide, A):
        for _ in range(2):
            assert _same_csr(csr_columns(matrix, keep), matrix[:, keep].tocsr())
        assert _same_csr(csr_columns(matrix, shuffled), matrix[:, shuffled].tocsr())


def test_rod_constraint_curvature_equals_the_coo_assembly():
    """The rod's constraint Hessian filled into its remembered pattern (fast path)
    against the COO assembly it replaced, zero multipliers (-0.0 entries) included."""
    p, _ = twisted_circle_problem(2 / 3, 1.0, 40)
    rows, cols = p._constraint_hessian_entries()
    rng = np.random.default_rng(3)
    for mu in (rng.standard_normal(p.n_constraints), np.zeros(p.n_constraints)):
        w = np.repeat(mu / p.rod.edge_length, 3)
        reference = sp.csr_matrix((np.concatenate([w, w, -w, -w]), (rows, cols)),
                                  shape=(p.n_dofs, p.n_dofs))
        assert _same_csr(p.constraint_hessian(None, mu), reference)


@pytest.mark.parametrize("excess_link", [0.0, 1.0, 3.0, 4.5])
def test_kkt_inertia_on_the_ring_equals_dense(excess_link):
    from supercoil.solvers.newton import lagrangian_hessian, least_squares_multipliers
    from supercoil.solvers.problem import free_dofs

    p, q = twisted_circle_problem(2 / 3, excess_link, 60)
    free = free_dofs(p)
    lam = least_squares_multipliers(p, q, free)
    H = lagrangian_hessian(p, q, lam).restrict(free)
    J = p.constraint_jacobian(q)[:, free]
    K = np.block([[H.dense(), J.toarray().T], [J.toarray(), np.zeros((60, 60))]])
    ev = np.linalg.eigvalsh(K)
    factor = KKTFactor(H, J)
    assert factor.negative_count == np.sum(ev < 0)
    assert factor.determinant_sign == int(np.prod(np.sign(ev)))


class CircleConstrainedQuadratic:
    """min (x-a)^T D (x-a)/2 on the unit sphere |x|^2 = 1: a toy problem with a known answer."""

    def __init__(self, a, d):
        self.a, self.d = np.asarray(a, float), np.asarray(d, float)
        self.n_dofs = len(a)
        self.n_constraints = 1
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.ones(len(a))

    def energy(self, q):
        r = q - self.a
        return 0.5 * float(r @ (self.d * r))

    def gradient(self, q):
        return self.d * (q - self.a)

    def hessian(self, q):
        return HessianParts(sp.diags(self.d).tocsr(), np.zeros((0, self.n_dofs)), np.zeros(0))

    def constraints(self, q):
        return np.array([0.5 * (q @ q - 1.0)])

    def constraint_jacobian(self, q):
        return sp.csr_matrix(q[None, :])

    def constraint_hessian(self, q, lam):
        return sp.identity(self.n_dofs, format="csr") * float(lam[0])

    def accept(self, q):
        pass


def test_newton_minimize_finds_the_constrained_minimum_with_quadratic_convergence():
    # isotropic D: the minimiser of |x - a| on the sphere is a/|a|
    a = np.array([3.0, -1.0, 2.0, 0.5])
    prob = CircleConstrainedQuadratic(a, np.ones(4))
    res = newton(prob, np.array([0.0, 1.0, 0.0, 0.0]), NewtonOptions(tolerance=1e-13))
    assert res.converged
    assert np.allclose(res.q, a / np.linalg.norm(a), atol=1e-12)
    r = np.array(res.residual_history)
    tail = r[(r > 1e-12) & (r < 1e-1)]
    # quadratic: log r_{k+1} / log r_k -> 2
    rates = np.log(tail[1:]) / np.log(tail[:-1])
    assert rates.size >= 1 and np.all(rates[-1:] > 1.8)


def test_newton_on_a_perturbed_ring_converges_quadratically_back_to_the_circle(rng):
    p, q = twisted_circle_problem(2 / 3, 1.0, 60)
    e_circle = p.energy(q)
    bump = smooth_closed_curve(60, wobble=0.4) - smooth_closed_curve(60, wobble=0.0)
    q0 = q + 0.02 * bump.ravel()
    res = newton(p, q0, NewtonOptions(tolerance=1e-11))
    assert res.converged, res.message
    assert p.energy(res.q) == pytest.approx(e_circle, rel=1e-10)
    r = np.array(res.residual_history)
    # quadratic convergence: r_{k+1} <= C r_k^2 over the last two steps, and the
    # local order log(r_{k+1}) / log(r_k) is at least 2 (nondimensional residuals < 1)
    assert len(r) >= 3
    assert np.all(r[-2:] <= 1e3 * r[-3:-1] ** 2), r
    assert np.log(r[-1]) / np.log(r[-2]) > 1.9, r


def test_newton_reports_failure_as_a_status():
    a = np.array([3.0, -1.0, 2.0])
    prob = CircleConstrainedQuadratic(a, np.array([1.0, 2.0, 3.0]))
    res = newton(prob, np.array([0.0, 1.0, 0.0]), NewtonOptions(max_iterations=1,
                                                                tolerance=1e-14))
    assert not res.converged
    assert res.status is Status.MAX_ITERATIONS
    assert "no convergence" in res.message


@pytest.mark.parametrize("mode", ["minimize", "stationary"])
def test_a_non_finite_newton_step_is_a_status_not_a_non_finite_state(mode, monkeypatch):
    """Where the KKT solve overflows (here made to: every solve gives inf), the step is
    refused before it reaches the state or the problem's own checks (the contact's step
    guard raised on a NaN cutoff where a quasi-static minimisation's shifted solve
    overflowed)."""
    import supercoil.solvers.newton as newton_module

    class Overflowing(newton_module.KKTFactor):
        def solve(self, rhs):
            return np.full_like(super().solve(rhs), np.inf)

    monkeypatch.setattr(newton_module, "KKTFactor", Overflowing)
    prob = CircleConstrainedQuadratic(np.array([3.0, -1.0, 2.0]), np.ones(3))
    q0 = np.array([0.0, 1.0, 0.0])
    res = newton(prob, q0, NewtonOptions(mode=mode, inertia_test="exact"))
    assert res.status is Status.NONFINITE and "Newton step is not finite" in res.message
    np.testing.assert_array_equal(res.q, q0)


@pytest.mark.parametrize("bad", [{"tolerance": 0.0}, {"max_iterations": 0},
                                 {"mode": "maximize"}, {"max_step_norm": -1.0}])
def test_newton_options_validate(bad):
    with pytest.raises(ValueError):
        NewtonOptions(**bad)


class DoubleWell:
    """E = -x^2/2 + x^4/4 + y^4: a saddle at the origin, minima at (+-1, 0)."""

    n_dofs, n_constraints = 2, 0
    fixed = np.zeros(0, dtype=np.int64)
    mass = np.ones(2)

    def energy(self, q):
        x, y = q
        return -0.5 * x * x + 0.25 * x**4 + y**4

    def gradient(self, q):
        x, y = q
        return np.array([-x + x**3, 4 * y**3])

    def hessian(self, q):
        x, y = q
        return HessianParts(sp.diags([-1 + 3 * x * x, 12 * y * y]).tocsr(),
                            np.zeros((0, 2)), np.zeros(0))

    def constraints(self, q):
        return np.zeros(0)

    def constraint_jacobian(self, q):
        return sp.csr_matrix((0, 2))

    def constraint_hessian(self, q, lam):
        return sp.csr_matrix((2, 2))

    def accept(self, q):
        pass


def test_minimize_with_the_exact_inertia_leaves_the_saddle():
    """From next to the saddle along the stable direction, the inertia-corrected
    step plus the negative-curvature escape reach a minimum (x = +-1, y = 0)."""
    res = newton(DoubleWell(), np.array([1e-3, 1.0]),
                 NewtonOptions(mode="minimize", tolerance=1e-10, max_iterations=200))
    assert res.converged
    np.testing.assert_allclose(abs(res.q[0]), 1.0, atol=1e-8)
    assert abs(res.q[1]) < 1e-2  # y^4 is flat at its minimum: slow, sublinear in y


def test_stationary_mode_converges_to_the_saddle_it_starts_next_to():
    res = newton(DoubleWell(), np.array([1e-3, 0.1]),
                 NewtonOptions(mode="stationary", tolerance=1e-12, max_iterations=200))
    assert res.converged and abs(res.q[0]) < 1e-8


def test_permutation_parity_by_pointer_jumping_equals_cycle_walking():
    """lu.permutation_parity (vectorised, fast path) against walking the cycles."""
    from supercoil.solvers.lu import permutation_parity

    def walked(perm):
        seen = np.zeros(perm.size, dtype=bool)
        parity = 1
        for start in range(perm.size):
            length, j = 0, start
            while not seen[j]:
                seen[j], j, length = True, perm[j], length + 1
            if length and length % 2 == 0:
                parity = -parity
        return parity

    rng = np.random.default_rng(8)
    for n in [*range(12), 63, 64, 65, 387, 1000]:
        for _ in range(5):
            perm = rng.permutation(n)
            assert permutation_parity(perm) == walked(perm)
    assert permutation_parity(np.array([1, 0, 2])) == -1  # one transposition


def test_pattern_memo_keeps_the_newest_entries_within_its_bounds():
    from supercoil.solvers.patterns import PatternMemo

    memo = PatternMemo(max_entries=3, max_bytes=10_000)
    for k in range(5):
        memo.put((k,), (np.zeros(100),))  # 800 bytes each
    assert len(memo) == 3 and memo.get((0,)) is None and memo.get((4,)) is not None
    memo.put(("big",), (np.zeros(1000),))  # 8000 bytes: the older ones make room
    assert memo.get(("big",)) is not None and memo.get((2,)) is None
    assert memo._total <= memo.max_bytes
    memo.put(("huge",), (np.zeros(2000),))  # larger than the bound: not kept
    assert memo.get(("huge",)) is None and memo.get(("big",)) is not None


def test_minimise_from_edges_stretched_beyond_the_trust_radius():
    """A minimisation whose constraints need a correction longer than the trust radius
    (a clamped rod in contact's ``step_size_ratio``: one edge length) takes it: no
    shift of the Hessian shortens that part of the step (the shifted step's limit is the
    constraints' own correction), so the shift is not raised without end. Oracle: below
    Greenhill's buckling (1 turn against 2.6 at F L^2/A = 20, C/A = 1.5) the straight rod
    is the minimum, reached from the nodes of the middle moved sideways by twice the
    edge length, alternately one way and the other (their edges stretched to 4.1 times
    theirs), with either test of the shifted Hessian."""
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.rod.model import Rod
    from supercoil.rod.open import ClampedRodEnergy, straight_rod

    n = 30
    straight = straight_rod(n)
    rod = ClampedRodEnergy(Rod(n_nodes=n, twist_stiffness=1.5, closed=False), straight,
                           turns=1.0, tension=20.0)
    problem = ContactProblem(rod, ContactOptions(diameter=0.02))
    h = rod.rod.edge_length
    moved = straight.copy()
    moved[10:20, 0] += 2 * h * (-1.0) ** np.arange(10)
    assert np.max(np.abs(rod.constraints(moved.ravel()))) > h  # beyond the trust radius
    for test in ("exact", "curvature"):
        res = newton(problem, moved.ravel(), NewtonOptions(
            mode="minimize", tolerance=1e-9, max_iterations=300, inertia_test=test))
        assert res.converged, res.message
        x = res.q.reshape(-1, 3)
        np.testing.assert_allclose(x[:, :2], 0.0, atol=1e-8)
        np.testing.assert_allclose(np.linalg.norm(np.diff(x, axis=0), axis=1), h, rtol=1e-9)
