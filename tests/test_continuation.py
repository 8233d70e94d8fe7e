"""Generic continuation on toy problems, each against a known answer.

Bratu's fold (independent Moore-Spence solve, observed order 2, Richardson
against the continuum value), pitchforks of a diagonal problem at known
parameter values (branch switching onto the known branches), a double
eigenvalue crossing under O(2) symmetry, a constrained point on a sphere
(multipliers), storing in a result file and the consistency checker.
"""

import dataclasses
import json
import time

import numpy as np
import pytest
from scipy.optimize import fsolve
from test_continuation_toys import (
    BRATU_FOLD,
    Bratu,
    CircleOfEquilibria,
    Corner,
    DiagonalQuartic,
    Helix,
    LoadedSphere,
    bratu_midpoint_exact,
)

from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    ContinuationStatus,
    UserEvent,
    consistency_check,
    continuation,
    switch_branch,
)
from supercoil.continuation.system import ExtendedSystem
from supercoil.io.store import load, save


def assert_consistent(branch, problem):
    report = consistency_check(branch, problem)
    assert report.ok, report.problems
    assert report.checked_points == len(branch)


def bratu_branch(n, lam0=3.0, low=None, **kw):
    """Bratu from the lower branch at lam0 round the fold back down to ``low`` (default lam0)."""
    p = Bratu(n, lam0, **kw.pop("problem_kw", {}))
    opts = ContinuationOptions(parameter_bounds=(lam0 if low is None else low, 4.0),
                               initial_step=0.05, max_step=0.5, **kw)
    return p, continuation(p, np.zeros(n + 1), parameter="lam", options=opts)


def moore_spence_fold(n):
    """Independent fold of the discrete Bratu problem: G = 0, G_u phi = 0, |phi| = 1."""
    p = Bratu(n)
    inner = np.arange(1, n)

    def equations(z):
        u = np.zeros(n + 1)
        u[inner] = z[:n - 1]
        phi, lam = z[n - 1:2 * n - 2], z[-1]
        p.lam = lam
        G = p.gradient(u)[inner]
        Gu = p.hessian(u).dense()[np.ix_(inner, inner)]
        return np.concatenate([G, Gu @ phi, [phi @ phi - 1.0]])

    x = np.linspace(0, 1, n + 1)[inner]
    guess = np.concatenate([4 * 1.2 * x * (1 - x), np.sin(np.pi * x) / np.sqrt(n / 2), [3.4]])
    z, _info, ok, msg = fsolve(equations, guess, full_output=True, xtol=1e-13)
    assert ok == 1, msg
    return z[-1]


def test_bratu_fold_is_located_converges_at_order_two_and_extrapolates_to_the_continuum():
    folds = {}
    for n in (16, 32, 64):
        p, b = bratu_branch(n)
        assert b.status is ContinuationStatus.PARAMETER_BOUND, b.message
        (fold,) = b.points_of_kind("fold")
        assert fold.located
        folds[n] = fold.parameter
        # the constrained Hessian is singular there: its eigenvalue nearest zero vanishes
        assert abs(fold.critical_eigenvalues[0]) < 1e-8
        assert_consistent(b, p)
    assert folds[16] == pytest.approx(moore_spence_fold(16), abs=1e-10)
    errors = np.array([BRATU_FOLD - folds[n] for n in (16, 32, 64)])
    order = np.log2(errors[:-1] / errors[1:])
    assert np.all((order > 1.95) & (order < 2.05)), order
    richardson = (4 * folds[64] - folds[32]) / 3
    assert abs(richardson - BRATU_FOLD) < 1e-6


def test_a_stop_condition_refuses_a_point_and_ends_the_run_before_it():
    """continuation(stop=...): the first corrected state the condition refuses is not
    accepted; the run ends at the point before with status STOPPED (an ok status) and the
    condition's message. Oracle: the same run without the condition, whose points up to
    the refused one are the same."""
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.05, max_step=0.5)
    free = continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts)
    first = int(np.argmax(free.states[:, 16] > 0.5))
    assert 2 <= first < len(free) - 1
    p = Bratu(32, 1.0)
    b = continuation(p, np.zeros(33), parameter="lam", options=opts,
                     stop=lambda q: "u(1/2) above 0.5" if q[16] > 0.5 else None)
    assert b.status is ContinuationStatus.STOPPED and b.status.ok
    assert b.message.endswith("u(1/2) above 0.5")
    assert len(b) == first
    np.testing.assert_array_equal(b.states, free.states[:first])
    assert np.all(b.states[:, 16] <= 0.5)
    assert np.array_equal(np.array(p.accepted[-len(b):]), b.states)


def test_an_admissibility_condition_shortens_the_steps_that_would_cross_it():
    """continuation(admissible=...): a corrected state it refuses is not accepted and the
    step is retried shorter (unlike ``stop``, the run goes on). Oracle: the same Bratu run
    without it (on the lower branch, u(1/2) grows with lam): every accepted state is
    admissible, the run ends at the minimum step within that step of the threshold, and
    the points before the first refused one are the unconditioned run's."""
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.05, max_step=0.5,
                               min_step=1e-6)
    free = continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts)
    first = int(np.argmax(free.states[:, 16] > 0.5))
    assert 2 <= first < len(free) - 1
    b = continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts,
                     admissible=lambda q: q[16] <= 0.5)
    assert np.all(b.states[:, 16] <= 0.5)
    assert len(b) > first
    np.testing.assert_array_equal(b.states[:first], free.states[:first])
    assert b.status is ContinuationStatus.STEP_TOO_SMALL
    assert "inadmissible" in b.message
    assert 0.5 - b.states[-1, 16] < 1e-5


class _NoPins:
    """segments.PinnedRod for a problem without symmetry pins (Bratu's fixed ends stay)."""

    def __init__(self, problem):
        self.fixed = self.gauge_dofs = problem.fixed
        self.repicked = 0

    def repin(self, q):
        self.repicked += 1

    def pin_quality(self, q):
        return 1.0


@pytest.mark.parametrize("refusing", ["once", "always"])
def test_follow_repicks_pins_where_their_grip_is_lost_and_fails_when_fresh_pins_refuse_too(
        refusing):
    """segments.follow(grip=...): a run refuses the first point where the grip fell below a
    quarter of its value at the run's start; the pins are picked again there and the
    branch goes on to its bound (the refused point is computed again, with the new
    pins). If fresh pins refuse the very next point too, the branch ends with a failed
    status (STEP_TOO_SMALL), not an ok one. Oracles: the bound reached and the pins'
    history (once); no point beyond the first run and the status (always)."""
    from supercoil.problems.segments import follow

    p = Bratu(32, 1.0)
    opts = ContinuationOptions(parameter_bounds=(1.0, 3.0), initial_step=0.05, max_step=0.2,
                               max_points=6)
    first = continuation(p, np.zeros(33), parameter="lam", options=opts)
    rod = _NoPins(p)
    refused = []

    def grip(q):
        # full grip at u(1/2) below 0.6 and at every run's start; lost once above it
        # ("once": only the first time a state above it is asked about)
        if q[16] <= 0.6 or (refusing == "once" and refused):
            return 1.0
        if not any(np.array_equal(q, r) for r in refused):
            refused.append(q.copy())
            return 0.1
        return 1.0 if refusing == "once" else 0.1

    branch, pins = follow(p, rod, first, dataclasses.replace(opts, max_points=200), "bratu",
                          None, max_points=200, segment_points=6, grip=grip)
    if refusing == "once":
        assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
        assert len(refused) == 1 and rod.repicked == 1 and len(pins) == 2
        # the pins were picked again at the last point before the refused one
        assert branch.states[pins[1][0], 16] <= 0.6 < refused[0][16]
    else:
        assert branch.status is ContinuationStatus.STEP_TOO_SMALL
        assert "refused" in branch.message
        assert np.all(branch.states[:, 16] <= 0.6)


