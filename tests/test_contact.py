"""Self-contact treatments, the contact problem, the step guard and contact output."""

from __future__ import annotations

import numpy as np
import pytest
from contact_toys import CrossedRods, assert_derivatives_match_differences, assert_fresh_pair_state

from supercoil.contact import potentials
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import COUNT_KEYS, PLACE_KEYS, contact_summary
from supercoil.contact.solve import solve_contact
from supercoil.solvers.newton import NewtonOptions


# ------------------------------------------------------------------ potentials
@pytest.mark.parametrize("name", ["penalty", "augmented", "barrier"])
def test_potential_derivatives_match_finite_differences(name):
    D = 0.1
    gaps = np.array([-3e-3, -1e-4, 2e-4, 7e-4, 1.5e-3])
    lam = np.array([0.5, 0.0, 2.0, 0.0, 1.0])

    def psi(g):
        if name == "penalty":
            return potentials.penalty(g, 50.0)
        if name == "augmented":
            return potentials.augmented(g, lam, 50.0)
        return potentials.barrier(g, 50.0, 1e-2 * D)

    gaps = np.abs(gaps) if name == "barrier" else gaps
    _, d1, d2 = psi(gaps)
    eps = 1e-8
    vp, d1p, _ = psi(gaps + eps)
    vm, d1m, _ = psi(gaps - eps)
    np.testing.assert_allclose(d1, (vp - vm) / (2 * eps), rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(d2, (d1p - d1m) / (2 * eps), rtol=1e-5, atol=1e-6)


def test_barrier_is_infinite_at_contact_and_c2_at_activation():
    v, d1, d2 = potentials.barrier(np.array([0.0, -1.0, 1.0 - 1e-12, 1.0 + 1e-12]), 3.0, 1.0)
    assert np.isinf(v[:2]).all()
    np.testing.assert_allclose(v[2:], 0.0, atol=1e-20)
    np.testing.assert_allclose(d1[2:], 0.0, atol=1e-10)
    np.testing.assert_allclose(d2[2:], 0.0, atol=1e-10)


def test_augmented_update_is_the_pair_force():
    # At a stationary point of psi_AL the force -psi' equals the updated multiplier.
    g = np.array([-1e-3, 2e-3, 0.0])
    lam = np.array([1.0, 0.05, 0.3])
    _, first, _ = potentials.augmented(g, lam, 100.0)
    np.testing.assert_allclose(-first, potentials.augmented_update(g, lam, 100.0))


# ------------------------------------------------------------ crossed rods
def _crossed(treatment, **kw):
    toy = CrossedRods(load=2.0)
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, treatment=treatment, **kw))
    return toy, problem


@pytest.mark.parametrize("treatment", ["exact", "augmented", "penalty", "barrier"])
def test_crossed_rods_contact_force_equals_load(treatment):
    toy, problem = _crossed(treatment)
    res = solve_contact(problem, toy.points.ravel(), NewtonOptions(max_iterations=200))
    assert res.converged, res.message
    summary = contact_summary(problem, res.q, res.multipliers)
    total = sum(c["force"] for c in summary["contacts"])
    force_scale = toy.rod.length**2 / toy.rod.bending_stiffness
    # oracle: vertical equilibrium of rod B, the contact carries the whole load
    np.testing.assert_allclose(total / force_scale, toy.load, rtol=1e-6)
    assert summary["n_contact_points"] == 1 and summary["n_contact_intervals"] == 0
    d_min = summary["min_gap_over_diameter"]
    if treatment == "penalty":
        # the penalty needs a penetration F / k
        np.testing.assert_allclose((1 - d_min) * 0.05, toy.load / problem.stiffness, rtol=1e-6)
    elif treatment == "barrier":
        assert 1.0 < d_min < 1.0 + problem.options.barrier_activation
    else:
        assert abs(d_min - 1.0) <= problem.options.penetration_tolerance


