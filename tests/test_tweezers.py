"""The tweezers problem: Greenhill with tension, the buckled branch, contact, invariants."""

import dataclasses
import math

import numpy as np
import pytest

from supercoil.continuation import consistency_check
from supercoil.problems.greenhill import (
    GREENHILL_ZERO_TENSION,
    critical_moment,
    critical_turns,
)
from supercoil.problems.ring import richardson
from supercoil.problems.tweezers import (
    TweezersOptions,
    clamped_problem,
    tweezers_branches,
    tweezers_records,
)
from supercoil.problems.tweezers.straight import straight_branch


def clamped_determinant(M, T, L=1.0, A=1.0):
    """The 4 x 4 determinant of w = c1 + c2 s + c3 e^{i k1 s} + c4 e^{i k2 s}, w = w' = 0 at 0, L.

    Independent of the reduction to g(m, t) in greenhill.py: built from the
    roots of A k^2 + M k + T = 0 directly.
    """
    disc = np.sqrt(complex(M * M - 4 * A * T))
    k1, k2 = (-M + disc) / (2 * A), (-M - disc) / (2 * A)
    e1, e2 = np.exp(1j * k1 * L), np.exp(1j * k2 * L)
    mat = np.array([[1, 0, 1, 1], [0, 1, 1j * k1, 1j * k2], [1, L, e1, e2],
                    [0, 1, 1j * k1 * e1, 1j * k2 * e2]], dtype=complex)
    return np.linalg.det(mat)


@pytest.mark.parametrize("tension", [1.0, 20.0, 75.0])
def test_critical_moment_is_a_root_of_the_clamped_determinant(tension):
    Mc = critical_moment(tension)
    # the determinant is i e^{-i M L / 2A} times a real function; it changes sign at Mc ...
    def real(M):
        return (clamped_determinant(M, tension) * np.exp(0.5j * M) / 1j).real

    below, above = real(Mc * (1 - 1e-6)), real(Mc * (1 + 1e-6))
    assert below * above < 0
    # ... and nowhere between the infinite-rod threshold 2 sqrt(T) and Mc
    grid = np.linspace(2 * math.sqrt(tension) * 1.001, Mc * 0.999, 400)
    values = np.array([real(M) for M in grid])
    assert np.all(np.sign(values) == np.sign(values[0]))


@pytest.mark.parametrize("tension", [0.0, 0.01, 1.0, 75.0, 1e5])
def test_critical_moment_equals_brents_root(tension):
    """Oracle: scipy's ``brentq`` on the same bracket (as critical_moment used before its
    bisection). The same root to 1e-14 relative, except where (*) is flat: near t = 0 it
    vanishes to second order in t, so that round-off blurs its zero (the two methods
    differ by 1.5e-11 at t = 0.01, measured)."""
    from scipy.optimize import brentq

    from supercoil.problems.greenhill import stability_function

    mc = critical_moment(tension)
    m = 0.5 * mc
    if tension < 1e-3:
        exact = brentq(lambda x: math.sin(x) - x * math.cos(x), math.pi, 1.5 * math.pi,
                       xtol=1e-15)
        rel = 1e-15
    else:
        # a bracket of +-1e-6: above the spurious zero at sqrt(t) (5e-5 below m at 1e5)
        exact = brentq(lambda x: stability_function(x, tension), m * (1 - 1e-6),
                       m * (1 + 1e-6), xtol=1e-14, rtol=4 * np.finfo(float).eps)
        rel = 1e-10 if tension < 1 else 1e-14
    assert m == pytest.approx(exact, rel=rel)


def test_greenhill_without_tension_and_the_limit():
    assert critical_moment(0.0) == pytest.approx(GREENHILL_ZERO_TENSION, rel=1e-10)
    # (*) tends to tan m = m continuously: the threshold grows linearly in t
    small = [critical_moment(t) for t in (0.01, 0.02)]
    slope = (small[1] - small[0]) / 0.01
    assert small[0] - slope * 0.01 == pytest.approx(GREENHILL_ZERO_TENSION, rel=1e-5)
    with pytest.raises(ValueError):
        critical_moment(-1.0)


def _located_turns(n, tension, twist_ratio=4 / 3):
    exact = critical_turns(twist_ratio, tension)
    opts = TweezersOptions(twist_ratio=twist_ratio, length_over_diameter=None, tension=tension,
                           turns=(0.0, 1.08 * exact), n_nodes=n)
    problem, q0 = clamped_problem(opts)
    branch = straight_branch(opts, problem, q0, None)
    points = branch.points_of_kind("bifurcation")
    assert len(points) == 1 and points[0].count_before == 0 and points[0].count_after == 2
    return points[0].parameter