def test_follow_lands_within_a_restart_stops_band_with_shorter_first_steps():
    """segments.follow(restart=...): a stop with hysteresis, made for each run from its
    first state, refuses states past its band on the far side (as the tweezers' sliding
    stop does). A step that crosses the whole band is refused by the run that starts on
    either side of it; the run is started again with shorter first steps until one lands
    within the band, and the branch goes on to its bound. Oracles: the bound reached, a
    point within the band, every run's states on one side of it."""
    from supercoil.problems.segments import follow

    low, high = 0.5, 0.52  # u(1/2): the band, narrower than a step
    p = Bratu(32, 1.0)
    opts = ContinuationOptions(parameter_bounds=(1.0, 3.0), initial_step=0.05, max_step=0.5,
                               max_points=200)

    def restart(q0):
        above = q0[16] >= low

        def refuse(q):
            if not above and q[16] >= high:
                return "crossed the band upwards"
            if above and q[16] < low:
                return "crossed the band downwards"
            return None

        return refuse

    first = continuation(p, np.zeros(33), parameter="lam", options=opts,
                         stop=restart(np.zeros(33)))
    assert first.status is ContinuationStatus.STOPPED  # one step crossed the band
    branch, _ = follow(p, _NoPins(p), first, opts, "bratu", None, max_points=200,
                       segment_points=200, restart=restart)
    assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
    u = branch.states[:, 16]
    assert np.any((u >= low) & (u < high))
    assert u[-1] > high


def test_bratu_through_the_fold_comes_back_down_the_upper_branch():
    user = UserEvent("threshold", lambda q, mu, lam: {"u_mid_minus_1": q[16] - 1.0})
    p = Bratu(32, 1.0)
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.05, max_step=0.5)
    b = continuation(p, np.zeros(33), parameter="lam", options=opts, events=[user],
                     records=lambda q, mu, lam: {"u_mid": q[16], "energy": p.energy(q)})
    assert b.status is ContinuationStatus.PARAMETER_BOUND, b.message
    assert b.parameter_values[0] == 1.0 and b.parameter_values[-1] == 1.0  # landed exactly
    (fold,) = b.points_of_kind("fold")
    lam, u_mid = b.parameter_values, b.records["u_mid"]
    i = fold.index
    assert np.all(np.diff(lam[:i + 1]) > 0) and np.all(np.diff(lam[i + 1:]) < 0)
    assert np.all(np.diff(u_mid) > 0)  # |u| grows all along, through the fold
    # the lower branch is stable, the upper one has one unstable mode; the
    # determinant sign (Chamekh, Mani-Aouadi & Moakher 2014) changes with the count
    # (one eigenvalue crosses)
    assert np.all(b.unstable_count[:i + 1] == 0) and np.all(b.unstable_count[i + 1:] == 1)
    assert np.all(b.determinant_sign == (-1) ** b.unstable_count)
    assert not b.points_of_kind("bifurcation")  # the count change is the fold's
    # both ends against the continuum solution (second order in h)
    h2 = (1 / 32) ** 2
    assert abs(u_mid[0] - bratu_midpoint_exact(1.0, upper=False)) < 2 * h2
    assert abs(u_mid[-1] - bratu_midpoint_exact(1.0, upper=True)) < 30 * h2
    # user event: u(1/2) = 1 on the lower branch, located by re-corrected bisection
    (threshold,) = b.points_of_kind("threshold")
    assert threshold.label == "u_mid_minus_1"
    assert abs(threshold.q[16] - 1.0) < 1e-9
    assert abs(threshold.records["u_mid"] - 1.0) < 1e-9
    assert threshold.index < fold.index
    # every accepted state is a branch point (rejected trials never accepted)
    accepted = np.array(p.accepted[-len(b):])
    assert np.array_equal(accepted, b.states)
    assert_consistent(b, p)


def test_bordered_solve_with_rank_one_hessian_terms_equals_the_assembled_one():
    folds = []
    for rank_one in (True, False):
        _, b = bratu_branch(24, lam0=2.0, problem_kw={"nonlocal_": -2.0, "rank_one": rank_one})
        (fold,) = b.points_of_kind("fold")
        folds.append((fold.parameter, b.parameter_values))
    assert folds[0][0] == pytest.approx(folds[1][0], abs=1e-11)
    assert np.allclose(folds[0][1], folds[1][1], atol=1e-11)
    assert folds[0][0] < BRATU_FOLD - 0.1  # the nonlocal softening term moves the fold


@pytest.mark.parametrize("singular_scale", [1.0, 1e-10, 0.0])
def test_band_bordered_solve_is_accurate_when_the_kkt_matrix_is_nearly_singular(singular_scale):
    """Band LU + block elimination + refinement against B == dense solve of B.

    K is banded and symmetric with its eigenvalue nearest zero moved to
    about ``singular_scale`` (near a fold K is nearly singular while B is
    regular); the solve must keep B's accuracy, not K's (when the band LU
    finds an exactly zero pivot, ``factor`` returns None and BorderedFactor
    uses SuperLU on B instead).
    """
    import scipy.sparse as sp

    from supercoil.continuation import band_bordered

    rng = np.random.default_rng(7)
    n, band = 120, 3
    A = np.zeros((n, n))
    for k in range(band + 1):
        d = rng.standard_normal(n - k)
        A += np.diag(d, k) + (np.diag(d, -k) if k else 0)
    values, vectors = np.linalg.eigh(A)
    # move the eigenvalue nearest zero to singular_scale, then cut back to the band
    i = int(np.argmin(np.abs(values)))
    A = A + (singular_scale - values[i]) * np.outer(vectors[:, i], vectors[:, i])
    A[np.abs(np.subtract.outer(np.arange(n), np.arange(n))) > band] = 0.0
    c, r = rng.standard_normal(n), rng.standard_normal(n + 1)
    B = np.block([[A, c[:, None]], [r[None, :]]])
    rhs = rng.standard_normal(n + 1)
    factor = band_bordered.BandBordered.factor(sp.csc_matrix(B))
    exact = np.linalg.solve(B, rhs)
    assert factor is not None or singular_scale == 0.0
    if factor is not None:
        z = factor.solve(rhs)
        assert np.max(np.abs(B @ z - rhs)) < 1e-12 * np.max(np.abs(B)) * np.max(np.abs(z))
        assert np.allclose(z, exact, rtol=1e-8, atol=1e-10 * np.max(np.abs(exact)))


