"""Dense constraint rows (the integral phase condition) as extra borders.

Oracles: the k-bordered band solve and the pinned bordered factor equal
``numpy.linalg.solve`` of the same matrix, also when the banded block is
nearly singular (a fold); the pinned KKT factor's negative count and
determinant sign equal those of the dense eigenvalues; branches computed
with dense rows pinned equal those computed with the rows left in the
sparse matrix (the path before pinning, forced by raising the density
threshold): toys, and the ring's integral-gauge branches at N = 48.
"""

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
from test_continuation import assert_consistent
from test_continuation_toys import DiagonalQuartic, LoadedSphere

from supercoil.continuation import ContinuationOptions, continuation, switch_branch
from supercoil.continuation.band_bordered import BandBordered
from supercoil.continuation.bordered import BorderedFactor
from supercoil.solvers import kkt, pinned_rows
from supercoil.solvers.problem import HessianParts


def _banded(rng, n, band, singular_scale=None):
    """Random symmetric band matrix; with ``singular_scale`` its eigenvalue nearest zero
    is moved there (then cut back to the band, so only nearly)."""
    A = np.zeros((n, n))
    for k in range(band + 1):
        d = rng.standard_normal(n - k)
        A += np.diag(d, k) + (np.diag(d, -k) if k else 0)
    if singular_scale is not None:
        values, vectors = np.linalg.eigh(A)
        i = int(np.argmin(np.abs(values)))
        A = A + (singular_scale - values[i]) * np.outer(vectors[:, i], vectors[:, i])
        A[np.abs(np.subtract.outer(np.arange(n), np.arange(n))) > band] = 0.0
    return A


def _relative_error(z, exact):
    return np.max(np.abs(z - exact)) / np.max(np.abs(exact))


@pytest.mark.parametrize("singular_scale", [None, 1e-4, 1e-9])
@pytest.mark.parametrize("seed", range(3))
def test_k_bordered_band_solve_equals_the_dense_solve(seed, singular_scale):
    """``[[K, C], [R^T, D]]`` with three borders, and the same with two of them auxiliary
    (``B = [[K + u v^T, c], [r^T, d]]``): both against numpy on the assembled matrix."""
    rng = np.random.default_rng(seed)
    n, k = 150, 3
    K = _banded(rng, n, 3, singular_scale)
    rows, cols = np.nonzero(K)
    C, R, D = rng.standard_normal((n, k)), rng.standard_normal((n, k)), rng.standard_normal((k, k))
    E = np.block([[K, C], [R.T, D]])
    factor = BandBordered.from_parts(sp.csr_matrix(E), rows, cols, K[rows, cols], C, R, D)
    assert factor is not None
    rhs = rng.standard_normal((n + k, 2))
    assert _relative_error(factor.solve(rhs), np.linalg.solve(E, rhs)) < 1e-10
    # one true border, the low-rank term u v^T carried by two auxiliary ones
    u, v, c, r = (rng.standard_normal(n) for _ in range(4))
    d = 0.3
    B = np.block([[K + np.outer(u, v), c[:, None]], [r[None, :], np.array([[d]])]])
    C = np.column_stack([c, u])
    R = np.column_stack([r, v])
    D = np.diag([d, -1.0])
    factor = BandBordered.from_parts(sp.csr_matrix(B), rows, cols, K[rows, cols], C, R, D)
    assert factor is not None
    rhs = rng.standard_normal(n + 1)
    z = factor.solve(rhs)
    assert factor._fallback is None  # refinement converged: no SuperLU
    assert _relative_error(z, np.linalg.solve(B, rhs)) < 1e-10


def test_k_bordered_solve_with_borders_of_very_different_scales_stays_on_the_band():
    """A scaled arclength border (1e8) next to O(1) auxiliary ones, K nearly singular:
    a single norm bound for the Schur complement rejected such regular cases."""
    rng = np.random.default_rng(5)
    n = 150
    K = _banded(rng, n, 3, 1e-9)
    rows, cols = np.nonzero(K)
    C = rng.standard_normal((n, 3)) * np.array([1e8, 1.0, 1e-3])
    R = rng.standard_normal((n, 3)) * np.array([1e8, 1e-3, 1.0])
    D = np.diag([1e8, -1.0, -1.0])
    E = np.block([[K, C], [R.T, D]])
    factor = BandBordered.from_parts(sp.csr_matrix(E), rows, cols, K[rows, cols], C, R, D)
    assert factor is not None
    rhs = rng.standard_normal(n + 3)
    z = factor.solve(rhs)
    assert factor._fallback is None
    assert _relative_error(z, np.linalg.solve(E, rhs)) < 1e-10


