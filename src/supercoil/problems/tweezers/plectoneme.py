"""The plectoneme from a contact branch that comes back onto itself (or onto the
contact-free branch, :mod:`supercoil.problems.tweezers.returned`): a switch at one of
its bifurcations.

From a centred localised loop (symmetric under the rotation by pi about an axis across
the rod's middle) the first contact is symmetric too, and so is the contact branch that
follows it, the plectoneme's ply growing from the loop's crossing along that axis; the
freely followed branch can leave that symmetric family at a pitchfork of the contact's
ripple and close a loop, and is then followed again held on the symmetry first
(:mod:`supercoil.problems.tweezers.mirrored`). A branch can also close near a
bifurcation to another family: measured on the 3 kbp hat curve at 1 pN and 150 mM, the
symmetric branch closes on itself at 6.77 turns, with a bifurcation located at 6.767
turns from which no switched branch starts (measured with the loop's sliding in the
count and out of it); without ``loop_sliding`` the loop slides off the middle and its
contact branch reaches the plectoneme by itself. So when the closed contact branch (or
the held one) ends before the last turn, :func:`switch_to_plectoneme` tries its
located bifurcations, the latest first (a closed branch's nearest to its closure first,
:func:`switch_order`), along either side of the critical mode at the amplitudes of
``AMPLITUDES``, and follows the first switched branch that starts (and does not close at
once) to the last turn.

A switched branch can itself come back onto the contact-free branch: it is then closed
there (:func:`~supercoil.problems.tweezers.returned.close_on_return`), as the contact
branch is, and the next switch is tried. Measured at L/D = 200, lambda = 80, C/A = 1.5,
N = 202: the branches switched at 9.495 and 9.498 turns lose turns in contact, release
every contact at 3.95 turns onto the contact-free branch, and follow it up to the
straight rod's bifurcation point (17.33 turns), where the rod is straight and the
azimuth pin can no longer be picked; without the closure that run was reported as a
failed plectoneme.

A switched branch can also close on itself, on a loop entered by a jump as the contact
branch's (:func:`switch_order`): measured at L/D = 200, lambda = 150, C/A = 1.5, N = 202,
the branch switched at the contact branch's crossing at 24.52 turns rose to 27.21 turns
and closed after 5264 points at 26.65 turns, coming back to its point 5226 just past a
count change at 26.645 turns among folds (it fails
:func:`~supercoil.problems.tweezers.verify.verified`, and no switch there starts: the
corrector diverges from all four first points). Such a branch is switched again at its
verified bifurcation nearest the closure (``NESTED`` levels deep). Among such close
sheets a switch can land back on the branch it left and run along it (there for 5195
points, back and forth): :class:`OnParent` stops it.

Each try has its own branch name (:func:`try_names`), and each branch followed is
handed to the caller once it ends, so that a result stopped during the switches is
continued by ``--resume`` without switching again: the tries that ended are taken as
stored and the one that was being followed goes on from its last point.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from typing import NamedTuple

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationStatus, SpecialPoint, switch_branch
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.segments import either, follow, set_pin
from supercoil.problems.tweezers.buckled import (
    RunRecords,
    resume_stored,
    resumed_pins,
    stored_pins,
)
from supercoil.problems.tweezers.contact import contact_options
from supercoil.problems.tweezers.mirrored import closed_before
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.pins import PIN_QUALITY, hold_azimuth
from supercoil.problems.tweezers.problem import tweezers_records
from supercoil.problems.tweezers.returned import close_on_return, returned_onto
from supercoil.problems.tweezers.verify import verify_bifurcations
from supercoil.rod.open import ClampedRodEnergy

AMPLITUDES = (5e-4, 5e-3)  # of D: the first point's distance from the bifurcation
HALVINGS = 5  # of that distance where the first point's corrector fails (switch_branch)
TRIES = 4  # the bifurcations tried, in the order of switch_order
NESTED = 2  # levels of switches at a closed switched branch's nearest bifurcation
PARENT_TOLERANCE = 1e-2  # of the parent's median step: a switched state on its path
PARENT_REACH = 3.0  # of the parent's median steps: the bifurcation's neighbourhood
PROJECTIONS = 8  # directions of the projection that picks the parent's nearby segments


def switch_order(contact: Branch) -> list[SpecialPoint]:
    """The located bifurcations of ``contact`` in the order :func:`switch_to_plectoneme`
    tries them: the latest first, or, where the branch closed on itself, the nearest to
    its last state first (``|q_b - q_last|``), then the others the latest first.

    A branch that comes from elsewhere and closes on a loop entered it where it crossed
    another branch: a smooth branch cannot run into a loop of its own, and through a
    simple bifurcation point each branch's unstable count changes, so the step that came
    back round the loop onto the branch's earlier path, with no change of count, passed
    the crossing on the other branch and was carried onto this one between their close
    sheets. The branch not followed leaves from that crossing, where the loop closes
    (measured at L/D = 200, lambda = 150, C/A = 1.5, N = 202: the contact branch crossed
    a bifurcation at 24.5185 turns, came back to it round a loop through folds at
    24.5071 and 24.5307 turns and closed there, 0.0007 turns from it; the latest
    bifurcation, at the loop's upper fold, is 0.013 turns from it)."""
    points = [p for p in contact.special_points if p.kind == "bifurcation"][::-1]
    if contact.status is not ContinuationStatus.CLOSED_LOOP or not points:
        return points
    last = contact.states[-1]
    nearest = min(points, key=lambda p: float(np.linalg.norm(p.q - last)))
    return [nearest] + [p for p in points if p is not nearest]


class Switched(NamedTuple):
    """:func:`switch_to_plectoneme`'s result: the switched branch that reaches furthest,
    its azimuth pins, the closed switched branches it was switched from (``(branch,
    pins)``, the outermost first; empty for a switch at the contact branch itself), and
    the seconds spent on each branch followed (those taken as stored: none)."""

    branch: Branch
    pins: tuple[tuple[int, tuple[int, ...]], ...]
    via: tuple[tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]], ...]
    seconds: Mapping[str, float]  # the time spent on each branch followed here, by name