@pytest.mark.parametrize("seed", range(4))
def test_permuted_bordered_matrix_equals_bmat_and_fancy_indexing(seed):
    """The bordered matrix assembled on entry arrays (fast path) against scipy's bmat
    and fancy indexing (the previous code): the same stored entries (explicit zeros
    of H and J kept, zeros of the dense border dropped), bit for bit."""
    import scipy.sparse as sp
    from conftest import split_into_halves

    from supercoil.continuation.bordered_matrix import permuted_bordered
    from supercoil.solvers.ordering import kkt_order

    rng = np.random.default_rng(seed)
    n, m = 50, 12
    H = sp.random(n, n, density=0.1, random_state=seed, format="csr")
    H = (H + H.T + sp.identity(n)).tocsr()
    H.data[::7] = 0.0  # explicit zeros stay stored
    J = sp.random(m, n, density=0.08, random_state=seed + 1, format="csr")
    J.data[::5] = 0.0
    column = rng.standard_normal(n + m)
    column[::3] = 0.0
    row = rng.standard_normal(n + m)
    row[1::4] = -0.0
    corner = 0.0 if seed % 2 else 1.5
    if seed == 3:  # every entry stored as two halves (not canonical): bmat sums them
        H = split_into_halves(H)
    order = np.concatenate([kkt_order(H, J), [n + m]])
    B = sp.bmat([[sp.bmat([[H, J.T], [J, None]]), sp.csr_matrix(column[:, None])],
                 [sp.csr_matrix(row[None, :]), sp.csr_matrix([[corner]])]], format="csc")
    reference = B[order][:, order].tocsr()
    reference.sort_indices()
    K = reference[:n + m, :n + m].tocoo()
    for _ in range(2):  # the second call takes the remembered layout
        mine, (k_rows, k_cols, k_values) = permuted_bordered(H, J, column, row, corner, order)
        for attribute in ("indptr", "indices", "data"):
            assert np.array_equal(getattr(mine, attribute), getattr(reference, attribute))
        assert sorted(zip(K.row, K.col, K.data)) == sorted(zip(k_rows, k_cols, k_values))


def test_secant_predictor_finds_the_same_fold():
    _, tangent = bratu_branch(16)
    _, secant = bratu_branch(16, predictor="secant")
    assert secant.points_of_kind("fold")[0].parameter == pytest.approx(
        tangent.points_of_kind("fold")[0].parameter, abs=1e-11)


def test_pitchforks_of_the_diagonal_problem_are_located_and_switching_lands_on_the_known_branches():
    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0, 8.0, 9.0])
    p = DiagonalQuartic(d)
    opts = ContinuationOptions(parameter_bounds=(0.0, 4.0), max_step=0.3)
    b = continuation(p, np.zeros(8), parameter="lam", options=opts)
    assert b.ok, b.message
    assert_consistent(b, p)
    bifurcations = b.points_of_kind("bifurcation")
    assert [pt.located for pt in bifurcations] == [True] * 3
    assert np.allclose([pt.parameter for pt in bifurcations], d[:3], atol=1e-9, rtol=0)
    assert [(pt.count_before, pt.count_after) for pt in bifurcations] == [(0, 1), (1, 2), (2, 3)]
    for i, pt in enumerate(bifurcations):
        assert abs(pt.critical_eigenvalues[0]) < 1e-8
        assert abs(abs(pt.critical_modes[0, i]) - 1.0) < 1e-8  # the mode is +-e_i
    assert np.array_equal(b.determinant_sign, (-1) ** b.unstable_count)
    for i, pt in enumerate(bifurcations[:2]):
        for side in (1, -1):
            new = switch_branch(p, b, pt, opts, side=side)
            assert new.status is ContinuationStatus.PARAMETER_BOUND, new.message
            assert new.parent == b.name and new.origin is pt
            x, lam = new.states, new.parameter_values
            assert np.allclose(np.sum(x**2, axis=1), lam - d[i], atol=1e-9, rtol=0)
            assert np.all(np.sign(x[:, i]) == side)
            assert np.max(np.abs(np.delete(x, i, axis=1))) < 1e-12
            # the branch from d_i has the i lower modes x_j (j < i) unstable
            assert np.all(new.unstable_count == i)
            assert_consistent(new, p)


def test_a_double_eigenvalue_crossing_under_o2_symmetry_is_seen_by_the_count_not_the_determinant():
    d = np.array([1.0, 1.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    p = DiagonalQuartic(d, rotation_pairs=[(0, 1)])
    opts = ContinuationOptions(parameter_bounds=(0.0, 2.0), max_step=0.3, phase_conditions=True)
    b = continuation(p, np.zeros(7), parameter="lam", options=opts)
    assert b.ok, b.message
    (pt,) = b.points_of_kind("bifurcation")
    assert pt.parameter == pytest.approx(1.0, abs=1e-9)
    assert (pt.count_before, pt.count_after) == (0, 2)
    assert np.all(b.determinant_sign == 1)  # the determinant's sign sees nothing
    assert set(np.unique(b.unstable_count)) == {0, 2}
    # the two critical modes span the (x_0, x_1) plane
    modes = pt.critical_modes
    assert modes.shape == (2, 7)
    assert np.allclose(modes[:, :2] @ modes[:, :2].T, np.eye(2), atol=1e-10)
    assert np.max(np.abs(modes[:, 2:])) < 1e-10
    assert_consistent(b, p)
    # switch along one null vector; the phase condition removes the orbit's null mode
    new = switch_branch(p, b, pt, opts)
    assert new.ok, new.message
    assert new.phase_modes.shape == (1, 7)
    x, lam = new.states, new.parameter_values
    assert np.allclose(np.sum(x**2, axis=1), lam - 1.0, atol=1e-9, rtol=0)
    assert np.allclose(x[:, :2] @ (modes[0, :2]), np.linalg.norm(x[:, :2], axis=1), atol=1e-9)
    assert np.all(new.unstable_count == 0) and np.all(new.zero_modes == 0)
    assert_consistent(new, p)


def test_a_constrained_point_on_a_sphere_exercises_multipliers_and_fixed_dofs():
    d = [3.0, 1.0, 1.5, 2.0, 2.5]
    p = LoadedSphere(d, 3.0)
    q0 = np.zeros(p.n_dofs)
    q0[0] = 1.0
    opts = ContinuationOptions(parameter_bounds=(0.0, 3.0), max_step=0.3, direction=-1)
    b = continuation(p, q0, parameter="lam", options=opts)
    assert b.status is ContinuationStatus.PARAMETER_BOUND, b.message
    assert b.parameter_values[-1] == 0.0
    # the pole: mu = -x . grad E = lambda - d_0
    assert np.allclose(b.multipliers[:, 0], b.parameter_values - d[0], atol=1e-10)
    bifurcations = b.points_of_kind("bifurcation")
    assert np.allclose([pt.parameter for pt in bifurcations], [2.0, 1.5, 1.0, 0.5], atol=1e-9)
    assert list(b.unstable_count[[0, -1]]) == [0, 4]
    assert_consistent(b, p)
    new = switch_branch(p, b, bifurcations[0], opts)
    assert new.status is ContinuationStatus.PARAMETER_BOUND, new.message
    x, lam = new.states, new.parameter_values
    # x_0 = lambda / (d_0 - d_1), x_1^2 = 1 - x_0^2, mu = -1, stable
    assert np.allclose(x[:, 0], lam / 2.0, atol=1e-10)
    assert np.allclose(x[:, 1] ** 2, 1 - x[:, 0] ** 2, atol=1e-10)
    assert np.all(x[:, -1] == 0.0)  # the fixed DOF stays
    assert np.allclose(new.multipliers[:, 0], -1.0, atol=1e-10)
    assert np.all(new.unstable_count == 0)
    assert_consistent(new, p)
    # without parameter_derivative: central difference, O(step^2) accurate
    system = ExtendedSystem(p, "lam", x[3])
    xx = system.pack(x[3], new.multipliers[3], lam[3])
    exact = np.zeros(system.n + 1)
    exact[0] = -1.0
    assert np.allclose(system.parameter_derivative(xx), exact, atol=1e-9)


def test_the_corrector_respects_the_problems_step_bound():
    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0, 8.0, 9.0])
    p = DiagonalQuartic(d)
    opts = ContinuationOptions(parameter_bounds=(0.0, 3.0), max_step=0.3)
    b = continuation(p, np.zeros(8), parameter="lam", options=opts)
    p.max_move = 0.01
    new = switch_branch(p, b, b.points_of_kind("bifurcation")[0], opts)
    assert new.ok and p.step_bound_calls > 0
    assert np.allclose(np.sum(new.states**2, axis=1), new.parameter_values - 1.0, atol=1e-9)