@pytest.mark.parametrize("tension", [0.0, 20.0])
def test_straight_branch_buckles_at_the_exact_threshold_with_order_two(tension):
    exact = critical_turns(4 / 3, tension)
    ns = (24, 48, 96)
    values = [_located_turns(n, tension) for n in ns]
    errors = np.abs(np.array(values) - exact) / exact
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.25), (errors, orders)
    assert abs(richardson(values[1], values[2]) - exact) / exact < 2e-4


# ----------------------------------------------------------------- the whole branch
@pytest.fixture(scope="module")
def small_run():
    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, tension=20.0,
                           turns=(0.0, 1.6), n_nodes=40, max_points=60)
    return tweezers_branches(opts)


KEYS = ("turns", "extension", "torque", "writhe", "twist", "energy", "load_potential",
        "n_contact_points", "n_contact_intervals", "min_gap_over_diameter")


def test_branches_keys_and_order(small_run):
    names = [b.name for b in small_run.branches]
    assert names == ["straight", "buckled", "buckled_contact"]
    assert small_run.ok, small_run.notes
    for b in small_run.branches:
        for key in KEYS:
            assert key in b.records, (b.name, key)
    contact = small_run.branch("buckled_contact")
    assert contact.parent == "buckled" and contact.origin.kind == "contact_onset"
    assert contact.parameter_values[-1] == pytest.approx(1.6, abs=1e-12)


def test_turns_equal_twist_plus_writhe_everywhere(small_run):
    for b in small_run.branches:
        r = b.records
        assert np.max(np.abs(r["twist"] + r["writhe"] - r["turns"])) < 1e-9, b.name
        assert not np.any(r["closure_failed"])
        # the torque of the reduced twist: 2 pi (C/A) Tw
        assert np.allclose(r["torque"], 2 * np.pi * (4 / 3) * r["twist"], rtol=1e-12)


def test_straight_then_buckled_extension_drops(small_run):
    straight = small_run.branch("straight")
    assert np.allclose(straight.records["extension"], 1.0, atol=1e-12)
    assert np.allclose(straight.records["writhe"], 0.0, atol=1e-12)
    buckled = small_run.branch("buckled")
    ext = buckled.records["extension"]
    assert ext[0] < 1.0 and np.all(np.diff(ext) < 0)
    # the energy bookkeeping: load potential is -F z
    assert np.allclose(buckled.records["load_potential"], -20.0 * ext, rtol=1e-12)
    # the count does not flicker on the contact-free buckled branch (one unstable mode)
    assert np.all(buckled.unstable_count == 1)


def test_contact_onset_and_no_penetration(small_run):
    buckled = small_run.branch("buckled")
    onset = buckled.points_of_kind("contact_onset")[0]
    assert onset.records["min_gap_over_diameter"] == pytest.approx(1.0, abs=1e-6)
    gaps = buckled.records["min_gap_over_diameter"]
    assert np.all(gaps[:-1] > 1.0)  # the last point is past the onset (kept to bracket it)
    contact = small_run.branch("buckled_contact")
    assert np.all(contact.records["min_gap_over_diameter"] > 1.0)
    assert np.max(contact.records["n_contact_points"] + contact.records["n_contact_intervals"]) >= 1
    # the loop that touches itself is stable (the contact turns the branch at a fold)
    assert contact.unstable_count[-1] == 0


def test_branches_are_consistent(small_run):
    for b in small_run.branches:
        # one azimuth pin per branch here (re-picked only when it degrades)
        assert len(small_run.pins[b.name]) == 1
        problem = small_run.pin_branch(b.name)
        points = np.unique(np.linspace(0, len(b) - 1, 6).astype(int))
        report = consistency_check(b, problem, points=points, residual_tolerance=1e-6)
        # A contact event next to a fold (the loop touching itself turns the branch)
        # lies beyond the stored points' range by the fold's curvature times the step
        # squared: the parameter between two points reaches the located fold's value,
        # so the range the event may lie in extends to the folds.
        folds = [p.parameter for p in b.points_of_kind("fold")]
        lo = min([float(b.parameter_values.min()), *folds])
        hi = max([float(b.parameter_values.max()), *folds])
        left = [msg for msg in report.problems if not (
            "outside the branch's parameter range" in msg
            and lo <= float(msg.split("= ")[1].split(":")[0]) <= hi)]
        assert not left, (b.name, left)