def try_names(contact: Branch, points: int = TRIES) -> list[tuple[SpecialPoint, float, int, str]]:
    """The switches :func:`switch_to_plectoneme` tries, in order: ``(point, amplitude,
    side, name)`` for the bifurcations of :func:`switch_order` (at most ``points``), each
    at the amplitudes of ``AMPLITUDES`` (of D) on either side of its critical mode. The
    first try at a point names its branch ``{contact}/bifurcation{index}``, the k-th
    ``{contact}/bifurcation{index}_try{k}``."""
    out = []
    for point in switch_order(contact)[:points]:
        tries = [(a, side) for a in AMPLITUDES for side in (1, -1)]
        for k, (amplitude, side) in enumerate(tries, start=1):
            name = f"{contact.name}/bifurcation{point.index}" + ("" if k == 1 else f"_try{k}")
            out.append((point, amplitude, side, name))
    return out


def tries_note(closed: Branch, tried: list[Branch]) -> str:
    """One note naming how each switch tried from ``closed`` ended (``tried``, as
    :func:`switch_to_plectoneme` collects them, the nested ones at a closed switched
    branch's bifurcations included): why a switch did not start, or where a switched
    branch ended and how far it reached."""
    said = []
    for branch in tried:
        if branch.status is ContinuationStatus.START_FAILED or len(branch) == 0:
            said.append(f"{branch.name}: {branch.message}")
        else:
            turns = branch.parameter_values
            said.append(f"{branch.name}: {branch.status.name.lower()} at {turns[-1]:.6g} "
                        f"turns after {len(branch)} points ({turns.min():.6g} to "
                        f"{turns.max():.6g} turns)")
    return f"switches tried from {closed.name}: " + "; ".join(said)


