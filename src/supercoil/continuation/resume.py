"""Continue an interrupted branch from its last point (``supercoil run --resume``).

A branch saved point by point (``continuation(on_point=...)``) and then
interrupted is continued by :func:`resume_branch` with the same extended
system: the branch's own phase conditions (``phase_modes``, ``phase_state``:
the gauge pins it was computed with, not new ones chosen at the last point),
the last point re-corrected at its parameter value, the tangent oriented like
the stored one, and the step controller's state the interrupted run stored
with its last point (``Branch.next_step``, ``Branch.gauge_moved``; for a
branch stored without it, :func:`_next_step`; or ``step``). From the same
state the steps that follow, failed ones included, are the same. The result is the whole branch, the stored
points followed by the new ones (indices and arclength continued), as the
uninterrupted run gives it (tested: the same points to round-off).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from supercoil.continuation.branch import POINT_ARRAYS, Branch
from supercoil.continuation.carry import branch_frames
from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.events import UserEvent
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.step import quadratic_term
from supercoil.continuation.system import ExtendedSystem
from supercoil.continuation.tracer import PointCallback, RecordFunction, Tracer
from supercoil.solvers.carried import with_frames
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.problem import ConstrainedEnergy


def head(branch: Branch, k: int) -> Branch:
    """The first ``k`` points of ``branch`` with the special points between them."""
    return dataclasses.replace(
        branch, special_points=tuple(p for p in branch.special_points if p.index + 1 < k),
        records={n: v[:k] for n, v in branch.records.items()}, frames=branch.frames[:k],
        **{n: getattr(branch, n)[:k] for n in POINT_ARRAYS})


def _next_step(system: ExtendedSystem, partial: Branch, opts: ContinuationOptions,
               problem: ConstrainedEnergy) -> float:
    """The step the interrupted run would have taken next, for a branch stored without
    it (``Branch.next_step`` NaN): an estimate.

    The last step's pseudo-arclength ``ds = W d . (x_k - x_{k-1})`` (``d`` the
    predictor direction at point ``k - 1``) is exact; whether the run then grew
    it depends on the corrector's iteration count, which is replayed (one
    correction from point ``k - 1``), as the tracer does: ``growth * ds`` (at
    most ``max_step``) after a fast correction, ``ds`` otherwise. The replay does
    not see what the run's corrector did differently (a predictor shortened at an
    obstacle, refinement with an old factor), nor a step that failed after point
    ``k - 1`` was stored.
    """
    k = len(partial)
    if k < 2:
        return opts.initial_step

    def packed(i):
        return system.pack(partial.states[i], partial.multipliers[i],
                           float(partial.parameter_values[i]))

    x_prev, x_last = packed(-2), packed(-1)
    d = system.reduced(partial.tangents[-2])
    if opts.predictor == "secant" and k >= 3:
        d = x_prev - packed(-3)
    d = d / system.norm(d)
    row = system.weights * d
    ds = float(row @ (x_last - x_prev))
    if not ds > 0:
        return opts.initial_step
    system.problem = with_frames(problem, partial.frames[-2])  # as the run had them there
    start = x_prev + ds * d
    if opts.predictor == "quadratic" and k >= 3:
        start = start + quadratic_term(system, system.reduced(partial.tangents[-3]),
                                       system.reduced(partial.tangents[-2]),
                                       float(partial.arclength[-2] - partial.arclength[-3]), ds)
    replay = correct(system, start, row, x_prev, ds, opts.tolerance,
                     opts.max_corrector_iterations)
    if replay.ok and replay.iterations <= opts.fast_iterations:
        return min(ds * opts.growth, opts.max_step)
    return ds


def resume_branch(problem: ConstrainedEnergy, partial: Branch,
                  options: ContinuationOptions | None = None, *,
                  records: RecordFunction | None = None, events: tuple[UserEvent, ...] = (),
                  on_point: PointCallback | None = None, step: float | None = None,
                  stop: Callable[[np.ndarray], str | None] | None = None,
                  admissible: Callable[[np.ndarray], bool] | None = None,
                  resumed: bool = True) -> Branch:
    """Continue ``partial`` (at least one point) under ``options`` (the options it was
    computed with: ``max_points`` counts the whole branch); see the module docstring.
    ``problem`` is as the interrupted run had it before the branch's first point; it is
    never changed (the frames of the stored points are ``partial.frames``, else carried
    along its states from it: :mod:`supercoil.continuation.carry`).

    ``records``, ``events``, ``stop`` and ``admissible`` must be those of the
    interrupted run (:func:`~supercoil.continuation.continuation`). ``on_point``
    receives the whole branch so far. Numerical failures end in the status. The
    message says after which point the run was resumed, unless ``resumed`` is False
    (a run its caller starts from points it made itself).
    """
    opts = options or ContinuationOptions()
    k = len(partial)
    if k == 0:
        raise ValueError(f"branch {partial.name!r} has no point to resume from; start it again")
    if k >= opts.max_points:
        return dataclasses.replace(partial, status=ContinuationStatus.MAX_POINTS,
                                   message=f"{k} points computed (max_points)")
    # the frames of the stored points (a state means the same configuration only with
    # the frames it was computed with): those the run kept, else carried along the
    # stored points in order from the problem, as the interrupted run carried them
    # (supercoil.continuation.carry); the problem is never changed
    partial = dataclasses.replace(partial, frames=branch_frames(problem, partial))
    lam = float(partial.parameter_values[-1])
    q = np.array(partial.states[-1], dtype=float)
    modes = partial.phase_modes if partial.phase_modes.size else None
    system = ExtendedSystem(with_frames(problem, partial.frames[-1]), partial.parameter, q,
                            modes,
                            partial.phase_state if modes is not None else None,
                            opts.parameter_weight, opts.finite_difference_step)
    gauge_moved = False
    if step is not None:
        step = min(max(step, opts.min_step), opts.max_step)
    elif np.isfinite(partial.next_step[-1]):
        step, gauge_moved = float(partial.next_step[-1]), bool(partial.gauge_moved[-1])
    else:
        step = min(max(_next_step(system, partial, opts, problem), opts.min_step),
                   opts.max_step)
        system.problem = with_frames(problem, partial.frames[-1])
    # the first k - 1 points, with every special point found so far: one between
    # points k - 2 and k - 1 was located when point k - 1 was added, and the
    # resumed run starts at point k - 1, so it would not search that interval again
    before = dataclasses.replace(head(partial, k - 1), special_points=tuple(
        p for p in partial.special_points if p.index + 1 < k))
    offset = float(partial.arclength[-1])

    tracer = Tracer(system, dataclasses.replace(opts, max_points=opts.max_points - (k - 1)),
                     partial.name, partial.parent, partial.origin, records, events,
                     on_point, prefix=before, prefix_arclength=offset)
    tracer.stop = stop
    if admissible is not None:
        tracer.admissible = admissible
    if k >= 2:
        tracer.before = (system.reduced(partial.tangents[-2]),
                         float(partial.arclength[-1] - partial.arclength[-2]))
        tracer.point_before = system.pack(partial.states[-2], partial.multipliers[-2],
                                          float(partial.parameter_values[-2]))
    x0 = system.pack(q, partial.multipliers[-1], lam)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    corr = correct(system, x0, e_lam, x0, 0.0, opts.tolerance, 4 * opts.max_corrector_iterations)
    if not corr.ok:
        return dataclasses.replace(partial, status=ContinuationStatus.START_FAILED,
                                   message=f"resume: the last stored point did not converge "
                                   f"again: {corr.message}")
    if opts.rephase and modes is not None and (k >= 2 or bool(partial.gauge_moved[-1])):
        # the interrupted run re-anchored the phase rows at the stored point (after its
        # step, or its moved gauge); the point corrected again lies a round-off away
        # (measured 3e-10), and rows left at the stored one differ from those of the
        # corrected point by as much: a failed step's regauge would take that for a
        # moved gauge where the uninterrupted run saw none. Re-anchored here, as it was:
        # by the problem at the point, with the point's frames (a Cosserat rod's sliding
        # mode reads its sections' rotations through them)
        q_again = system.q(corr.x)
        again = branch_phase_modes(system.problem_at(float(corr.x[-1])), q_again, opts)
        if again is not None and again.shape == system.phase_modes.shape:
            system.set_phase(again, q_again)
    guess = system.reduced(partial.tangents[-1])
    try:
        t0 = tangent(system, corr.x, system.weights * guess)
        tracer.add_point(corr.x, t0, next_step=step, publish=False)
        tracer.moved[-1] = gauge_moved
        tracer.publish()
    except (SingularMatrixError, InertiaError) as exc:
        return dataclasses.replace(partial, status=ContinuationStatus.START_FAILED,
                                   message=f"resume: the last stored point is singular ({exc})")
    status, message = tracer.run(step, gauge_moved)
    whole = tracer.branch(status, message)
    if status is ContinuationStatus.MAX_POINTS:
        message = f"{len(whole)} points computed (max_points)"
    return dataclasses.replace(whole, message=f"{message} (resumed after point {k - 1})"
                               if resumed else message)