def _kkt_with_dense_rows(rng, n=240, m=8, r=2, singular_scale=None):
    """A banded Hessian (rank-one term included), ``m`` local constraints and ``r``
    dense rows; returns ``(H, J, dense K)``."""
    S = _banded(rng, n, 3, singular_scale) + 6.0 * np.eye(n) * (singular_scale is None)
    local = np.zeros((m, n))
    for i in range(m):
        start = int(rng.integers(0, n - 3))
        local[i, start:start + 3] = rng.standard_normal(3)
    dense = rng.standard_normal((r, n))
    U, w = rng.standard_normal((1, n)), np.array([0.4])
    H = HessianParts(sp.csr_matrix(S), U, w)
    J = sp.csr_matrix(np.vstack([local, dense]))
    Jd = J.toarray()
    K = np.block([[S + w[0] * np.outer(U[0], U[0]), Jd.T], [Jd, np.zeros((m + r, m + r))]])
    return H, J, K


@pytest.mark.parametrize("singular_scale", [None, 1e-7])
@pytest.mark.parametrize("seed", range(3))
def test_bordered_factor_with_dense_rows_keeps_the_band_and_equals_the_dense_solve(
        seed, singular_scale):
    rng = np.random.default_rng(10 + seed)
    H, J, K = _kkt_with_dense_rows(rng, singular_scale=singular_scale)
    assert pinned_rows.dense_rows(J).tolist() == [8, 9]
    size = K.shape[0]
    column, row = rng.standard_normal(size), rng.standard_normal(size + 1)
    B = np.block([[K, column[:, None]], [row[None, :]]])
    factor = BorderedFactor(H, J, column, row)
    assert isinstance(factor._lu, BandBordered)  # not SuperLU
    rhs = rng.standard_normal(size + 1)
    assert _relative_error(factor.solve(rhs), np.linalg.solve(B, rhs)) < 1e-10


@pytest.mark.parametrize("shift", [0.0, 2.5])
@pytest.mark.parametrize("seed", range(3))
def test_pinned_kkt_factor_has_the_inertia_and_determinant_sign_of_the_dense_matrix(
        seed, shift):
    """Haynsworth with the pinned rows (kkt module doc) against the dense eigenvalues;
    the shift puts many eigenvalues of H below zero."""
    rng = np.random.default_rng(20 + seed)
    H, J, K = _kkt_with_dense_rows(rng)
    n = H.sparse.shape[0]
    factor = kkt.KKTFactor(H, J, shift=shift, mass=np.ones(n))
    K = K - shift * np.diag(np.r_[np.ones(n), np.zeros(K.shape[0] - n)])
    values = np.linalg.eigvalsh(K)
    assert factor.negative_count == int(np.sum(values < 0))
    assert factor.determinant_sign == int(np.sign(np.prod(np.sign(values))))
    rhs = rng.standard_normal(K.shape[0])
    assert _relative_error(factor.solve(rhs), np.linalg.solve(K, rhs)) < 1e-10


def test_a_pin_that_misses_the_null_mode_falls_back_to_the_unpinned_factors():
    """``H`` singular along ``e_0`` and the dense row largest elsewhere: ``K_pin`` is
    singular, ``K`` is not; both factors fall back and stay exact."""
    rng = np.random.default_rng(3)
    n = 120
    diagonal = 1.0 + rng.random(n)
    diagonal[0] = 0.0
    diagonal[5:9] = -1.0
    dense = rng.uniform(0.5, 1.0, (1, n))
    dense[0, 0] = 0.1  # regularises K, but the pin goes to the largest entry
    H = HessianParts(sp.diags(diagonal, format="csr"), np.zeros((0, n)), np.zeros(0))
    J = sp.csr_matrix(dense)
    assert pinned_rows.PinnedRows.of(J).pins[0] != 0
    K = np.block([[np.diag(diagonal), dense.T], [dense, np.zeros((1, 1))]])
    values = np.linalg.eigvalsh(K)
    factor = kkt.KKTFactor(H, J)
    assert factor.negative_count == int(np.sum(values < 0))
    assert not factor._pinned
    assert factor.determinant_sign == int(np.sign(np.prod(np.sign(values))))
    column, row = rng.standard_normal(n + 1), rng.standard_normal(n + 2)
    B = np.block([[K, column[:, None]], [row[None, :]]])
    rhs = rng.standard_normal(n + 2)
    z = BorderedFactor(H, J, column, row).solve(rhs)
    assert _relative_error(z, np.linalg.solve(B, rhs)) < 1e-10


