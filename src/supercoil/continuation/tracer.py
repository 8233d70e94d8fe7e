"""The tracer: follows one branch point by point, and keeps what each point carries.

From a corrected point and its tangent, :class:`Tracer` takes steps
(:func:`~supercoil.continuation.step.take_step`), growing them after fast
corrections and shrinking them after failures, until a parameter bound, the
arclength or point budget, a caller's stop, a closed loop
(:mod:`supercoil.continuation.closure`) or a step below the minimum. At every
accepted point the system follows the problem carried there
(:meth:`ExtendedSystem.carry_to`), then the stability
(:mod:`supercoil.continuation.stability`), the caller's records and user
events are evaluated, and the interval to the previous point is searched for
special points (:mod:`supercoil.continuation.special_points`). The phase rows
may move (:mod:`supercoil.continuation.phase`). :meth:`Tracer.branch` is the
branch so far as a :class:`~supercoil.continuation.branch.Branch`, with the
frames the problem carried at each point.

The problem the tracer was given is never changed: at each accepted point the
system follows a new problem carried there (``carried_to``). Record and event
functions that need it take a keyword ``problem``: they are then called with the
problem at the point (its parameter value and its carried frames).
"""

from __future__ import annotations

import dataclasses
import logging
import re
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from supercoil.continuation.bordered import BorderedFactor
from supercoil.continuation.branch import Branch, SpecialPoint
from supercoil.continuation.branch_rows import BranchRows
from supercoil.continuation.closure import retraced, returned_to
from supercoil.continuation.columns import Columns
from supercoil.continuation.events import UserEvent, point_values, takes_problem, user_values
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.phase import regauged, rephased_tangent
from supercoil.continuation.secant_jump import chord_step
from supercoil.continuation.special_points import locate_events, special_point
from supercoil.continuation.stability import (
    count_factor,
    factor_count,
    inertia,
    point_stability,
)
from supercoil.continuation.step import TURN_FAILURE, take_step
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.carried import frames_of
from supercoil.solvers.errors import InertiaError, SingularMatrixError

log = logging.getLogger(__name__)

RecordFunction = Callable[[np.ndarray, np.ndarray, float], Mapping[str, object]]
PointCallback = Callable[[Branch], None]
PARTIAL_MESSAGE = "in progress: the branch so far (its computation has not ended)"
def _failure_kind(failure: str) -> str:
    """``failure`` without its numbers: failures of one kind at different steps."""
    return re.sub(r"[-+]?\d+(\.\d*)?(e[-+]?\d+)?", "#", failure)


def _earlier_failures(failed: list[tuple[float, str]]) -> str:
    """``"; before it, ..."``: the failures of other kinds than the last among the steps
    that shrank to the minimum from the last point (``(step, failure)`` in order), each
    kind with its last message, its steps and their number; empty if there were none.
    The last failure alone can mislead: measured on a tweezers contact branch, the
    corrector raised the residual from 7.7e-7 (the point's own, far above the
    tolerance) at every step from 1.7e-6 down to 2e-7, and below that the trust
    region, scaled with the step, stopped every first iterate."""
    last = _failure_kind(failed[-1][1]) if failed else ""
    kinds: dict[str, list] = {}
    for step, failure in failed:
        kind = _failure_kind(failure)
        if kind != last:
            entry = kinds.setdefault(kind, [failure, step, step, 0])
            entry[0], entry[1], entry[2] = failure, min(entry[1], step), max(entry[2], step)
            entry[3] += 1
    if not kinds:
        return ""
    return "; before it, " + "; ".join(
        f"{failure} at {n} step{'s' if n > 1 else ''} of {low:.2g}"
        + (f" to {high:.2g}" if high > low else "")
        for failure, low, high, n in kinds.values())


