"""Stability with hard contact against the barrier's, on a small ring's β with contact.

The ring diagram's contact is the barrier (a smooth potential on gaps below 1 % of D,
integrated over the cubic B-spline); Coleman & Swigon's is a hard constraint. Each state here
is solved again at the same ΔLk with the ``exact`` treatment on the same spline
(active piece pairs held at ``g = d - D = 0``, multipliers minus the contact forces),
as ``benchmarks/bench_hard_contact_check.py`` does at their L/D = 122.

Oracles: the KKT residual, Lk = Tw + Wr and positive multipliers of the hard
equilibrium; its unstable count (``stability.analysis.analyse``) equals the number of
negative eigenvalues of a dense reduced Hessian written out here (the Hessian of the
Lagrangian on a null-space basis of the active Jacobian and of the M-weighted rigid
motions and sliding, no pins); the barrier's stored count equals the hard one on a
clearly stable and a clearly unstable state. And where they differ
(``benchmarks/results/beta_stability.md``): between the
contact onset and B₁ the barrier, whose spring is still soft there, keeps β's
unstable modes, while the hard contact with a positive force has none.
"""

import numpy as np
import pytest
from scipy.linalg import eigh, null_space

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import independent_pairs, solve_contact
from supercoil.contact.spline_distance import local_minimum_pairs
from supercoil.problems.ring_branches import ring_records, twisted_circle_problem
from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
from supercoil.problems.ring_diagram.records import kkt_residual
from supercoil.solvers.newton import NewtonOptions, lagrangian_hessian
from supercoil.stability.analysis import analyse

# β of a coarse ring (about 7 s): its contact branch from the onset through B₁ and P to ΔLk 6
OPTIONS = DiagramOptions(2 / 3, 40.0, n_nodes=48, modes=(3,), max_excess_link=6.0,
                         free_max_points=60, contact_max_points=120)


@pytest.fixture(scope="module")
def diagram():
    return ring_diagram(OPTIONS)


@pytest.fixture(scope="module")
def beta(diagram):
    return diagram.branch("beta_contact")


def dense_unstable_count(problem, q, multipliers, tolerance=1e-6):
    """Negative eigenvalues (below -tolerance) of ``Z^T H_L Z y = mu Z^T M Z y``, ``Z`` a
    null-space basis of the constraint Jacobian and of ``S^T M`` (S: rigid motions and
    the material sliding), on all DOFs."""
    n = problem.n_dofs
    H = lagrangian_hessian(problem, q, multipliers).restrict(np.arange(n)).dense()
    S = np.vstack([problem.symmetry_modes(q), problem.near_symmetry_modes(q)])
    mass = problem.mass
    Z = null_space(np.vstack([problem.constraint_jacobian(q).toarray(), S * mass]))
    values = eigh(Z.T @ H @ Z, Z.T @ (mass[:, None] * Z), eigvals_only=True)
    return int(np.sum(values < -tolerance))


def hard_contact(branch, i):
    """``(base, hard problem, result)``: point ``i`` of ``branch`` solved with hard contact,
    the active set starting at the barrier's contacts (local minima of the spline
    distance within the barrier's reach)."""
    q = branch.states[i]
    base, _ = twisted_circle_problem(OPTIONS.twist_ratio, float(branch.parameter_values[i]),
                                     OPTIONS.n_nodes)
    base.accept(q)
    base.repin(q)
    hard = ContactProblem(base, ContactOptions(OPTIONS.diameter, treatment="exact",
                                               curve="spline", formulation="pairs"))
    st = hard.pair_state(q, 1.01 * OPTIONS.diameter)
    minima = local_minimum_pairs(q.reshape(-1, 3), hard.curve.pieces, st.pairs, st.s, st.t)
    hard.active, _ = independent_pairs(hard, q, st.pairs[minima], -st.distance[minima])
    res = solve_contact(hard, q, NewtonOptions(mode="stationary", tolerance=1e-10,
                                               max_iterations=100))
    return base, hard, res


def assert_hard_equilibrium(branch, i, base, hard, res):
    assert res.converged and res.admissible, res.message
    forces = -res.multipliers[hard.n_equalities:]
    assert len(forces) >= 1 and forces.min() > 0  # strictly active: the cone is a subspace
    assert kkt_residual(hard, res.q, res.multipliers) < 1e-8
    assert res.max_penetration_over_diameter < 1e-8
    records = ring_records(base)(res.q, res.multipliers, float(branch.parameter_values[i]))
    assert records["link_error"] < 1e-9
    # the same state: the hard contacts close the barrier's gaps (< 1 % of D)
    assert np.max(np.abs(res.q - branch.states[i])) < 0.05 * OPTIONS.diameter


def test_hard_contact_count_is_the_dense_count_and_the_barriers(beta):
    """A clearly stable state (count 0 between B₁ and P) and a clearly unstable one (count
    2 past P, at ΔLk 6)."""
    stable = int(np.argmin(np.abs(beta.parameter_values - 3.0)))
    unstable = len(beta) - 1
    assert beta.unstable_count[stable] == 0 and beta.unstable_count[unstable] == 2
    for i in (stable, unstable):
        base, hard, res = hard_contact(beta, i)
        assert_hard_equilibrium(beta, i, base, hard, res)
        count = analyse(hard, res.q, res.multipliers).unstable_count
        assert count == dense_unstable_count(hard, res.q, res.multipliers)
        assert count == beta.unstable_count[i]


def test_between_the_contact_onset_and_b1_only_the_barrier_is_unstable(beta):
    """The barrier's points with contact forces before B₁ (count 3 or 2, the modes of β
    without contact) are stable with hard contact: the hard contact stiffens at once,
    the barrier's spring over 1 % of D only as its gap closes."""
    onset = beta.points_of_kind("contact_onset")[0].index
    b1 = beta.points_of_kind("bifurcation")[0].index
    window = [i for i in range(onset + 1, b1) if beta.unstable_count[i] >= 2]
    assert window
    for i in window[:: max(1, len(window) // 3)]:
        base, hard, res = hard_contact(beta, i)
        assert_hard_equilibrium(beta, i, base, hard, res)
        assert analyse(hard, res.q, res.multipliers).unstable_count == 0
        assert dense_unstable_count(hard, res.q, res.multipliers) == 0


def test_analyse_counts_every_barrier_state_as_the_continuation_and_the_dense_oracle(
        diagram, beta):
    """``analyse`` at every point of the barrier's β (the ring's rigid pins re-picked at the
    state) gives the continuation's stored count and the dense null-space count. It removed
    the material sliding by pinning a DOF, which counts on another subspace: with the
    contact giving the sliding a clear curvature, 14 of these 75 states were off by one
    (certified all the same); now an integral phase row removes it, as the eigenvalues'
    projection and the continuation's integral gauge do."""
    cp = diagram.contact_problem
    for i in range(len(beta)):
        q, mu = beta.states[i], beta.multipliers[i]
        cp.accept(q)
        cp.base.repin(q)
        at = cp.at(excess_link=float(beta.parameter_values[i]))
        report = analyse(at, q, mu)
        assert report.certified, (i, report.message)
        assert report.unstable_count == beta.unstable_count[i], i
        assert dense_unstable_count(at, q, mu) == beta.unstable_count[i], i