def test_branch_runs_merged_once_then_extended_equal_the_merge_of_all_runs(tmp_path):
    """The tweezers' follow() reports merge(merge(runs so far), partial run) (fast path)
    instead of merge(runs so far + partial run): the same branch, bit for bit; and a
    result file stores the merged branch bit for bit."""
    from supercoil.problems.segments import merge_branches

    p = Bratu(16, 3.0)
    user = UserEvent("threshold", lambda q, mu, lam: {"u_mid_minus_1": q[8] - 1.0})
    opts = ContinuationOptions(parameter_bounds=(0.0, 4.0), max_step=0.3, max_points=6)
    runs = [continuation(p, np.zeros(17), parameter="lam", events=[user], options=opts,
                         records=lambda q, mu, lam: {"u_mid": q[8]})]
    for _ in range(3):
        last = runs[-1]
        p.lam = float(last.parameter_values[-1])
        runs.append(continuation(p, last.states[-1], last.multipliers[-1], parameter="lam",
                                 events=[user], options=opts,
                                 records=lambda q, mu, lam: {"u_mid": q[8]}))
    assert sum(len(b.special_points) for b in runs) >= 2
    for k in range(1, len(runs)):
        reference = merge_branches(runs[:k + 1], "merged")
        fast = merge_branches([merge_branches(runs[:k], "merged"), runs[k]], "merged")
        for f in dataclasses.fields(Branch):
            a, c = getattr(reference, f.name), getattr(fast, f.name)
            if isinstance(a, np.ndarray):
                assert np.array_equal(a, c), f.name
            elif f.name == "records":
                assert all(np.array_equal(a[r], c[r]) for r in a)
            elif f.name == "special_points":
                assert [(s.index, s.arclength, s.branch, s.parameter) for s in a] == \
                    [(s.index, s.arclength, s.branch, s.parameter) for s in c]
            else:
                assert a == c, f.name
    merged = merge_branches(runs, "merged")
    save(tmp_path / "merged.h5", [merged])
    stored = load(tmp_path / "merged.h5").branch("merged")
    assert np.array_equal(stored.states, merged.states)
    assert stored.summary() == merged.summary()


def test_save_load_round_trip_and_the_checker_catches_corruption(tmp_path):
    p = Bratu(16, 3.0)
    user = UserEvent("threshold", lambda q, mu, lam: {"u_mid_minus_1": q[8] - 1.0})
    b = continuation(p, np.zeros(17), parameter="lam", events=[user],
                     options=ContinuationOptions(parameter_bounds=(3.0, 4.0), max_step=0.5),
                     records=lambda q, mu, lam: {"u_mid": q[8], "profile": q[::4]})
    assert len(b.special_points) == 2
    save(tmp_path / "bratu.h5", [b])
    loaded = load(tmp_path / "bratu.h5").branch(b.name)
    for f in dataclasses.fields(Branch):
        if f.name in ("special_points", "origin", "records", "status"):
            continue
        a, c = getattr(b, f.name), getattr(loaded, f.name)
        assert np.array_equal(a, c) if isinstance(a, np.ndarray) else a == c, f.name
    assert loaded.status is b.status
    assert loaded.records.keys() == b.records.keys()
    assert all(np.array_equal(loaded.records[k], b.records[k]) for k in b.records)
    for s, t in zip(b.special_points, loaded.special_points, strict=True):
        for f in dataclasses.fields(s):
            u, v = getattr(s, f.name), getattr(t, f.name)
            if isinstance(u, np.ndarray):
                assert np.array_equal(u, v), f.name
            elif isinstance(u, dict):
                assert all(np.array_equal(u[k], v[k]) for k in u)
            else:
                assert u == v, f.name
    assert json.loads(json.dumps(loaded.summary())) == b.summary()
    with pytest.raises(ValueError):
        b.states[0, 0] = 1.0  # immutable
    assert_consistent(loaded, p)
    # a corrupted stored count and a misplaced special point are caught
    count = b.unstable_count.copy()
    count[2] += 1
    report = consistency_check(dataclasses.replace(b, unstable_count=count), p)
    assert not report.ok and any("point 2: stored unstable_count" in m for m in report.problems)
    fold = b.points_of_kind("fold")[0]
    moved = dataclasses.replace(fold, index=fold.index - 1)
    report = consistency_check(dataclasses.replace(b, special_points=(moved,)), p)
    assert not report.ok and any("not between its neighbours" in m for m in report.problems)


def test_failures_are_returned_as_a_status():
    p, first = bratu_branch(16)
    p.lam = 3.0
    tight = ContinuationOptions(initial_step=0.5, min_step=0.5, max_step=0.5,
                                max_corrector_iterations=1)
    b = continuation(p, first.states[0], parameter="lam", options=tight)
    assert b.status is ContinuationStatus.STEP_TOO_SMALL and not b.ok
    assert len(b) == 1 and "minimum step" in b.message
    bad = continuation(Bratu(16, 3.0), np.full(17, 50.0), parameter="lam")
    assert bad.status is ContinuationStatus.START_FAILED and len(bad) == 0
    with pytest.raises(ValueError):
        continuation(Bratu(16, 5.0), np.zeros(17), parameter="lam",
                     options=ContinuationOptions(parameter_bounds=(0.0, 4.0)))
    with pytest.raises(ValueError):
        continuation(Bratu(16, 1.0), np.zeros(17), parameter="not_there")