def test_dense_rows_follow_the_documented_rule():
    n = 400
    J = sp.lil_matrix((4, n))
    J[0, :12] = 1.0  # a contact constraint
    J[1, 7] = 1.0  # a node gauge
    J[2, :40] = 1.0  # max(32, 0.1 n) = 40 entries: not more than the limit
    J[3, ::2] = 1.0  # a mode over every other DOF
    assert pinned_rows.dense_rows(J.tocsr()).tolist() == [3]


@pytest.fixture
def rows_left_dense(monkeypatch):
    """The path before pinning: no row is dense enough."""
    def apply():
        monkeypatch.setattr(pinned_rows, "DENSE_ROW_MIN_ENTRIES", 10**9)
    return apply


@pytest.fixture
def every_row_pinned(monkeypatch):
    def apply():
        monkeypatch.setattr(pinned_rows, "DENSE_ROW_MIN_ENTRIES", 0)
        monkeypatch.setattr(pinned_rows, "DENSE_ROW_FRACTION", 0.0)
    return apply


def _assert_same_branch(a, b, atol):
    assert a.status == b.status and len(a) == len(b), (a.message, b.message)
    assert np.allclose(a.states, b.states, rtol=0, atol=atol)
    assert np.allclose(a.parameter_values, b.parameter_values, rtol=0, atol=atol)
    assert np.array_equal(a.unstable_count, b.unstable_count)
    assert [p.kind for p in a.special_points] == [p.kind for p in b.special_points]
    assert np.allclose([p.parameter for p in a.special_points],
                       [p.parameter for p in b.special_points], rtol=0, atol=atol)


def test_toy_branches_are_the_same_with_every_constraint_row_pinned(every_row_pinned):
    """The O(2) switch (a phase condition) and the sphere (a dense constraint row)."""
    def run():
        p = DiagonalQuartic(np.array([1.0, 1.0, 3.0, 4.0, 5.0, 6.0, 7.0]),
                            rotation_pairs=[(0, 1)])
        opts = ContinuationOptions(parameter_bounds=(0.0, 2.0), max_step=0.3,
                                   phase_conditions=True)
        b = continuation(p, np.zeros(7), parameter="lam", options=opts)
        (pt,) = b.points_of_kind("bifurcation")
        switched = switch_branch(p, b, pt, opts)
        sphere = LoadedSphere([3.0, 1.0, 1.5, 2.0, 2.5], 3.0)
        q0 = np.zeros(sphere.n_dofs)
        q0[0] = 1.0
        on_sphere = continuation(sphere, q0, parameter="lam", options=ContinuationOptions(
            parameter_bounds=(0.0, 3.0), max_step=0.3, direction=-1))
        return (b, p), (switched, p), (on_sphere, sphere)

    before = run()
    every_row_pinned()
    assert pinned_rows.dense_rows(sp.csr_matrix([[1.0, 0.0]])).size == 1
    for (old, _), (new, problem) in zip(before, run()):
        _assert_same_branch(old, new, 1e-10)
        assert_consistent(new, problem)


def test_ring_integral_gauge_branches_are_the_same_pinned_or_not(rows_left_dense):
    """The alpha branch and the start of its contact branch at N = 48 (integral gauge),
    with the phase row pinned (now) and left in the sparse matrix (before)."""
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    options = DiagramOptions(2 / 3, 40.0, n_nodes=48, modes=(2,), max_excess_link=2.0,
                             free_max_points=60, contact_max_points=12, gauge="integral")
    pinned = ring_diagram(options)
    rows_left_dense()
    dense = ring_diagram(options)
    assert [b.name for b in pinned.branches] == ["circle", "alpha", "alpha_contact"]
    for a, b in zip(dense.branches, pinned.branches):
        _assert_same_branch(a, b, 1e-9)


