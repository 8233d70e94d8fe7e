"""Pseudo-arclength continuation with adaptive steps, stability and events.

Keller's predictor–corrector (Keller 1977; Allgower & Georg 1990, ch. 2): from
the point ``x_k`` with unit tangent ``t_k`` the predictor is
``x_k + ds t_k`` (or along the secant), the corrector Newton's method on
``F(x) = 0, W t_k . (x - x_k) = ds`` with the bordered Jacobian factorised as
one sparse matrix (:mod:`supercoil.continuation.bordered`), and the new
tangent solves ``[[K, F_lambda], [W t_k]] t = e_last`` (same orientation;
:mod:`supercoil.continuation.step`). Steps grow after fast corrections and
shrink after failures (no convergence, divergence, a singular matrix, or a
tangent turned by more than ``max_turn_degrees``, the guard against jumping
between branches). A step that crosses a parameter bound is replaced by a
correction at exactly the bound. A problem's ``step_bound`` also vets the
predictor step (a predictor that is not collision-free is shortened to 90 % of
the allowed fraction, the corrector covering the rest) and its
``admissible(q)`` every corrected point. With ``max_corrector_distance`` the
corrector stops, as a failure, at an iterate that lies more than that many
steps from the predicted point (a jump across a corner of the branch). At
every accepted point the problem's ``accept(q)`` is called, then the stability
(:mod:`supercoil.continuation.stability`), the caller's records and user
events are evaluated, and the interval to the previous point is searched for
folds, bifurcations and user events (:mod:`supercoil.continuation.events`);
the loop over points is :class:`~supercoil.continuation.tracer.Tracer`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from supercoil.continuation.branch import Branch
from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.events import UserEvent
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.system import ExtendedSystem
from supercoil.continuation.tracer import PointCallback, RecordFunction, Tracer
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.newton import least_squares_multipliers
from supercoil.solvers.parameters import problem_at
from supercoil.solvers.problem import ConstrainedEnergy


def continuation(problem: ConstrainedEnergy, q0: np.ndarray,
                 multipliers0: np.ndarray | None = None, parameter: str = "parameter",
                 options: ContinuationOptions | None = None, *, name: str = "branch",
                 records: RecordFunction | None = None,
                 events: Sequence[UserEvent] = (),
                 on_point: PointCallback | None = None,
                 stop: Callable[[np.ndarray], str | None] | None = None,
                 admissible: Callable[[np.ndarray], bool] | None = None,
                 start: float | None = None,
                 phase: tuple[np.ndarray, np.ndarray] | None = None,
                 guess: np.ndarray | None = None, first_index: int = 0) -> Branch:
    """Follow the equilibria of ``problem`` through ``q0`` as its ``parameter`` varies.

    ``q0`` (n_dofs,) is a (near-)equilibrium at the parameter value ``start``
    (default: the problem's, ``problem.<parameter>``); it is first corrected at
    fixed parameter. ``multipliers0`` (m,) default to
    least squares. ``records(q, multipliers, parameter)`` returns named
    per-point values kept in ``Branch.records``; ``events`` are
    :class:`UserEvent` s. ``on_point(partial_branch)``, if given, is called
    after each accepted point (events between it and the previous point
    located) with the branch so far (status ``MAX_POINTS``, message
    ``PARTIAL_MESSAGE``), e.g. to save it; an exception it raises (a
    KeyboardInterrupt) propagates. ``stop(q)``, if given, is asked about each corrected
    state before it is accepted: a non-empty message refuses it and ends the run at
    the point before (status ``STOPPED``), e.g. when a problem's gauge pins lose their
    grip there and must be picked again. ``admissible(q)`` (with the keyword
    ``problem``, if it takes it, the problem carried to the last point), if given, replaces the
    problem's own ``admissible`` (if any): a corrected state it refuses is not
    accepted, and the step is retried shorter (e.g. a contact-free ring that would
    pass through itself). Returns a :class:`Branch` whose ``status`` says how
    the run ended; numerical failures never raise. The problem's parameter is
    never set (the residuals are those of ``problem.at(**{parameter: value})``,
    :func:`~supercoil.solvers.parameters.problem_at`) and its frames never move: the
    run carries new problems from point to point (``carried_to``), and the branch
    keeps their frames (``Branch.frames``). ``records`` and events that need the
    problem at the point take it as the keyword ``problem``.

    ``phase``: the phase rows to start with, ``(modes, q_phase)`` (a computed branch's
    ``phase_modes`` and ``phase_state``), instead of those chosen at ``q0``; ``guess``: a
    tangent at ``q0`` on all DOFs (a computed branch's ``tangents[k]``). With ``guess``
    the start is corrected on the hyperplane through ``q0`` orthogonal to it and its
    tangent oriented along it (``direction`` unused), so that a start at a fold, where
    the parameter cannot be held, converges; together they continue a computed branch
    from one of its points in the gauge it was computed in (see
    :func:`~supercoil.problems.segments.follow`). ``first_index``: the index of the
    point at ``q0`` on the branch that this run continues (the run's messages number its
    points on that branch; the returned branch is still the run's own, from index 0).
    """
    opts = options or ContinuationOptions()
    if not hasattr(problem, parameter):
        raise ValueError(f"the problem has no parameter attribute {parameter!r}")
    lam0 = float(getattr(problem, parameter) if start is None else start)
    low, high = opts.parameter_bounds
    if not low <= lam0 <= high:
        raise ValueError(f"the starting {parameter} = {lam0} is outside the bounds {low, high}")
    q0 = np.array(q0, dtype=float)
    at_start = problem_at(problem, **{parameter: lam0})
    if phase is None:
        modes, q_phase = branch_phase_modes(at_start, q0, opts), q0
    else:
        modes, q_phase = phase
        modes = None if np.size(modes) == 0 else np.asarray(modes, dtype=float)
    system = ExtendedSystem(problem, parameter, q0, modes, q_phase, opts.parameter_weight,
                            opts.finite_difference_step)
    mu0 = (least_squares_multipliers(at_start, q0, system.free) if multipliers0 is None
           else np.asarray(multipliers0, dtype=float))
    tracer = Tracer(system, opts, name, None, None, records, events, on_point)
    tracer.first = first_index
    tracer.stop = stop
    if admissible is not None:
        tracer.admissible = admissible
    x0 = system.pack(q0, mu0, lam0)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    row, sign = e_lam, opts.direction
    if guess is not None:
        row, sign = system.weights * system.reduced(guess), 1
    corr = correct(system, x0, row, x0, 0.0, opts.tolerance, 4 * opts.max_corrector_iterations)
    if not corr.ok:
        hint = (" (a state of a computed branch means its configuration only in the frames "
                "it was computed in: start from frames_at(problem, branch, k), "
                "supercoil.continuation.carry)" if hasattr(problem, "with_frames") else "")
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"the starting point did not converge: {corr.message}{hint}")
    try:
        t0 = sign * tangent(system, corr.x, row, corr.hessian)
        tracer.add_point(corr.x, t0, next_step=opts.initial_step)
    except (SingularMatrixError, InertiaError) as exc:
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"the starting point is singular ({exc}): start away from folds "
                             f"and bifurcation points")
    status, message = tracer.run(opts.initial_step)
    return tracer.branch(status, message)