@pytest.mark.parametrize("treatment", ["penalty", "barrier"])
def test_remembered_summaries_equal_fresh_ones_and_are_copies(treatment):
    """contact_summary remembers its result per (state, multipliers, stiffness): oracle,
    the uncached summary; a caller's edit does not reach the memo; another stiffness is
    another summary (the penalty's force is stiffness times penetration)."""
    from supercoil.contact.report import computed_contact_summary

    toy, problem = _crossed(treatment)
    res = solve_contact(problem, toy.points.ravel(), NewtonOptions(max_iterations=200))
    first = contact_summary(problem, res.q, res.multipliers)
    assert first == computed_contact_summary(problem, res.q, res.multipliers)
    first["contacts"].clear()
    again = contact_summary(problem, res.q.copy(), res.multipliers.copy())
    assert again == computed_contact_summary(problem, res.q, res.multipliers) and again["contacts"]
    again["contacts"][0]["force"] = -1.0  # an edit inside an entry does not reach it either
    assert contact_summary(problem, res.q, res.multipliers) == computed_contact_summary(
        problem, res.q, res.multipliers)
    for keys in (COUNT_KEYS, PLACE_KEYS):  # a selection of keys: those of the summary
        part = contact_summary(problem, res.q, res.multipliers, keys)
        assert part == {k: again[k] for k in keys} and list(part) == list(keys)
    part["contact_points"].clear()
    assert contact_summary(problem, res.q, res.multipliers, PLACE_KEYS)["contact_points"]
    problem.stiffness *= 2.0
    stiffer = contact_summary(problem, res.q, res.multipliers)
    assert stiffer == computed_contact_summary(problem, res.q, res.multipliers)
    assert stiffer["contacts"][0]["force"] != again["contacts"][0]["force"]


def test_penalty_tends_to_exact_as_stiffness_grows():
    toy, exact = _crossed("exact")
    ref = solve_contact(exact, toy.points.ravel())
    z_exact = ref.q[3 * toy.n + 2]
    errors = []
    for k in (1e3, 1e4, 1e5):
        # a tolerance that keeps the stiffness as given (not raised to a penetration bound)
        toy, pen = _crossed("penalty", stiffness=k, penalty_tolerance=1.0)
        res = solve_contact(pen, toy.points.ravel())
        assert res.converged
        errors.append(abs(res.q[3 * toy.n + 2] - z_exact))
    # penetration F/k: the error falls tenfold per tenfold stiffness
    np.testing.assert_allclose(np.array(errors[:-1]) / np.array(errors[1:]), 10.0, rtol=1e-3)


def test_contact_energy_derivatives_match_finite_differences():
    toy, problem = _crossed("penalty", stiffness=50.0)
    q = toy.points.ravel().copy()
    rng = np.random.default_rng(3)
    q[3 * toy.n:] += 1e-3 * rng.standard_normal(3 * toy.n)
    # push B into A so that pairs penetrate
    q[3 * toy.n + 2 :: 3] -= 0.25 - 0.045
    assert problem.contact_energy(q) > 0
    assert_derivatives_match_differences(problem, q, range(3 * toy.n, 6 * toy.n, 5))


def test_active_contact_removes_the_free_direction_from_stability():
    """Rod B resting on A: without the contact its vertical translation is a zero
    mode (the load is linear); the active contact removes it from the admissible
    directions, and the state is strictly stable."""
    from supercoil.stability.analysis import analyse

    toy, problem = _crossed("exact")
    res = solve_contact(problem, toy.points.ravel())
    with_contact = analyse(problem, res.q, res.multipliers, n_modes=3)
    assert with_contact.unstable_count == 0 and with_contact.zero_modes == 0
    without = analyse(toy, res.q, np.zeros(0), n_modes=3)
    assert without.zero_modes == 1 and without.unstable_count == 0


def test_step_guard_stops_a_segment_passing_through_another():
    toy, problem = _crossed("penalty")
    q = toy.points.ravel()
    dq = np.zeros_like(q)
    dq[3 * toy.n + 2 :: 3] = -0.5  # B moves from z = 0.25 to -0.25: straight through A
    # an end-of-step check sees nothing wrong
    assert problem.min_distance(q + dq) > problem.diameter
    bound = problem.step_bound(q, dq)
    # the guard stops B at half a diameter above A's centreline at the latest
    assert 0 < bound <= (0.25 - 0.5 * problem.diameter) / 0.5 + 1e-12
    assert problem.min_distance(q + bound * dq) >= 0.5 * problem.diameter * (1 - 1e-9)


def test_barrier_step_guard_keeps_a_gap():
    toy, problem = _crossed("barrier")
    q = toy.points.ravel()
    dq = np.zeros_like(q)
    dq[3 * toy.n + 2 :: 3] = -0.5
    bound = problem.step_bound(q, dq)
    assert problem.min_distance(q + bound * dq) > problem.diameter


def test_options_validate():
    with pytest.raises(ValueError, match="diameter"):
        ContactOptions(diameter=0.0)
    with pytest.raises(ValueError, match="diameter"):
        ContactOptions(diameter=-1.0)
    with pytest.raises(ValueError, match="treatment"):
        ContactOptions(diameter=0.1, treatment="springs")
    assert ContactOptions(diameter=0.2).exclusion_length == pytest.approx(0.1 * np.pi)


