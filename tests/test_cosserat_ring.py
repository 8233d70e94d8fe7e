"""The closed Cosserat ring: derivatives of the periodic rod, Lk = Tw + Wr kept exactly,
the twisted circle's energy against the continuous rod's exact circle, and Michell's
threshold (count rising by two, second order in h, the Kirchhoff limit, the first-order
shift by shear and extension)."""

import numpy as np
import pytest

from supercoil.continuation import ContinuationOptions, continuation, switch_branch
from supercoil.continuation.options import ContinuationStatus
from supercoil.cosserat import circle
from supercoil.cosserat.closed import (
    ClosedCosseratEnergy,
    LinkingError,
    symmetry_generators,
    twisted_circle,
)
from supercoil.cosserat.ring import (
    CircleInertia,
    kirchhoff_circle_energy,
    michell_threshold,
    relax_circle,
    ring_problem,
    solve_cosserat_ring,
)
from supercoil.cosserat.rod import CosseratRod, retract
from supercoil.cosserat.rotations import exp_so3
from supercoil.errors import InputError
from supercoil.solvers.carried import with_frames
from supercoil.stability.analysis import sliding_phase_modes
from supercoil.topology import twist_from_frames, writhe
from supercoil.topology.crossings import closest_approach


def perturbed(x, R, rng, size):
    """A smooth non-planar perturbation of ``(x, R)`` (Fourier modes 2 and 3): rotations
    by about ``size``, displacements by about ``size`` times the ring's radius."""
    s = 2 * np.pi * np.arange(len(x)) / len(x)
    modes = np.stack([np.cos(k * s) for k in (2, 3)] + [np.sin(k * s) for k in (2, 3)], 1)
    dx = size * np.linalg.norm(x[0] - x.mean(axis=0)) * modes @ rng.standard_normal((4, 3))
    w = size * modes @ rng.standard_normal((4, 3))
    return x + dx, exp_so3(w) @ R


def test_closed_rod_derivatives_against_finite_differences(rng):
    rod = CosseratRod(9, length=1.2, bending_stiffness=1.1, twist_stiffness=0.7,
                      shear_stiffness=30.0, stretch_stiffness=45.0, closed=True)
    problem = ClosedCosseratEnergy(rod, excess_link=1.3)
    assert problem.link == 1 and problem.rod.intrinsic_twist == pytest.approx(
        2 * np.pi * (1 - 1.3) / 1.2)
    x, R = perturbed(*problem.configuration(problem.initial_state()), rng, 0.05)
    rod = problem.rod
    # gradient of the periodic rod (element n-1 joins node n-1 to node 0) on the manifold
    g = rod.gradient(x, R)
    v, e = rng.standard_normal(rod.n_dofs), 1e-6
    fd = (rod.energy(*retract(x, R, e * v)) - rod.energy(*retract(x, R, -e * v))) / (2 * e)
    assert fd == pytest.approx(g @ v, rel=1e-8)
    # the chart's Hessian off its centre, against the chart's gradient
    q = problem.state(x, R)
    problem.accept(q)
    q = q + 0.05 * rng.standard_normal(q.size)
    H = problem.hessian(q).dense()
    fd = (problem.gradient(q + e * v) - problem.gradient(q - e * v)) / (2 * e)
    assert np.allclose(H @ v, fd, atol=1e-6 * np.max(np.abs(fd)))
    assert np.allclose(H, H.T, atol=1e-12 * np.max(np.abs(H)))
    # the excess link's exact derivative
    exact = problem.parameter_derivative(q, np.zeros(0), "excess_link")
    problem.excess_link = 1.3 + e
    plus = problem.gradient(q)
    problem.excess_link = 1.3 - e
    minus = problem.gradient(q)
    assert np.allclose((plus - minus) / (2 * e), exact, atol=1e-7 * np.max(np.abs(exact)))
    assert problem.parameter_derivative(q, np.zeros(0), "tension") is None