def switch_to_plectoneme(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
                         contact: Branch, on_point=None, pinned=None,
                         say: Callable[[str], None] = lambda message: None,
                         free: Branch | None = None, reach: float = 1.0,
                         stored: Mapping[str, tuple[Branch, bool]] | None = None,
                         on_branch: Callable[[Branch, bool], None] | None = None,
                         depth: int = 0, tried: list[Branch] | None = None) -> Switched | None:
    """The branch switched at a bifurcation of ``contact`` (module doc) that reaches
    furthest in turns, followed as the contact branch is, with its azimuth pins; None
    when no switch gives a branch. ``free``: the contact-free branch, onto which a
    switched branch that comes back is closed (``reach``: the closest approach, in D,
    below which a contact acts).

    ``on_branch(branch, True)`` receives each switched branch followed, once it ends
    (those that reach less far too). ``stored`` (name -> ``(branch, complete)``, a
    resumed run's) gives the tries already made (:func:`try_names`): a complete one is
    taken as it is (or passed over, stored as not started); an incomplete one, the one
    the interrupted run was computing, continued from its last point.

    A switched branch that closes on itself before the last turn (not onto ``free``),
    having reached further in turns than any try before it, is itself switched at its
    verified bifurcation nearest the closure (:func:`switch_order`), ``NESTED`` levels
    deep; the result's ``via`` lists the closed branches it was switched from, the
    outermost first.

    ``tried``, when given, receives each try's branch as it ended, in the order tried
    (nested tries included): taken as stored, followed, or with the status
    ``START_FAILED`` and the reason in its message when the switch did not start."""
    base = contact_options(opts)
    records = RunRecords(tweezers_records(cp, rod, True))
    events = (contact_count_event(cp),)
    stored = stored or {}
    tried = [] if tried is None else tried

    def ended(branch: Branch, complete: bool) -> None:
        tried.append(branch)
        if on_branch is not None:
            on_branch(branch, complete)

    tries = try_names(contact, TRIES if depth == 0 else 1)
    best = None
    seconds: dict[str, float] = {}
    for point, amplitude, side, name in tries:
        old, complete = stored.get(name, (None, False))
        if complete and old.status is ContinuationStatus.START_FAILED:
            tried.append(old)
            continue  # stored as a switch that did not start
        if complete:
            tried.append(old)
            branch, pins = old, stored_pins(old)
        else:
            start = time.perf_counter()
            followed = _switched(opts, rod, cp, contact, point, amplitude, side, name, base,
                                 records, events, on_point, pinned, say, old, ended)
            seconds[name] = time.perf_counter() - start
            if followed is None:
                continue
            branch, pins = followed
            branch = classify_contact_events(branch, cp)
            if free is not None:
                branch = close_on_return(branch, free, opts.diameter, reach)
            ended(branch, True)
        found = Switched(branch, pins, (), seconds)
        if depth < NESTED and closed_before(branch, opts.turns[1]) and (
                free is None or returned_onto(branch, free, opts.diameter, reach) is None) \
                and (best is None or branch.parameter_values.max()
                     > best.branch.parameter_values.max()):
            # the furthest reaching so far, closed on itself: switched again, at its
            # verified bifurcations only
            branch = verify_bifurcations(branch, opts.segment)
            inner = switch_to_plectoneme(opts, rod, cp, branch, on_point, pinned, say, free,
                                         reach, stored, on_branch, depth + 1, tried)
            if inner is not None:
                seconds.update(inner.seconds)
                if inner.branch.parameter_values[-1] > branch.parameter_values[-1]:
                    found = Switched(inner.branch, inner.pins, ((branch, pins), *inner.via),
                                     seconds)
        if best is None or found.branch.parameter_values[-1] > \
                best.branch.parameter_values[-1]:
            best = found
        if best.branch.status is ContinuationStatus.PARAMETER_BOUND \
                and best.branch.parameter_values[-1] >= opts.turns[1] - 1e-9:
            return best
    return best


def _switched(opts, rod, cp, contact, point, amplitude, side, name, base, records, events,
              on_point, pinned, say, old=None, on_branch=None):
    """The branch ``name`` switched at ``point`` (``amplitude`` in D, ``side`` of its
    critical mode) and followed, with its pins, or None when it does not start (fewer
    than two points, closed in its first run, or back on ``contact`` in it
    (:class:`OnParent`, which ends the later runs too): handed to ``on_branch`` with the
    status ``START_FAILED``). ``old``: the stored incomplete branch of an interrupted
    run, continued from its last point instead."""
    resumed = old is not None and len(old) >= 2
    guard = OnParent(contact, point)
    stop = either(pinned, guard)
    if resumed:
        first = resume_stored({name: (old, False)}, rod, cp, name, base, records, events,
                              on_point, stop, sliding=False, max_points=opts.max_points)
        say(f"{name}: continued from point {len(old) - 1}")
    else:
        pin = contact.records["azimuth_pin"]
        at = min(point.index + 1, len(contact) - 1)
        if pin[at] >= 0:
            hold_azimuth(rod, (int(pin[at]),), cp)
        else:
            set_pin(cp, rod, point.q)
        records.begin(0)
        first = switch_branch(cp, contact, point, base, side=side,
                              amplitude=amplitude * opts.diameter, name=name,
                              records=records, events=events, on_point=on_point, stop=stop,
                              halvings=HALVINGS)
    in_first_run = not np.any(first.records.get("run_start", np.zeros(1)))
    if len(first) < 2 or (in_first_run and (first.status is ContinuationStatus.CLOSED_LOOP
                                            or guard.ended(first))):
        if on_branch is not None:
            on_branch(dataclasses.replace(
                first, status=ContinuationStatus.START_FAILED,
                message=f"the switch did not start: {first.message}"), True)
        return None
    if not resumed:
        say(f"{name}: switched at {point.parameter:.6g} turns")
    branch, pins = follow(cp, rod, first, base, name, records, events,
                          max_points=opts.max_points, segment_points=opts.segment_points,
                          on_point=on_point, quality=PIN_QUALITY, refuse=stop,
                          on_run=records.begin)
    return (branch, resumed_pins(old, pins)) if resumed else (branch, pins)