def test_contact_predictor_keeps_the_branch(small_run):
    """Oracle for the contact branch's quadratic predictor (``contact_predictor``): the
    tangent predictor gives the same special points, within the contact event
    tolerance, the same end state and the same counts, with more points."""
    old = tweezers_branches(dataclasses.replace(small_run.options, contact_predictor="tangent"))
    new_branch, old_branch = small_run.branch("buckled_contact"), old.branch("buckled_contact")
    assert len(new_branch) < len(old_branch)
    new_specials, old_specials = new_branch.special_points, old_branch.special_points
    assert [p.kind for p in new_specials] == [p.kind for p in old_specials]
    for p, o in zip(new_specials, old_specials, strict=True):
        assert p.parameter == pytest.approx(o.parameter, abs=1e-5), p.kind
        assert p.unstable_count == o.unstable_count
    for key in ("extension", "writhe", "torque", "energy"):
        assert new_branch.records[key][-1] == pytest.approx(old_branch.records[key][-1],
                                                            abs=1e-8), key
    # the count at every new point is the old branch's at the two old points nearest in
    # arclength (the same start), wherever those agree (away from the count's changes)
    old_s = old_branch.arclength
    for s, count in zip(new_branch.arclength, new_branch.unstable_count):
        near = np.argsort(np.abs(old_s - s))[:2]
        if old_branch.unstable_count[near[0]] == old_branch.unstable_count[near[1]]:
            assert count == old_branch.unstable_count[near[0]], s


def test_records_function_matches_straight_state():
    opts = TweezersOptions(twist_ratio=1.5, length_over_diameter=None, tension=3.0,
                           turns=(0.0, 1.0), n_nodes=20)
    problem, q0 = clamped_problem(opts)
    problem.turns = 0.7
    rec = tweezers_records(problem, problem, False)(q0, np.full(problem.n_constraints, 3.0), 0.7)
    assert rec["twist"] == pytest.approx(0.7, abs=1e-14)
    assert rec["energy"] == pytest.approx(2 * np.pi**2 * 1.5 * 0.7**2, rel=1e-13)
    assert rec["torque"] == pytest.approx(2 * np.pi * 1.5 * 0.7, rel=1e-13)


@pytest.mark.parametrize("kwargs", [
    {"tension": None}, {"tension": 1.0, "end_distance": 0.5}, {"tension": -1.0},
    {"turns": (2.0, 1.0)}, {"twist_ratio": 0.0}, {"length_over_diameter": 2.0},
    {"tension": None, "end_distance": 2.5}, {"n_nodes": 5}, {"contact_predictor": "cubic"}])
def test_bad_options(kwargs):
    base = {"twist_ratio": 1.0, "length_over_diameter": 30.0, "tension": 1.0}
    base.update(kwargs)
    with pytest.raises(ValueError):
        TweezersOptions(**base)


def test_displacement_control_starts_from_the_clamped_elastica():
    """At 0 turns and z/L = 0.7 the axial force is the clamped elastica's, order 2 in N.

    The clamped-clamped first mode is four quarter-waves of a cantilever of length
    L/4: P L^2/A = 16 K(m)^2 with z/L = 2 E(m)/K(m) - 1 (Love, sec. 263; m = k^2).
    """
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipk

    from supercoil.problems.segments import set_pin
    from supercoil.problems.tweezers.problem import axial_force
    from supercoil.solvers.newton import NewtonOptions, newton

    m = brentq(lambda m: 2 * ellipe(m) / ellipk(m) - 1 - 0.7, 1e-9, 0.999)
    exact = -16 * ellipk(m) ** 2  # compression
    forces = []
    for n in (20, 40, 80):
        opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, end_distance=0.7,
                               turns=(0.0, 1.0), n_nodes=n)
        problem, q0 = clamped_problem(opts)
        assert problem.extension(q0) == pytest.approx(0.7, abs=1e-13)
        set_pin(problem, problem, q0)
        res = newton(problem, q0, NewtonOptions(mode="stationary"))
        assert res.converged
        forces.append(axial_force(problem, res.multipliers))
    errors = np.abs(np.array(forces) - exact) / abs(exact)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.2), (errors, orders)
    assert abs(richardson(forces[1], forces[2]) - exact) / abs(exact) < 1e-3


def test_up_down_path_shows_hysteresis(small_run):
    """Turning up snaps the straight rod into the touching loop just past its buckling;
    turning down keeps the loop until the contact branch's fold, then snaps back."""
    from supercoil.problems.tweezers_protocol import quasistatic_path

    path = quasistatic_path(small_run.options, "up-down", step=0.1)
    assert path.ok, path.message
    points = path.points
    assert all(p["unstable_count"] == 0 for p in points)  # an experiment sees stable states
    up = [j for j in path.jumps if j["direction"] > 0]
    down = [j for j in path.jumps if j["direction"] < 0]
    assert len(up) == 1 and len(down) == 1
    bifurcation = small_run.branch("straight").points_of_kind("bifurcation")[0].parameter
    assert bifurcation < up[0]["turns"] <= bifurcation + 0.1 + 1e-9
    assert up[0]["extension"] == pytest.approx(1.0, abs=1e-9) and up[0]["extension_after"] < 0.4
    contact = small_run.branch("buckled_contact")
    fold = contact.points_of_kind("fold")[0].parameter
    assert fold - 0.1 - 1e-9 <= down[0]["turns"] < fold
    assert down[0]["extension_after"] == pytest.approx(1.0, abs=1e-3)  # back to straight
    assert points[-1]["extension"] == pytest.approx(1.0, abs=1e-6)
    # the stable looped states of the path lie on the contact branch
    ext = contact.records["extension"]
    lam = contact.parameter_values
    rising = np.flatnonzero(np.diff(lam) > 0)
    for p in points:
        if p["extension"] < 0.9 and lam[rising[0]] < p["turns"] < lam[-1]:
            on_branch = np.interp(p["turns"], lam[rising[0]:], ext[rising[0]:])
            assert p["extension"] == pytest.approx(on_branch, abs=2e-3)