def test_seven_exact_symmetries_leave_energy_and_gradient_unchanged(rng):
    # rigid motions and the sections' rotation about d3 (isotropy): the energy is
    # invariant, so each generator is orthogonal to the gradient at any state
    rod = CosseratRod(12, twist_stiffness=0.8, shear_stiffness=50.0, stretch_stiffness=70.0,
                      closed=True, intrinsic_twist=-2.0)
    x, R = twisted_circle(rod, 2, 0.1, 0.01)
    x, R = x + 0.02 * rng.standard_normal(x.shape), exp_so3(
        0.05 * rng.standard_normal((12, 3))) @ R
    g = rod.gradient(x, R)
    modes = symmetry_generators(x, R).reshape(7, -1)
    assert np.allclose(modes @ g, 0, atol=1e-11 * np.abs(g).max())
    E = rod.energy(x, R)
    Q = exp_so3(np.array([0.3, -1.1, 0.7]))
    assert rod.energy(x @ Q.T + 5.0, Q @ R) == pytest.approx(E, rel=1e-13)
    assert rod.energy(x, R @ exp_so3(np.array([0.0, 0.0, 0.9]))) == pytest.approx(E, rel=1e-13)


def test_continuous_circle_mode_matrix_has_the_symmetries_as_null_vectors():
    # the derivation's own check: three null vectors at m = 0 (rotation about the axis,
    # translation along it, the sections' rotation about d3), two at m = 1 (the other
    # rigid motions), none at m = 2 below Michell's threshold
    for stiffness in (300.0, 1e4):
        scale = stiffness
        values = [np.linalg.eigvalsh(circle.mode_matrix(0.8, 1.4, m, stiffness, 2 * stiffness))
                  for m in (0, 1, 2)]
        assert np.all(np.abs(values[0][:3]) < 1e-9 * scale) and values[0][3] > 1e-3 * scale
        assert np.all(np.abs(values[1][:2]) < 1e-9 * scale) and values[1][2] > 1.0
        assert values[2][0] > 1.0


@pytest.mark.parametrize("excess_link", [0.0, 0.7, 1.6, -2.3])
def test_twisted_circle_energy_converges_to_the_exact_circle(excess_link):
    # discrete circle -> the continuous Cosserat circle at second order in h; that one
    # -> 2 pi^2 (A + C dLk^2) / L as GA = EA grow (first order in 1 / GA)
    C, stiffness = 0.8, 2e3
    exact = circle.circle_state(C, excess_link, stiffness, stiffness).energy
    errors = []
    for n in (16, 32, 64):
        problem = ring_problem(C, excess_link, n, stiffness, stiffness)
        state = circle.circle_state(C, excess_link, stiffness, stiffness)
        x, R, _ = relax_circle(problem.rod, problem.link, state.tilt, state.stretch)
        errors.append(problem.rod.energy(x, R) - exact)
    if excess_link == 0.0:  # pure bending: the element is exact
        assert np.max(np.abs(errors)) < 1e-11
    else:
        orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert np.all(np.abs(orders - 2) < 0.05), orders
    kirchhoff = kirchhoff_circle_energy(C, excess_link)
    gaps = [circle.circle_state(C, excess_link, k, k).energy - kirchhoff for k in (1e4, 1e5, 1e6)]
    if excess_link != 0.0:
        assert np.allclose(np.array(gaps[:-1]) / np.array(gaps[1:]), 10, rtol=1e-3)
    assert abs(gaps[-1]) < 5e-5 * kirchhoff


def test_link_is_kept_exactly_tw_plus_wr():
    # Tw of the projected d1 ribbon (from the frames alone) plus the double-sum writhe
    # equals the excess link at every state reached continuously, planar or not
    problem = ring_problem(0.8, 1.7, 48, 3e3, 2e3)
    assert problem.link == 2
    q = problem.initial_state()
    assert problem.frame_twist(q) == pytest.approx(2.0, abs=1e-12)  # planar: Wr = 0
    x0, R0 = problem.configuration(q)
    worst = 0.0
    for step in range(1, 7):  # a path away from the plane, accepted state by state
        x, R = perturbed(x0, R0, np.random.default_rng(5), 0.03 * step)
        q = problem.state(x, R)
        problem.accept(q)
        points, d1 = problem.ribbon(q)
        tw, wr = twist_from_frames(points, d1, closed=True), writhe(points)
        worst = max(worst, abs(tw + wr - problem.link),
                    abs(problem.twist(q) + problem.writhe(q) - 1.7))
    assert abs(wr) > 0.3
    assert worst < 1e-8
    # the relaxed circle at several excess links
    for dlk in (0.4, 1.7, 2.6):
        result = solve_cosserat_ring(0.8, dlk, 40, 3e3, 2e3)
        assert result.link_error < 1e-8 and abs(result.writhe) < 1e-12
        assert result.twist == pytest.approx(dlk, abs=1e-8)


