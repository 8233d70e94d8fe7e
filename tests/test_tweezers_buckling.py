"""The tweezers' buckling of long rods under a large tension: the located bifurcation
against Greenhill's clamped condition on coarse meshes, the switch onto the buckled
branch, and where the loop's sliding is an approximate symmetry (Champneys & Thompson
1996 for the localised loop)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from supercoil.errors import InputError
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.problems.tweezers.problem import clamped_problem
from supercoil.problems.tweezers.straight import (
    GREENHILL_GAP,
    resolution_note,
    straight_branch,
    unreached_note,
)
from supercoil.rod.sliding import sliding_threshold


def located(lam: float, n: int) -> tuple[float, TweezersOptions]:
    """The straight rod's first bifurcation (turns) at ``lambda = L sqrt(F/A)``, N nodes."""
    opts = TweezersOptions(twist_ratio=1.5, length_over_diameter=None, tension=lam**2,
                           n_nodes=n, turns=(0.0, 1.6 * critical_turns(1.5, lam**2)))
    rod, q0 = clamped_problem(opts)
    branch = straight_branch(opts, rod, q0, None)
    return branch.points_of_kind("bifurcation")[0].parameter, opts


def test_coarse_buckling_is_late_by_the_segments_estimate_and_the_note_names_enough_nodes():
    """Oracle: Greenhill's clamped condition (exact, :mod:`~supercoil.problems.greenhill`).
    At lambda = 40 the discrete rod buckles late by about (k h)^2 / 8, k = sqrt(F/A): 43 %
    at k h = 2, 12 % at 1; the note names the N (66) at which the gap is below 5 %, and
    there is none there."""
    lam = 40.0
    exact = critical_turns(1.5, lam**2)
    at_42, opts = located(lam, 42)
    kh = lam / 40
    assert at_42 / exact - 1 == pytest.approx(kh**2 / 8, rel=0.05)
    note = resolution_note(opts, at_42)
    assert note is not None and "--nodes >= 66 " in note
    at_66, opts = located(lam, 66)
    assert 0 < at_66 / exact - 1 < GREENHILL_GAP
    assert at_66 / exact - 1 == pytest.approx((lam / 64) ** 2 / 8, rel=0.05)
    assert resolution_note(opts, at_66) is None


def test_a_threshold_below_the_last_turn_that_the_mesh_does_not_reach_is_named():
    """At lambda = 40, N = 42 the discrete rod buckles 12 % above Greenhill's clamped
    condition (previous test): run up to 6 % above it, the straight rod does not buckle,
    and the result says why and names N = 84 (the estimate (k h)^2 / 8 at half the 6 %),
    at which the rod buckles below that last turn (oracle: the exact threshold and the
    located bifurcation at N = 84)."""
    lam = 40.0
    exact = critical_turns(1.5, lam**2)
    opts = TweezersOptions(twist_ratio=1.5, length_over_diameter=None, tension=lam**2,
                           n_nodes=42, turns=(0.0, 1.06 * exact))
    result = tweezers_branches(opts)
    assert [b.name for b in result.branches] == ["straight"]
    assert not result.branch("straight").points_of_kind("bifurcation")
    assert any("does not buckle below" in n for n in result.notes)
    assert any("below the last turn" in n and "--nodes >= 84 " in n for n in result.notes)
    at_84 = dataclasses.replace(opts, n_nodes=84)
    rod, q0 = clamped_problem(at_84)
    found = straight_branch(at_84, rod, q0, None).points_of_kind("bifurcation")
    assert found and found[0].parameter < at_84.turns[1]
    assert unreached_note(at_84) is None
    assert unreached_note(dataclasses.replace(opts, turns=(0.0, 0.99 * exact))) is None


def test_buckled_branch_leaves_the_straight_rod_at_lambda_150():
    """L sqrt(F/A) = 150 at N = 102 (segments 1.5 times sqrt(A/F)): the critical mode is a
    helix of 4 segments a turn, and a first point at a fixed arclength turned the rod's
    edges by radians. The switch finds the subcritical branch (turns falling from the
    bifurcation), on which turns = Tw + Wr, and the result says the mesh under-resolves
    the helix."""
    result = tweezers_branches(TweezersOptions(
        twist_ratio=1.5, length_over_diameter=None, tension=22500.0, n_nodes=102,
        turns=(36.0, 40.0), max_points=12))
    straight, buckled = result.branch("straight"), result.branch("buckled")
    start = straight.points_of_kind("bifurcation")[0].parameter
    assert len(buckled) == 12
    turns = buckled.parameter_values
    assert turns[0] < start and np.all(np.diff(turns) < 0)
    r = buckled.records
    assert np.max(np.abs(r["twist"] + r["writhe"] - r["turns"])) < 1e-9
    assert r["extension"][-1] < r["extension"][0] < 1.0
    assert any("above Greenhill's clamped condition" in n and "--nodes >= 240" in n
               for n in result.notes)


def test_loop_sliding_applies_in_contact_only_where_the_mesh_resolves_the_loops_core():
    """The loop's core is sqrt(A/F) = L / lambda long: on segments longer than half of
    it the mesh pins the loop in contact, and the sliding is no approximate symmetry of
    the contact branch (no phase row there); the contact-free branch carries the row on
    every mesh."""
    def opts(n):
        return TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=22500.0,
                               n_nodes=n, loop_sliding=True)

    assert opts(202).loop_slides and opts(302).loop_slides
    assert not opts(202).loop_slides_in_contact and opts(302).loop_slides_in_contact
    off = dataclasses.replace(opts(302), loop_sliding=False)
    assert not off.loop_slides and not off.loop_slides_in_contact
    # the default, None, is the same as True
    for n in (202, 302):
        default = dataclasses.replace(opts(n), loop_sliding=None)
        assert default.loop_slides == opts(n).loop_slides
        assert default.loop_slides_in_contact == opts(n).loop_slides_in_contact
    with pytest.raises(InputError, match="^loop_sliding must be True, False or None"):
        dataclasses.replace(opts(302), loop_sliding="yes")
    rod, _ = clamped_problem(opts(202))
    assert rod.sliding_tail == sliding_threshold(202) and rod.impenetrable
    assert clamped_problem(off)[0].sliding_tail is None