@pytest.mark.slow
def test_long_rod_buckled_branch_is_the_localised_loop():
    """A long rod under tension: the contact-free buckled states are Love's localised loop.

    For an infinite rod under tension T and axial moment M, m = M / (2 sqrt(A T)) < 1,
    the homoclinic (Coyne 1990; Champneys & Thompson 1996) has
    cos(theta) = 1 - 2 (1 - m^2) sech^2(sqrt((1 - m^2) T / A) s), so the end shortening is
    4 sqrt(1 - m^2) sqrt(A / T) and the writhe (tails along the axis) (2/pi) arccos(m).
    At F L^2/A = 900 the loop's length scale is L/30: the clamps are far away.
    """
    tension = 900.0
    opts = TweezersOptions(twist_ratio=1.0, length_over_diameter=None, tension=tension,
                           turns=(0.0, 1.05 * critical_turns(1.0, tension)), n_nodes=200,
                           max_points=70)
    result = tweezers_branches(opts)
    buckled = result.branch("buckled")
    r = buckled.records
    m = r["torque"] / (2 * np.sqrt(tension))
    checked = 0
    for i in np.flatnonzero((m > 0.4) & (m < 0.8)):
        shortening = 4 * np.sqrt(1 - m[i] ** 2) / np.sqrt(tension)
        assert 1 - r["extension"][i] == pytest.approx(shortening, rel=1e-2)
        assert r["writhe"][i] == pytest.approx(2 / np.pi * np.arccos(m[i]), abs=3e-3)
        checked += 1
    assert checked >= 5


def test_force_ramp_returns_to_its_start(small_run):
    """At fixed turns the force ramp down and back up retraces the touching loop (no jump),
    and the extension grows with the force (a stable state under a dead load)."""
    from supercoil.problems.tweezers_protocol import quasistatic_path

    path = quasistatic_path(small_run.options, "force-ramp", step=0.2, force_range=(4.0, 36.0),
                            force_step=8.0)
    assert path.ok, path.message
    ramp = [p for p in path.points if p["ramp"] == "tension"]
    assert all(p["stable"] for p in ramp) and all(p["turns"] == 1.6 for p in ramp)
    assert [j for j in path.jumps if j["ramp"] == "tension"] == []
    by_force = {}
    for p in ramp:
        by_force.setdefault(round(p["tension"], 9), []).append(p["extension"])
    for values in by_force.values():  # reversible: each force visited twice, same state
        assert max(values) - min(values) < 1e-6
    forces = sorted(by_force)
    ext = [by_force[f][0] for f in forces]
    assert np.all(np.diff(ext) > 0)
    assert all(p["tension"] == pytest.approx(p["load_potential"] / -p["extension"])
               for p in ramp)


def test_continuation_in_force_locates_the_buckling_force():
    """At 2 turns the straight rod, unloaded from above, buckles at the force F_c with
    critical_moment(F_c) = 2 pi (C/A) turns (the same exact condition), order 2 in N."""
    from scipy.optimize import brentq

    from supercoil.problems.greenhill import critical_moment
    from supercoil.problems.tweezers.straight import straight_force_branch

    turns, ratio = 2.0, 4 / 3
    exact = brentq(lambda t: critical_moment(t) - 2 * np.pi * ratio * turns, 1e-3, 500.0)
    values = []
    for n in (24, 48, 96):
        opts = TweezersOptions(twist_ratio=ratio, length_over_diameter=None, tension=1.0,
                               n_nodes=n)
        branch = straight_force_branch(opts, turns, (0.5 * exact, 1.5 * exact))
        (point,) = branch.points_of_kind("bifurcation")
        assert (point.count_before, point.count_after) == (0, 2)
        values.append(point.parameter)
    errors = np.abs(np.array(values) - exact) / exact
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.2), (errors, orders)


def _same_hessian(a, b):
    """Bit-for-bit equal ``HessianParts`` (stored pattern, values, rank-one terms)."""
    return (np.array_equal(a.sparse.indptr, b.sparse.indptr)
            and np.array_equal(a.sparse.indices, b.sparse.indices)
            and np.array_equal(a.sparse.data, b.sparse.data)
            and np.array_equal(a.vectors, b.vectors)
            and np.array_equal(a.coefficients, b.coefficients))