def test_newton_never_lets_a_rod_pass_through_another():
    """A load far beyond what a soft penalty can hold: without the collision
    guard the Newton iterates would carry rod B through rod A (the penalty
    force then pushes it further down). With the guard B stays above A, and
    the state is flagged as inadmissible instead of being returned silently."""
    toy = CrossedRods(load=50.0)
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, treatment="penalty",
                                                 stiffness=10.0))
    res = solve_contact(problem, toy.points.ravel(), NewtonOptions(max_iterations=60))
    z_b = res.q[3 * toy.n + 2 :: 3]
    # B's segment over the crossing (y = 0, between its two middle nodes) is
    # still above A's centreline (z = 0): squeezed, but never passed through
    middle = [toy.n // 2 - 1, toy.n // 2]
    assert np.all(z_b[middle] > 0)
    assert not res.admissible
    assert "penetration" in res.message


def test_a_pulling_contact_is_flagged_not_dropped():
    """Hold rod B on A with the contact as an equality while the load pulls B
    away: the multiplier is a negative (pulling) contact force, which the
    output must flag; the exact solve itself releases it."""
    toy = CrossedRods(load=-2.0, height=0.05)  # B's centreline exactly D above A's
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, treatment="exact"))
    q0 = toy.points.ravel()
    st = problem.pair_state(q0, 0.05 * (1 + 1e-9))
    problem.active = st.pairs[:1]
    from supercoil.solvers.newton import newton

    held = newton(problem, q0, NewtonOptions(mode="stationary"))
    assert held.converged
    summary = contact_summary(problem, held.q, held.multipliers)
    assert summary["negative_contact_forces"] == 1
    force_scale = toy.rod.length**2 / toy.rod.bending_stiffness
    np.testing.assert_allclose(summary["contacts"][0]["force"] / force_scale, -2.0, rtol=1e-8)



def test_exact_active_set_releases_a_pulling_contact():
    """B anchored by springs at z = 0.25 and pushed onto A: contact, force = load.
    Reverse the load on the same problem: the previous active set gives a
    pulling force, the active-set loop releases it, and B hangs above A where
    the anchor balances the load (z = 0.25 + load / anchor)."""
    toy = CrossedRods(load=30.0, anchor=100.0)
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, treatment="exact"))
    pushed = solve_contact(problem, toy.points.ravel())
    assert pushed.converged and len(problem.active) >= 1
    force_scale = toy.rod.length**2 / toy.rod.bending_stiffness
    total = sum(c["force"] for c in contact_summary(problem, pushed.q,
                                                     pushed.multipliers)["contacts"])
    # anchor holds part of the load: contact force = load - anchor * (0.25 - z)
    z = pushed.q[3 * toy.n + 2 :: 3].mean()
    np.testing.assert_allclose(total / force_scale, 30.0 - 100.0 * (0.25 - z), rtol=1e-6)
    pulled = CrossedRods(load=-30.0, anchor=100.0)
    problem.base = pulled  # same problem object, previous active set kept
    released = solve_contact(problem, pushed.q)
    assert released.converged and len(problem.active) == 0
    np.testing.assert_allclose(released.q[3 * toy.n + 2 :: 3], 0.25 + 30.0 / 100.0, rtol=1e-8)
    summary = contact_summary(problem, released.q, released.multipliers)
    assert summary["contacts"] == [] and summary["negative_contact_forces"] == 0


# --------------------------------------------------------------- grouping
def test_grouping_a_line_contact_across_the_seam():
    from supercoil.contact.report import group_contacts

    h = 0.01
    k = np.arange(6)
    a = np.mod(0.98 + k * h, 1.0)  # strand 1 runs across s = 0
    b = 0.5 - k * h  # antiparallel strand 2
    lo, hi = np.minimum(a, b), np.maximum(a, b)  # stored as s1 < s2: the order flips at 0
    force = np.full(6, 2.0)
    points, intervals = group_contacts(lo, hi, force, h, closed=True)
    assert points == [] and len(intervals) == 1
    iv = intervals[0]
    np.testing.assert_allclose([iv["s1_start"], iv["s1_end"]], [0.45, 0.5], atol=1e-12)
    np.testing.assert_allclose([iv["s2_start"], iv["s2_end"]], [0.98, 0.03], atol=1e-12)
    # total force over the length the six contacts stand for (5 h + h)
    np.testing.assert_allclose(iv["force_per_length"], 12.0 / (6 * h))