class OnParent:
    """A ``continuation`` ``stop`` for a branch switched at ``point`` of ``parent``: it
    refuses a state, farther than ``PARENT_REACH`` of the parent's steps from the
    bifurcation, that lies on the parent's path (within ``PARENT_TOLERANCE`` of a step of
    the polygon through its states): the switch fell back onto the branch it left. Two
    solution curves meet only at their bifurcation point; among the close sheets of a
    plectoneme held by the mesh the switch can still land on the parent (measured at
    L/D = 200, lambda = 150, C/A = 1.5, N = 202: a branch switched at 26.649 turns ran
    back along its parent for 5195 points, within 1e-7 to 2e-5 of its polygon, against
    steps of 2.3e-4). :meth:`ended`: whether it ended a run (a refused trial step that
    the run then halved and took does not). ``what`` names ``parent`` in the refusal."""

    def __init__(self, parent: Branch, point: SpecialPoint,
                 what: str = "the branch it was switched from"):
        states = np.asarray(parent.states, dtype=float)
        self.what = what
        self.name, self.q = parent.name, np.asarray(point.q, dtype=float)
        self.start, self.chord = states[:-1], np.diff(states, axis=0)
        self.length2 = np.einsum("ij,ij->i", self.chord, self.chord)
        step = float(np.median(np.sqrt(self.length2))) if self.length2.size else 0.0
        self.tolerance, self.reach = PARENT_TOLERANCE * step, PARENT_REACH * step
        self.refusals: list[str] = []
        # the polygon projected on a few orthonormal directions: a projection shortens
        # distances, so only the segments within the tolerance there need the full one
        basis = np.random.default_rng(0).standard_normal((states.shape[1], PROJECTIONS))
        self.basis = np.linalg.qr(basis)[0] if states.shape[1] >= PROJECTIONS else None
        if self.basis is not None:
            self.start_p, self.chord_p = self.start @ self.basis, self.chord @ self.basis
            self.length2_p = np.einsum("ij,ij->i", self.chord_p, self.chord_p)

    def distance(self, q: np.ndarray, within: float = math.inf) -> tuple[float, int]:
        """The distance of ``q`` from the parent's polygon and the first point of the
        nearest segment; ``(inf, -1)`` where no segment lies within ``within``."""
        rows = np.arange(self.length2.size)
        if self.basis is not None and math.isfinite(within):
            d = segment_distances(q @ self.basis, self.start_p, self.chord_p,
                                   self.length2_p)
            rows = rows[d <= within]
        if rows.size == 0:
            return math.inf, -1
        d = segment_distances(q, self.start[rows], self.chord[rows], self.length2[rows])
        i = int(np.argmin(d))
        return float(d[i]), int(rows[i])


    def __call__(self, q: np.ndarray) -> str | None:
        if self.tolerance <= 0 or np.linalg.norm(q - self.q) <= self.reach:
            return None
        d, i = self.distance(np.asarray(q, dtype=float), self.tolerance)
        if d > self.tolerance:
            return None
        message = (f"back on {self.what} ({self.name}): within "
                   f"{d:.2g} of its path between its points {i} and {i + 1}")
        self.refusals.append(message)
        return message

    def ended(self, run: Branch) -> bool:
        """Whether ``run`` stopped on one of this stop's refusals."""
        return run.status is ContinuationStatus.STOPPED and any(
            m in run.message for m in self.refusals)


def segment_distances(q: np.ndarray, start: np.ndarray, chord: np.ndarray,
                       length2: np.ndarray) -> np.ndarray:
    """The distances of ``q`` from the segments ``start + t chord``, ``0 <= t <= 1``."""
    rel = q - start
    t = np.clip(np.einsum("ij,ij->i", rel, chord) / np.where(length2 > 0, length2, 1.0),
                0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * chord, axis=1)