def test_losing_the_link_is_refused():
    problem = ring_problem(0.8, 1.0, 24, 1e3, 1e3)
    x, R = problem.configuration(problem.initial_state())
    # one section turned half a turn: its elements' relative rotations leave the short way
    R2 = R.copy()
    R2[5] = exp_so3(np.pi * 0.9 * R[5][:, 2]) @ R[5]
    assert not problem.admissible(problem.state(x, R2))
    assert "short way" in problem.refusal
    with pytest.raises(LinkingError, match="short way"):
        problem.accept(problem.state(x, R2))
    # a whole turn of the link slipped (d1 turned back once, smoothly): the integer changes
    problem = ring_problem(0.8, 1.0, 24, 1e3, 1e3)
    x, R = problem.configuration(problem.initial_state())
    angles = -2 * np.pi * np.arange(24) / 24
    unwound = R @ exp_so3(angles[:, None] * np.array([0.0, 0.0, 1.0]))
    assert problem.admissible(problem.initial_state())
    assert not problem.admissible(problem.state(x, unwound))
    assert "linking number would change from 1 to 0" in problem.refusal
    with pytest.raises(LinkingError, match="linking number changed from 1 to 0"):
        problem.accept(problem.state(x, unwound))
    # too coarse a mesh for the turns asked
    with pytest.raises(LinkingError, match="use more nodes"):
        ring_problem(0.8, 3.0, 8)


def test_circle_count_jumps_by_two_at_michell_and_the_determinant_misses_it():
    C, n, stiffness = 0.8, 40, 1e4
    below = solve_cosserat_ring(C, 2.0, n, stiffness, stiffness)
    above = solve_cosserat_ring(C, 2.4, n, stiffness, stiffness)
    assert (below.unstable_count, above.unstable_count) == (0, 2)
    assert below.zero_modes == above.zero_modes == 0
    assert below.determinant_sign == above.determinant_sign == 1
    assert below.converged and above.converged and below.residual < 1e-9
    # the crossing pair: equal eigenvalues (cos and sin of mode 2)
    assert above.lowest_eigenvalues[1] == pytest.approx(above.lowest_eigenvalues[0], rel=1e-6)
    # on the circle the sliding is a rigid rotation plus the isotropy: no phase row
    count = CircleInertia(C, n, stiffness, stiffness, 2)
    q = count.equilibrium(2.0)
    assert sliding_phase_modes(count.problem, q).shape[0] == 0
    summary = above.summary()
    assert summary["model"] == "cosserat" and summary["max_shear_strain"] > 0


def test_threshold_converges_at_second_order_to_the_continuous_circle():
    # bisection on the count (then Brent on the crossing eigenvalue) at N = 20, 40, 80:
    # second order in h towards the singular mode matrix's threshold (shear and
    # extension included, GA = EA = 1000 A/L^2: 4.5 % below Michell's)
    C, stiffness = 0.8, 1e3
    exact = circle.michell_threshold(C, 2, stiffness, stiffness)
    values = np.array([michell_threshold(C, n, 2, stiffness, stiffness) for n in (20, 40, 80)])
    errors = values - exact
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.02), orders
    richardson = (4 * values[-1] - values[-2]) / 3
    assert richardson == pytest.approx(exact, rel=1e-6)
    assert exact == pytest.approx(np.sqrt(3) / C * (1 - 0.0449), rel=1e-3)


def test_threshold_tends_to_michell_as_shear_and_stretch_stiffen():
    C = 0.8
    michell = np.sqrt(3) / C
    # continuous circle: the shift is first order in 1/GA, 1/EA, with the coefficients
    # (C - 3A/2) kappa^2 / GA and -A kappa^2 / (2 EA); the remainder is second order
    for mode in (2, 3):
        michell_m = np.sqrt(mode**2 - 1) / C
        for shear, stretch in ((1e4, 1e4), (1e4, 1e8), (1e8, 1e4), (2e4, 5e3)):
            exact = circle.michell_threshold(C, mode, stretch, shear)
            first = circle.first_order_threshold(C, mode, stretch, shear)
            remainder = abs(exact - first) / michell_m
            shift = abs(first - michell_m) / michell_m
            assert remainder < 0.02 * shift
    # the discrete threshold (Richardson in h, its O(h^4) remainder 2e-6) at
    # GA = EA = 1e6 A/L^2 is Michell's to the first-order shift 4.7e-5
    values = [michell_threshold(C, n, 2, 1e6, 1e6) for n in (32, 64)]
    richardson = (4 * values[1] - values[0]) / 3
    assert richardson == pytest.approx(circle.michell_threshold(C, 2, 1e6, 1e6), rel=3e-6)
    assert richardson == pytest.approx(michell, rel=6e-5)


