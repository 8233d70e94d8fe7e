"""What a mesh too coarse for the loop's core does to the contact branch, said plainly.

The localised loop of a rod under the tension ``F``, and the end loop of the
plectoneme that grows from it, bend over the core length ``sqrt(A/F)``
(:mod:`supercoil.problems.greenhill`). On segments longer than ``SLIDING_CORE`` of
it (:attr:`~supercoil.problems.tweezers.options.TweezersOptions.mesh_pins_loop`) the
core spans a segment or two and the mesh pins it: the energy of the discrete end loop
depends on where the nodes sit in it, and the plectoneme grows by one node of each
strand at a time, across a pair of folds per node (docs/tweezers.md, "The plectoneme
on coarse meshes"). Measured at L/D = 100, ``lambda = L sqrt(F/A)`` = 80, N = 102
(segments 0.8 of the core): the torque of the ply rises from 90.8 to 94.5 and falls
back as each node enters, the turns going back by 0.3 across the period, and the
contact branch folded 415 times between 6.5 and 13.6 turns in 4000 points; at
``lambda`` = 150, N = 204 (0.74 of the core) 204 times between 20 and 41.4 turns;
on segments of 0.37-0.4 of the core (``lambda`` = 40, N = 102; 80, N = 204; 150 at
L/D = 200, N = 404) the contact branches reach the last turn in 863-2606 points.
:func:`pinned_loop_note` names that cause where such a branch ends before its last
turn.

Finer meshes can still snake where the plectoneme grows: its end loop stays pinned for
a stretch and the branch crosses a pair of folds (or, narrower than the steps, a pair
of count changes) per node of each strand that enters the ply. :func:`snakes_on` finds
such a snake from the events alone: at least ``SNAKE_PAIRS`` pairs, every other event
a steady period apart (the longest at most ``SNAKE_STEADY`` times the shortest), and
the extension falling by two segments per period (within ``SNAKE_SEGMENTS_OFF``): a
node of each strand, ``2 h`` of rod, taken from the tails, so that the period in turns
is ``2 h / |dz/dn|`` with the plectoneme's slope dz/dn. Nothing in the continuum does
that: its plectoneme grows smoothly. The count changes in a snake are reported as
``count_change`` with the label ``snake``
(:func:`~supercoil.problems.tweezers.verify.verify_bifurcations`) and
:func:`snake_note` names the snake. On segments up to
:func:`~supercoil.problems.tweezers.options.resolved_core` of the core (a third up to
lambda = 22.6, a quarter at lambda = 80, 0.22 at 150) no snake was met and the
unstable counts agree with a mesh 1.5 times finer away from the branch's events
(``benchmarks/grid_counts_refinement.py``; ``benchmarks/snake_edge.py`` measures the
edge); on coarser ones :func:`unresolved_loop_note` says so on every contact branch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from supercoil.continuation import Branch
from supercoil.continuation.branch import COUNT_KINDS
from supercoil.problems.tweezers.options import (
    SLIDING_CORE,
    TweezersOptions,
    mesh_resolves_loop,
    resolved_core,
    resolved_nodes,
)

# the fewest pairs of events that make a snake
SNAKE_PAIRS = 4
# the longest period within a snake over its shortest, at most
SNAKE_STEADY = 1.5
# the extension's fall per period, in segments, differs from 2 by at most this
SNAKE_SEGMENTS_OFF = 0.5


@dataclass(frozen=True)
class Snake:
    """A run of events along a branch that the mesh makes (module doc).

    ``kind``: ``fold`` or ``count_change`` (the events it is made of); ``events`` their
    number and ``pairs`` = ``events // 2``; ``start`` and ``stop`` the branch indices of
    its first and last events (each lies between its index and the next point);
    ``turns`` the least and most turns of its events; ``period`` the median turns
    between every other event; ``width`` the median turns between the two events of a
    pair; ``segments`` the median fall of the extension per period over the segment h."""

    kind: str
    events: int
    start: int
    stop: int
    turns: tuple[float, float]
    period: float
    width: float
    segments: float

    @property
    def pairs(self) -> int:
        return self.events // 2

    def holds(self, index: int) -> bool:
        """Whether an event between points ``index`` and ``index + 1`` lies in the snake."""
        return self.start <= index <= self.stop


def snakes_of(kind: str, indices, turns, extension, segment: float) -> list[Snake]:
    """The snakes (module doc) in a sequence of events of one ``kind`` along a branch, in
    its order: their branch ``indices``, ``turns`` and ``extension`` (z/L); ``segment``
    the mesh's h/L. Greedy from the first event: a snake is extended while each next
    period keeps the extension's fall within ``SNAKE_SEGMENTS_OFF`` of two segments, the
    same direction of the turns and the periods within ``SNAKE_STEADY``."""
    t = np.asarray(turns, dtype=float)
    z = np.asarray(extension, dtype=float)
    index = np.asarray(indices, dtype=np.int64)
    if len(t) < 2 * SNAKE_PAIRS:
        return []
    period = t[2:] - t[:-2]
    fall = np.abs(z[2:] - z[:-2]) / segment
    good = (np.abs(fall - 2.0) <= SNAKE_SEGMENTS_OFF) & (period != 0.0)
    snakes = []
    i = 0
    while i < len(period):
        if not good[i]:
            i += 1
            continue
        j, low, high = i, abs(period[i]), abs(period[i])
        while (j + 1 < len(period) and good[j + 1]
               and np.sign(period[j + 1]) == np.sign(period[i])
               and max(high, abs(period[j + 1])) <= SNAKE_STEADY * min(low, abs(period[j + 1]))):
            j += 1
            low, high = min(low, abs(period[j])), max(high, abs(period[j]))
        if j - i + 3 >= 2 * SNAKE_PAIRS:
            gaps = np.abs(np.diff(t[i:j + 3]))
            snakes.append(Snake(kind, j - i + 3, int(index[i]), int(index[j + 2]),
                                (float(t[i:j + 3].min()), float(t[i:j + 3].max())),
                                float(np.median(np.abs(period[i:j + 1]))),
                                float(min(np.median(gaps[0::2]), np.median(gaps[1::2]))),
                                float(np.median(fall[i:j + 1]))))
            i = j + 3
        else:
            i += 1
    return snakes


def snakes_on(branch: Branch, segment: float) -> list[Snake]:
    """The snakes of ``branch`` (its record ``extension`` read at its events, linear in
    arclength) on a mesh of segments ``segment`` (h/L): among its folds, and among its
    changes of the unstable count (bifurcations and count changes but the sliding's, whose
    mechanism is another: docs/continuation.md); ordered by their first event."""
    extension = branch.records.get("extension") if len(branch) else None
    if extension is None:
        return []
    extension = np.asarray(extension, dtype=float)
    s = np.asarray(branch.arclength, dtype=float)
    found = []
    for kind, points in (
            ("fold", [p for p in branch.special_points if p.kind == "fold"]),
            ("count_change", [p for p in branch.special_points
                              if p.kind in COUNT_KINDS and p.label != "sliding"])):
        points = sorted(points, key=lambda p: p.arclength)
        z = []
        for p in points:
            k = min(p.index, len(branch) - 2)
            ds = s[k + 1] - s[k]
            w = 0.0 if ds == 0 else min(max((p.arclength - s[k]) / ds, 0.0), 1.0)
            z.append((1 - w) * extension[k] + w * extension[k + 1])
        found += snakes_of(kind, [p.index for p in points], [p.parameter for p in points],
                           z, segment)
    return sorted(found, key=lambda snake: snake.start)


def snake_note(options: TweezersOptions, branch: Branch) -> str | None:
    """A note for a tweezers ``branch`` that grew through the mesh's snake (module doc):
    its pairs, the turns they span, their period and the extension's fall per period, and
    the ``--nodes`` that resolve the end loop. None without a snake."""
    if not options.load_control or len(branch) < 2:
        return None
    snakes = snakes_on(branch, options.segment)
    if not snakes:
        return None
    first, last = min(s.turns[0] for s in snakes), max(s.turns[1] for s in snakes)
    longest = max(snakes, key=lambda snake: snake.events)
    kinds = " and ".join(sorted({f"{s.kind}s" for s in snakes}))
    nodes = resolving_nodes(options)
    finer = (f"--nodes >= {nodes} resolve the end loop" if nodes and nodes > options.n_nodes
             else "a finer mesh resolves it")
    return (f"{branch.name}: the plectoneme grew through the mesh's snake, "
            f"{sum(s.pairs for s in snakes)} pairs of {kinds} between {first:.4g} and "
            f"{last:.4g} turns (the longest run: {longest.pairs} pairs, one per "
            f"{longest.period:.3g} turns, the extension falling by {longest.segments:.2g} "
            f"segments per pair: a node of each strand entering the ply): the end loop "
            f"stays pinned to the mesh between nodes, and the unstable counts there are the "
            f"mesh's, not the rod's (its count changes are count_change, label snake); "
            f"{finer}")


def resolving_nodes(options: TweezersOptions) -> int | None:
    """The fewest nodes whose segments are at most
    :func:`~supercoil.problems.tweezers.options.resolved_core` times the loop's core
    ``sqrt(A/F)`` (None without a tension)."""
    if not options.load_control or not options.tension:
        return None
    return resolved_nodes(options.tension)


def pinned_loop_note(options: TweezersOptions, branch: Branch) -> str | None:
    """A note for a contact ``branch`` that ended before the last turn on a mesh that pins
    the loop's core (module doc): the ratio of the segments to the core, the folds the
    branch went through and the turns they spanned, and the ``--nodes`` that resolve the
    core. None where the mesh resolves it or the branch reached the last turn."""
    if not options.mesh_pins_loop or not len(branch):
        return None
    turns = branch.parameter_values
    if turns[-1] >= options.turns[1] - 1e-9:
        return None
    k = math.sqrt(options.tension)
    folds = len(branch.points_of_kind("fold"))
    return (f"{branch.name}: the mesh pins the loop's core: its segments "
            f"({options.segment:.3g} L) are {options.core_segments:.2g} times "
            f"sqrt(A/F) = {1 / k:.3g} L (more than {SLIDING_CORE:g}), so the plectoneme grows "
            f"by a node of each strand at a time, across a pair of folds per node: "
            f"{folds} folds between {float(turns.min()):.4g} and {float(turns.max()):.4g} "
            f"turns in {len(branch)} points; --nodes >= {resolving_nodes(options)} resolve "
            f"the core")


def unresolved_loop_note(options: TweezersOptions, branch: Branch) -> str | None:
    """A note for a contact ``branch`` computed on segments longer than
    :func:`~supercoil.problems.tweezers.options.resolved_core` of the loop's core (module doc): its growth may cross the mesh's pairs of folds, and
    its counts between them are the mesh's; the ``--nodes`` that resolve the core. None on
    a mesh that resolves it, without a tension or for an empty branch."""
    if not options.load_control or mesh_resolves_loop(options.tension, options.n_nodes) \
            or not len(branch):
        return None
    folds = len(branch.points_of_kind("fold"))
    return (f"{branch.name}: its segments are {options.core_segments:.2g} times the loop's "
            f"core sqrt(A/F) (more than {resolved_core(options.tension):.2g} at lambda = "
            f"{math.sqrt(options.tension):.3g}): the plectoneme's end loop is "
            f"under-resolved, and its growth may cross a pair of folds of the discrete "
            f"contact per node of each strand, between which the unstable count is the "
            f"mesh's, not the rod's ({folds} folds on this branch); --nodes >= "
            f"{resolving_nodes(options)} resolve it")
