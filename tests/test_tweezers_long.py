"""Long rods in the tweezers: the sliding of a localised loop, verified bifurcations, and
the hard-core plectoneme (Neukirch & van der Heijden 2002; Clauvelin, Audoly & Neukirch
2009 without electrostatics)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from supercoil.continuation import SpecialPoint
from supercoil.problems.ply import hard_core_ply, spanning_note
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.problems.tweezers.verify import VERIFY_POINTS, verify_bifurcations
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.rod.sliding import SLIDING_TAIL


def clamped(points: np.ndarray) -> ClampedRodEnergy:
    return ClampedRodEnergy(Rod(len(points), twist_stiffness=1.5, closed=False),
                            straight_rod(len(points)), 0.0, tension=1.0)


def bump_curve(n: int, width: float, amplitude: float = 0.02) -> tuple[np.ndarray, callable]:
    """Nodes of the curve ``X(s) = (a b(s), 0, s - 1/2)``, ``b`` a Gaussian of ``width``
    about the middle, at the clamped rod's node spacing, and ``X``."""
    h = 1.0 / (n - 2)
    s = (np.arange(n) - 0.5) * h

    def curve(s):
        s = np.asarray(s, dtype=float)
        return np.stack([amplitude * np.exp(-((s - 0.5) / width) ** 2), 0 * s, s - 0.5],
                        axis=-1)

    return curve(s), curve


def test_sliding_generator_is_the_derivative_of_the_shifted_curve():
    """``g_i = (x_{i+1} - x_{i-1})/2 - h e_z`` is ``-h d/da [X(s_i - a) + a e_z]`` at
    ``a = 0`` up to the central difference's ``O(h^3)``: checked at two meshes, the
    error falling by about 8 when h halves."""
    errors = []
    for n in (202, 402):
        x, curve = bump_curve(n, 0.05)
        rod = clamped(x)
        h = rod.rod.edge_length
        g, tail = rod.sliding(x.ravel())
        s = (np.arange(n) - 0.5) * h
        eps = 1e-6
        shifted = (curve(s - eps) - curve(s + eps)) / (2 * eps) + np.array([0, 0, 1.0])
        inner = slice(2, n - 2)
        err = np.abs(g.reshape(-1, 3)[inner] + h * shifted[inner]).max()
        errors.append(err / h)
        assert tail < SLIDING_TAIL  # the bump's tails are straight to round-off
        assert rod.near_symmetry_modes(x.ravel()).shape == (1, 3 * n)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)  # O(h^2) relative to h


def test_sliding_is_no_symmetry_where_the_structure_reaches_the_clamps():
    x = straight_rod(60)
    rod = clamped(x)
    assert rod.near_symmetry_modes(x.ravel()).shape == (0, 180)  # nothing to slide
    wide, _ = bump_curve(60, 0.3)  # reaches the clamps
    assert rod.sliding(wide.ravel())[1] > SLIDING_TAIL
    assert rod.near_symmetry_modes(wide.ravel()).shape == (0, 180)
    rod.sliding_tail = None
    narrow, _ = bump_curve(60, 0.04)
    assert rod.near_symmetry_modes(narrow.ravel()).shape == (0, 180)


class FreeBranchDone(Exception):
    """Raised by ``on_branch`` once the contact-free branch is final (the contact branch
    is not needed here)."""


def contact_free_branch(n_nodes: int):
    """The contact-free branch of the long loop (C/A = 1, L/D = 100, F L^2/A = 1200:
    lambda = 35, T R^2/A = 0.03, the ply of the plectoneme that follows) at ``n_nodes``."""
    found = []

    def keep(branch, contact):
        if branch.name == "buckled":
            found.append(branch)
            raise FreeBranchDone

    with pytest.raises(FreeBranchDone):
        tweezers_branches(TweezersOptions(twist_ratio=1.0, length_over_diameter=100,
                                          tension=1200, n_nodes=n_nodes, turns=(0.0, 17.0),
                                          max_points=400, loop_sliding=True),
                          on_branch=keep)
    return found[0]


@pytest.fixture(scope="module")
def long_loops():
    return {n: contact_free_branch(n) for n in (102, 153)}


def test_long_loop_reaches_contact_with_one_unstable_mode(long_loops):
    """The localised loop's branch reaches its first contact at N and 1.5 N; the
    sliding of the loop, nearly null, is out of the count, which is one all along (the
    subcritical branch off the straight rod's double eigenvalue keeps one of the pair,
    the rotation about the axis removed), with no bifurcation; its states are
    equilibria of the problem without the sliding's phase row (KKT residual below
    1e-6). Without the row the corrector diverged at N = 160, and the count took 0, 1
    and 2 with eight located "bifurcations"."""
    for branch in long_loops.values():
        assert [p.kind for p in branch.special_points] == ["contact_onset"]
        assert np.all(branch.unstable_count == 1)
        assert np.max(branch.records["sliding_residual"]) < 1e-6