def test_invalid_rings_are_refused():
    with pytest.raises(InputError, match="twist_ratio"):
        solve_cosserat_ring(0.0, 1.0)
    with pytest.raises(InputError, match="n_nodes"):
        solve_cosserat_ring(1.0, 1.0, n_nodes=4)
    with pytest.raises(InputError, match="excess_link"):
        solve_cosserat_ring(1.0, float("nan"))
    with pytest.raises(InputError, match="stretch_stiffness"):
        solve_cosserat_ring(1.0, 1.0, stretch_stiffness=-1.0)
    with pytest.raises(InputError, match="closed"):
        ClosedCosseratEnergy(CosseratRod(10), 1.0)
    rod = CosseratRod(20, closed=True)
    x, R = twisted_circle(rod, 1)
    with pytest.raises(InputError, match="linking number"):
        ClosedCosseratEnergy(rod, 1.0, x, R, link=2)
    with pytest.raises(InputError, match="mode"):
        circle.michell_threshold(1.0, 1, 1e4, 1e4)
    with pytest.raises(InputError, match="straight"):
        rod.straight()


def test_continuation_finds_michell_and_the_buckled_branch_keeps_the_link():
    # the generic continuation in excess_link follows the relaxed circle and detects the
    # pair crossing where the bisection puts it; switching onto the buckled branch gives
    # non-planar equilibria (Michell's branch, subcritical: dLk falls as the writhe
    # grows), on which Lk = Tw + Wr holds to round-off until the centreline passes
    # through itself (a phantom ring), which accept refuses
    C, stiffness, n = 0.8, 1e4, 40
    problem = ring_problem(C, 1.8, n, stiffness, stiffness)
    state = circle.circle_state(C, 1.8, stiffness, stiffness)
    q0 = problem.state(*relax_circle(problem.rod, problem.link, state.tilt, state.stretch)[:2])
    problem.accept(q0)

    def records(q, multipliers, excess_link, problem):
        # the problem at the point: a state is read in the frames carried to it
        tw, wr = problem.frame_twist(q), problem.writhe(q)
        return {"link_error": tw + wr - problem.link, "writhe": wr}

    options = ContinuationOptions(parameter_bounds=(1.5, 2.6), initial_step=0.1, max_step=0.2,
                                  max_points=30)
    branch = continuation(problem, q0, parameter="excess_link", options=options,
                          records=records)
    (point,) = branch.points_of_kind("bifurcation")
    assert (point.count_before, point.count_after) == (0, 2)
    assert point.parameter == pytest.approx(michell_threshold(C, n, 2, stiffness, stiffness),
                                            rel=1e-8)
    options = ContinuationOptions(parameter_bounds=(1.0, 3.0), initial_step=0.05,
                                  max_step=0.1, max_points=25)
    buckled = switch_branch(problem, branch, point, options, records=records,
                            stop=lambda q: "writhe" if abs(problem.writhe(q)) > 0.6 else None)
    writhes = np.abs(buckled.records["writhe"])
    assert len(buckled) >= 10 and writhes[-1] > 0.5
    assert np.all(np.diff(writhes) > 0) and np.all(np.diff(buckled.parameter_values) < 0)
    assert np.max(np.abs(buckled.records["link_error"])) < 1e-8
    assert np.all(buckled.unstable_count == 1)
    # on along the branch from its last point, in the frames and the gauge it was
    # computed in (its carried frames, phase rows and tangent): the guard refuses the
    # step that would pass the centreline through itself, the step is retried shorter
    # until it cannot be, and the branch ends there with the link kept
    at_last = with_frames(problem, buckled.frames[-1])
    onwards = ContinuationOptions(parameter_bounds=(0.5, 3.0), initial_step=0.05,
                                  max_step=0.1, max_points=60)
    last = continuation(at_last, buckled.states[-1], parameter="excess_link",
                        options=onwards, records=records,
                        start=float(buckled.parameter_values[-1]),
                        phase=(buckled.phase_modes, buckled.phase_state),
                        guess=buckled.tangents[-1])
    assert not last.ok and "linking number would change" in last.message
    assert len(last) >= 2 and np.max(np.abs(last.records["link_error"])) < 1e-8
    assert np.all(np.diff(last.parameter_values) < 0)
    # the last point is the nearest to touching: closest approach far below the
    # circle's (diameter 1 / pi), the centreline about to pass through itself
    x = with_frames(problem, last.frames[-1]).configuration(last.states[-1])[0]
    assert closest_approach(x) < 0.1 * closest_approach(problem.configuration(q0)[0])
    # the same state read in the circle's frames is another configuration, far from
    # equilibrium: the start fails, and says which frames a branch's state needs
    wrong = continuation(problem, buckled.states[-1], parameter="excess_link",
                         options=ContinuationOptions(parameter_bounds=(0.5, 3.0),
                                                     max_corrector_iterations=1),
                         start=float(buckled.parameter_values[-1]))
    assert wrong.status == ContinuationStatus.START_FAILED and "frames_at" in wrong.message