class Tracer:
    """Follows one branch from a corrected point and tangent; collects points and events."""

    def __init__(self, system: ExtendedSystem, options: ContinuationOptions, name: str,
                 parent: str | None, origin: SpecialPoint | None,
                 records: RecordFunction | None, events: Sequence[UserEvent],
                 on_point: PointCallback | None = None, prefix: Branch | None = None,
                 prefix_arclength: float = 0.0):
        """``prefix``: points that come before this run's on the branch (a resumed
        branch's stored points): :meth:`branch` is ``prefix`` followed by this run's
        points, their indices shifted by ``len(prefix)`` and their arclength by
        ``prefix_arclength`` (that of this run's first point on the whole branch)."""
        self.system = system
        self.on_point = on_point
        self.stop: Callable[[np.ndarray], str | None] | None = None  # see pseudo_arclength.continuation()
        # see pseudo_arclength.continuation(); by default the problem's own admissible(q),
        # if it has one: that of the problem carried to the last point
        self.admissible: Callable[[np.ndarray], bool] | None = (
            self._carried_admissible if hasattr(system.problem, "admissible") else None)
        self.opts = options
        self.name, self.parent, self.origin = name, parent, origin
        self.records_fn = records
        self.events = tuple(events)
        self.xs: list[np.ndarray] = []
        self.ts: list[np.ndarray] = []
        self.stabs = []
        self.s: list[float] = []
        self.recs: list[dict] = []
        self.frames: list = []  # the problem's carried frames at each point
        self.user: list[list[dict]] = []
        self.specials: list[SpecialPoint] = []
        # the step controller's state after each point (Branch.next_step, .gauge_moved)
        self.steps: list[float] = []
        self.moved: list[bool] = []
        # (tangent, step) of the point before the first one, for the quadratic
        # predictor of a resumed branch (set by resume_branch)
        self.before: tuple[np.ndarray, float] | None = None
        # the point before the first one, for the secant predictor of a resumed branch
        self.point_before: np.ndarray | None = None
        # (x, full Hessian) of the last point added, assembled after its carry: the
        # rephase tangent there needs no new one (phase rows are linear)
        self._accepted_hessian: tuple[np.ndarray, object] | None = None
        # each point converted once into the columns branch() reads
        self.rows = BranchRows(prefix, prefix_arclength)
        # the branch's index of this run's first point: messages number points on the branch
        self.first = 0 if prefix is None else len(prefix)
        # each point's parameter value and unstable count, for the closure tests
        self._parameters = Columns()
        self._counts: list[int] = []
        # the secant steps past a lost tangent: (index of the point jumped from, length);
        # the number of points when the last one was tried (once from a point)
        self.secant_jumps: list[tuple[int, float]] = []
        self._jump_tried_at = -1

    def _previous_tangent(self) -> tuple[np.ndarray, float] | None:
        """The tangent at the point before the last and the arclength between the two."""
        if len(self.xs) >= 2:
            return self.ts[-2], self.s[-1] - self.s[-2]
        return self.before if len(self.xs) == 1 else None

    def _carried_admissible(self, q: np.ndarray) -> bool:
        return self.system.problem.admissible(q)

    def _vet(self, q: np.ndarray) -> bool:
        """``admissible(q)``, with ``problem=`` the problem carried to the last point if
        it takes that keyword."""
        if takes_problem(self.admissible):
            return self.admissible(q, problem=self.system.problem)
        return self.admissible(q)

    # -- per point ------------------------------------------------------------------------
    def _records(self, x):
        if self.records_fn is None:
            return {}
        return dict(point_values(self.records_fn, self.system, x))

    def add_point(self, x: np.ndarray, t: np.ndarray, search_events: bool = True,
                  full_hessian=None, next_step: float = float("nan"),
                  publish: bool = True, counted=None) -> None:
        """Keep ``x``: stability, records and user values first (an exception leaves the
        branch as it was), then the point, then the events since the previous one;
        then, with ``publish``, hand the branch to ``on_point`` (:meth:`publish`).
        ``next_step``: the step the run will try first from ``x``.

        ``full_hessian``: the Hessian on all DOFs at ``x`` if known (a converged
        :class:`~supercoil.continuation.corrector.Correction`'s), for the stability
        and the rephase tangent. It was assembled before the problem was carried to
        ``x`` (the rod's reference frames transported there): that changes the Hessian by round-off
        only (measured on the ring's alpha branch at N = 200: at most 3e-16 of its
        largest entry, as much as assembling it twice at ``x`` with other states
        evaluated in between does). A problem whose ``accept`` moves its coordinates
        (``accept_moves_coordinates``: a chart re-based at ``x``) has it assembled again.
        ``counted``: the count's factor at ``x`` with that Hessian in the current phase
        rows (:func:`~supercoil.continuation.stability.count_factor`, made by the
        check of a count change without a fold, :meth:`_count_jumped`), or None.
        """
        system = self.system
        system.carry_to(system.q(x))
        self._accepted_hessian = None
        if getattr(system.problem, "accept_moves_coordinates", False):
            # a chart re-based at x (a Cosserat rod's rotations) changes the coordinates
            # the Hessian is written in at first order in the step: the corrector's
            # Hessian would give the tangent in the old chart (measured: 5e-4 rad off at
            # steps of 2e-4, which moved the next point along the branch by 3e-9)
            full_hessian = None
        full = system.full_hessian(x) if full_hessian is None else full_hessian
        stability = point_stability(system, x, self.opts.zero_tolerance, self.opts.n_modes,
                                    full, None if full_hessian is None else counted)
        records = self._records(x)
        user = [user_values(ev, system, x) for ev in self.events]
        self.s.append(0.0 if not self.xs else self.s[-1] + system.norm(x - self.xs[-1]))
        self.xs.append(x)
        self.ts.append(t)
        self.stabs.append(stability)
        self._parameters.put("p", len(self.xs) - 1, x[-1])
        self._counts.append(stability.unstable_count)
        self.recs.append(records)
        self.frames.append(frames_of(system.problem))
        self.user.append(user)
        self.steps.append(float(next_step))
        self.moved.append(False)
        self._accepted_hessian = (x, full)
        if len(self.xs) >= 2 and search_events:
            self._search_events()
        if publish:
            self.publish()

    def publish(self) -> None:
        """Hand the branch so far to ``on_point``, once its last point is complete: its
        tangent and phase rows final (after a rephase), and the step controller's
        state from it known, so that a run resumed from it takes the same steps."""
        if self.on_point is not None:
            self.on_point(self.branch(ContinuationStatus.MAX_POINTS, PARTIAL_MESSAGE,
                                      partial=True))

    # -- events between the last two points -------------------------------------------------
    def _search_events(self) -> None:
        k = len(self.xs) - 2
        before, after = self.stabs[k].unstable_count, self.stabs[k + 1].unstable_count
        segment, found = locate_events(self.system, self.opts, self.events, self.xs[k],
                                       self.xs[k + 1], self.ts[k], self.ts[k + 1], before,
                                       after, self.user[k], self.user[k + 1])
        for ev in found:
            self.specials.append(special_point(self.system, self.opts, ev, segment, self.name,
                                               k, self.s[k], self.ts[k + 1], before, after,
                                               self._records))

    # -- phase rows -------------------------------------------------------------------------
    def _regauge(self, ds: float) -> bool:
        """Move the phase rows to those of the last point and correct it in the new gauge
        (:func:`~supercoil.continuation.phase.regauged`); False if the gauge is unchanged.
        A point that moved is added to the branch (at the same parameter value), else
        the last point is replaced; either way it is published with the step ``ds``,
        to be retried from it once without moving the gauge again."""
        moved = regauged(self.system, self.opts, self.xs[-1], self.ts[-1])
        if moved is None:
            return False
        x, t = moved
        if self.system.norm(x - self.xs[-1]) > self.opts.min_step:
            # the same equilibrium up to the gauge's slide: no events between the two
            # (their counts and values come from different gauges)
            self.add_point(x, t, search_events=False, publish=False)
        else:
            self.xs[-1], self.ts[-1] = x, t
            self._parameters.put("p", len(self.xs) - 1, x[-1])
        self.steps[-1], self.moved[-1] = ds, True
        try:
            if self.opts.rephase:
                self._rephase()
        finally:
            self.publish()
        return True

    def _rephase(self, factor: BorderedFactor | None = None) -> None:
        """Re-anchor the integral phase condition at the last point and recompute its
        tangent (``ContinuationOptions.rephase``;
        :func:`~supercoil.continuation.phase.rephased_tangent`). ``factor``: the step's
        corrector factor (``ContinuationOptions.factor_refinement``)."""
        x = self.xs[-1]
        known = self._accepted_hessian
        full = known[1] if known and known[0] is x else None
        t = rephased_tangent(self.system, self.opts, x, self.ts[-1], full, factor)
        if t is not None:
            self.ts[-1] = t

    # -- the stepping loop ------------------------------------------------------------------
    def run(self, step: float, gauge_moved: bool = False) -> tuple[ContinuationStatus, str]:
        """Step from the last point until a bound, a stop or a failure; ``(status, message)``.
        ``step``: the first step tried; ``gauge_moved``: the last point was corrected in
        moved phase rows after a failed step (they are not moved again before a step
        succeeds)."""
        try:
            status, message = self._run(step, gauge_moved)
        except (SingularMatrixError, InertiaError) as exc:
            status, message = self._stability_failed(exc)
        n = len(self.secant_jumps)
        if n:
            where = ", ".join(str(k) for k, _ in self.secant_jumps)
            plural = "s" if n > 1 else ""
            message += (f"; {n} step{plural} along the chord past a lost tangent "
                        f"(from point{plural} {where})")
        return status, message

    def _back_on_sheet(self, j: int, taken) -> bool:
        """Whether the corrected point of ``taken``, found on the earlier chord ``j`` followed
        the other way (:func:`~supercoil.continuation.closure.retraced`), has that chord's
        raw count and not the step start's: the two sheets of a fold differ by one, so a
        point of the sheet ahead that runs close beside the one followed (a sharp fold,
        whose sheets part like the square root of the distance from it) keeps the count of
        the step's start."""
        before = {self.stabs[j].negative_count, self.stabs[j + 1].negative_count}
        if len(before) != 1 or self.stabs[-1].negative_count in before:
            return False
        return self._count_at(taken) in before

    def _count_at(self, taken) -> int | None:
        """The raw count (:func:`~supercoil.continuation.stability.inertia`) at the
        corrected point of ``taken``, or None where the factorisation fails."""
        full = taken.full_hessian
        try:
            negative, _sign = inertia(self.system, taken.x, self.opts.zero_tolerance,
                                      None if full is None else full.restrict(self.system.free))
        except (SingularMatrixError, InertiaError):
            return None
        return negative

    def _start_factor_count(self) -> int | None:
        """The factor's count (:func:`~supercoil.continuation.stability.factor_count`) at
        the last point, in the current phase rows; None where the factorisation fails."""
        kept = self._accepted_hessian
        full = (kept[1] if kept is not None and kept[0] is self.xs[-1]
                else self.system.full_hessian(self.xs[-1]))
        try:
            return factor_count(self.system, self.xs[-1], full.restrict(self.system.free))
        except (SingularMatrixError, InertiaError):
            return None

    def _count_jumped(self, taken, start: int | None) -> bool:
        """Whether the corrected point of ``taken`` has another raw count than the step's
        start while the parameter keeps its direction (no fold between them). The
        factors' counts are compared first (``start``: the start's, one sparse
        factorisation at each end); only where they differ is the count with the stiff
        sliding left out computed. The end's factor is kept with ``taken``
        (``taken.counted``) for the point's stability, should it be accepted."""
        if start is None or taken.t[-1] * self.ts[-1][-1] <= 0.0:
            return False
        full = taken.full_hessian
        try:
            factor = count_factor(self.system, taken.x,
                                  None if full is None else full.restrict(self.system.free))
        except (SingularMatrixError, InertiaError):
            return False
        taken.counted = factor
        if factor.reduced_negative_count == start:
            return False
        negative = self._count_at(taken)
        return negative is not None and negative != self.stabs[-1].negative_count

    def _retraced(self, taken) -> str | None:
        """Why the corrected point of ``taken`` is refused as lying on the branch's own
        path, followed the other way (:func:`~supercoil.continuation.closure.retraced`),
        or None."""
        j = retraced(self.system, self.opts, self.xs, self.ts, taken.x, taken.t,
                     self._parameters.view("p", len(self.xs)))
        if j is not None and self._back_on_sheet(j, taken):
            return (f"the corrected point lies on the branch's own path near its point {j}, "
                    f"followed the other way (a jump back across a fold's sheets)")
        return None

    def _secant_jump(self, failed: list[tuple[float, str]]):
        """``(taken, ds)``: a step along the chord past a lost tangent
        (:func:`~supercoil.continuation.secant_jump.chord_step`), where every step down to
        the minimum was refused for its tangent's turn, tried once from a point; else the
        text to add to the stop's message."""
        if not failed or TURN_FAILURE not in failed[-1][1] or self._jump_tried_at == len(self.xs):
            return ""
        self._jump_tried_at = len(self.xs)
        jump = chord_step(self.system, self.opts, self.xs, self.s,
                          None if self.admissible is None else self._vet, self.stop,
                          self._retraced)
        if not isinstance(jump, str):
            k = self.first + len(self.xs) - 1
            log.info("point %d: the tangent lost, a step of %.3g along the chord went", k,
                     jump[1])
            self.secant_jumps.append((k, jump[1]))
        return jump

    def _attempt(self, length: float):
        """A step of ``length`` from the last point (:func:`take_step`)."""
        return take_step(self.system, self.opts, self.xs[-1], self.ts[-1],
                         self.xs[-2] if len(self.xs) >= 2 else self.point_before,
                         self._previous_tangent(), length,
                         None if self.admissible is None else self._vet, self.stop)

    def _stability_failed(self, exc: Exception) -> tuple[ContinuationStatus, str]:
        return ContinuationStatus.STEP_TOO_SMALL, (
            f"stability at point {self.first + len(self.xs)} failed: {exc}")

    def _run(self, step: float, regauged_here: bool) -> tuple[ContinuationStatus, str]:
        system, opts = self.system, self.opts
        low, high = opts.parameter_bounds
        ds = step
        failed: list[tuple[float, str]] = []  # (step, failure) since the last point
        refused = None  # (step, length): a count change refused since the last point
        while len(self.xs) < opts.max_points:
            if self.s[-1] >= opts.max_arclength:
                return ContinuationStatus.MAX_ARCLENGTH, (
                    f"arclength {self.s[-1]:.4g} reached max_arclength after {self.first + len(self.xs)} points")
            x_k = self.xs[-1]
            taken = self._attempt(ds)
            if taken.refusal:
                return ContinuationStatus.STOPPED, (
                    f"stopped after {self.first + len(self.xs)} points at {system.parameter} = "
                    f"{x_k[-1]:.10g}: {taken.refusal}")
            if taken.leaves_bound:
                return ContinuationStatus.PARAMETER_BOUND, (
                    f"{system.parameter} = {taken.bound:.10g} is a bound and the branch leaves "
                    f"the interval there ({self.first + len(self.xs)} points)")
            start = (self._start_factor_count() if taken.failure is None
                     and opts.detect_closed_loops and ds >= 4 * opts.min_step else None)
            if self._count_jumped(taken, start):
                # a count change with no fold: a bifurcation crossed, or a step across the
                # sheets of a fold onto another sheet; half the step tells them apart, and
                # where it fails it cannot: the step is taken again shorter
                half = self._attempt(0.5 * ds)
                if half.refusal or half.leaves_bound or half.failure is not None:
                    refused = (taken, ds)
                    taken = dataclasses.replace(taken, failure=(
                        "the step changed the unstable count with no fold and half of it "
                        f"failed ({half.failure or half.refusal or 'it leaves the bound'})"))
                elif not self._count_jumped(half, start):
                    log.debug("step %.3g changed the count with no fold; half of it did not",
                              ds)
                    taken, ds = half, 0.5 * ds
            if taken.failure is None and opts.detect_closed_loops:
                taken.failure = self._retraced(taken)
            if taken.failure is not None:
                log.debug("step %.3g rejected: %s", ds, taken.failure)
                failed.append((ds, taken.failure))
                if opts.regauge and system.r and not regauged_here:
                    try:
                        moved = self._regauge(ds)
                    except (SingularMatrixError, InertiaError) as exc:
                        return ContinuationStatus.STEP_TOO_SMALL, (
                            f"stability at the point corrected in a moved gauge failed: {exc}")
                    if moved:
                        regauged_here = True  # retry the same step once with the moved gauge
                        refused = None  # a step of the gauge before
                        log.debug("gauge moved at point %d", len(self.xs) - 1)
                        continue
                if ds > opts.min_step:
                    ds = max(ds * opts.shrink, opts.min_step)
                    continue
                if refused is not None and (not opts.detect_closed_loops
                                            or self._retraced(refused[0]) is None):
                    # every shorter step failed as well: the start lies so close to a
                    # bifurcation that steps ending near it fail; the refused step crossed it
                    log.debug("no step shorter than %.3g went; it is taken", refused[1])
                    taken, ds = refused
                else:
                    jump = self._secant_jump(failed)
                    if isinstance(jump, str):
                        return ContinuationStatus.STEP_TOO_SMALL, (
                            f"stopped after {self.first + len(self.xs)} points at "
                            f"{system.parameter} = {x_k[-1]:.10g}: {taken.failure} at the "
                            f"minimum step {opts.min_step:.1e}{_earlier_failures(failed)}{jump}")
                    taken, ds = jump
            refused = None
            regauged_here = False
            failed.clear()
            x_new, bound, corr = taken.x, taken.bound, taken.correction
            log.debug("step %.3g accepted at %s = %.10g after %d corrector iterations",
                      ds, system.parameter, x_new[-1], corr.iterations)
            if corr.iterations <= opts.fast_iterations:
                ds = min(ds * opts.growth, opts.max_step)
            try:
                self.add_point(x_new, taken.t, full_hessian=taken.full_hessian, next_step=ds,
                               publish=False, counted=taken.counted)
                try:
                    if opts.rephase and system.r:
                        self._rephase(corr.factor if opts.factor_refinement and bound is None
                                      else None)
                finally:
                    self.publish()
            except (SingularMatrixError, InertiaError) as exc:
                return self._stability_failed(exc)
            if bound is None and x_new[-1] in (low, high):
                bound = x_new[-1]  # the step ended exactly on the bound
            if bound is not None:
                return ContinuationStatus.PARAMETER_BOUND, (
                    f"reached {system.parameter} = {bound:.10g} after {self.first + len(self.xs)} points")
            if opts.detect_closed_loops:
                try:
                    j = returned_to(system, opts, self.xs, self.ts, self._counts,
                                    self._parameters.view("p", len(self.xs)))
                except (SingularMatrixError, InertiaError) as exc:
                    return self._stability_failed(exc)
                if j is not None:
                    return ContinuationStatus.CLOSED_LOOP, (
                        f"the branch closed on itself: after {self.first + len(self.xs)} points it came "
                        f"back to point {self.first + j} ({system.parameter} = {self.xs[j][-1]:.6g}; "
                        f"arclength {self.s[-1] - self.s[j]:.4g} per lap)")
        return ContinuationStatus.MAX_POINTS, f"{self.first + len(self.xs)} points computed (max_points)"

    # -- result -------------------------------------------------------------------------------
    def branch(self, status: ContinuationStatus, message: str,
               partial: bool = False) -> Branch:
        """The branch so far, after the ``prefix`` if given; a ``partial`` one (handed
        to ``on_point`` at every point) costs O(1) a point
        (:class:`~supercoil.continuation.branch_rows.BranchRows`)."""
        return self.rows.branch(self, status, message, partial)
