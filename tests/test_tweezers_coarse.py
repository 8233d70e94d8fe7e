"""A mesh too coarse for the loop's core: where it pins the loop, the node count that
resolves it, and the note that says so when the contact branch ends early."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers.coarse import pinned_loop_note, resolving_nodes
from supercoil.problems.tweezers.options import (
    RESOLVED_CORE,
    SLIDING_CORE,
    mesh_resolves_loop,
)


class Folded:
    """The parts of a branch the note reads: its name, turns and folds."""

    def __init__(self, turns, folds: int):
        self.name = "buckled_contact"
        self.parameter_values = np.asarray(turns, dtype=float)
        self.folds = [object()] * folds

    def __len__(self) -> int:
        return len(self.parameter_values)

    def points_of_kind(self, kind: str):
        return self.folds if kind == "fold" else []


def options(lam: float, nodes: int) -> TweezersOptions:
    return TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=lam**2,
                           n_nodes=nodes, turns=(0.0, 25.0))


def test_the_mesh_pins_the_loop_on_segments_longer_than_half_its_core():
    """``h sqrt(F/A) > SLIDING_CORE`` (a half) with ``h = L / (N - 2)`` pins the loop,
    ``<= RESOLVED_CORE`` (a third) resolves it, checked against the ratio itself at every
    N around the thresholds; ``resolving_nodes`` is the first N that resolves it (brute
    force)."""
    for lam in (40.0, 80.0, 150.0):
        first = resolving_nodes(options(lam, 100))
        assert first == next(n for n in range(4, 10_000) if 3 * lam <= n - 2)
        for n in range(first - 80, first + 30):
            o = options(lam, n)
            assert math.isclose(o.core_segments, lam / (n - 2))
            assert o.mesh_pins_loop == (lam / (n - 2) > SLIDING_CORE)
            assert mesh_resolves_loop(o.tension, n) == (n >= first)
            assert RESOLVED_CORE < SLIDING_CORE
    assert TweezersOptions(twist_ratio=1.5, length_over_diameter=100, end_distance=0.5,
                           n_nodes=102).core_segments is None
    assert not TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=0.0,
                               n_nodes=102).mesh_pins_loop


def test_the_note_names_the_cause_where_a_pinned_contact_branch_ends_early():
    """At lambda = 80 on N = 102 (segments 0.8 of the core) a branch that stopped at 13.6
    of 25 turns gets the note with its folds, the turns they span and the N that resolves
    the core (242, segments of a third of it); at N = 204 (0.4), or having reached the
    last turn, none."""
    early = Folded([6.5, 9.6, 13.6, 13.55], folds=415)
    note = pinned_loop_note(options(80, 102), early)
    assert note is not None
    assert "0.8 times" in note and "415 folds between 6.5 and 13.6 turns" in note
    assert "--nodes >= 242" in note and "4 points" in note
    assert pinned_loop_note(options(80, 204), early) is None
    assert pinned_loop_note(options(80, 102), Folded([6.5, 25.0], folds=415)) is None


def test_no_branch_is_held_on_its_symmetry_where_the_mesh_pins_the_loop():
    """The held branch's phase row would hold the mesh's force, not round-off, on a mesh
    that pins the loop's core (the quintic contact curve at L/D = 100, lambda = 150,
    N = 102: up to 6.4e-2 of KKT residual): :func:`mirrored_contact` declines there before
    it reads the branch, as it does without ``loop_sliding``, and the contact branch's
    runs carry no sliding row (``loop_slides_in_contact``); the contact-free runs do."""
    from supercoil.problems.tweezers.mirrored import mirrored_contact

    for lam, nodes in ((150.0, 102), (80.0, 102)):
        pinned = dataclasses.replace(options(lam, nodes), loop_sliding=True)
        assert pinned.mesh_pins_loop and pinned.loop_slides
        assert not pinned.loop_slides_in_contact
        assert mirrored_contact(pinned, None, None, None, None, "buckled_contact", {}) is None


def test_on_a_pinned_mesh_the_row_holds_the_contact_free_branch_without_moving_its_contact():
    """L/D = 40, lambda = 40, N = 52 (``h sqrt(F/A)`` = 0.8, a mesh that pins the loop):
    the contact-free branch carries the sliding's phase row, which holds a force (the
    KKT residual without it) that grows as the loop closes on itself and is named in a
    note. Oracle: the same branch without the row (``loop_sliding=False``) is a branch of
    equilibria of the rod alone; the two meet the contact at the same turns (to 1e-8)
    with the same writhe. The contact branch carries no row: its points are equilibria
    of the rod with its contact (KKT residual below 1e-6)."""
    from supercoil.problems.greenhill import critical_turns
    from supercoil.problems.tweezers import tweezers_branches

    held = TweezersOptions(twist_ratio=1.5, length_over_diameter=40, tension=1600.0,
                           n_nodes=52, turns=(0.0, 1.5 * critical_turns(1.5, 1600.0)),
                           max_points=90, loop_sliding=True)
    assert held.mesh_pins_loop and held.loop_slides and not held.loop_slides_in_contact
    onsets = {}
    for options in (held, dataclasses.replace(held, loop_sliding=False)):
        result = tweezers_branches(options)
        free, contact = result.branch("buckled"), result.branch("buckled_contact")
        (onset,) = free.points_of_kind("contact_onset")
        onsets[options.loop_sliding] = (onset.parameter, free.records["writhe"][-1])
        force = free.records["sliding_residual"]
        if options.loop_sliding:
            assert 1e-6 < force.max() < 1e-4 and np.median(force) < 1e-8
            assert any(n.startswith("buckled: the sliding of the localised loop is held")
                       for n in result.notes)
            assert any(n.startswith("loop_sliding is applied on the contact-free branches "
                                    "only") for n in result.notes)
        else:
            assert force.max() < 1e-8
        assert len(contact) == 90 and contact.records["sliding_residual"].max() < 1e-6
    (with_row, writhe), (without, writhe_free) = onsets[True], onsets[False]
    assert abs(with_row - without) < 1e-8 and abs(writhe - writhe_free) < 1e-6