def _framed(points: np.ndarray, turns: float = 0.0) -> np.ndarray:
    """Rotations ``(n, 3, 3)`` of a closed polygon's nodes: ``d3`` along the central
    difference, ``d1`` from the polygon's parallel-transport frames, then turned about
    ``d3`` by ``turns`` whole turns spread evenly along the ring."""
    from supercoil.rod.closed import initial_reference_frames

    n = len(points)
    d3 = np.roll(points, -1, axis=0) - np.roll(points, 1, axis=0)
    d3 /= np.linalg.norm(d3, axis=1, keepdims=True)
    u = initial_reference_frames(points)
    d1 = u - np.sum(u * d3, axis=1, keepdims=True) * d3
    d1 /= np.linalg.norm(d1, axis=1, keepdims=True)
    angle = 2 * np.pi * turns * np.arange(n) / n
    d1, d2 = (np.cos(angle)[:, None] * d1 + np.sin(angle)[:, None] * np.cross(d3, d1),
              -np.sin(angle)[:, None] * d1 + np.cos(angle)[:, None] * np.cross(d3, d1))
    return np.stack([d1, d2, d3], axis=2)


def test_a_crossing_change_that_keeps_the_link_is_refused_by_the_knot_type():
    # a trefoil ring; its over-strand pushed through the under-strand (an unknot, the
    # writhe changed by about 2) with the sections turned the other way by as many
    # turns: the ribbon's link is kept, the knot type is not, and the guard refuses it
    from knot_toys import pushed_down

    from supercoil.topology.knots import identify, knot_curve

    x = knot_curve("3_1", 120)
    rod = CosseratRod(120, twist_stiffness=0.8, shear_stiffness=1e3,
                      stretch_stiffness=1e3, closed=True)
    problem = ClosedCosseratEnergy(rod, 0.0, x, _framed(x))
    assert problem.admissible(problem.initial_state())
    assert problem.passage_guard.knot_guard.reference.name == "3_1"
    y = pushed_down(x, 1.0)
    assert identify(y).name == "0_1"
    jump = writhe(y) - writhe(x)
    assert abs(abs(jump) - 2) < 0.2

    def link(turns):
        q = problem.state(y, _framed(y, turns))
        return q, problem.frame_twist(q) + problem.writhe(q)

    _q, untwisted = link(0.0)
    per_turn = link(1.0)[1] - untwisted  # +-1: the sign of a turn of d1 about d3
    assert abs(abs(per_turn) - 1) < 1e-6
    q, kept = link(np.rint((problem.link - untwisted) / per_turn))
    assert abs(kept - problem.link) < 1e-6  # the link is the start's
    assert not problem.admissible(q)
    assert "3_1" in problem.refusal and "0_1" in problem.refusal
    # halfway down the strands have not passed: admitted
    assert problem.admissible(problem.state(pushed_down(x, 0.4), _framed(x)))


def test_with_self_contact_an_element_turned_past_a_quarter_turn_is_refused():
    # one section turned by 0.6 pi about its d3: the centreline (all that the contact's
    # guards see) is the circle's and the link is kept, but its elements turn by more
    # than pi / 2; the contact problem refuses the state as the ring does
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem

    problem = ring_problem(0.8, 1.0, 24, 1e3, 1e3)
    x, R = problem.configuration(problem.initial_state())
    R2 = R.copy()
    R2[5] = exp_so3(0.6 * np.pi * R[5][:, 2]) @ R[5]
    turned = problem.state(x, R2)
    assert abs(problem.frame_twist(turned) + problem.writhe(turned) - problem.link) < 0.5
    cp = ContactProblem(problem, ContactOptions(diameter=0.02, treatment="barrier"))
    assert not cp.admissible(turned)
    assert "short way" in cp.refusal
    problem.state(x, R)
    assert cp.admissible(problem.initial_state())