def _three_points(small_run, name):
    """``(branch, i, problem, system, x, q, mu)`` at the second, middle and last points
    of the small run's branch ``name``, the problem pinned and at that point."""
    from supercoil.continuation.system import ExtendedSystem

    branch = small_run.branch(name)
    problem = small_run.pin_branch(name)
    for i in (1, len(branch) // 2, len(branch) - 1):
        q, mu, lam = branch.states[i], branch.multipliers[i], branch.parameter_values[i]
        problem.accept(q)
        system = ExtendedSystem(problem, branch.parameter, q)
        x = system.pack(q, mu, lam)
        yield branch, i, system.problem_at(lam), system, x, q, mu


@pytest.mark.parametrize("name", ["buckled", "buckled_contact"])
def test_point_stability_assembles_once_and_equals_the_separate_parts(small_run, name):
    """One assembly of the Lagrangian's Hessian serves the count and the eigenproblem:
    its restrictions equal the two separately assembled Hessians bit for bit, and the
    point's stability equals the inertia and eigenpairs computed each on its own."""
    from supercoil.continuation.stability import eigenpairs, inertia, point_stability
    from supercoil.solvers.newton import lagrangian_hessian
    from supercoil.stability.analysis import eigen_dofs

    for branch, i, problem, system, x, q, mu in _three_points(small_run, name):
        full = system.full_hessian(x)
        assert _same_hessian(full.restrict(system.free), system.hessian(x))
        dofs = eigen_dofs(problem)
        assert dofs.size > system.free.size  # the gauge pin is released there
        assert _same_hessian(full.restrict(dofs), lagrangian_hessian(problem, q, mu).restrict(dofs))
        stab = point_stability(system, x, 1e-6, 2)
        neg, sign = inertia(system, x, 1e-6)
        values, modes = eigenpairs(system, x, neg + 2)
        assert (stab.negative_count, stab.determinant_sign) == (neg, sign)
        assert stab.unstable_count == branch.unstable_count[i]
        # the point's shift-invert factor is ordered from the count's: round-off apart
        scale = np.max(np.abs(values))
        np.testing.assert_allclose(stab.eigenvalues, values, rtol=0, atol=1e-9 * scale)
        overlap = np.abs(np.einsum("ij,ij->i", stab.modes * problem.mass, modes))
        assert np.all(overlap > 1 - 1e-8)


@pytest.mark.parametrize("name", ["buckled", "buckled_contact"])
def test_point_stability_equals_the_dense_eigenpairs(small_run, name):
    """point_stability (the shift-invert factor ordered from the count's, the azimuth
    gauge pin inserted) against the freshly ordered eigenpairs and the dense
    constrained eigenproblem: the same eigenvalues to round-off, the branch's counts."""
    from supercoil.continuation.stability import eigenpairs, point_stability
    from supercoil.stability.analysis import eigen_system
    from supercoil.stability.eigen import dense_constrained_eigenpairs

    for branch, i, problem, system, x, q, mu in _three_points(small_run, name):
        stab = point_stability(system, x, 1e-6, 2)
        values, _modes = eigenpairs(system, x, stab.negative_count + 2)
        _dofs, H, J, mass, sym = eigen_system(problem, q, mu)
        dense, _ = dense_constrained_eigenpairs(H, J, mass, sym)
        dense = np.sort(dense[np.argsort(np.abs(dense + 1e-3))[:values.size]])
        scale = np.max(np.abs(dense))
        np.testing.assert_allclose(stab.eigenvalues, values, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(stab.eigenvalues, dense, rtol=0, atol=1e-9 * scale)
        assert (stab.unstable_count, stab.zero_modes) == (branch.unstable_count[i],
                                                          branch.zero_modes[i])


def test_straight_branch_bifurcations_do_not_depend_on_its_step():
    """The straight rod's points only bracket its count changes: with the branch's
    steps of up to one turn, the bifurcations (and the counts between them) are those
    of steps of a quarter turn, within the event tolerance."""
    from supercoil.continuation import ContinuationOptions, continuation
    from supercoil.problems.tweezers import straight

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 4.0), n_nodes=40)
    problem, q0 = clamped_problem(opts)
    coarse = straight_branch(opts, problem, q0, None)
    problem, q0 = clamped_problem(opts)
    fine = continuation(problem, q0, parameter="turns", name="straight", options=(
        ContinuationOptions(initial_step=0.05, max_step=0.25, parameter_bounds=opts.turns,
                            max_points=opts.max_points, event_tolerance=opts.event_tolerance)))
    assert straight.STRAIGHT_MAX_STEP > 0.25 and len(coarse) < len(fine)
    a, b = coarse.points_of_kind("bifurcation"), fine.points_of_kind("bifurcation")
    assert len(a) == len(b) >= 3
    for p, r in zip(a, b):
        assert p.located and r.located
        assert (p.count_before, p.count_after) == (r.count_before, r.count_after)
        assert abs(p.parameter - r.parameter) <= 10 * opts.event_tolerance
    # the first is the clamped Greenhill threshold up to the O(h^2) error (0.6 % at N = 40)
    assert a[0].parameter == pytest.approx(critical_turns(4 / 3, 20.0), rel=1e-2)


