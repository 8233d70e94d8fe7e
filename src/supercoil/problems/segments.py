"""Continuation in runs, the symmetry pins re-picked between them.

A problem that removes a continuous symmetry by fixing some DOFs (the
rigid motions of a ring, the rotation of a clamped rod about its axis) keeps
those pins for a whole continuation run, and pins chosen at the start can
lose their grip as the shape changes: the pinned Hessian then has a nearly
null symmetry mode, Newton and the unstable count degrade. :func:`follow`
continues a branch in runs, re-picking the pins between runs where the rod's
``pin_quality`` fell below a threshold, and merges the runs into one branch.
The pinned coordinates keep their values at the state where they are
picked, so that state stays a state of the problem.

The rod protocol (:class:`PinnedRod`): ``fixed`` and ``gauge_dofs`` (the
pins), ``repin(q)`` and ``pin_quality(q)`` in ``[0, 1]``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from itertools import pairwise
from typing import Protocol

import numpy as np

from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    ContinuationStatus,
    UserEvent,
    continuation,
)
from supercoil.continuation.branch import POINT_ARRAYS
from supercoil.continuation.carry import frames_at
from supercoil.continuation.columns import Columns
from supercoil.solvers.carried import carried

# a run that refused its first point is started again from the same point with its
# first step shortened by this factor, at most this many times (see follow)
REFUSED_SHRINK = 0.25
REFUSED_RETRIES = 4


class PinnedRod(Protocol):
    fixed: np.ndarray
    gauge_dofs: np.ndarray

    def repin(self, q: np.ndarray) -> None: ...

    def pin_quality(self, q: np.ndarray) -> float: ...


class RunRecords:
    """Per-point records ``records`` with ``run_start``: the index on the branch of the
    first point of the continuation run that computed the point (:meth:`begin`, as
    :func:`follow`'s ``on_run``), so that an interrupted run is resumed up to its own
    end (e.g. :func:`~supercoil.problems.tweezers.buckled.resume_stored`)."""

    def __init__(self, records):
        self.records = records
        self.start = 0

    def begin(self, index: int) -> None:
        self.start = index

    def __call__(self, q: np.ndarray, multipliers: np.ndarray, parameter: float,
                 problem=None) -> dict:
        return (self.records(q, multipliers, parameter, problem=problem)
                | {"run_start": self.start})


def set_pin(problem, rod: PinnedRod, q: np.ndarray) -> None:
    """Re-pick the rod's symmetry pins for ``q`` (``rod.repin``), on the rod and on its
    contact wrapper (``problem``, whose ``fixed`` copies the rod's)."""
    rod.repin(q)
    if problem is not rod:
        problem.fixed = rod.fixed


def replay_pins(problem, rod: PinnedRod, branch: Branch, q0: np.ndarray,
                segment_points: int, max_points: int, quality: float = 0.5) -> int:
    """Pin ``rod`` (and ``problem``) as an uninterrupted :func:`follow` had it pinned when it
    computed the last point of ``branch`` (a stored partial branch whose records hold
    :class:`RunRecords`' ``run_start``), and return the index of the first point of that
    run. The first run's pins are picked at ``q0`` (its start); a later run's where it
    starts if the run before it stopped short of its ``segment_points`` (a refusal) or
    the pins' quality had fallen below ``quality`` there, as :func:`follow` decides."""
    starts = sorted({0, *(int(v) for v in branch.records["run_start"])})
    set_pin(problem, rod, q0)
    for before, start in pairwise(starts):
        size = min(segment_points, max_points - before)
        if start - before + 1 < size or rod.pin_quality(branch.states[start]) < quality:
            set_pin(problem, rod, branch.states[start])
    return starts[-1]


# a branch's per-point arrays: those a merge takes from each run after its first point,
# and the step controller's state, taken from a run's first point on
_STEPS = ("next_step", "gauge_moved")
_ARRAYS = tuple(n for n in POINT_ARRAYS if n not in _STEPS + ("arclength",))


def merge_branches(parts: list[Branch], name: str) -> Branch:
    """One branch from consecutive runs (each starts at the last point of the previous).
    The step controller's state at a junction is the next run's at its first point
    (the step that run tried first from it); the phase conditions are the last run's
    (those its last point was computed with, which a resumed run continues with)."""
    first = parts[0]
    arrays = {k: [getattr(first, k)] for k in _ARRAYS}
    steps = {k: [getattr(first, k)] for k in _STEPS}
    arclength = [first.arclength]
    records = {k: [v] for k, v in first.records.items()}
    specials = list(first.special_points)
    offset, s0 = len(first), float(first.arclength[-1]) if len(first) else 0.0
    phase = first
    for part in parts[1:]:
        if len(part) < 2:
            continue
        phase = part
        for k, values in arrays.items():
            values.append(getattr(part, k)[1:])
        for k, values in steps.items():
            values[-1] = values[-1][:-1]
            values.append(getattr(part, k))
        arclength.append(part.arclength[1:] + s0)
        for k, values in records.items():
            values.append(part.records[k][1:])
        specials += [dataclasses.replace(p, index=p.index + offset - 1,
                                         arclength=p.arclength + s0) for p in part.special_points]
        offset += len(part) - 1
        s0 += float(part.arclength[-1])
    last = parts[-1]
    merged = {k: np.concatenate(v) for k, v in (arrays | steps).items()}
    return dataclasses.replace(
        first, name=name, arclength=np.concatenate(arclength),
        records={k: np.concatenate(v) for k, v in records.items()},
        special_points=tuple(dataclasses.replace(p, branch=name) for p in specials),
        status=last.status, message=last.message, phase_modes=phase.phase_modes,
        phase_state=phase.phase_state, **merged)


def grip_stop(grip: Callable[[np.ndarray], float], q: np.ndarray, fraction: float = 0.25
              ) -> Callable[[np.ndarray], str | None]:
    """A ``continuation`` ``stop`` that refuses a state where ``grip`` (the pins' hold, see
    :func:`follow`) fell below ``fraction`` of its value at ``q``, the run's start."""
    held = grip(q)

    def refuse(state: np.ndarray) -> str | None:
        now = grip(state)
        if now < fraction * held:
            return f"the symmetry pins' grip fell to {now / held:.2g} of its value at the run's start"
        return None

    return refuse


def either(*stops: Callable[[np.ndarray], str | None] | None
           ) -> Callable[[np.ndarray], str | None] | None:
    """A ``continuation`` ``stop`` that refuses what any of ``stops`` (None: absent) does,
    asked in order."""
    given = [s for s in stops if s is not None]
    if len(given) <= 1:
        return given[0] if given else None

    def refuse(q: np.ndarray) -> str | None:
        for stop in given:
            message = stop(q)
            if message:
                return message
        return None

    return refuse


class MergedRuns:
    """The branch merged from consecutive runs (:func:`merge_branches`) at every point
    of the run in progress, in O(n) a point. The runs are written into growing
    columns (:mod:`~supercoil.continuation.columns`): ``first`` once, each point of a
    run as it comes (its last point again where it changed: a run replaces only its
    last point), and the merged branch's arrays are views of them. Merging the runs
    again at every point cost O(k n) a point, O(k^2 n) over the branch.

    Call it with each partial branch of the run in progress (it starts at the merged
    branch's last point), then :meth:`commit` the run when it ends."""

    def __init__(self, first: Branch, name: str):
        self.first, self.name = first, name
        self.k0 = len(first)  # points of the runs committed
        self.s0 = float(first.arclength[-1]) if self.k0 else 0.0
        self.columns = Columns()
        for key in _ARRAYS + _STEPS + ("arclength",):
            self.columns.fill(key, getattr(first, key))
        for key, values in first.records.items():
            self.columns.fill("record:" + key, values)
        self.specials = [dataclasses.replace(p, branch=name) for p in first.special_points]
        self.committed = len(self.specials)  # special points of the committed runs
        self.phase = first  # the last run with a step (its phase conditions)
        self.merged_runs = 0
        self.written = 0  # points of the run in progress written so far

    def __call__(self, partial: Branch) -> Branch:
        """The runs so far followed by ``partial``, the run in progress, as
        ``merge_branches([*runs, partial], name)`` gives it."""
        if self.merged_runs == 0 and len(partial) < 2 or not self.k0:
            return merge_branches([self.first, partial], self.name)
        cols, k0 = self.columns, self.k0
        # a run of one point adds nothing (merge_branches skips it)
        for i in range(max(self.written - 1, 0), len(partial) if len(partial) >= 2 else 0):
            r = k0 - 1 + i
            fresh = i >= self.written
            values = {key: getattr(partial, key)[i] for key in _STEPS}
            if i:
                values.update({key: getattr(partial, key)[i] for key in _ARRAYS})
                values["arclength"] = partial.arclength[i] + self.s0
                values.update({"record:" + key: v[i] for key, v in partial.records.items()})
            for key, value in values.items():
                if fresh or not np.array_equal(cols.get(key, r), value, equal_nan=True):
                    cols.put(key, r, value)
        self.written = len(partial) if len(partial) >= 2 else 0
        del self.specials[self.committed:]
        self.specials += [dataclasses.replace(p, index=p.index + k0 - 1,
                                              arclength=p.arclength + self.s0, branch=self.name)
                          for p in partial.special_points]
        total = k0 + len(partial) - 1 if len(partial) >= 2 else k0
        phase = partial if len(partial) >= 2 else self.phase
        return dataclasses.replace(
            self.first, name=self.name,
            records={key: cols.view("record:" + key, total) for key in self.first.records},
            special_points=tuple(self.specials), status=partial.status,
            message=partial.message, phase_modes=phase.phase_modes,
            phase_state=phase.phase_state,
            **{key: cols.view(key, total) for key in _ARRAYS + _STEPS + ("arclength",)})

    def commit(self, run: Branch) -> None:
        """The run in progress ended as ``run`` (its final branch): the next calls
        continue after it."""
        if len(run) >= 2 and self.k0:
            self(run)
            self.k0 += len(run) - 1
            self.s0 += float(run.arclength[-1])
            self.committed = len(self.specials)
            self.phase = run
            self.merged_runs += 1
        self.written = 0


def follow(problem, rod: PinnedRod, first: Branch, options: ContinuationOptions,
           name: str, records, events: tuple[UserEvent, ...] = (),
           stop: Callable[[Branch], bool] | None = None, max_points: int = 400,
           segment_points: int = 30, on_point: Callable[[Branch], None] | None = None,
           quality: float = 0.5, grip: Callable[[np.ndarray], float] | None = None,
           grip_fraction: float = 0.25,
           refuse: Callable[[np.ndarray], str | None] | None = None,
           restart: Callable[[np.ndarray], Callable[[np.ndarray], str | None]] | None = None,
           on_run: Callable[[int], None] | None = None,
           run_options: Callable[[np.ndarray], ContinuationOptions] | None = None,
           ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]]:
    """Continue ``first`` (a computed run) in runs of ``segment_points``, re-pinning between.

    Each run starts at the last point of the previous one, in the direction
    its tangent had; the pins are re-picked there when ``rod.pin_quality``
    fell below ``quality``. Stops when a run ends early (a bound,
    a failure), when ``stop(run)`` is true, or at ``max_points``. Returns the
    merged branch and its pins: ``(first point index, pinned DOFs)`` per
    change (the pinned coordinate keeps its value from that point on).
    ``on_point(merged_so_far)`` is called after each accepted point of the
    later runs (``first``'s own points were reported by its caller).

    ``grip(q)``: the current pins' hold on the symmetry at ``q`` (the rod's
    ``pin_grip``, a determinant that is zero where they do not remove it). A run
    refuses a point where it fell below ``grip_fraction`` of its value at the run's
    start and ends at the point before (``continuation``'s ``stop``); the pins are
    re-picked there and the branch goes on. A fixed pin set can pass through a
    configuration where it does not remove a rigid motion at all: measured on the
    ring's alpha branch (N = 200, dLk 3.667), the grip fell to 5 % of the best
    choice's at one point, and the unstable count flickered there.

    ``refuse(q)``: a ``continuation`` ``stop`` asked in every run (after the grip's),
    e.g. to end a run as soon as what ``stop(run)`` waits for has happened instead of
    at the end of the run (a refusal it makes ends the branch when ``stop(run)`` is
    then true; otherwise the pins are re-picked as after the grip's).

    ``restart(q)``: a ``stop`` made for each run from its first state ``q``, asked
    after ``refuse`` (e.g. the end of a run where the state's approximate symmetries
    change, so that the next run starts with the phase rows they need); the run
    then ends ``STOPPED`` and the next one starts at its last point. A run that refuses
    its very first point starts again from the same point with its first step shortened
    by ``REFUSED_SHRINK``, at most ``REFUSED_RETRIES`` times: a stop with hysteresis
    (:func:`~supercoil.problems.tweezers.pins.sliding_stop`) is refused by both sides
    when one step crosses its whole band (measured at L/D = 200, lambda = 150, N = 202:
    the sliding's tail ratio fell threefold a step on the localising loop, from 2.4e-4
    to 8.4e-5 across the band 1.1e-4 to 2.4e-4), and a shorter step lands within it.

    ``on_run(index)``: called before each later run with the index of its first point
    on the merged branch (e.g. to record where each run starts, so that an interrupted
    run can be resumed up to its own end).

    ``run_options(q)``: the options of a later run from its first state ``q`` (e.g. its
    phase rows), instead of ``options``; asked before ``restart(q)``.
    """
    parts = [first]
    # the runs merged so far, extended at every point of the run in progress
    merger = MergedRuns(first, name) if on_point is not None else None
    pins = [(0, tuple(int(d) for d in rod.gauge_dofs))]
    total = len(first)
    run = first
    last = first  # the last run with a step (its tangent and step start the next run)
    stopped_at = None
    stuck = False
    shorter = 1.0  # the next run's first step, as a fraction of the last run's last
    while run.ok and total < max_points and not (stop and stop(run)) \
            and run.status.name in ("MAX_POINTS", "STOPPED"):
        if run.status.name == "STOPPED":
            if stopped_at == total:  # the fresh run refused its very first point too
                # a shorter first step lands between the refusals' thresholds (a stop
                # with hysteresis: one step crossed its whole band)
                shorter *= REFUSED_SHRINK
                if shorter < REFUSED_SHRINK ** REFUSED_RETRIES:
                    stuck = True
                    break
            else:
                shorter = 1.0
            stopped_at = total
        elif len(run) < 2:
            break
        if len(run) >= 2:
            last = run
        elif len(last) < 2:  # no step yet to start the next run from
            break
        q = last.states[-1]
        if run.status.name == "STOPPED" or rod.pin_quality(q) < quality:
            set_pin(problem, rod, q)
            pins.append((total - 1, tuple(int(d) for d in rod.gauge_dofs)))
        # the next run starts with the frames the last run with a step ended with
        # (problem unchanged)
        carrying = carried(frames_at(problem, last, len(last) - 1), q)
        direction = 1 if last.tangents[-1, -1] >= 0 else -1
        step = float(np.clip(shorter * (last.arclength[-1] - last.arclength[-2]),
                             options.min_step, options.max_step))
        opts = dataclasses.replace(options if run_options is None else run_options(q),
                                   direction=direction, initial_step=step,
                                   max_points=min(segment_points, max_points - total + 1))
        report = None if merger is None else (
            lambda partial, merger=merger: on_point(merger(partial)))
        held = None if grip is None else grip_stop(grip, q, grip_fraction)
        if on_run is not None:
            on_run(total - 1)
        stops = either(held, refuse, None if restart is None else restart(q))
        run = continuation(carrying, q, last.multipliers[-1], parameter=last.parameter,
                           start=float(last.parameter_values[-1]),
                           options=opts, name=name, records=records, events=events,
                           on_point=report, stop=stops, first_index=total - 1)
        if run.status is ContinuationStatus.START_FAILED and len(last.phase_modes):
            # the last point is an equilibrium of the last run's gauge, not of the one
            # chosen there: near a fold or a bifurcation point the state must move far to
            # meet the new one and Newton diverges (measured on the trefoil ring at C/A 1.4,
            # L/D 170, N 180, at dLk 4.927 just past its bifurcation point at 4.920: a
            # first step of 0.73 D). The
            # run starts again in the last run's gauge, on its tangent's hyperplane.
            run = continuation(carrying, q, last.multipliers[-1], parameter=last.parameter,
                               start=float(last.parameter_values[-1]), options=opts,
                               name=name, records=records, events=events, on_point=report,
                               stop=stops, phase=(last.phase_modes, last.phase_state),
                               guess=last.tangents[-1], first_index=total - 1)
        parts.append(run)
        if merger is not None:
            merger.commit(run)
        total += len(run) - 1
    merged = merge_branches(parts, name)
    if stuck:
        merged = dataclasses.replace(
            merged, status=ContinuationStatus.STEP_TOO_SMALL,
            message=f"stopped after {total} points: freshly picked pins refused the next "
                    f"point too, with first steps down to {shorter / REFUSED_SHRINK:.2g} of "
                    f"the last ({merged.message})")
    elif merged.ok and total >= max_points and merged.status.name in ("MAX_POINTS", "STOPPED"):
        merged = dataclasses.replace(merged, status=ContinuationStatus.MAX_POINTS,
                                     message=f"{total} points computed (max_points)")
    return merged, tuple(pins)