def test_long_loop_counts_agree_at_n_and_one_and_a_half_n(long_loops):
    """The same counts at the same turns on both meshes (each point of the finer branch
    against the coarse branch's nearest in turns), and the first contact at the same
    turns to the discretisation's error (measured 2.601 and 2.611)."""
    coarse, fine = long_loops[102], long_loops[153]
    nearest = np.abs(coarse.parameter_values[None, :]
                     - fine.parameter_values[:, None]).argmin(axis=1)
    assert np.array_equal(fine.unstable_count, coarse.unstable_count[nearest])
    onsets = [b.points_of_kind("contact_onset")[0].parameter for b in (coarse, fine)]
    assert onsets[0] == pytest.approx(onsets[1], rel=0.01)


def branch_with_counts(small_run, counts, bifurcations, folds=()):
    """``small_run``'s contact branch with the unstable counts ``counts`` (its first
    points) and special points: a located bifurcation at each index of ``bifurcations``
    (from the count there to the next one) and a fold at each of ``folds``."""
    base = small_run.branches[-1]
    n = len(counts)
    assert len(base) >= n
    branch = dataclasses.replace(
        base, unstable_count=np.asarray(counts, dtype=np.int64),
        **{k: getattr(base, k)[:n] for k in (
            "parameter_values", "states", "multipliers", "zero_modes", "determinant_sign",
            "nearest_eigenvalue", "tangents", "arclength")},
        records={k: v[:n] for k, v in base.records.items()})
    template = next(p for b in small_run.branches for p in b.special_points)
    points = [dataclasses.replace(template, kind="bifurcation", label="bifurcation", index=k,
                                  count_before=counts[k], count_after=counts[k + 1],
                                  located=True) for k in bifurcations]
    points += [dataclasses.replace(template, kind="fold", label="fold", index=k,
                                   count_before=counts[k], count_after=counts[k + 1])
               for k in folds]
    return dataclasses.replace(branch, special_points=tuple(
        sorted(points, key=lambda p: p.index)))


@pytest.fixture(scope="module")
def small_run():
    return tweezers_branches(TweezersOptions(
        twist_ratio=4 / 3, length_over_diameter=20, tension=20.0, turns=(0.0, 1.6),
        n_nodes=40, max_points=60))


def kinds(branch):
    return [(p.index, p.kind) for p in branch.special_points]


def test_a_persistent_count_change_is_a_bifurcation(small_run):
    counts = [0] * 6 + [1] * 6
    branch = verify_bifurcations(branch_with_counts(small_run, counts, [5]))
    assert kinds(branch) == [(5, "bifurcation")]


def test_a_flicker_is_a_count_change(small_run):
    """1 -> 2 -> 1 over two points (the measured flicker of a grazing eigenvalue)."""
    counts = [1] * 5 + [2, 2] + [1] * 5
    branch = verify_bifurcations(branch_with_counts(small_run, counts, [4, 6]))
    assert kinds(branch) == [(4, "count_change"), (6, "count_change")]
    assert all(isinstance(p, SpecialPoint) for p in branch.special_points)


def test_a_fold_bounds_the_window(small_run):
    """A change whose count a fold changes again within the window is still a
    bifurcation (the fold explains the second change): 0 -> 1 at 3, the fold 1 -> 0 at 5."""
    counts = [0] * 4 + [1, 1] + [0] * 6
    branch = verify_bifurcations(branch_with_counts(small_run, counts, [3], folds=[5]))
    assert kinds(branch) == [(3, "bifurcation"), (5, "fold")]
    assert VERIFY_POINTS >= 3  # the window is wider than the two points the fold leaves


def ply_energy(ply, length: float, angle: float, turns: float) -> float:
    """``U/A`` of a rod of length 1 with ``length`` of it in a uniform two-ply of
    ``angle`` and the rest straight, the end turned by ``turns`` (``hard_core_ply``'s
    model): the strands' bending ``kappa^2 l / 2`` with ``kappa = sin^2(angle)/R``, the
    twist ``C (2 pi Tw)^2 / 2`` with ``Tw = turns - l sin(2 angle)/(4 pi R)`` (Fuller;
    White & Bauer) and the dead load's ``-T (1 - l)``."""
    R = 0.5 * ply.diameter
    kappa = math.sin(angle) ** 2 / R
    twist = turns - length * math.sin(2 * angle) / (4 * math.pi * R)
    return (0.5 * kappa**2 * length + 0.5 * ply.twist_ratio * (2 * math.pi * twist) ** 2
            - ply.tension * (1 - length))