@pytest.mark.parametrize("bad", [{"initial_step": 0.0}, {"min_step": 1.0}, {"shrink": 1.0},
                                 {"growth": 0.5}, {"parameter_bounds": (1.0, 0.0)},
                                 {"max_points": 1}, {"direction": 0}, {"predictor": "euler"},
                                 {"max_turn_degrees": 180.0}, {"max_corrector_distance": 0.0},
                                 {"max_corrector_distance": -1.0},
                                 {"max_corrector_distance": float("nan")}])
def test_options_validate(bad):
    with pytest.raises(ValueError):
        ContinuationOptions(**bad)


def test_branch_cost_stays_small():
    start = time.perf_counter()
    _, b = bratu_branch(64)
    elapsed = time.perf_counter() - start
    assert b.ok and elapsed < 5.0, elapsed


def test_critical_modes_are_brought_back_to_the_gauge_pins_before_switching():
    from supercoil.continuation.switching import pinned_mode

    p = DiagonalQuartic(np.ones(4), rotation_pairs=[(0, 1)])
    p.gauge_dofs = np.array([1])
    q = np.array([2.0, 0.0, 0.0, 0.0])
    mode = np.array([0.3, 0.5, -0.2, 0.1])
    pinned = pinned_mode(p, q, mode)
    # mode minus the rotation generator (0, 2, 0, 0) scaled to zero the pinned DOF
    assert np.allclose(pinned, [0.3, 0.0, -0.2, 0.1], atol=1e-15)


class _Arctan:
    """``E = x atan(x) - log(1 + x^2) / 2 - lambda x`` in each of two coordinates.

    The equilibrium is ``x = tan(lambda)``; plain Newton on ``atan(x) = lambda``
    diverges from ``|x - tan(lambda)| > 1.39`` (it overshoots ever further), the
    textbook case for a damped Newton step.
    """

    n_constraints = 0

    def __init__(self, lam: float = 0.0):
        self.n_dofs = 2
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.ones(2)
        self.lam = lam

    def energy(self, q):
        return float(np.sum(q * np.arctan(q) - 0.5 * np.log1p(q**2) - self.lam * q))

    def gradient(self, q):
        return np.arctan(q) - self.lam

    def hessian(self, q):
        import scipy.sparse as sp

        from supercoil.solvers.problem import HessianParts

        return HessianParts(sp.diags(1.0 / (1.0 + q**2)).tocsr(), np.zeros((0, 2)), np.zeros(0))

    def parameter_derivative(self, q, multipliers, name):
        return -np.ones(2)

    def constraints(self, q):
        return np.zeros(0)

    def constraint_jacobian(self, q):
        import scipy.sparse as sp

        return sp.csr_matrix((0, 2))

    def constraint_hessian(self, q, multipliers):
        import scipy.sparse as sp

        return sp.csr_matrix((2, 2))

    def accept(self, q):
        pass


def test_the_corrector_damps_steps_that_would_overshoot():
    """From x = 3 at lambda = 0 (root x = 0) a full Newton step lands at -19 and
    diverges; the damped corrector converges to the exact root (at fixed lambda)."""
    from supercoil.continuation.corrector import correct

    problem = _Arctan(0.0)
    system = ExtendedSystem(problem, "lam", np.zeros(2))
    x0 = system.pack(np.array([3.0, -3.0]), np.zeros(0), 0.0)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    result = correct(system, x0, e_lam, x0, 0.0, 1e-12, 40)
    assert result.ok, result.message
    assert np.allclose(result.x[:2], 0.0, atol=1e-12) and result.x[-1] == 0.0


@pytest.mark.parametrize("max_step", [0.05, 0.3])
def test_a_closed_branch_stops_after_one_lap_with_both_folds_located(max_step):
    # Oracle: the equilibria are the circle x0^2 + lambda^2 = 1 (folds at lambda = +-1,
    # where the count changes by one); the run must stop once round, not at max_points.
    p = CircleOfEquilibria(lam=0.0)
    opts = ContinuationOptions(initial_step=0.05, max_step=max_step, max_points=2000)
    branch = continuation(p, np.array([1.0, 0.0, 0.0]), parameter="lam", options=opts)
    assert branch.status is ContinuationStatus.CLOSED_LOOP, branch.message
    assert branch.ok
    lap = branch.arclength[-1]
    assert 2 * np.pi - 2 * max_step <= lap <= 2 * np.pi + 2 * max_step
    assert len(branch) < 1000
    q0, lam = branch.states[:, 0], branch.parameter_values
    assert np.max(np.abs(q0**2 + lam**2 - 1)) < 1e-9
    folds = sorted(sp.parameter for sp in branch.special_points if sp.kind == "fold")
    assert len(folds) == 2
    assert folds == pytest.approx([-1.0, 1.0], abs=1e-8)
    assert not [sp for sp in branch.special_points if sp.kind == "bifurcation"]
    np.testing.assert_array_equal(branch.unstable_count, (q0 < 0).astype(int))


def test_a_resumed_branch_numbers_the_points_of_its_messages_on_the_whole_branch():
    """Oracle: the circle of equilibria x0^2 + lambda^2 = 1, interrupted after 40 points
    and resumed; the message's point count is the whole branch's, and the point it
    names lies on the branch at the parameter value the message gives."""
    import re

    from supercoil.continuation.resume import resume_branch

    opts = ContinuationOptions(initial_step=0.05, max_step=0.05, max_points=40)
    partial = continuation(CircleOfEquilibria(lam=0.0), np.array([1.0, 0.0, 0.0]),
                           parameter="lam", options=opts)
    assert partial.status is ContinuationStatus.MAX_POINTS
    assert partial.message == "40 points computed (max_points)"
    whole = resume_branch(CircleOfEquilibria(lam=0.0), partial,
                          dataclasses.replace(opts, max_points=2000))
    assert whole.status is ContinuationStatus.CLOSED_LOOP, whole.message
    found = re.search(r"after (\d+) points it came back to point (\d+) \(lam = (\S+);",
                      whole.message)
    assert found, whole.message
    count, j, lam = int(found[1]), int(found[2]), float(found[3])
    assert count == len(whole)
    assert 0 <= j < len(whole) - 1
    assert whole.parameter_values[j] == pytest.approx(lam, abs=1e-5)


def test_an_open_branch_is_not_taken_for_a_closed_one():
    # Bratu round its fold and back down passes near no earlier point with the same tangent.
    _p, branch = bratu_branch(40, lam0=1.0, low=0.5)
    assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
    # A helix of small pitch (2 pi eps = 0.025 in lambda) passes within a tenth of a step
    # of its earlier points with the same tangent every turn; it must reach its bound.
    p = Helix(eps=0.004)
    opts = ContinuationOptions(initial_step=0.05, max_step=0.3, max_points=4000,
                               parameter_bounds=(0.0, 0.3))
    branch = continuation(p, np.array([1.0, 0.0]), parameter="lam", options=opts)
    assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
    assert branch.parameter_values[-1] == 0.3


