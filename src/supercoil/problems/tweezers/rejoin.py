"""A contact branch that closed on a loop it entered, followed again from before the loop.

On a mesh that pins the loop's core the plectoneme grows across pairs of folds between
sheets of equilibria that lie a step or two apart, and a step can carry the branch
onto a closed curve that crosses it (or passes within a step of it) at a small angle;
the tracer then goes round that curve and reports the branch closed on itself, at a
point of the curve, not at the branch's own start (:mod:`supercoil.continuation.closure`).
The points before the curve were the branch's own. Measured at L/D = 100,
lambda = 150, C/A = 1.5, N = 204: the contact branch came within 2e-3 of a curve of
equilibria at 40.01 turns (point 3685; the median step 1.8e-3), went round it from
point 3686 (39.82 to 40.09 turns) and was found closed after 4378 points; none of the
sixteen switches at its bifurcations nearest the closure started. Followed again from
its point 3636 (below), the branch closed on another curve after 484 points (40.24 turns
at most), 0.03 to 0.08 away from the first and as far from its mirror image; followed
again from before that one, it went on past 40.24 turns
(``benchmarks/results/long_dna_grid.md``, "Rows continued over several sittings").

:func:`cycle_entry` finds the closed curve on the branch (its points from the point it
came back to, to its end) and the first point of the branch on it (the points from there
to the closure lie within ``CYCLE_TOLERANCE`` of the curve's polygon, measured as
:class:`~supercoil.problems.tweezers.plectoneme.OnParent` does). :func:`rejoined`
follows the branch again, as ``{branch}/rejoined``, from ``RETREAT`` points before that
entry, with a first step of ``FIRST_STEP`` of the step the branch took there, and
refuses a state on the curve (within its tolerance and farther than ``PARENT_REACH``
steps from the entry, where the two meet): the run is then started again with a
shorter step (:func:`~supercoil.problems.segments.follow`), and a branch that still
lands on it ends there (``STEP_TOO_SMALL``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import NamedTuple

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationStatus, SpecialPoint
from supercoil.continuation.branch import POINT_ARRAYS
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.segments import RunRecords, either, follow
from supercoil.problems.tweezers.buckled import resume_stored, resumed_pins, stored_pins
from supercoil.problems.tweezers.contact import contact_options
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.pins import PIN_QUALITY
from supercoil.problems.tweezers.plectoneme import OnParent, segment_distances
from supercoil.problems.tweezers.problem import tweezers_records
from supercoil.rod.open import ClampedRodEnergy

SUFFIX = "/rejoined"
CYCLE_TOLERANCE = 0.05  # of the curve's median step: a point of the branch on the curve
RETREAT = 50  # points before the entry from which the branch is followed again
FIRST_STEP = 0.25  # of the branch's step there: the first step of the new run
REJOINS = 4  # times a branch closed so is followed again (each from the last)


class Rejoined(NamedTuple):
    """:func:`rejoined`'s result: the branch followed again, its azimuth pins, the point
    of the closed branch where the curve was entered (``entry``) and the one the new
    branch is continued from (``start``: its second point, the one before it its first),
    and the guards that refuse the curves met so far (this one last)."""

    branch: Branch
    pins: tuple[tuple[int, tuple[int, ...]], ...]
    entry: int
    start: int
    guards: tuple[OnParent, ...]


def points(branch: Branch, lo: int, hi: int) -> Branch:
    """The points ``lo`` to ``hi - 1`` of ``branch`` as a branch (no special points)."""
    return dataclasses.replace(
        branch, special_points=(), records={n: v[lo:hi] for n, v in branch.records.items()},
        frames=branch.frames[lo:hi], **{n: getattr(branch, n)[lo:hi] for n in POINT_ARRAYS})


def cycle_entry(branch: Branch) -> tuple[int, int] | None:
    """``(entry, back)`` of a branch closed on itself (module doc): ``back`` the point its
    end came back to (the curve is its points from ``back`` on), ``entry <= back`` the
    first point from which every point up to ``back`` lies on that curve; None for a
    branch that is not closed on itself or too short to say."""
    if branch.status is not ContinuationStatus.CLOSED_LOOP or len(branch) < 8:
        return None
    q = np.asarray(branch.states, dtype=float)
    n = len(q) - 1
    back = int(np.argmin(np.linalg.norm(q[:n - 3] - q[n], axis=1)))
    curve = q[back:]
    start, chord = curve[:-1], np.diff(curve, axis=0)
    length2 = np.einsum("ij,ij->i", chord, chord)
    if not np.any(length2 > 0):
        return None
    tolerance = CYCLE_TOLERANCE * float(np.median(np.sqrt(length2)))
    entry = back
    while entry > 0 and segment_distances(q[entry - 1], start, chord, length2).min() \
            <= tolerance:
        entry -= 1
    return entry, back


def rejoined(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
             closed: Branch, stored: Mapping[str, tuple[Branch, bool]] | None = None,
             on_point=None, pinned=None, say: Callable[[str], None] = lambda message: None,
             refused: tuple[OnParent, ...] = ()) -> Rejoined | None:
    """The branch ``closed`` followed again from before the closed curve it entered
    (module doc), or None where ``closed`` did not close on itself (:func:`cycle_entry`).
    ``refused``: the guards of the curves met before (:attr:`Rejoined.guards`), refused
    too. A stored branch of that name (``stored``) is taken as it is when complete and
    continued from its last point otherwise."""
    found = cycle_entry(closed)
    if found is None:
        return None
    entry, back = found
    name = closed.name + SUFFIX
    start = max(1, entry - RETREAT)
    old, complete = (stored or {}).get(name, (None, False))
    curve = points(closed, back, len(closed))
    guards = (*refused, OnParent(curve, _point(closed, entry, "cycle_entry"),
                                 what="a closed curve the branch had entered"))
    if complete:
        return Rejoined(old, stored_pins(old), entry, start, guards)
    mark = _point(closed, start, "restart")
    stop = either(pinned, *guards)
    base = contact_options(opts)
    records = RunRecords(tweezers_records(cp, rod, True))
    events = (contact_count_event(cp),)
    seeded = old is None or len(old) < 2
    if seeded:
        old = points(closed, start - 1, start + 1)
        step = float(closed.arclength[start + 1] - closed.arclength[start])
        next_step = np.full(2, np.nan)
        next_step[-1] = FIRST_STEP * step
        old = dataclasses.replace(old, name=name, parent=closed.name, origin=mark,
                                  status=ContinuationStatus.MAX_POINTS, next_step=next_step,
                                  records=dict(old.records) | {"run_start": np.zeros(2)})
        say(f"{name}: {closed.name} followed again from its point {start}, before the "
            f"closed curve it entered at its point {entry}")
    first = resume_stored({name: (old, False)}, rod, cp, name, base, records, events,
                          on_point, stop, sliding=False, max_points=opts.max_points,
                          resumed=not seeded)  # a run started from two points is no resumed one
    if first is None:
        return None
    branch, pins = follow(cp, rod, first, base, name, records, events,
                          max_points=opts.max_points, segment_points=opts.segment_points,
                          on_point=on_point, quality=PIN_QUALITY, refuse=stop,
                          on_run=records.begin)
    branch = dataclasses.replace(classify_contact_events(branch, cp), parent=closed.name,
                                 origin=mark)
    return Rejoined(branch, resumed_pins(old, pins), entry, start, guards)


def _point(branch: Branch, index: int, kind: str) -> SpecialPoint:
    """Point ``index`` of ``branch`` as a special point of ``kind``."""
    return SpecialPoint(kind=kind, label=kind, branch=branch.name, index=index,
                        parameter=float(branch.parameter_values[index]),
                        arclength=float(branch.arclength[index]), q=branch.states[index],
                        multipliers=branch.multipliers[index], tangent=branch.tangents[index],
                        unstable_count=int(branch.unstable_count[index]))