@pytest.mark.parametrize("ld,tension", [(40, 320), (100, 6400), (200, 22500)])
def test_hard_core_ply_is_stationary_in_its_length_and_angle(ld, tension):
    """The ply of :func:`~supercoil.problems.ply.hard_core_ply` makes ``ply_energy``
    stationary in the ply's length and angle (central differences, 4th order) at the
    turns that put half the rod in it, and spans the rod where its twist and writhe add
    up to the turns with all of it in the ply."""
    ply = hard_core_ply(1 / ld, tension, 1.5)
    turns = ply.twist_turns + 0.5 / ply.rod_per_turn
    h = 1e-4
    for dl, da in ((h, 0.0), (0.0, h)):
        def f(k, dl=dl, da=da):
            return ply_energy(ply, 0.5 + k * dl, ply.angle + k * da, turns)
        derivative = (8 * (f(1) - f(-1)) - (f(2) - f(-2))) / (12 * h)
        assert abs(derivative) < 1e-7 * tension
    R = 0.5 / ld
    writhe = math.sin(2 * ply.angle) / (4 * math.pi * R)
    assert ply.spanning_turns == pytest.approx(ply.twist_turns + writhe, rel=1e-12)
    assert 2 * math.pi * 1.5 * ply.twist_turns == pytest.approx(ply.torque, rel=1e-12)


def test_plectoneme_torque_plateau_and_slope_are_the_hard_core_plys():
    """C/A = 1.5, L/D = 40, F L^2/A = 320 (T R^2/A = 0.05), N = 82: along the plectoneme's
    growth (the contact branch past its last fold, where a contact interval runs along
    the ply) the torque is flat and the extension falls linearly with the turns, at the
    ply's values to 2 % (measured: 1.0 % and 0.7 % above the torque at N = 82 and 123,
    the slope within 0.7 % and 1.2 %)."""
    ld, tension = 40.0, 320.0
    result = tweezers_branches(TweezersOptions(
        twist_ratio=1.5, length_over_diameter=ld, tension=tension, n_nodes=82,
        turns=(0.0, 4.4)))
    assert result.ok
    ply = hard_core_ply(1 / ld, tension, 1.5)
    contact = result.branches[-1]
    last_fold = max(p.index for p in contact.special_points if p.kind == "fold")
    turns = contact.parameter_values[last_fold + 1:]
    torque = contact.records["torque"][last_fold + 1:]
    extension = contact.records["extension"][last_fold + 1:]
    intervals = contact.records["n_contact_intervals"][last_fold + 1:]
    plateau = (intervals > 0) & (torque <= 1.02 * torque.min())
    assert np.count_nonzero(plateau) >= 8
    assert np.all(np.diff(turns) > 0)
    assert torque.min() == pytest.approx(ply.torque, rel=0.02)
    slope = np.polyfit(turns[plateau], extension[plateau], 1)[0]
    assert slope == pytest.approx(ply.extension_per_turn, rel=0.02)
    assert math.degrees(ply.angle) == pytest.approx(23.53, abs=0.01)  # the ply at 0.05


def test_a_run_past_the_spanning_ply_says_so_and_its_torque_rises():
    """C/A = 4/3, L/D = 20, F L^2/A = 100, N = 44 to 4.2 turns: the hard-core ply would
    span the rod at 3.397 turns; the run's note says so, and past it the contact
    branch's torque lies above the ply's and rises with the turns (the turns go into
    twist), its extension falling more slowly than on the ply (measured 0.167 at 4.2
    turns where the ply would have none left)."""
    result = tweezers_branches(TweezersOptions(
        twist_ratio=4 / 3, length_over_diameter=20, tension=100.0, n_nodes=44,
        turns=(0.0, 4.2)))
    assert result.ok
    ply = result.ply
    assert spanning_note(ply, 3.0) is None
    assert spanning_note(ply, 4.2) in result.notes
    contact = result.branches[-1]
    past = contact.parameter_values > ply.spanning_turns
    assert np.count_nonzero(past) >= 3
    torque = contact.records["torque"][past]
    assert np.all(torque > ply.torque) and np.all(np.diff(torque) > 0)
    extension = contact.records["extension"][past]
    turns = contact.parameter_values[past]
    slope = (extension[-1] - extension[0]) / (turns[-1] - turns[0])
    assert ply.extension_per_turn < slope < 0