class _NoisyQuartic(DiagonalQuartic):
    """The diagonal problem with a gradient noise of 1e-9 (a deterministic function of q),
    a stand-in for round-off above the corrector's estimate of its floor."""

    def gradient(self, q):
        seed = int.from_bytes(np.asarray(q, dtype=float).tobytes()[-8:], "little")
        noise = np.random.default_rng(seed).uniform(-1e-9, 1e-9, size=q.size)
        return super().gradient(q) + noise


@pytest.mark.parametrize("tolerance, converges", [(1e-11, True), (1e-13, False)])
def test_the_corrector_accepts_a_residual_at_round_off_only_near_the_tolerance(
        tolerance, converges):
    # Oracle: the solution is q = 0 (d_i > lambda); the noise keeps max|F| near 1e-9, so
    # Newton stalls there with steps of 1e-9 / 1e4, negligible: accepted when the noise
    # is within 1e3 tolerances, a failure otherwise.
    from supercoil.continuation.corrector import correct

    p = _NoisyQuartic([1e4, 2e4, 3e4], lam=0.0)
    system = ExtendedSystem(p, "lam", np.zeros(3))
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    x0 = system.pack(np.array([1e-3, -2e-3, 5e-4]), np.zeros(0), 0.0)
    result = correct(system, x0, e_lam, x0, 0.0, tolerance, 30)
    assert result.ok is converges, result.message
    if converges:
        assert np.max(np.abs(system.q(result.x))) < 1e-12
        assert "round-off" in result.message or result.residual <= tolerance


class _StubSegment:
    """A segment whose count steps from 2 to 1 at ``u = 0.37`` and whose trial
    corrections fail at the listed parameters (as the corrector can at a contact
    onset); the nearest eigenvalue does not change sign (a contact-type change)."""

    def __init__(self, failing):
        self.failing = set(failing)
        self.d = np.ones(3)
        self.length = 1.0
        self.x_b = np.ones(3)

    def point(self, u):
        from supercoil.continuation.zeroin import LocationFailed
        if float(u) in self.failing:
            raise LocationFailed(f"trial correction at u = {u} failed")
        return np.full(3, float(u))

    def count(self, u):
        self.point(u)
        return 2 if u < 0.37 else 1

    def factor_count(self, u):
        return self.count(u)  # nothing left out: an eigenvalue crosses

    def nearest_eigenvalue(self, u):
        return -300.0

    def tangent(self, u):
        return self.d


def test_count_change_is_located_past_a_failed_trial_point():
    from supercoil.continuation.events import locate_count_change

    clean = locate_count_change(_StubSegment(()), 1e-9, 1e-3)
    assert clean.located and abs(clean.u - 0.37) < 1e-8
    # the first bisection points (0.5, then 0.25) fail: 0.3 / 0.7 of the bracket are tried
    hurdles = locate_count_change(_StubSegment((0.5, 0.25)), 1e-9, 1e-3)
    assert hurdles.located and abs(hurdles.u - 0.37) < 1e-8
    assert (hurdles.count_before, hurdles.count_after) == (2, 1)
    # the reported point is one that was corrected (the first with the new count)
    assert hurdles.u >= 0.37
    # every trial of a bracket failing is still reported as not located
    hopeless = locate_count_change(_StubSegment((0.5, 0.3, 0.7)), 1e-9, 1e-3)
    assert not hopeless.located


def test_two_count_changes_in_one_segment_are_each_located():
    """Pitchforks at lambda = 1.0 and 1.1 fall between two points of the trivial branch
    (steps of 0.3): both are located (to the event tolerance), one after the other."""
    d = np.array([1.0, 1.1, 3.0, 4.0, 5.0])
    p = DiagonalQuartic(d)
    b = continuation(p, np.zeros(5), parameter="lam",
                     options=ContinuationOptions(parameter_bounds=(0.0, 2.0), max_step=0.3))
    lam = b.parameter_values
    assert not np.any((lam > 1.0) & (lam < 1.1))  # one segment holds both changes
    points = b.points_of_kind("bifurcation")
    assert [(pt.count_before, pt.count_after) for pt in points] == [(0, 1), (1, 2)]
    assert np.allclose([pt.parameter for pt in points], d[:2], atol=1e-9, rtol=0)
    for i, pt in enumerate(points):
        assert abs(abs(pt.critical_modes[0, i]) - 1.0) < 1e-8
    assert_consistent(b, p)


def test_a_nearly_double_eigenvalue_crossing_is_one_event_at_a_branch_point():
    """d_0 = 1 and d_1 = 1.0005 (a double eigenvalue split by 5e-4, as an E mode of a D_m
    ring by the mesh): the count changes by 2 within one segment and the two eigenvalues
    cross as a cluster, so one event is reported at an accepted point of the branch with
    two critical modes (e_0, e_1), and its tolerance covers the distance to the crossing
    of the pair's mean eigenvalue, lambda = 1.00025 (exact: the branch is x = 0)."""
    d = np.array([1.0, 1.0005, 3.0, 4.0, 5.0])
    p = DiagonalQuartic(d)
    b = continuation(p, np.zeros(5), parameter="lam",
                     options=ContinuationOptions(parameter_bounds=(0.0, 2.0), max_step=0.3))
    (pt,) = b.points_of_kind("bifurcation")
    assert (pt.count_before, pt.count_after) == (0, 2)
    assert pt.parameter in set(b.parameter_values)  # an accepted point, not a trial
    assert abs(pt.parameter - 1.00025) <= pt.tolerance * (1 + 1e-9)
    assert pt.tolerance < 0.3  # within one step
    modes = pt.critical_modes
    assert modes.shape == (2, 5)
    assert np.allclose(np.abs(modes[:, :2]), np.eye(2), atol=1e-10)
    assert_consistent(b, p)


def test_segment_warm_start_locates_the_same_user_event_in_fewer_iterations():
    """Oracle for :meth:`Segment.start`: trial corrections started on the segment's own
    chord (the old start) locate a user event with a step-function indicator (as the
    contact counts' are) at the same place; the warm start, between the nearest
    corrected trial points, needs fewer corrector iterations."""
    from supercoil.continuation import corrector, events
    from supercoil.continuation.events import Segment, locate_user_event

    class ChordSegment(Segment):
        def start(self, u):
            return self.x_a + u * self.d

    p, b = bratu_branch(32)
    k = 3
    system = ExtendedSystem(p, "lam", b.states[k])
    x_a = system.pack(b.states[k], b.multipliers[k], b.parameter_values[k])
    x_b = system.pack(b.states[k + 1], b.multipliers[k + 1], b.parameter_values[k + 1])
    middle = 0.3 * b.states[k][16] + 0.7 * b.states[k + 1][16]
    event = UserEvent("threshold", lambda q, mu, lam: {"u_mid": 0.5 if q[16] > middle
                                                       else -0.5})
    iterations = {}
    located = {}
    real_correct = corrector.correct
    for name, cls in (("chord", ChordSegment), ("warm", Segment)):
        counted = []

        def counting(*args, counted=counted):
            corr = real_correct(*args)
            counted.append(corr.iterations)
            return corr

        events.correct = counting
        try:
            segment = cls(system, x_a, x_b, 1e-12, 10, 1e-6)
            located[name] = locate_user_event(segment, event, "u_mid", 1e-8 / segment.length)
        finally:
            events.correct = real_correct
        iterations[name] = sum(counted)
    assert located["chord"].located and located["warm"].located
    length = system.norm(x_b - x_a)
    assert abs(located["warm"].u - located["chord"].u) * length < 2e-8
    assert abs(system.q(located["warm"].x)[16] - middle) < 1e-6
    assert iterations["warm"] < 0.7 * iterations["chord"]


