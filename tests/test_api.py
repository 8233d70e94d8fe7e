"""The public API (``import supercoil``): problems, verbs and results, against exact values."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

import supercoil as sc
from supercoil.problems.greenhill import critical_turns


def circle_energy(twist_ratio, excess_link):
    return 2 * np.pi**2 * (1 + twist_ratio * excess_link**2)


def michell(twist_ratio, mode=2):
    return np.sqrt(mode**2 - 1) / twist_ratio


# ------------------------------------------------------------------------ problems
@pytest.mark.parametrize("make", [
    lambda: sc.Rod(twist_ratio=-1.0),
    lambda: sc.Rod(twist_ratio=float("nan")),
    lambda: sc.Rod(twist_ratio=1.0, nodes=3),
    lambda: sc.Rod(twist_ratio=1.0, nodes=10**9),
    lambda: sc.Rod(twist_ratio=1.0, nodes=12.5),
    lambda: sc.Rod(twist_ratio=1.0, curvature="exact"),
    lambda: sc.Barrier(length_over_diameter=3.0),
    lambda: sc.Contact(length_over_diameter=100.0),
    lambda: sc.Ring(sc.Rod(1.0), excess_link=float("inf")),
    lambda: sc.Ring(sc.Rod(1.0), excess_link=1.0, initial=np.zeros((10, 3))),
    lambda: sc.Ring(sc.Rod(1.0), 1.0, contact=sc.Barrier(50.0), initial=np.zeros((10, 2))),
    lambda: sc.Tweezers(sc.Rod(1.0, nodes=40)),
    lambda: sc.Tweezers(sc.Rod(1.0, nodes=40), tension=1.0, end_distance=0.5),
    lambda: sc.Tweezers(sc.Rod(1.0, nodes=40), end_distance=1.0),
    lambda: sc.Tweezers(sc.Rod(1.0, nodes=40), tension=-1.0),
    lambda: sc.Tweezers(sc.Rod(1.0, nodes=40), tension=1.0, contact=sc.ExactContact(50.0)),
    lambda: sc.ring_diagram(sc.Rod(1.0, nodes=24), sc.Barrier(50.0), not_an_option=1),
    lambda: sc.ring_diagram(sc.Rod(1.0, nodes=24), sc.Barrier(50.0), modes=(1,)),
    lambda: sc.equilibrium(sc.Tweezers(sc.Rod(1.0, nodes=40), tension=1.0)),
])
def test_invalid_input_is_an_input_error_naming_the_input(make):
    with pytest.raises(sc.InputError) as info:
        make()
    assert len(str(info.value)) > 20  # says what is wrong and what is valid


def test_problems_are_immutable_and_compare_by_value():
    rod = sc.Rod(twist_ratio=2 / 3, nodes=48)
    with pytest.raises(dataclasses.FrozenInstanceError):
        rod.nodes = 50
    assert rod == sc.Rod(2 / 3, 48)
    assert sc.Barrier(100) == sc.Barrier(100.0) and sc.Barrier(100) != sc.Penalty(100)
    assert sc.Barrier(100).diameter == pytest.approx(0.01, rel=1e-15)


# --------------------------------------------------------------------- equilibrium
@pytest.fixture(scope="module")
def circle_states():
    rod = sc.Rod(twist_ratio=2 / 3, nodes=48)
    return sc.equilibrium(sc.Ring(rod, 1.0)), sc.equilibrium(sc.Ring(rod, 3.0))


def test_twisted_circle_is_stable_below_michell_and_a_saddle_above(circle_states):
    below, above = circle_states
    assert 1.0 < michell(2 / 3) < 3.0 < michell(2 / 3, 3)
    assert below.status is sc.EquilibriumStatus.STABLE and below.unstable_count == 0
    # Michell's pair (cos and sin of mode 2) has crossed: the count jumps by two
    assert above.status is sc.EquilibriumStatus.UNSTABLE and above.unstable_count == 2
    for eq in circle_states:
        assert abs(eq.writhe) < 1e-10  # a planar circle
        assert eq.twist == pytest.approx(eq.excess_link, abs=1e-10)
        # the regular polygon's energy tends to the circle's as O(1/N^2)
        exact = circle_energy(2 / 3, eq.excess_link)
        assert abs(eq.energy - exact) / exact < 2 * (2 * np.pi / 48) ** 2


def test_stability_recomputed_from_the_state_equals_the_solves(circle_states):
    for eq in circle_states:
        again = sc.stability(eq, n_modes=4)
        assert again.unstable_count == eq.unstable_count
        assert again.zero_modes == eq.stability.zero_modes
        k = min(len(again.eigenvalues), len(eq.stability.eigenvalues))
        np.testing.assert_allclose(again.eigenvalues[:k], eq.stability.eigenvalues[:k],
                                   rtol=1e-8)
        assert again.modes.shape == (len(again.eigenvalues), 48, 3)
    # the unstable modes of the circle above Michell's point are its m = 2 modes: the
    # out-of-plane displacement z has two sign changes per half turn (cos 2 theta)
    unstable = sc.stability(circle_states[1], n_modes=1).modes[0]
    z = unstable[:, 2] - unstable[:, 2].mean()
    assert np.count_nonzero(np.diff(np.sign(np.append(z, z[0])))) == 4


def test_results_are_read_only_with_short_reprs(circle_states):
    eq = circle_states[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        eq.energy = 0.0
    with pytest.raises(ValueError):
        eq.points[0, 0] = 1.0
    with pytest.raises(TypeError):
        eq.record["energy"] = 0.0
    text = repr(eq)
    assert text.count("\n") <= 3 and len(text) < 400 and "array" not in text


def test_supercoiled_ring_keeps_its_link_and_does_not_penetrate():
    rod = sc.Rod(twist_ratio=2 / 3, nodes=60)
    eq = sc.equilibrium(sc.Ring(rod, 3.0, contact=sc.Barrier(length_over_diameter=60)))
    assert eq.status is sc.EquilibriumStatus.STABLE, eq.message
    # Lk = Tw + Wr with Tw from the material frames and Wr from the double sum
    assert abs(eq.twist + eq.writhe - 3.0) < 1e-6
    assert abs(sc.writhe(eq.points) - eq.writhe) < 1e-12
    assert 0.5 < eq.writhe < 3.0  # supercoiled: part of the link became writhe
    assert eq.contacts["min_gap_over_diameter"] >= 1 - 1e-3
    assert eq.contacts["n_contact_points"] + eq.contacts["n_contact_intervals"] >= 1


# ---------------------------------------------------------------- a user's energy
def pitchfork():
    """E = x^4/4 - lam x^2/2 + y^2/2: x = 0 loses stability at lam = 0 to x = +-sqrt(lam)."""
    return sc.Energy(
        energy=lambda q, lam: q[0] ** 4 / 4 - lam * q[0] ** 2 / 2 + q[1] ** 2 / 2,
        gradient=lambda q, lam: np.array([q[0] ** 3 - lam * q[0], q[1]]),
        hessian=lambda q, lam: sp.diags([3 * q[0] ** 2 - lam, 1.0]),
        n_dofs=2)


def test_continuation_of_a_users_energy_finds_and_switches_the_pitchfork():
    energy = pitchfork()
    options = sc.ContinuationOptions(max_step=0.1, event_tolerance=1e-10)
    trivial = sc.continuation(energy, [0.0, 0.0], start=-1.0, bounds=(-1.0, 1.0),
                              options=options)
    assert trivial.ok and trivial.parameter_values[-1] == pytest.approx(1.0, abs=1e-12)
    (point,) = trivial.points_of_kind("bifurcation")
    assert abs(point.parameter) < 1e-8
    assert (point.count_before, point.count_after) == (0, 1)
    branch = sc.switch_branch(energy, trivial, point, bounds=(-1.0, 1.0), options=options)
    x, lam = branch.states[:, 0], branch.parameter_values
    assert len(branch) > 5 and np.all(lam > 0)
    np.testing.assert_allclose(x**2, lam, atol=1e-8)
    assert np.all(branch.unstable_count[lam > 1e-3] == 0)  # the buckled branch is stable
    again = sc.continuation(energy, [0.0, 0.0], start=-1.0, bounds=(-1.0, 1.0),
                            options=options)
    np.testing.assert_array_equal(again.parameter_values, trivial.parameter_values)


def test_continuation_refuses_a_start_of_the_wrong_size():
    with pytest.raises(sc.InputError):
        sc.continuation(pitchfork(), [0.0, 0.0, 0.0], start=0.0)


# ------------------------------------------------------------ diagrams and tweezers
def test_ring_diagram_locates_michells_point():
    rod = sc.Rod(twist_ratio=2 / 3, nodes=24)
    diagram = sc.ring_diagram(rod, sc.Barrier(length_over_diameter=40), modes=(2,),
                              max_excess_link=2.8, free_max_points=40, contact_max_points=5)
    assert list(diagram.branches)[:2] == ["circle", "alpha"]
    first = [p for p in diagram.branches["circle"].special_points if p.kind == "bifurcation"]
    # O(h^2) discretisation error at N = 24
    assert first[0].parameter == pytest.approx(michell(2 / 3), rel=2e-2)
    assert (first[0].count_before, first[0].count_after) == (0, 2)
    # the contact-free branch ends at its located first contact: no state of it lies
    # inside the tube (its closest approach is D at the last point, above D before)
    gaps = diagram.branches["alpha"].records["min_gap_over_diameter"]
    assert np.all(gaps[:-1] > 1.0) and abs(gaps[-1] - 1.0) < 1e-6
    assert diagram.branches["alpha"].special_points[-1].kind == "contact_onset"
    # the contact branch stopped at its point limit: the diagram says so, and why
    assert diagram.status is sc.RunStatus.INCOMPLETE and not diagram.ok
    assert diagram.branches["alpha_contact"].status is sc.ContinuationStatus.MAX_POINTS
    assert "alpha_contact: MAX_POINTS" in diagram.message
    assert repr(diagram).count("\n") <= 3


def test_tweezers_buckle_at_greenhills_threshold_and_keep_turns_equal_tw_plus_wr():
    rod = sc.Rod(twist_ratio=4 / 3, nodes=40)
    problem = sc.Tweezers(rod, tension=20.0, contact=sc.Barrier(length_over_diameter=20))
    result = sc.tweezers(problem, turns=(0.0, 1.6), max_points=60)
    straight = result.branches["straight"]
    (buckling,) = straight.points_of_kind("bifurcation")
    assert buckling.parameter == pytest.approx(critical_turns(4 / 3, 20.0), rel=1e-2)
    for b in result.branches.values():
        turns = b.parameter_values
        np.testing.assert_allclose(b.records["twist"] + b.records["writhe"], turns, atol=1e-6)


def test_branch_and_special_point_reprs_are_short():
    energy = pitchfork()
    branch = sc.continuation(energy, [0.0, 0.0], start=-1.0, bounds=(-1.0, 1.0),
                             options=sc.ContinuationOptions(max_step=0.1))
    text = repr(branch)
    assert text.count("\n") <= 2 and "array" not in text and "1 bifurcation" in text
    assert repr(branch.special_points[0]).startswith("SpecialPoint(bifurcation")


def test_save_and_load_round_trip_every_array(tmp_path, circle_states):
    rod = sc.Rod(twist_ratio=2 / 3, nodes=24)
    diagram = sc.ring_diagram(rod, sc.Barrier(length_over_diameter=40), modes=(2,),
                              max_excess_link=2.8, free_max_points=40, contact_max_points=5)
    path = sc.save(diagram, tmp_path / "diagram.h5")
    with pytest.raises(sc.InputError):
        sc.save(diagram, path)  # never overwritten unless asked
    loaded = sc.load(path)
    for name, branch in diagram.branches.items():
        again = loaded.branch(name)
        np.testing.assert_array_equal(again.states, branch.states)
        np.testing.assert_array_equal(again.parameter_values, branch.parameter_values)
        np.testing.assert_array_equal(again.unstable_count, branch.unstable_count)
        assert [p.kind for p in again.special_points] == [p.kind for p in branch.special_points]
    # the stored diagram draws: the figures of every kind it has data for
    figures = sc.plot(path, out=tmp_path / "figures" / "ring")  # created, as by the command
    assert {p.parent for p in figures} == {tmp_path / "figures" / "ring"}
    names = {p.name for p in figures}
    assert {"diagram.png", "contact_map.png", "configurations.png"} <= names, names
    assert all(p.stat().st_size > 5_000 for p in figures)
    with pytest.raises(sc.InputError):
        sc.plot(path, kind="no-such-figure", out=tmp_path)
    with pytest.raises(sc.InputError, match="is a file"):
        sc.plot(path, out=path)
    eq = circle_states[1]
    loaded = sc.load(sc.save(eq, tmp_path / "ring.h5"))
    np.testing.assert_array_equal(loaded.branch("ring").states[0], eq.points.ravel())
    assert loaded.branch("ring").unstable_count[0] == 2