def test_buckled_run_ends_at_the_point_past_its_onset(small_run, monkeypatch):
    """Oracle for the contact-free runs' stop after a located onset: without it (the run
    going on to its segment's end, then cut by ``truncate_after``) the buckled branch has
    the same points and onset to round-off, and the run computed points past the cut."""
    from supercoil.problems.tweezers import compute

    buckled = small_run.branch("buckled")
    onset = buckled.points_of_kind("contact_onset")[0]
    assert len(buckled) == onset.index + 2
    assert buckled.message.endswith("the contact onset is located")
    computed = []

    def counting(branch):
        if branch.name == "buckled":
            computed.append(len(branch))

    monkeypatch.setattr(compute, "stop_after_onset", lambda on_point: (on_point, None))
    old = tweezers_branches(small_run.options, on_point=counting).branch("buckled")
    assert max(computed) > len(old)  # the old run went past the point kept
    old_onset = old.points_of_kind("contact_onset")[0]
    assert len(old) == len(buckled) and old_onset.index == onset.index
    assert old_onset.parameter == pytest.approx(onset.parameter, abs=1e-12)
    assert np.max(np.abs(old.states - buckled.states)) < 1e-12
    assert np.array_equal(old.unstable_count, buckled.unstable_count)


def _generic_straight(opts):
    """The straight branch without the pencil: the continuation's own localisation
    (bisection on the inertia count, then Brent's method on the eigenvalue nearest zero),
    with the same steps."""
    from supercoil.continuation import ContinuationOptions, continuation
    from supercoil.problems.tweezers import straight

    problem, q0 = clamped_problem(opts)
    return continuation(problem, q0, parameter="turns", name="straight", options=(
        ContinuationOptions(initial_step=0.05, max_step=straight.STRAIGHT_MAX_STEP,
                            parameter_bounds=opts.turns, max_points=opts.max_points,
                            event_tolerance=opts.event_tolerance)))


def test_straight_state_is_an_equilibrium_at_every_turns():
    """The pencil's premise: the straight rod with the multipliers of its first point
    solves the equilibrium equations at any turns (residual <= 1e-10), and the branch
    stores that one state at every point."""
    from supercoil.continuation.system import ExtendedSystem

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 4.0), n_nodes=40)
    problem, q0 = clamped_problem(opts)
    branch = straight_branch(opts, problem, q0, None)
    assert np.array_equal(branch.states, np.broadcast_to(q0, branch.states.shape))
    system = ExtendedSystem(problem, "turns", q0)
    for turns in (0.0, 0.37, 2.2, 3.9, 7.5):
        residual = system.residual(system.pack(q0, branch.multipliers[0], turns))
        assert np.max(np.abs(residual)) <= 1e-10, turns


def test_straight_pencil_matches_the_continuations_localisation():
    """Oracle: the continuation's bisection-then-Brent localisation at the same points.
    The same bifurcations (counts before and after, within the event tolerance), each
    certified by the inertia on both sides; the critical pair at zero to round-off."""
    from supercoil.continuation.stability import inertia
    from supercoil.continuation.system import ExtendedSystem

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 4.0), n_nodes=40)
    problem, q0 = clamped_problem(opts)
    fast = straight_branch(opts, problem, q0, None)
    slow = _generic_straight(opts)
    a, b = fast.points_of_kind("bifurcation"), slow.points_of_kind("bifurcation")
    assert len(a) == len(b) >= 3
    np.testing.assert_array_equal(fast.unstable_count, slow.unstable_count)
    system = ExtendedSystem(problem, "turns", q0)
    mu = fast.multipliers[0]
    for p, r in zip(a, b):
        assert p.located and (p.count_before, p.count_after) == (r.count_before, r.count_after)
        assert p.count_after - p.count_before == 2  # the axisymmetric rod's pair
        assert p.index == r.index
        assert abs(p.parameter - r.parameter) <= opts.event_tolerance
        assert np.all(np.abs(p.critical_eigenvalues) <= 1e-6)
        assert p.unstable_count == p.count_before
        for side, count in ((-1, p.count_before), (1, p.count_after)):
            x = system.pack(q0, mu, p.parameter + side * 10 * opts.event_tolerance)
            assert inertia(system, x)[0] == count


def test_straight_pencil_falls_back_when_not_certified(monkeypatch):
    """A pencil that fails its check (here: linearity asked to better than exactly)
    gives way to the continuation's localisation: the generic branch, bit for bit."""
    from supercoil.problems.tweezers import straight

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 2.0), n_nodes=30)
    monkeypatch.setattr(straight, "PENCIL_LINEARITY", -1.0)
    problem, q0 = clamped_problem(opts)
    fallback = straight_branch(opts, problem, q0, None)
    slow = _generic_straight(opts)
    assert len(fallback.special_points) == len(slow.special_points) == 1
    assert fallback.special_points[0].parameter == slow.special_points[0].parameter
    np.testing.assert_array_equal(fallback.unstable_count, slow.unstable_count)