def test_rephase_anchors_the_integral_condition_at_the_previous_point():
    """``ContinuationOptions.rephase``: every point of the ring's branches (integral gauge)
    satisfies the phase condition of the point before it, ``<M g(q_{k-1}), q_k - q_{k-1}>
    = 0`` on the free DOFs; and the gauge does not change the physics: the writhe of the
    contact-free alpha branch as a function of the excess link is the node gauge's."""
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.problems.ring_branches import twisted_circle_problem
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
    from supercoil.solvers.problem import free_dofs
    from supercoil.stability.analysis import sliding_phase_modes

    options = DiagramOptions(2 / 3, 40.0, n_nodes=48, modes=(2,), max_excess_link=2.0,
                             free_max_points=60, contact_max_points=25, gauge="integral")
    diagram = ring_diagram(options)
    base, _ = twisted_circle_problem(options.twist_ratio, 0.0, options.n_nodes, "angle")
    contact = ContactProblem(base, ContactOptions(diameter=options.diameter))
    for name, problem in (("alpha", base), ("alpha_contact", contact)):
        branch = diagram.branch(name)
        checked = 0
        for k in range(2, len(branch)):
            # the rigid pins of the step from k - 1 to k (RingDiagram.pins)
            diagram.pin_branch(name, k - 1, True, problem)
            free = free_dofs(problem)
            mass = np.asarray(problem.mass, dtype=float)[free]
            q0, q1 = branch.states[k - 1], branch.states[k]
            at = problem.at(excess_link=float(branch.parameter_values[k - 1]))
            modes = sliding_phase_modes(at, q0)
            if modes.size == 0:
                continue
            g = modes[0, free] / np.linalg.norm(modes[0])
            step = (q1 - q0)[free]
            assert abs(g @ (mass * step)) <= 1e-8 * np.linalg.norm(step), (name, k)
            checked += 1
        assert checked >= 10, name
    node = ring_diagram(dataclasses.replace(options, gauge="node"))
    a, b = diagram.branch("alpha"), node.branch("alpha")
    # compare on the stretch where the excess link is monotone along both branches
    for branch in (a, b):
        assert np.all(np.diff(branch.parameter_values[:8]) < 0)
    lam = np.linspace(max(a.parameter_values[7], b.parameter_values[7]),
                      min(a.parameter_values[0], b.parameter_values[0]), 5)
    wa = np.interp(lam, a.parameter_values[:8][::-1], a.records["writhe"][:8][::-1])
    wb = np.interp(lam, b.parameter_values[:8][::-1], b.records["writhe"][:8][::-1])
    np.testing.assert_allclose(wa, wb, atol=1e-5)  # measured 3e-7 (interpolation included)


class _NearlySymmetric(DiagonalQuartic):
    """DiagonalQuartic whose rotation in the (x_0, x_1) plane is declared an approximate
    symmetry (as a closed rod's material sliding): ``goldstone_modes`` returns it."""

    def near_symmetry_modes(self, q):
        mode = np.zeros((1, self.n_dofs))
        mode[0, 0], mode[0, 1] = -q[1], q[0]
        return mode


def test_a_tangent_recomputed_in_a_new_gauge_is_oriented_without_the_slide():
    """``phase.orientation``: the old tangent minus its M-orthogonal projection on the
    approximate-symmetry modes. Oracle: a tangent whose slide part points against the old
    one but whose remaining part agrees with it (what a moved gauge produces: measured on
    the ring's alpha branch, where the plain product turned the branch back) is oriented
    along the old one; the row is M-orthogonal to the slide and leaves a slide-free
    tangent as it was."""
    from supercoil.continuation.phase import orientation
    from supercoil.continuation.system import ExtendedSystem

    problem = _NearlySymmetric(np.array([1.0, 1.0 + 1e-6, 3.0, 4.0]))
    q = np.array([0.6, 0.8, 0.0, 0.0])
    system = ExtendedSystem(problem, "lam", q)
    x = system.pack(q, np.zeros(0), 2.0)
    slide = np.concatenate([[-0.8, 0.6, 0.0, 0.0], [0.0]])  # the rotation at q
    body = np.array([0.0, 0.0, 0.3, 0.1, 0.05])  # dlambda > 0
    t_old = body + 5.0 * slide
    t_new = body - 5.0 * slide
    assert t_new @ (system.weights * t_old) < 0  # the plain product flips it
    row = orientation(system, x, t_old)
    assert t_new @ row > 0
    assert abs(row[:4] @ slide[:4]) < 1e-12
    np.testing.assert_allclose(orientation(system, x, body), system.weights * body, atol=1e-15)
