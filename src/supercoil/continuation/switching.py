"""Branch switching at a bifurcation point along the critical mode (Seydel 2010, sec. 5.6).

At a bifurcation point ``x*`` of a branch with unit tangent ``t_old``, the
critical mode ``phi`` (an eigenvector of the constrained Hessian for the
eigenvalue crossing zero, :attr:`SpecialPoint.critical_modes`) is made
W-orthogonal to ``t_old``: ``v = phi - (phi . W t_old) t_old``, normalised.
The predictor is ``x* + side * eps * v`` and the corrector solves
``F(x) = 0`` with the arclength condition ``W v . (x - x*) = side * eps``,
a hyperplane orthogonal to the old tangent at distance ``eps``, which the old
branch crosses only far away: Newton cannot fall back onto it. The new
branch then continues from that point with the tangent oriented away from
``x*``. Where the corrector fails from that predictor the distance can be halved
(``halvings`` times at most), as a continuation step is: the predictor's error
is quadratic in ``eps``, and a stiff contact makes the quadratic term large (measured
at L/D = 100, lambda = 150, C/A = 1.5, N = 204 on the tweezers' closed contact branch:
from ``eps`` = 5e-4 D and 5e-3 D the corrector failed at all four of its bifurcations
tried, on both sides, most at its second or third iteration). The old branch, curving
away from its tangent, crosses the hyperplane at distance ``eps`` only ``O(sqrt(eps))``
away from the predictor, so a shorter distance puts it relatively farther. A caller
with its own sequence of distances to try (the ring diagram's secondary branches) needs
none.

Double zero eigenvalues from a symmetry (an O(2) orbit: eigenvalues crossing
in pairs) are switched along one vector of the null space (``mode``, or an
explicit ``direction``); the other solutions nearby are its images under the
symmetry. The new branch is then a family of orbits, and the Jacobian has
the symmetry's null mode: the problem must pin a gauge, or
``ContinuationOptions(phase_conditions=True)`` adds the phase condition
``<M s, q - q_pred> = 0`` for the symmetry modes ``s`` of
``problem.symmetry_modes`` at the predicted point (they vanish at a
symmetric point, so they are taken on the new branch).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from supercoil.continuation.branch import Branch, SpecialPoint
from supercoil.continuation.carry import frames_at
from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.events import UserEvent
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.system import ExtendedSystem
from supercoil.continuation.tracer import PointCallback, RecordFunction, Tracer
from supercoil.solvers.carried import carried, with_frames
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.problem import ConstrainedEnergy


def pinned_mode(problem: ConstrainedEnergy, q: np.ndarray, mode: np.ndarray) -> np.ndarray:
    """The mode made zero on the gauge pins by adding symmetry modes.

    Critical modes are computed with gauge pins released and the symmetry
    modes projected out (:mod:`supercoil.stability.analysis`); the pinned
    system's null vector is the same mode plus the symmetry motion that
    brings the pinned DOFs back to zero (least squares on the pins).
    """
    gauge = np.asarray(getattr(problem, "gauge_dofs", ()), dtype=np.int64)
    getter = getattr(problem, "symmetry_modes", None)
    if gauge.size == 0 or getter is None:
        return mode
    modes = np.atleast_2d(np.asarray(getter(q), dtype=float))
    if modes.size == 0:
        return mode
    coefficients = np.linalg.lstsq(modes[:, gauge].T, mode[gauge], rcond=None)[0]
    return mode - coefficients @ modes


def _parent_tangent(branch: Branch, point: SpecialPoint) -> np.ndarray:
    """The parent branch's tangent at ``point``: its stored tangents at the two points
    around it, interpolated in arclength (``point.tangent`` when they are not there).

    At a branch point the bordered matrix is singular along the critical mode, so the
    tangent solved there is an arbitrary mix of the two branches' tangents (measured at
    a pitchfork of a C_2 ring branch: 46 % of it odd under the axis, where the parent's
    is even), and a critical direction made orthogonal to it is skewed: the two sides
    of a pitchfork then started at different distances and were not each other's
    images. At the regular points around it the tangent is well determined."""
    t_point = np.asarray(point.tangent, dtype=float)
    i = int(point.index)
    tangents = np.asarray(branch.tangents, dtype=float)
    if not (0 <= i < len(branch) - 1) or tangents.ndim != 2 or tangents.shape[1] != t_point.size:
        return t_point
    a, b = tangents[i], tangents[i + 1]
    if a @ b < 0:
        b = -b
    s0, s1 = float(branch.arclength[i]), float(branch.arclength[i + 1])
    w = min(1.0, max(0.0, (point.arclength - s0) / (s1 - s0))) if s1 > s0 else 0.5
    t = (1.0 - w) * a + w * b
    return t if np.all(np.isfinite(t)) and np.any(t) else t_point


def switch_branch(problem: ConstrainedEnergy, branch: Branch, special_point: SpecialPoint,
                  options: ContinuationOptions | None = None, *, side: int = 1,
                  mode: int = 0, direction: np.ndarray | None = None,
                  amplitude: float | None = None, name: str | None = None,
                  records: RecordFunction | None = None,
                  events: tuple[UserEvent, ...] = (),
                  on_point: PointCallback | None = None,
                  stop: Callable[[np.ndarray], str | None] | None = None,
                  admissible: Callable[[np.ndarray], bool] | None = None,
                  halvings: int = 0) -> Branch:
    """Follow the branch that bifurcates from ``special_point`` of ``branch`` (see module doc).

    ``side`` (+1 / -1) picks the half-branch along ``+-`` the critical mode
    number ``mode`` (or along ``direction``, a full DOF vector in the null
    space); ``amplitude`` is the distance of the first point from the
    bifurcation (arclength metric; default ``options.initial_step``), halved where
    the corrector fails from it, at most ``halvings`` times (module doc).
    The problem is never changed: the run starts from it carrying the frames the
    special point was located with (``special_point.frames``; else those of the
    branch's point before it, :func:`~supercoil.continuation.carry.frames_at`), carried
    to the special point, so that the branch does not depend on what was computed
    before.
    ``on_point``, ``stop`` and ``admissible`` as in
    :func:`~supercoil.continuation.continuation`.
    """
    opts = options or ContinuationOptions()
    if side not in (1, -1):
        raise ValueError(f"side must be +1 or -1, got {side!r}")
    if direction is None:
        if special_point.critical_modes.shape[0] <= mode:
            raise ValueError(f"the special point has {special_point.critical_modes.shape[0]} "
                             f"critical modes, mode {mode} asked for")
        direction = special_point.critical_modes[mode]
    direction = pinned_mode(problem, special_point.q, np.asarray(direction, dtype=float))
    eps = opts.initial_step if amplitude is None else float(amplitude)
    label = name or f"{branch.name}/{special_point.kind}{special_point.index}"
    start = (with_frames(problem, special_point.frames) if special_point.frames is not None
             else frames_at(problem, branch, special_point.index)
             if 0 <= special_point.index < len(branch) else problem)
    problem = carried(start, special_point.q)
    q_star = np.array(special_point.q, dtype=float)
    plain = ExtendedSystem(problem, branch.parameter, q_star,
                           parameter_weight=opts.parameter_weight)
    n, m = plain.n, plain.m
    # old tangent and critical direction in the layout [q_free, mu, lambda]
    t_full = _parent_tangent(branch, special_point)
    t_old = np.concatenate([t_full[:problem.n_dofs][plain.free],
                            t_full[problem.n_dofs:problem.n_dofs + m], t_full[-1:]])
    t_old = t_old / plain.norm(t_old)
    v = np.concatenate([direction[plain.free], np.zeros(m + 1)])
    v = v - (v @ (plain.weights * t_old)) * t_old
    v = v / plain.norm(v)
    x_plain = plain.pack(q_star, special_point.multipliers, special_point.parameter)
    tried = []
    for _ in range(max(0, int(halvings)) + 1):
        q_pred = plain.q(x_plain + side * eps * v)
        modes = branch_phase_modes(plain.problem_at(special_point.parameter), q_pred, opts)
        system = ExtendedSystem(problem, branch.parameter, q_star, modes, q_pred,
                                opts.parameter_weight, opts.finite_difference_step)
        u = np.concatenate([v[:n + m], np.zeros(system.r), v[-1:]])
        x_star = system.pack(q_star, special_point.multipliers, special_point.parameter)
        row = system.weights * u
        corr = correct(system, x_star + side * eps * u, row, x_star, side * eps,
                       opts.tolerance, 4 * opts.max_corrector_iterations)
        tried.append(eps)
        if corr.ok:
            break
        eps *= 0.5
    tracer = Tracer(system, opts, label, branch.name, special_point, records, events,
                     on_point)
    tracer.stop = stop
    if admissible is not None:
        tracer.admissible = admissible
    if not corr.ok:
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"no point found on the bifurcating branch: {corr.message} "
                             f"(at the distances {tried[0]:.3g} to {tried[-1]:.3g})")
    secant = corr.x - x_star
    try:
        t1 = tangent(system, corr.x, system.weights * secant / system.norm(secant))
        tracer.add_point(corr.x, t1, next_step=opts.initial_step)
    except (SingularMatrixError, InertiaError) as exc:
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"the first point of the new branch is singular ({exc}); with a "
                             f"continuous symmetry, pin a gauge or use phase_conditions=True")
    status, message = tracer.run(opts.initial_step)
    return tracer.branch(status, message)