@pytest.mark.parametrize("ld,lam", [(20, 10), (40, 10)])
def test_every_branch_reaches_its_bound_on_a_small_grid(ld, lam):
    """From 0 turns through buckling and the first contact to 1.5 times the exact
    buckling turns (:func:`~supercoil.problems.greenhill.critical_turns`), C/A = 1.5,
    N = 2 n0 (n0 = L/D + 2, segments of D); lambda = 18 at L/D = 40 is the ply test's (to
    4.4 turns, 1.14 times the buckling turns).
    Every branch complete, the last on the bound."""
    from supercoil.problems.greenhill import critical_turns

    stop = 1.5 * critical_turns(1.5, lam**2)
    result = tweezers_branches(TweezersOptions(
        twist_ratio=1.5, length_over_diameter=ld, tension=lam**2, n_nodes=2 * (ld + 2),
        turns=(0.0, stop)))
    assert result.ok, result.notes
    assert [b.name for b in result.branches] == ["straight", "buckled", "buckled_contact"]
    assert result.branches[-1].parameter_values[-1] == pytest.approx(stop, abs=1e-9)


def test_a_thin_rods_loop_touches_itself_just_above_one_turn():
    """C/A = 1.5, L/D = 200, lambda = 10, N = n0: the subcritical branch is the localised
    loop (Love; Coyne 1990), whose writhe approaches 1 while its twist and torque fall
    with the end rotation; a thin rod's loop closes on itself where Tw is small, at
    turns = Tw + Wr just above 1, long before the branch could come back to 0 turns.
    Oracle: Fuller's closure at every point (the rod never passed through itself: a
    phantom rod's step from 1.06 to 0.96 turns carries one strand through the other, Wr
    jumping from 0.97 to -0.98 with the gap above D at both points), the writhe at the
    onset and the contact branch's start."""
    result = tweezers_branches(TweezersOptions(
        twist_ratio=1.5, length_over_diameter=200, tension=100.0, n_nodes=202,
        turns=(0.0, 3.34), max_points=30))
    buckled = result.branch("buckled")
    r = buckled.records
    assert np.max(np.abs(r["twist"] + r["writhe"] - r["turns"])) < 1e-9
    assert np.all(np.diff(buckled.parameter_values) < 0)  # subcritical, to the onset
    (onset,) = buckled.points_of_kind("contact_onset")
    assert 1.0 < onset.parameter < 1.1
    assert onset.records["writhe"] == pytest.approx(1.0, abs=0.05)
    assert 0 < onset.records["twist"] < 0.1
    assert onset.records["min_gap_over_diameter"] == pytest.approx(1.0, abs=1e-6)
    # its 30 points used up before the last turn: a branch stopped by the points it was
    # given is not followed again held on its symmetry (that is for one that stops)
    contact = result.branches[-1]
    assert contact.name == "buckled_contact" and len(contact) == 30


class ContactStarted(Exception):
    """Raised by ``on_point`` once the contact branch has the points a test needs."""


def test_centred_loop_stays_centred_and_its_contact_branch_starts():
    """At L/D = 100, lambda = 40, C/A = 1.5, N = 102 the localised loop bifurcates from the
    straight rod's symmetric critical mode: the clamped rod and the loop are invariant
    under the rotation by pi about an axis across the rod's middle, so the nodes' distances
    to the axis are mirror-symmetric (``r_i = r_{N-1-i}``) and the loop feels no force
    along its sliding. The contact-free branch, whose sliding is held by a phase row,
    keeps that symmetry (to 1e-3 of the largest radius; before the row's mode left out
    the turned end's axial translation and took the modes at each step's midpoint the
    loop slid off the middle, the radii's asymmetry 0.68, and the row held 2e-5 at the
    contact), its states are equilibria without the row to the contact branch's
    tolerance, and the contact branch's start from them converges (it diverged), its
    points in the barrier's hard core (gap above D) with ``Lk = Tw + Wr``."""
    kept = {}

    def watch(branch):
        if branch.name == "buckled_contact" and len(branch) >= 12:
            kept["contact"] = branch
            raise ContactStarted

    def final(branch, contact):
        kept[branch.name] = branch

    options = TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=1600,
                              n_nodes=102, turns=(0.0, 12.0), max_points=400,
                              loop_sliding=True)
    with pytest.raises(ContactStarted):
        tweezers_branches(options, on_point=watch, on_branch=final)
    free, contact = kept["buckled"], kept["contact"]
    radii = np.linalg.norm(free.states.reshape(len(free), -1, 3)[:, :, :2], axis=2)
    asymmetry = np.abs(radii - radii[:, ::-1]).max(axis=1) / radii.max(axis=1)
    assert np.all(asymmetry < 1e-3)
    assert np.max(free.records["sliding_residual"]) < options.contact_tolerance
    assert np.all(contact.records["min_gap_over_diameter"] > 1.0)
    assert np.all(contact.records["closure_error"] < 1e-9)
    assert np.max(contact.records["n_contact_points"]) >= 1
