"""Newton corrector on the bordered system and tangents (Keller 1977).

The corrector solves

    F(x) = 0,   b . (x - x_ref) = sigma,

with ``b`` a row in the arclength metric (``W t`` for pseudo-arclength,
``e_lambda`` to land on a parameter bound), by Newton's method on the bordered
Jacobian ``[[K, F_lambda], [b^T]]`` (:class:`BorderedFactor`). Where the problem holds
its states on a family (a symmetric one: :meth:`ExtendedSystem.held`), the start, every
iterate, step and tangent are projected onto it. Trial points are
never accepted by the problem (``problem.accept`` is called by the caller once
a point is kept), and a problem's ``step_bound(q, dq)`` shortens every Newton
step. Newton is damped: a step that raises ``max |F|`` is halved. Where no halving
lowers it, the full step is tried with one more Newton step from it (a watchdog,
Chamberlain, Powell, Lemarechal & Pedersen 1982), kept if the two land below the
residual they started from. ``max |F|`` is not a merit that Newton's steps must
lower: on a rod under tension a localised loop's sliding is a soft mode (eigenvalue
0.007 against 1e7 for the stiff ones), a Newton step from a residual near round-off
moves along it by the noise over its eigenvalue, and the sliding orbit's curvature
then shows up in the stiff forces to second order (the Maratos effect of
constrained optimisation). The tangent at ``x`` solves ``[[K, F_lambda], [b^T]] z = e_last``:
``z`` spans the kernel of ``[K, F_lambda]`` and ``b . z = 1`` orients it like ``b``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from supercoil.continuation.bordered import BorderedFactor
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.errors import SingularMatrixError
from supercoil.solvers.newton import roundoff_floor

BACKTRACKS = 4  # step halvings per corrector iteration (damped Newton)
# converged at round-off: residual at most ROUNDOFF_RESIDUALS tolerances and a Newton
# step below NEGLIGIBLE_STEP relative (arclength metric)
ROUNDOFF_RESIDUALS = 1e3
NEGLIGIBLE_STEP = 1e-10
# ... or: an iterate within FLOOR_MARGIN round-off floors (roundoff_floor's estimate at
# it) whose Newton step raised the residual, the watchdog not helping. The estimate takes
# one rounding of each coordinate through the stiffness; the gradient's differences and
# products round a few times more. It is tight on long rods under tension: converged
# residuals at 0.83-1.11 of it at F L^2/A = 22500, and Newton stalled at 2.57 of it at a
# run's start (lambda = 150, C/A = 1, N = 302, 48.85 turns). Along a soft mode the
# noise-driven Newton step overshoots from there (lambda = 150, C/A = 1.5, N = 302, the
# localising loop: from 1.02 floors to 1.9e4 floors); the watchdog's next step lands
# below the floor, and without it the margin accepts the iterate before the rise
FLOOR_MARGIN = 4.0
# a chord step is tried only within this many tolerances: its contraction is 1e-4-1e-2
# (measured on the tweezers' contact branch, where it landed from residuals up to 7e-6
# against a tolerance of 1e-8, and not from 1e-5 and above)
CHORD_REACH = 1e3
# ... and not within this many round-off floors (of the last iterate with a Hessian):
# there the residual may not fall (the straight rod's branches, tolerance 1e-10, stop at
# 1-3e-10 by the floor) and the Newton path's floor test decides
CHORD_ABOVE_FLOOR = 3.0
# The watchdog (module doc), measured on the tweezers at L/D = 200, lambda = 20,
# N = 202, C/A = 1.5 (1.47 turns, the buckled loop before its first contact): from a
# residual of 9.9e-8 the full step's max|F| rose to 1.3e-4 and every halving left it
# above 9.9e-8, while the next Newton step from the full step landed at 1.3e-9. The
# damped corrector kept the last halving there, converged by a factor of about 4 per
# iteration and took the minimum step for divergence.


@dataclass(frozen=True)
class Correction:
    x: np.ndarray | None
    ok: bool
    iterations: int
    residual: float
    message: str
    # the Hessian at ``x`` (converged) if it was assembled (None when the residual met
    # the tolerance before a Newton step needed it), for a tangent or inertia there
    # before any accept
    hessian: object = field(default=None, repr=False, compare=False)
    # the same on all DOFs (``hessian`` is its restriction to the free ones)
    full_hessian: object = field(default=None, repr=False, compare=False)
    # the bordered factor of the last Newton step (at the iterate before ``x``; None
    # when ``x`` is the start): a preconditioner for the tangent at ``x``
    factor: object = field(default=None, repr=False, compare=False)


def bordered_factor(system: ExtendedSystem, x: np.ndarray, row: np.ndarray,
                    hessian=None) -> BorderedFactor:
    H = system.hessian(x) if hessian is None else hessian
    return BorderedFactor(H, system.jacobian_arrays(x), system.parameter_derivative(x), row)


def correct(system: ExtendedSystem, x_start: np.ndarray, row: np.ndarray, x_ref: np.ndarray,
            sigma: float, tolerance: float, max_iterations: int,
            refine_below: float | None = None, max_distance: float | None = None,
            center: np.ndarray | None = None, chord_below: float | None = None) -> Correction:
    """Newton on ``F(x) = 0, row . (x - x_ref) = sigma`` from ``x_start`` (see module doc).

    ``refine_below``: a Newton step at an iterate whose residual is below this
    fraction of the residual where the last bordered factor was made is solved by
    iterative refinement with that factor (:meth:`BorderedFactor.refined_solve`:
    the exact Newton step to the accuracy of a new factor's solve), a new factor
    only when refinement does not converge. None: a new factor at every step.
    ``max_distance``: the correction fails as soon as an iterate lies farther than
    this (arclength metric) from ``center`` (default ``x_start``), the trust
    region of a continuation step (``ContinuationOptions.max_corrector_distance``),
    widened by the norm of ``x_ref``'s own Newton correction (:func:`own_correction`,
    made only where an iterate lies beyond ``max_distance``): a point accepted within
    the tolerance lies that far from the branch, so that every correction from a
    predictor near it may move that far, whatever the step.

    ``chord_below``: at an iterate whose residual is below this fraction of the
    residual where the last bordered factor was made (Newton's quadratic regime),
    within ``CHORD_REACH`` tolerances and above ``CHORD_ABOVE_FLOOR`` round-off
    floors, a *chord step* is tried first: the Newton step solved with that factor
    (no Hessian, no new factor). Its contraction is that of the bordered matrix's
    change over the last step, measured 1e-4 to 1e-2 on the tweezers' contact
    branch. It is kept only when it lands within ``tolerance`` (the correction
    then ends there, as the Newton step would have: the iteration count, which the
    step control reads, is the same); otherwise it is dropped and the Newton step
    is made from the same iterate. The converged point differs from the Newton
    one below the tolerance only.
    """
    problem = system.problem
    x = system.held(np.array(x_start, dtype=float))
    bounded = hasattr(problem, "step_bound")
    centre = x_start if center is None else center
    reach = _Reach(system, x_ref, row, max_distance)
    previous = np.inf
    x_previous = x
    res = np.nan
    factor = None
    factor_residual = np.inf
    floor = 0.0  # round-off floor at the last iterate with a Hessian
    previous_floor = 0.0  # ... at x_previous
    F = system.residual(x)
    it = 0
    while it <= max_iterations:
        if not np.all(np.isfinite(F)):
            return Correction(None, False, it, np.inf, f"non-finite residual at iteration {it}")
        res = _max_abs(F)
        if res <= tolerance:
            # no Hessian: a caller that needs one at x (a tangent, a count) assembles
            # it, the same matrix; the trial points of a user event need none
            return Correction(x, True, it, res, f"converged in {it} iterations (residual "
                              f"{res:.2e})", factor=factor)
        chord_reach = min(chord_below * factor_residual, CHORD_REACH * tolerance) \
            if chord_below is not None else 0.0
        if factor is not None and it < max_iterations \
                and CHORD_ABOVE_FLOOR * floor < res <= chord_reach:
            landed = _chord_step(system, factor, x, F, row, x_ref, sigma, tolerance,
                                 bounded, reach, centre)
            if landed is not None:
                x_chord, res_chord = landed
                return Correction(x_chord, True, it + 1, res_chord, f"converged in {it + 1} "
                                  f"iterations (residual {res_chord:.2e}; the last a chord "
                                  f"step)", factor=factor)
        full = system.full_hessian(x)
        H = full.restrict(system.free)  # = system.hessian(x)
        floor = roundoff_floor(H, system.q(x))
        if res <= floor:
            return Correction(x, True, it, res, f"converged in {it} iterations (residual "
                              f"{res:.2e})", H, full, factor)
        if it == max_iterations:
            break
        rising = it >= 2 and res > previous
        if rising and previous <= FLOOR_MARGIN * previous_floor:
            return Correction(x_previous, True, it - 1, previous,
                              f"converged in {it - 1} iterations to round-off (residual "
                              f"{previous:.2e}, {previous / previous_floor:.2f} of the floor "
                              f"estimate; the next rose to {res:.2e})")
        if rising and res > ROUNDOFF_RESIDUALS * tolerance:
            return Correction(None, False, it, res, f"corrector diverging at iteration {it} "
                              f"(residual {res:.2e} > {previous:.2e})")
        try:
            dx = None
            if refine_below is not None and factor is not None \
                    and res <= refine_below * factor_residual:
                step = factor.refined_solve(H, system.jacobian_arrays(x),
                                            system.parameter_derivative(x), row,
                                            np.concatenate([F, [row @ (x - x_ref) - sigma]]))
                dx = None if step is None or not np.all(np.isfinite(step)) else -step
            if dx is None:
                factor, factor_residual = bordered_factor(system, x, row, H), res
                dx = -factor.solve(np.concatenate([F, [row @ (x - x_ref) - sigma]]))
        except SingularMatrixError as exc:
            return Correction(None, False, it, res, f"iteration {it}: {exc}")
        dx = system.held_direction(x, dx)
        if rising:
            # A residual near the tolerance that rose again while Newton would move
            # the point (multipliers included) by a negligible step is round-off: the
            # contact barrier's stiffness puts that floor above roundoff_floor's
            # estimate (measured: the residual rose from 8e-8 to 3e-7 against a
            # tolerance of 1e-8, and the step "diverged"). The previous, lower
            # iterate is returned.
            multipliers = x[system.n:-1]
            d_multipliers = float(np.max(np.abs(dx[system.n:-1]), initial=0.0))
            if (system.norm(dx) <= NEGLIGIBLE_STEP * max(1.0, system.norm(x)) and
                    d_multipliers <= NEGLIGIBLE_STEP * (1.0 + float(
                        np.max(np.abs(multipliers), initial=0.0)))):
                return Correction(x_previous, True, it - 1, previous,
                                  f"converged in {it - 1} iterations to round-off (residual "
                                  f"{previous:.2e}; the next rose to {res:.2e} with a Newton "
                                  f"step of {system.norm(dx):.1e})")
            return Correction(None, False, it, res, f"corrector diverging at iteration {it} "
                              f"(residual {res:.2e} > {previous:.2e})")
        x_previous = x
        previous = res
        previous_floor = floor
        alpha = 1.0
        if bounded:
            dq = np.zeros(problem.n_dofs)
            dq[system.free] = dx[:system.n]
            alpha = min(1.0, float(problem.step_bound(system.q(x), dq)))
            if alpha <= 1e-10:
                return Correction(None, False, it, res, f"iteration {it}: the step guard "
                                  f"allows no step (fraction {alpha:.1e})")
        # Damped Newton: a step that raises max|F| is halved (at most
        # BACKTRACKS times; the last trial is kept and the divergence test
        # above judges it). The stiff contact barrier made full steps from the
        # predictor overshoot: measured, most rejected contact-branch steps
        # "diverged" at iteration 2.
        first = None
        for _ in range(BACKTRACKS + 1):
            x_trial = system.held(x + alpha * dx)
            F = system.residual(x_trial)
            if np.all(np.isfinite(F)) and (not F.size or np.max(np.abs(F)) < res):
                break
            if first is None:
                first = (x_trial, F)
            alpha *= 0.5
        else:
            ahead = _watchdog(system, *first, row, x_ref, sigma, res, bounded) \
                if it + 2 <= max_iterations else None
            if ahead is not None:
                x_trial, F, factor, factor_residual = ahead
                it += 1
        x = x_trial
        if not reach.within(system.norm(x - centre), factor):
            return Correction(None, False, it + 1, _max_abs(F),
                              f"iterate {it + 1} lies farther than "
                              f"{reach.describe()} from the predictor (a jump across a "
                              f"corner or to another branch?)")
        it += 1
    return Correction(None, False, max_iterations, res, f"no convergence in {max_iterations} "
                      f"corrector iterations (residual {res:.2e} > {tolerance:.1e})")


def own_correction(system: ExtendedSystem, factor: BorderedFactor, x: np.ndarray,
                   row: np.ndarray) -> float:
    """The norm (arclength metric) of the Newton correction of ``x`` onto the branch
    across the row ``row``: ``dx`` solves ``[[K, F_lambda], [row]] dx = -(F(x), 0)``,
    with ``factor`` (a bordered factor with ``row`` at a point near ``x``; the first
    order of the correction). Infinite where the solve fails."""
    F = system.residual(x)
    try:
        dx = factor.solve(np.concatenate([F, [0.0]]))
    except SingularMatrixError:
        return np.inf
    return system.norm(dx) if np.all(np.isfinite(dx)) else np.inf


class _Reach:
    """The corrector's trust region (:func:`correct`'s ``max_distance``), widened by
    the start point's own correction, which is made once, where an iterate first lies
    beyond ``max_distance``."""

    def __init__(self, system: ExtendedSystem, x_ref: np.ndarray, row: np.ndarray,
                 max_distance: float | None):
        self.system, self.x_ref, self.row = system, x_ref, row
        self.max_distance = max_distance
        self.own: float | None = None

    def within(self, distance: float, factor: BorderedFactor | None) -> bool:
        if self.max_distance is None or distance <= self.max_distance:
            return True
        if self.own is None and factor is not None and np.array_equal(factor.row, self.row):
            self.own = own_correction(self.system, factor, self.x_ref, self.row)
        return distance <= self.max_distance + self._slack()

    def _slack(self) -> float:
        return self.own if self.own is not None and np.isfinite(self.own) else 0.0

    def describe(self) -> str:
        own = f" + {self.own:.2e} (the start's own correction)" if self._slack() else ""
        return f"{self.max_distance:.2e}{own}"


def _whole_step(system: ExtendedSystem, factor: BorderedFactor, x: np.ndarray, F: np.ndarray,
                row: np.ndarray, x_ref: np.ndarray, sigma: float, bounded: bool
                ) -> tuple[np.ndarray, np.ndarray] | None:
    """The Newton step from ``x`` (residual ``F``) solved with ``factor``:
    ``(x + dx, F there)`` if ``dx`` is finite, free of collisions whole
    (``step_bound``) and lands on a finite residual; None otherwise."""
    try:
        dx = -factor.solve(np.concatenate([F, [row @ (x - x_ref) - sigma]]))
    except SingularMatrixError:
        return None
    if not np.all(np.isfinite(dx)):
        return None
    dx = system.held_direction(x, dx)
    if bounded:
        dq = np.zeros(system.problem.n_dofs)
        dq[system.free] = dx[:system.n]
        if float(system.problem.step_bound(system.q(x), dq)) < 1.0:
            return None
    x_new = system.held(x + dx)
    F_new = system.residual(x_new)
    return (x_new, F_new) if np.all(np.isfinite(F_new)) else None


def _max_abs(F: np.ndarray) -> float:
    return float(np.max(np.abs(F))) if F.size else 0.0


def _watchdog(system: ExtendedSystem, x_full: np.ndarray, F_full: np.ndarray,
              row: np.ndarray, x_ref: np.ndarray, sigma: float, res: float,
              bounded: bool) -> tuple[np.ndarray, np.ndarray, BorderedFactor, float] | None:
    """One Newton step from ``x_full`` (residual ``F_full``, a full step that raised
    ``max |F|`` above ``res``): ``(x, F, factor, max |F_full|)`` there if it lands below
    ``res``, the step whole (``step_bound``) and its factor the one made at ``x_full``;
    None otherwise (module doc)."""
    if not np.all(np.isfinite(F_full)):
        return None
    try:
        factor = bordered_factor(system, x_full, row)
    except SingularMatrixError:
        return None
    landed = _whole_step(system, factor, x_full, F_full, row, x_ref, sigma, bounded)
    if landed is None or _max_abs(landed[1]) >= res:
        return None
    return landed[0], landed[1], factor, _max_abs(F_full)


def _chord_step(system: ExtendedSystem, factor: BorderedFactor, x: np.ndarray, F: np.ndarray,
                row: np.ndarray, x_ref: np.ndarray, sigma: float, tolerance: float,
                bounded: bool, reach: _Reach, center: np.ndarray
                ) -> tuple[np.ndarray, float] | None:
    """The chord step of :func:`correct` from ``x`` (residual ``F``) with an earlier
    iterate's ``factor``: ``(x + dx, max|F|)`` there if the whole step is free of
    collisions (``step_bound``), stays in the trust region and lands within
    ``tolerance``; None otherwise (the caller then makes the Newton step)."""
    landed = _whole_step(system, factor, x, F, row, x_ref, sigma, bounded)
    if landed is None or not reach.within(system.norm(landed[0] - center), factor):
        return None
    res = _max_abs(landed[1])
    return (landed[0], res) if res <= tolerance else None


def tangent(system: ExtendedSystem, x: np.ndarray, row: np.ndarray,
            hessian=None, preconditioner: BorderedFactor | None = None) -> np.ndarray:
    """Unit tangent (arclength metric) at ``x``, oriented so that ``row . t > 0``.

    ``hessian``: ``system.hessian(x)`` if already known (a converged
    :class:`Correction`'s, the problem not accepted since). ``preconditioner``: a
    bordered factor with the same ``row`` at a nearby point (a converged
    :class:`Correction`'s ``factor``): the tangent is then solved by iterative
    refinement with it (:meth:`BorderedFactor.refined_solve`, to the accuracy of a
    new factor's solve) and only factorised afresh when that does not converge.
    """
    e_last = np.zeros(system.size)
    e_last[-1] = 1.0
    if preconditioner is not None and np.array_equal(preconditioner.row, row):
        H = system.hessian(x) if hessian is None else hessian
        z = preconditioner.refined_solve(H, system.jacobian_arrays(x),
                                         system.parameter_derivative(x), row, e_last)
        if z is not None and np.all(np.isfinite(z)):
            z = system.held_direction(x, z)
            return z / system.norm(z)
    factor = bordered_factor(system, x, row, hessian)
    z = system.held_direction(x, factor.solve(e_last))
    return z / system.norm(z)