def test_quadratic_predictor_term_is_the_curvature_of_a_circle():
    """On the unit circle x(s) = (cos s, sin s) the term is ds^2/2 x''(s) to first order
    in the last step (the difference quotient of the tangents)."""
    from supercoil.continuation.step import quadratic_term

    class Plane:
        weights = np.ones(2)

        def norm(self, v):
            return float(np.sqrt(v @ v))

    s0, h, ds = 0.3, 1e-3, 0.05
    t_previous = np.array([-np.sin(s0 - h), np.cos(s0 - h)])
    t_last = np.array([-np.sin(s0), np.cos(s0)])
    term = quadratic_term(Plane(), t_previous, t_last, h, ds)
    exact = 0.5 * ds**2 * -np.array([np.cos(s0), np.sin(s0)])
    assert np.linalg.norm(term - exact) < 0.5 * ds**2 * h
    # predictor error: O(ds^3) against the tangent predictor's O(ds^2)
    x0, x1 = np.array([np.cos(s0), np.sin(s0)]), np.array([np.cos(s0 + ds), np.sin(s0 + ds)])
    assert np.linalg.norm(x0 + ds * t_last + term - x1) < 0.2 * ds**3
    assert np.linalg.norm(x0 + ds * t_last - x1) > 0.4 * ds**2
    # no term after a step of no length, or one larger than half the step
    assert not np.any(quadratic_term(Plane(), t_previous, t_last, 0.0, ds))
    assert not np.any(quadratic_term(Plane(), -t_last, t_last, 1e-3, ds))


def test_quadratic_predictor_follows_bratu_through_the_same_fold():
    """The same fold (Moore-Spence oracle of the tangent run) with the quadratic predictor."""
    _, tangent_run = bratu_branch(16)
    _, quadratic_run = bratu_branch(16, predictor="quadratic")
    (fold_t,) = tangent_run.points_of_kind("fold")
    (fold_q,) = quadratic_run.points_of_kind("fold")
    assert fold_q.located and fold_q.parameter == pytest.approx(fold_t.parameter, abs=1e-10)
    assert quadratic_run.status is tangent_run.status
    assert quadratic_run.parameter_values[-1] == pytest.approx(tangent_run.parameter_values[-1])


def test_user_event_bracket_from_corrected_points_gives_the_same_root():
    """Oracle for the narrowed bracket of :func:`locate_user_event`: two indicators of one
    transition are located where Brent's method on the whole segment puts them, and the
    second costs a few corrections, not a whole localisation."""
    from supercoil.continuation import events
    from supercoil.continuation.events import Segment, locate_user_event, user_values
    from supercoil.continuation.zeroin import brentq_reference

    p, b = bratu_branch(16)
    k = 3
    system = ExtendedSystem(p, "lam", b.states[k])
    x_a = system.pack(b.states[k], b.multipliers[k], b.parameter_values[k])
    x_b = system.pack(b.states[k + 1], b.multipliers[k + 1], b.parameter_values[k + 1])
    middle = 0.5 * (b.states[k][8] + b.states[k + 1][8])
    # step functions, as the contact counts' indicators are (Brent's method bisects)
    event = UserEvent("threshold", lambda q, mu, lam: {
        "first": 0.5 if q[8] > middle else -0.5, "second": -0.5 if q[8] > middle else 0.5})
    segment = Segment(system, x_a, x_b, 1e-12, 10, 1e-6)
    xtol = 1e-6 / segment.length
    reference = Segment(system, x_a, x_b, 1e-12, 10, 1e-6)
    exact = brentq_reference(
        lambda u: user_values(event, system, reference.point(u))["first"], 0.0, 1.0, xtol)
    calls = []
    real_correct = events.correct

    def counting(*args):
        calls.append(1)
        return real_correct(*args)

    events.correct = counting
    try:
        first = locate_user_event(segment, event, "first", xtol)
        n_first = len(calls)
        second = locate_user_event(segment, event, "second", xtol)
        n_second = len(calls) - n_first
    finally:
        events.correct = real_correct
    assert first.located and second.located
    assert abs(first.u - exact) <= 2 * xtol and abs(second.u - exact) <= 2 * xtol
    assert n_first >= 10 and n_second <= 2


def test_segment_evaluations_are_computed_once_and_equal_fresh_ones(monkeypatch):
    """A segment keeps the counts, nearest eigenvalues and tangents of its trial points
    (never accepted): a second evaluation returns the first (no new inertia or
    eigenproblem), equal to what a fresh segment computes, and the pitchfork at
    ``lambda = d_0`` is located at its exact value with each evaluation done once."""
    from supercoil.continuation import events
    from supercoil.continuation.events import Segment, locate_count_change

    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0])
    p = DiagonalQuartic(d)
    system = ExtendedSystem(p, "lam", np.zeros(6))
    x_a, x_b = system.pack(np.zeros(6), np.zeros(0), 0.8), system.pack(np.zeros(6), np.zeros(0),
                                                                          1.3)
    calls = {"inertia_with_factor": [], "eigenpairs": []}
    for name in calls:
        original = getattr(events, name)

        def counted(system, x, *args, _original=original, _name=name):
            calls[_name].append(float(x[-1]))
            return _original(system, x, *args)

        monkeypatch.setattr(events, name, counted)
    segment = Segment(system, x_a, x_b, 1e-10, 10, 1e-8)
    first = [(segment.count(u), segment.nearest_eigenvalue(u), segment.tangent(u))
             for u in (0.0, 0.6, 1.0)]
    second = [(segment.count(u), segment.nearest_eigenvalue(u), segment.tangent(u))
              for u in (0.0, 0.6, 1.0)]
    fresh = Segment(system, x_a, x_b, 1e-10, 10, 1e-8)
    for (c1, e1, t1), (c2, e2, t2), u in zip(first, second, (0.0, 0.6, 1.0)):
        assert c1 == c2 == fresh.count(u) and e1 == e2 == fresh.nearest_eigenvalue(u)
        assert np.array_equal(t1, t2) and np.array_equal(t1, fresh.tangent(u))
    assert [c for c, _, _ in first] == [0, 1, 1]
    assert first[1][1] == pytest.approx(1.0 - (0.8 + 0.6 * 0.5), abs=1e-12)
    calls["inertia_with_factor"].clear()
    calls["eigenpairs"].clear()
    located = locate_count_change(segment, 1e-9 / segment.length, 1e-3)
    assert located.located and located.x[-1] == pytest.approx(1.0, abs=1e-9)
    for name, lams in calls.items():
        assert len(lams) == len(set(lams)), name  # no point evaluated twice
    # the further search from the bracket the bisection left reuses its counts
    calls["inertia_with_factor"].clear()
    assert locate_count_change(segment, 1e-9 / segment.length, 1e-3, located.resume) is None
    assert calls["inertia_with_factor"] == []


