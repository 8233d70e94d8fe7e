"""A mesh too coarse for the loop's core: where it pins the loop, the node count that
resolves it, the mesh's snake along the plectoneme's growth, and the notes that say so."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers.coarse import (
    SNAKE_PAIRS,
    pinned_loop_note,
    resolving_nodes,
    snakes_of,
)
from supercoil.problems.tweezers.options import (
    RESOLVED_CORE,
    SLIDING_CORE,
    mesh_resolves_loop,
    resolved_core,
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
    ``<= min(1/3, 1.25 / ln(lambda / 0.54))`` resolves it, checked against the ratio
    itself at every N around the thresholds; ``resolving_nodes`` is the first N that
    resolves it (brute force)."""
    for lam in (10.0, 22.0, 40.0, 80.0, 150.0):
        rule = min(1 / 3, 1.25 / math.log(lam / 0.54))
        assert math.isclose(resolved_core(lam**2), rule)
        first = resolving_nodes(options(lam, 100))
        assert first == next(n for n in range(4, 10_000) if lam / (n - 2) <= rule + 1e-12)
        for n in range(max(12, first - 80), first + 30):
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
    the core (322, segments of a quarter of it); at N = 204 (0.4), or having reached the
    last turn, none."""
    early = Folded([6.5, 9.6, 13.6, 13.55], folds=415)
    note = pinned_loop_note(options(80, 102), early)
    assert note is not None
    assert "0.8 times" in note and "415 folds between 6.5 and 13.6 turns" in note
    assert "--nodes >= 322" in note and "4 points" in note
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


def washboard_folds(period: float, amplitude: float, segment: float, nodes: int):
    """The folds of a plectoneme that grows through a washboard: ``u`` nodes of each
    strand in the ply at the turns ``t(u) = period u + amplitude sin(2 pi u)`` and the
    extension ``z(u) = 0.8 - 2 segment u`` (each node of each strand takes ``h`` from the
    tails), for ``u`` in ``[0, nodes]``: the turns fold back where ``dt/du = 0``,
    ``u = k +- arccos(-period / (2 pi amplitude)) / (2 pi)``, exactly. Returns their
    ``u``, turns and extension, in order along the branch."""
    c = math.acos(-period / (2 * math.pi * amplitude)) / (2 * math.pi)
    u = np.sort(np.concatenate([np.arange(nodes) + c, np.arange(1, nodes + 1) - c]))
    u = u[(u > 0) & (u < nodes)]
    return (u, period * u + amplitude * np.sin(2 * math.pi * u),
            0.8 - 2 * segment * u)


def test_a_washboard_growth_is_a_snake_with_its_exact_period_width_and_segments():
    """Oracle: the washboard's folds in closed form (:func:`washboard_folds`, the
    Peierls-Nabarro picture of a structure pinned by a lattice): every other fold one
    ``period`` apart in turns, a pair's two folds ``t(u1) - t(u2)`` apart, the extension
    two segments lower per period. A washboard too shallow to fold back has no events; one
    whose extension falls by one segment per period (not a node of each strand), or whose
    period doubles halfway, is no single snake."""
    h, period, amplitude = 0.005, 0.2, 0.05
    u, turns, z = washboard_folds(period, amplitude, h, nodes=8)
    index = np.arange(len(u)) * 5
    (snake,) = snakes_of("fold", index, turns, z, h)
    assert snake.events == len(u) == 16 and snake.pairs == 8 >= SNAKE_PAIRS
    assert snake.start == 0 and snake.stop == index[-1] and snake.holds(index[7])
    assert not snake.holds(index[-1] + 1)
    assert math.isclose(snake.period, period, rel_tol=1e-12)
    assert math.isclose(snake.segments, 2.0, rel_tol=1e-12)
    width = abs(turns[1] - turns[2])  # a fold back at u = 1 - c, forward at 1 + c
    assert math.isclose(snake.width, min(width, abs(turns[0] - turns[1])), rel_tol=1e-12)
    assert snake.turns == (pytest.approx(turns.min()), pytest.approx(turns.max()))
    with pytest.raises(ValueError):  # too shallow: dt/du never vanishes
        washboard_folds(period, 0.9 * period / (2 * math.pi), h, nodes=8)
    assert snakes_of("fold", index, turns, 0.8 - (z - 0.8) / 2, h) == []  # one segment
    assert snakes_of("fold", index[:2 * SNAKE_PAIRS - 1], turns[:2 * SNAKE_PAIRS - 1],
                     z[:2 * SNAKE_PAIRS - 1], h) == []  # too few pairs
    stretched = turns.copy()
    stretched[8:] = turns[8] + 2 * (turns[8:] - turns[8])  # the period doubles
    runs = snakes_of("fold", index, stretched, z, h)
    assert all(r.events < len(u) for r in runs)


@pytest.fixture(scope="module")
def pinned_run():
    """L/D = 40, lambda = 40, N = 52 (``h sqrt(F/A)`` = 0.8, a mesh that pins the loop),
    the sliding's phase row on the contact-free branch, 130 points per branch."""
    from supercoil.problems.greenhill import critical_turns
    from supercoil.problems.tweezers import tweezers_branches

    held = TweezersOptions(twist_ratio=1.5, length_over_diameter=40, tension=1600.0,
                           n_nodes=52, turns=(0.0, 1.5 * critical_turns(1.5, 1600.0)),
                           max_points=130, loop_sliding=True)
    return held, tweezers_branches(held)