def test_grouping_a_point_across_the_seam_and_separate_points():
    from supercoil.contact.report import group_contacts

    h = 0.01
    # one point contact split over two pairs on either side of s = 0, and a
    # second contact far from it; forces 1, 3 and 5
    s1 = np.array([0.4, 0.402, 0.2])
    s2 = np.array([0.999, 0.001, 0.7])
    points, intervals = group_contacts(s1, s2, np.array([1.0, 3.0, 5.0]), h, closed=True)
    assert intervals == [] and len(points) == 2
    seam = min(points, key=lambda p: abs(p["force"] - 4.0))
    assert seam["force"] == pytest.approx(4.0)
    # force-weighted position: (0.999 * 1 + 1.001 * 3) / 4 = 1.0005 -> 0.0005
    assert seam["s1"] == pytest.approx(0.0005) and seam["s2"] == pytest.approx(0.4015)
    # on an open rod the same positions are far apart: three points
    points, intervals = group_contacts(s1, s2, np.array([1.0, 3.0, 5.0]), h, closed=False)
    assert len(points) == 3 and intervals == []


def test_a_state_that_changed_the_linking_number_is_refused():
    """Newton's per-step guard: a figure-eight with one strand just above the
    other at its crossing (z = +-eps), then the same curve with the strands
    swapped (its mirror image: a crossing change). The double-sum writhe jumps
    by 2 while the writhe carried by the rod's frames does not: the second
    state is refused, the first is admissible."""
    from supercoil.geometry.curves import resample_closed
    from supercoil.rod.closed import ClosedRodEnergy
    from supercoil.rod.model import Rod
    from supercoil.topology import writhe

    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    eps = 0.01

    def eight(e):
        return resample_closed(np.stack([np.sin(t), np.sin(t) * np.cos(t), e * np.cos(t)], 1),
                               80)

    above, swapped = eight(eps), eight(-eps)
    base = ClosedRodEnergy(Rod(n_nodes=80, twist_stiffness=1.0), above, 0.0)
    problem = ContactProblem(base, ContactOptions(diameter=0.005))
    assert problem.admissible(above.ravel())
    # the crossing change: carried and double-sum writhe differ by 2 turns
    gap = problem.base.writhe_local(swapped.ravel()) - writhe(swapped)
    assert abs(abs(gap) - 2.0) < 0.1
    assert not problem.admissible(swapped.ravel())


def test_pair_states_from_the_verlet_list_equal_a_new_broad_phase():
    """pair_state serves cutoffs up to 2 D from a neighbour list kept since the last
    broad phase (fast path); against the broad phase run at each state (the previous
    code): the same pairs, distances and feet, bit for bit, through small moves (list
    reused), large ones (list rebuilt) and the cutoffs the solvers ask for."""
    from supercoil.problems.ring import twisted_circle_problem

    rod, q = twisted_circle_problem(2 / 3, 0.0, 80)
    x0 = q.reshape(-1, 3).copy()
    x0[:, 1] *= 0.06  # a flattened ring: the two long sides face each other
    D = 0.02
    problem = ContactProblem(rod, ContactOptions(diameter=D))
    rng = np.random.default_rng(11)
    x = x0.copy()
    reused = 0
    for step in range(60):
        scale = D * (0.02 if step % 7 else 0.6)  # mostly small moves, now and then a jump
        x = x + scale * rng.standard_normal(x.shape)
        state = x.ravel()
        for cutoff in (D, 1.01 * D, D + 0.3 * D * rng.random(), 2.0 * D, 3.0 * D):
            before = problem.curve._verlet
            fast = problem.pair_state(state, cutoff)
            reused += problem.curve._verlet is before
            assert_fresh_pair_state(problem, state, cutoff, fast)
    assert reused > 100  # the list did serve most states


@pytest.mark.parametrize("count", [0, 1, 5, 60, 128, 129, 300])
@pytest.mark.parametrize("periodic", [False, True])
def test_close_pairs_of_the_grouping_equal_the_tree(count, periodic, monkeypatch):
    """Oracle: ``cKDTree.query_pairs`` in the max norm (with ``boxsize`` 1 when
    periodic), which the grouping asked before. Points paired in numpy (up to
    TREE_ABOVE_POINTS) or by the tree: the same pairs, also across the seam s = 0."""
    from scipy.spatial import cKDTree

    from supercoil.contact import report

    rng = np.random.default_rng(count)
    points = rng.random((count, 2)) * (1.2 if periodic else 0.6) - 0.1
    for reach in (0.015, 0.1):
        tree = cKDTree(np.mod(points, 1.0) if periodic else points,
                       boxsize=1.0 if periodic else None)
        expected = {tuple(map(int, p)) for p in tree.query_pairs(reach, p=np.inf)}
        for threshold in (0, 10**6):
            monkeypatch.setattr(report, "TREE_ABOVE_POINTS", threshold)
            found = report.close_pairs(points, reach, periodic)
            assert all(i < j for i, j in found) and len(set(found)) == len(found)
            assert set(found) == expected