def test_straight_pencil_is_certified_between_roots_not_at_them(monkeypatch):
    """The certifying counts are taken halfway between consecutive roots (and the ends),
    where the inertia resolves them: counts that round-off would decide next to a root
    (at N = 1000 the eigenvalues 1e-8 turns from it are 1e-17 of the largest; simulated
    here by a count that lies there) do not matter, a wrong count halfway does."""
    from supercoil.continuation import ContinuationOptions, continuation, stability
    from supercoil.problems.tweezers import straight

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 4.0), n_nodes=40)
    problem, q0 = clamped_problem(opts)
    cont = ContinuationOptions(initial_step=0.05, max_step=straight.STRAIGHT_MAX_STEP,
                               parameter_bounds=opts.turns, event_tolerance=opts.event_tolerance,
                               detect_bifurcations=False)
    branch = continuation(problem, q0, parameter="turns", options=cont, name="straight")
    honest = straight.straight_bifurcations(problem, branch, cont)
    roots = np.array([p.parameter for p in honest])
    assert roots.size >= 3
    true_inertia = stability.inertia
    checked = []

    def lying_near_roots(system, x, *args, **kwargs):
        neg, sign = true_inertia(system, x, *args, **kwargs)
        checked.append(float(x[-1]))
        return (neg + 1, sign) if np.min(np.abs(roots - x[-1])) < 1e-3 else (neg, sign)

    monkeypatch.setattr(stability, "inertia", lying_near_roots)
    again = straight.straight_bifurcations(problem, branch, cont)
    assert [p.parameter for p in again] == roots.tolist()
    stops = [0.0, *roots.tolist(), branch.parameter_values[-1]]
    away = [t for t in checked if np.min(np.abs(roots - t)) >= 1e-3]  # the others: the
    # special points' own stability (their count is the certified count before)
    np.testing.assert_allclose(away, 0.5 * (np.array(stops[:-1]) + np.array(stops[1:])))

    def lying_halfway(system, x, *args, **kwargs):
        neg, sign = true_inertia(system, x, *args, **kwargs)
        return (neg + 1, sign) if abs(x[-1] - away[1]) < 1e-12 else (neg, sign)

    monkeypatch.setattr(stability, "inertia", lying_halfway)
    assert straight.straight_bifurcations(problem, branch, cont) is None


def test_switch_pin_is_the_one_repin_picks_and_the_mode_does_not_move_it():
    """``_pin_node`` pins what ``repin(q* + 1e-3 mode)`` picks when one node is farthest
    (the mode's symmetric tie broken by a small bump), and the rotated mode has no
    component on the pinned coordinate whichever of two tied nodes is taken."""
    from supercoil.problems.tweezers import pins

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=None, tension=20.0,
                           turns=(0.0, 2.0), n_nodes=30)
    problem, q0 = clamped_problem(opts)
    point = straight_branch(opts, problem, q0, None).special_points[0]
    mode = point.critical_modes[0]
    radius = np.linalg.norm(mode.reshape(-1, 3)[:, :2], axis=1)
    tied = np.flatnonzero(radius >= (1 - 1e-6) * radius.max())
    assert tied.size == 2 and tied.sum() == opts.n_nodes - 1  # symmetric about the middle
    for bump in (1.0 + 1e-3, 1.0 / (1.0 + 1e-3)):
        bumped = mode.copy().reshape(-1, 3)
        bumped[tied[1], :2] *= bump
        direction, node = pins.rotated_mode(bumped.ravel())
        assert node == (tied[1] if bump > 1 else tied[0])
        pins.pin_node(problem, node)
        pinned = problem.gauge_dofs.copy()
        problem.repin(point.q + 1e-3 * direction)
        np.testing.assert_array_equal(problem.gauge_dofs, pinned)
        assert direction[pinned[0]] == pytest.approx(0.0, abs=1e-14)
    direction, node = pins.rotated_mode(mode)
    assert node == tied[0] and direction[3 * node + 1] == pytest.approx(0.0, abs=1e-14)


def test_every_point_keeps_a_pin_of_quality(small_run):
    """The pin is checked at every point (``pin_stop``): each stored point of the buckled
    branches has, with the pin it was computed with, a pin quality of at least
    ``PIN_QUALITY``."""
    from supercoil.problems.tweezers import pins

    for branch in small_run.branches[1:]:
        for i, q in enumerate(branch.states):
            small_run.pin_branch(branch.name, i)
            assert small_run.rod_problem.pin_quality(q) >= pins.PIN_QUALITY, (branch.name, i)
    small_run.pin_branch("straight")