def test_the_pinned_plectoneme_snakes_a_node_of_each_strand_per_pair_of_folds(pinned_run):
    """On the pinned mesh the contact branch grows its plectoneme through the mesh's
    snake. Oracles: the extension falls by two segments per period (a node of each strand:
    to 2 %), and the period in turns is ``2 h / |dz/dn|`` with the slope of the hard-core
    ply (Neukirch & van der Heijden 2002) to 10 % (the pinned ply's torque is a few per
    cent above the plateau: :mod:`supercoil.problems.tweezers.coarse`); each count change
    inside it is a ``count_change`` labelled ``snake``, none a ``bifurcation``."""
    from supercoil.problems.ply import hard_core_ply
    from supercoil.problems.tweezers.coarse import snakes_on

    held, result = pinned_run
    contact = result.branch("buckled_contact")
    (snake,) = snakes_on(contact, held.segment)
    assert snake.kind == "fold" and snake.pairs >= SNAKE_PAIRS
    assert abs(snake.segments - 2.0) < 0.04
    ply = hard_core_ply(held.diameter, held.tension, held.twist_ratio)
    assert abs(snake.period / (2 * held.segment / abs(ply.extension_per_turn)) - 1) < 0.1
    inside = [p for p in contact.special_points if snake.holds(p.index)
              and p.kind in ("bifurcation", "count_change") and p.label != "sliding"]
    assert inside and all(p.kind == "count_change" and p.label == "snake" for p in inside)


def test_on_a_pinned_mesh_the_row_holds_the_contact_free_branch_without_moving_its_contact(
        pinned_run):
    """L/D = 40, lambda = 40, N = 52 (``h sqrt(F/A)`` = 0.8, a mesh that pins the loop):
    the contact-free branch carries the sliding's phase row, which holds a force (the
    KKT residual without it) that grows as the loop closes on itself and is named in a
    note. Oracle: the same branch without the row (``loop_sliding=False``) is a branch of
    equilibria of the rod alone; the two meet the contact at the same turns (to 1e-8)
    with the same writhe. The contact branch carries no row: its points are equilibria
    of the rod with its contact (KKT residual below 1e-6)."""
    from supercoil.problems.tweezers import tweezers_branches

    held, held_result = pinned_run
    assert held.mesh_pins_loop and held.loop_slides and not held.loop_slides_in_contact
    onsets = {}
    free_run = dataclasses.replace(held, loop_sliding=False, max_points=90)
    for options, result in ((held, held_result), (free_run, tweezers_branches(free_run))):
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
        assert len(contact) == options.max_points
        assert contact.records["sliding_residual"].max() < 1e-6
    (with_row, writhe), (without, writhe_free) = onsets[True], onsets[False]
    assert abs(with_row - without) < 1e-8 and abs(writhe - writhe_free) < 1e-6