def test_a_converged_correction_assembles_a_hessian_only_for_a_newton_step(monkeypatch):
    """A point whose residual already meets the tolerance is returned without a Hessian;
    one that needed Newton steps carries the Hessian at the converged point only when
    the round-off test needed it. Tangents with and without it are the same vector."""
    from supercoil.continuation.corrector import correct, tangent

    p = DiagonalQuartic(np.array([1.0, 2.0, 3.5]))
    system = ExtendedSystem(p, "lam", np.zeros(3))
    assemblies = []
    original = ExtendedSystem.hessian

    def counted(self, x):
        assemblies.append(float(x[-1]))
        return original(self, x)

    original_full = ExtendedSystem.full_hessian

    def counted_full(self, x):  # the corrector assembles on all DOFs and restricts
        assemblies.append(float(x[-1]))
        return original_full(self, x)

    monkeypatch.setattr(ExtendedSystem, "hessian", counted)
    monkeypatch.setattr(ExtendedSystem, "full_hessian", counted_full)
    x = system.pack(np.zeros(3), np.zeros(0), 0.5)  # on the trivial branch: converged
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    corr = correct(system, x, e_lam, x, 0.0, 1e-10, 10)
    assert corr.ok and corr.iterations == 0 and corr.hessian is None and assemblies == []
    t_lazy = tangent(system, corr.x, e_lam, corr.hessian)
    t_given = tangent(system, corr.x, e_lam, original(system, corr.x))
    assert np.array_equal(t_lazy, t_given)
    # a start off the branch takes Newton steps, each with its Hessian
    start = system.pack(np.array([0.1, -0.05, 0.02]), np.zeros(0), 0.5)
    corr = correct(system, start, e_lam, start, 0.0, 1e-10, 20)
    assert corr.ok and corr.iterations >= 2
    assert np.max(np.abs(corr.x[:3])) < 1e-9
    assert len(assemblies) == 1 + corr.iterations  # the lazy tangent's, then one per step


def test_the_corrector_trust_region_stops_an_iterate_beyond_it_and_changes_nothing_inside():
    """At fixed lambda on the corner toy (root x_0 = sqrt(((1 - lambda)/a)^2 - delta^2)),
    Newton from x_0 = 3 moves by about 2.4: a trust radius of 1 stops it with a failure,
    one of 10 returns the unguarded correction bit for bit. The reference point, the
    step's start, lies on the branch (the radius is widened by its own correction)."""
    from supercoil.continuation.corrector import correct

    problem = Corner(0.8, 1e-4, lam=0.5)
    system = ExtendedSystem(problem, "lam", np.zeros(3))
    x0 = system.pack(np.array([3.0, 0.0, 0.0]), np.zeros(0), 0.5)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    root = np.sqrt((0.5 / 0.8) ** 2 - 1e-8)
    on = system.pack(np.array([root, 0.0, 0.0]), np.zeros(0), 0.5)
    free = correct(system, x0, e_lam, on, 0.0, 1e-12, 20)
    assert free.ok and free.x[0] == pytest.approx(root, abs=1e-12)
    inside = correct(system, x0, e_lam, on, 0.0, 1e-12, 20, max_distance=10.0)
    assert inside.ok and np.array_equal(inside.x, free.x)
    assert inside.iterations == free.iterations
    stopped = correct(system, x0, e_lam, on, 0.0, 1e-12, 20, max_distance=1.0)
    assert not stopped.ok and stopped.x is None
    assert "farther than" in stopped.message and stopped.iterations < free.iterations


def test_a_trust_region_of_one_step_keeps_the_branch_through_a_sharp_fold_with_fewer_iterations(
        monkeypatch):
    """The corner toy's fold (exact: lambda = 1 - a delta, tangent turning by 2 atan(a)
    within a radius of about 2e-4): steps that cross it converge far on the other leg and
    are refused by the turn test. With max_corrector_distance = 1 they stop after a
    Newton step or two: the same points, bit for bit, the same located fold, fewer
    corrector iterations."""
    from supercoil.continuation import closure, phase, step
    from supercoil.continuation import pseudo_arclength as pa

    a, delta = 0.8, 1e-4
    runs = {}
    modules = (pa, step, phase, closure)  # every correction of the continuation
    for distance in (None, 1.0):
        calls = []
        original = pa.correct

        def counted(*args, _calls=calls, _original=original, **kwargs):
            result = _original(*args, **kwargs)
            _calls.append(result)
            return result

        for module in modules:
            monkeypatch.setattr(module, "correct", counted)
        problem = Corner(a, delta, lam=1.0 - a * np.hypot(1.0, delta))
        opts = ContinuationOptions(initial_step=0.05, max_step=0.5, parameter_bounds=(-1.0, 1.0),
                                   max_corrector_distance=distance)
        branch = continuation(problem, np.array([1.0, 0.0, 0.0]), parameter="lam",
                              options=opts)
        for module in modules:
            monkeypatch.setattr(module, "correct", original)
        runs[distance] = (branch, calls)
    (plain, plain_calls), (guarded, guarded_calls) = runs[None], runs[1.0]
    assert plain.status is guarded.status is ContinuationStatus.PARAMETER_BOUND
    assert np.array_equal(plain.states, guarded.states)
    assert np.array_equal(plain.parameter_values, guarded.parameter_values)
    for branch in (plain, guarded):
        (fold,) = branch.points_of_kind("fold")
        assert fold.located and fold.parameter == pytest.approx(1.0 - a * delta, abs=1e-9)
        assert_consistent(branch, Corner(a, delta))
    stopped = [c for c in guarded_calls if "farther than" in c.message]
    assert stopped and all(c.iterations <= 2 for c in stopped)
    assert sum(c.iterations for c in guarded_calls) < sum(c.iterations for c in plain_calls)


def test_a_stop_at_the_minimum_step_names_the_failures_that_shrank_the_step():
    """The message of a run stopped at the minimum step gives the last failure and, of
    each other kind among the steps that shrank to it (their numbers aside), the last
    message, how many steps and their range."""
    from supercoil.continuation.tracer import _earlier_failures

    failed = [(1.7e-6, "corrector diverging at iteration 2 (residual 1.02e-06 > 7.82e-07)"),
              (8e-7, "corrector diverging at iteration 3 (residual 1.01e-06 > 7.80e-07)"),
              (1e-7, "iterate 1 lies farther than 1.01e-07 from the predictor"),
              (1e-12, "iterate 1 lies farther than 1.00e-12 from the predictor")]
    assert _earlier_failures(failed) == (
        "; before it, corrector diverging at iteration 3 (residual 1.01e-06 > 7.80e-07) "
        "at 2 steps of 8e-07 to 1.7e-06")
    assert _earlier_failures(failed[2:]) == ""
    assert _earlier_failures([]) == ""