def test_long_runs_keep_the_branch_of_short_runs(small_run):
    """Oracle: short runs, the pin checked between them (30 points at the benchmark's size;
    8 here, so that the branches of this small run are cut into several). Runs as long
    as the pin holds (the default) give the same special points within their tolerances
    (two localisations, each to its tolerance in arclength, which weighs the parameter
    by the branch's ``parameter_weight``), the same counts where the old branch's
    neighbours agree, and the same last state up to the rotation about the axis (the
    pins, which fix it, may differ: two nodes tie for the farthest from the axis)."""
    short = tweezers_branches(dataclasses.replace(small_run.options, segment_points=8))
    assert len(short.branch("buckled_contact")) > 2 * 8
    for new, old in zip(small_run.branches, short.branches, strict=True):
        assert new.name == old.name
        a, b = new.special_points, old.special_points
        assert [p.kind for p in a] == [p.kind for p in b], new.name
        weight = small_run.options.diameter if new.name == "buckled_contact" else 1.0
        for p, r in zip(a, b):
            assert weight * abs(p.parameter - r.parameter) <= 2 * max(p.tolerance, r.tolerance)
        for s, count in zip(new.arclength, new.unstable_count):
            near = np.argsort(np.abs(old.arclength - s))[:2]
            if old.unstable_count[near[0]] == old.unstable_count[near[1]]:
                assert count == old.unstable_count[near[0]], (new.name, s)
        assert new.parameter_values[-1] == pytest.approx(old.parameter_values[-1], abs=1e-12)
        for key in ("extension", "writhe", "torque", "energy"):
            assert new.records[key][-1] == pytest.approx(old.records[key][-1], abs=1e-7), key


def test_pin_stop_refuses_a_state_its_pin_does_not_hold(small_run):
    """``pin_stop`` refuses exactly the states whose pin quality is below PIN_QUALITY: a
    stored state is accepted, the same state turned a quarter turn about the axis (the
    pinned node's rotation then moves across its pinned coordinate) refused."""
    from supercoil.problems.tweezers import pins

    branch = small_run.branch("buckled_contact")
    small_run.pin_branch(branch.name, len(branch) - 1)
    rod = small_run.rod_problem
    q = branch.states[-1]
    stop = pins.pin_stop(rod)
    assert rod.pin_quality(q) >= pins.PIN_QUALITY and stop(q) is None
    x = q.reshape(-1, 3)
    turned = np.column_stack([-x[:, 1], x[:, 0], x[:, 2]]).ravel()
    assert rod.pin_quality(turned) < pins.PIN_QUALITY
    assert "pin's quality fell" in stop(turned)
    small_run.pin_branch("straight")


def test_max_points_bounds_every_branch(small_run):
    """Runs are as long as ``segment_points`` (2000 by default): ``max_points`` still bounds
    each branch, and a branch it stops is reported incomplete."""
    opts = dataclasses.replace(small_run.options, max_points=10)
    result = tweezers_branches(opts)
    assert all(len(b) <= 10 for b in result.branches)
    assert result.branches[-1].status.name == "MAX_POINTS" and not result.ok


def test_a_mesh_coarser_than_the_resolved_core_says_its_counts_are_the_mesh_s(small_run):
    """The note on segments longer than min(1/3, 1.25 / ln(lambda / 0.54)) of the loop's
    core sqrt(A/F) = 1/lambda: at lambda = 20 (a third) and h lambda = 0.4 it names the
    ratio, the branch's folds and the nodes that resolve the core (2 + ceil(3 lambda));
    at exactly a third and below none. At lambda = 40 a third is not enough (the bound
    is 0.29: 140 nodes). Without a tension, none."""
    from supercoil.problems.tweezers.coarse import unresolved_loop_note

    branch = small_run.branch("buckled_contact")
    folds = len(branch.points_of_kind("fold"))
    lam = 20.0
    coarse = dataclasses.replace(small_run.options, tension=lam**2, n_nodes=52)
    note = unresolved_loop_note(coarse, branch)
    assert note is not None
    assert note.startswith("buckled_contact: its segments are 0.4 times the loop's core")
    assert "(more than 0.33 at lambda = 20)" in note
    assert f"({folds} folds on this branch); --nodes >= {2 + 60} resolve it" in note
    for nodes in (62, 100):  # h lambda = 1/3 exactly, and 0.2
        assert unresolved_loop_note(dataclasses.replace(coarse, n_nodes=nodes), branch) is None
    third = dataclasses.replace(coarse, tension=40.0**2, n_nodes=122)
    note = unresolved_loop_note(third, branch)
    assert "(more than 0.29 at lambda = 40)" in note and "--nodes >= 140 resolve it" in note
    assert unresolved_loop_note(dataclasses.replace(third, n_nodes=140), branch) is None
    assert unresolved_loop_note(dataclasses.replace(coarse, tension=0.0), branch) is None
