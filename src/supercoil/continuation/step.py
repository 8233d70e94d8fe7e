"""One step of pseudo-arclength continuation: predict, correct, vet, land on a bound.

From the point ``x_k`` with unit tangent ``t_k`` the predictor is
``x_k + ds d`` (``d`` the tangent or the secant, plus a curvature term for the
``"quadratic"`` predictor), shortened where the problem's ``step_bound`` says
the state would pass through an obstacle; the corrector is Newton's method on
``F(x) = 0, W d . (x - x_k) = ds`` (:func:`~supercoil.continuation.corrector.correct`);
the new tangent solves ``[[K, F_lambda], [W t_k]] t = e_last``. The corrected
point is refused when it is inadmissible or the tangent turned by more than
``max_turn_degrees`` (the guard against jumping between branches); a step that
crosses a parameter bound is replaced by a correction at exactly the bound.
:func:`take_step` reports what happened; the caller
(:class:`~supercoil.continuation.tracer.Tracer`) decides on the step size.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from supercoil.continuation.corrector import Correction, correct, tangent
from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.errors import SingularMatrixError

# with ContinuationOptions.factor_refinement, Newton steps at iterates whose residual is
# below this fraction of the one where the corrector last factorised are solved by
# refinement with that factor (measured on the ring's alpha_contact at N = 200: 181
# such steps converged, 37 fell back to a new factor; at 0.1, 229 and 196)
REFINE_BELOW = 1e-2
# with ContinuationOptions.chord_steps, an iterate whose residual is below this fraction
# of the one where the corrector last factorised first tries a chord step with that
# factor (corrector.correct's chord_below; on the tweezers' branches 1e-2, 1e-1 and 1
# tried the same steps, CHORD_REACH deciding, and 1e-3 12 fewer)
CHORD_BELOW = 1e-2
# the start of the failure of a step whose tangent turned too far
TURN_FAILURE = "the tangent turned by more than"


def quadratic_term(system: ExtendedSystem, t_previous: np.ndarray, t_last: np.ndarray,
                   last_step: float, ds: float) -> np.ndarray:
    """``ds^2 / 2 * kappa``, the second-order term of the ``"quadratic"`` predictor.

    ``kappa = (t_last - t_previous) / last_step`` estimates the branch's
    curvature ``d^2x/ds^2`` from the unit tangents at the last two points,
    ``last_step`` apart in arclength (a difference quotient, first order in
    the step). Zero when the last step has no length or when the term exceeds
    ``ds / 2`` (the tangents turned by more than the quadratic model of one
    step can follow, e.g. a tangent recomputed in a moved gauge).
    """
    if not last_step > 0:
        return np.zeros_like(t_last)
    term = 0.5 * ds**2 * (t_last - t_previous) / last_step
    return term if system.norm(term) <= 0.5 * ds else np.zeros_like(t_last)


def midpoint_phase(system: ExtendedSystem, opts: ContinuationOptions, q_k: np.ndarray,
                   x_mid: np.ndarray) -> None:
    """Set the phase rows of a step from ``q_k`` to the modes at its predicted midpoint
    ``x_mid``, anchored at ``q_k`` moved by the problem's ``phase_offset(q_k)`` if it has
    one (``ContinuationOptions.midpoint_phase``); unchanged if the modes there have
    another shape (a run keeps its number of rows)."""
    modes = branch_phase_modes(system.problem, system.q(x_mid), opts)
    if modes is not None and modes.shape == system.phase_modes.shape:
        offset = getattr(system.problem, "phase_offset", None)
        system.set_phase(modes, q_k if offset is None else q_k + offset(q_k))


@dataclass
class Step:
    """What :func:`take_step` did. ``failure``: why the step is refused (None:
    accepted); ``refusal``: the caller's ``stop`` refused the corrected state (the run
    ends); ``leaves_bound``: the step starts on a parameter bound and heads out of the
    interval (the run ends). Else ``x``, ``t``: the new point and its tangent;
    ``full_hessian``: the Hessian on all DOFs at ``x`` (None after landing on a
    bound); ``bound``: the bound landed on, if any; ``correction``: the corrector's
    result; ``counted``: the count's factor at ``x``
    (:func:`~supercoil.continuation.stability.count_factor`) where the caller made it."""

    x: np.ndarray | None = None
    t: np.ndarray | None = None
    full_hessian: object = None
    bound: float | None = None
    correction: Correction | None = None
    failure: str | None = None
    refusal: str | None = None
    leaves_bound: bool = False
    counted: object = None


def take_step(system: ExtendedSystem, opts: ContinuationOptions, x_k: np.ndarray,
              t_k: np.ndarray, x_before: np.ndarray | None,
              previous: tuple[np.ndarray, float] | None, ds: float,
              admissible: Callable[[np.ndarray], bool] | None,
              stop: Callable[[np.ndarray], str | None] | None) -> Step:
    """One step of length ``ds`` from the point ``x_k`` (tangent ``t_k``; ``x_before`` the
    point before it, for the secant predictor; ``previous`` the tangent at that point
    and the arclength between the two, for the quadratic one). ``admissible(q)`` and
    ``stop(q)`` vet the corrected state (module doc)."""
    low, high = opts.parameter_bounds
    d = t_k
    if opts.predictor == "secant" and x_before is not None:
        d = x_k - x_before
        d = d / system.norm(d)
    row = system.weights * d
    problem = system.problem
    q_k = system.q(x_k)
    start = x_k + ds * d
    if opts.predictor == "quadratic" and previous is not None:
        start = start + quadratic_term(system, previous[0], t_k, previous[1], ds)
    predicted = start
    if opts.midpoint_phase and system.r:
        midpoint_phase(system, opts, q_k, x_k + 0.5 * ds * d)
    if hasattr(problem, "step_bound"):
        fraction = float(problem.step_bound(q_k, system.q(start) - q_k))
        if fraction < 1.0:
            # The predictor would carry the state through an obstacle (or
            # too close to it for a barrier): it is shortened to 90 % of what
            # collision detection allows, and the corrector's guarded Newton
            # steps cover the rest of the arclength step. (Rejecting and
            # halving the step instead kept contact branches at steps of a
            # fifth of D.)
            start = x_k + 0.9 * fraction * ds * d
    corr = correct(system, start, row, x_k, ds, opts.tolerance,
                   opts.max_corrector_iterations,
                   REFINE_BELOW if opts.factor_refinement else None,
                   None if opts.max_corrector_distance is None
                   else opts.max_corrector_distance * ds, predicted,
                   CHORD_BELOW if opts.chord_steps else None)
    step = Step(correction=corr)
    if not corr.ok:
        step.failure = corr.message
        return step
    x_new = corr.x
    # one assembly at the new point for its tangent, count and eigenpairs (the
    # corrector's if it made one there)
    full = corr.full_hessian if corr.full_hessian is not None else system.full_hessian(x_new)
    hessian = corr.hessian if corr.hessian is not None else full.restrict(system.free)
    try:
        t_new = tangent(system, x_new, system.weights * t_k, hessian,
                        corr.factor if opts.factor_refinement else None)
    except SingularMatrixError as exc:
        step.failure = f"tangent: {exc}"
        return step
    if admissible is not None and not admissible(system.q(x_new)):
        reason = getattr(problem, "refusal", None)
        step.failure = ("the corrected state is inadmissible: "
                        + (reason or "e.g. its linking number or knot type changed"))
        return step
    cos_turn = math.cos(math.radians(opts.max_turn_degrees))
    if t_new @ (system.weights * t_k) < cos_turn:
        step.failure = (f"{TURN_FAILURE} {opts.max_turn_degrees} degrees "
                        f"(a jump to another branch?)")
        return step
    if stop is not None:
        refusal = stop(system.q(x_new))
        if refusal:
            step.refusal = refusal
            return step
    if low <= x_new[-1] <= high:
        step.x, step.t, step.full_hessian = x_new, t_new, full
        return step
    bound = low if x_new[-1] < low else high
    if x_k[-1] == bound:  # started on the bound, heading out
        step.bound, step.leaves_bound = bound, True
        return step
    u = (bound - x_k[-1]) / (x_new[-1] - x_k[-1])
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    landing = correct(system, x_k + u * (x_new - x_k), e_lam, x_k, bound - x_k[-1],
                      opts.tolerance, opts.max_corrector_iterations)
    if not landing.ok:
        step.failure = f"landing on the bound {bound:.6g}: {landing.message}"
        return step
    x_new = landing.x
    x_new[-1] = bound
    try:
        t_new = tangent(system, x_new, system.weights * t_k)
    except SingularMatrixError as exc:
        step.failure = f"tangent at the bound: {exc}"
        return step
    step.x, step.t, step.bound = x_new, t_new, bound
    return step
