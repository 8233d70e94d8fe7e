"""Pseudo-arclength continuation with adaptive steps, stability and events.

Keller's predictor–corrector (Keller 1977; Allgower & Georg 1990, ch. 2): from
the point ``x_k`` with unit tangent ``t_k`` the predictor is
``x_k + ds t_k`` (or along the secant), the corrector Newton's method on
``F(x) = 0, W t_k . (x - x_k) = ds`` with the bordered Jacobian factorised as
one sparse matrix (:mod:`supercoil.continuation.bordered`), and the new
tangent solves ``[[K, F_lambda], [W t_k]] t = e_last`` (same orientation).
Steps grow after fast corrections and shrink after failures (no convergence,
divergence, a singular matrix, or a tangent turned by more than
``max_turn_degrees``, the guard against jumping between branches). A step
that crosses a parameter bound is replaced by a correction at exactly the
bound. A problem's ``step_bound`` also vets the predictor step (a predictor
that is not collision-free is shortened to 90 % of the allowed fraction, the
corrector covering the rest) and its ``admissible(q)`` every corrected point.
With ``max_corrector_distance`` the corrector stops, as a failure, at an
iterate that lies more than that many steps from the predicted point (a jump
across a corner of the branch). At every accepted point the problem's
``accept(q)`` is called, then the stability
(:mod:`supercoil.continuation.stability`), the caller's records and user
events are evaluated, and the interval to the previous point is searched for
folds, bifurcations and user events (:mod:`supercoil.continuation.events`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from supercoil.continuation.bordered import BorderedFactor
from supercoil.continuation.branch import Branch, SpecialPoint
from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.events import (
    Segment,
    UserEvent,
    locate_count_change,
    locate_fold,
    locate_user_event,
    user_values,
)
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.stability import point_stability
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.kkt import InertiaError, SingularMatrixError
from supercoil.solvers.newton import least_squares_multipliers
from supercoil.solvers.problem import ConstrainedEnergy
from supercoil.stability.analysis import (
    goldstone_modes,
    near_symmetry_gauge,
    sliding_phase_modes,
)

log = logging.getLogger(__name__)

RecordFunction = Callable[[np.ndarray, np.ndarray, float], Mapping[str, object]]
PointCallback = Callable[[Branch], None]
PARTIAL_MESSAGE = "in progress: the branch so far (its computation has not ended)"
CLOSURE_TOLERANCE = 1e-6  # a closed branch passes through its earlier point to this (relative)
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


def branch_phase_modes(problem: ConstrainedEnergy, q: np.ndarray,
                       options: ContinuationOptions) -> np.ndarray | None:
    """Phase-condition modes of a branch started at ``q`` (None when there are none).

    ``phase_conditions``: the symmetry modes (:func:`phase_modes`).
    ``near_symmetry_gauge``: one row per approximate symmetry that is not a
    combination of the exact ones at ``q`` (a closed rod's material sliding
    off the circle): with ``gauge="node"`` a unit row on the DOF of
    :func:`~supercoil.stability.analysis.near_symmetry_gauge` (``q_i =
    q_i(start)``), with ``gauge="integral"`` the mode itself, M-orthogonal to
    the exact symmetries (:func:`~supercoil.stability.analysis.sliding_phase_modes`;
    the condition ``<M g, q - q_start> = 0``). Either keeps Newton and the tangent off the
    nearly singular direction; its multiplier is the small force that the
    discretisation's ripple exerts along the sliding, which the stored
    points' residual (without it) shows.
    """
    rows = []
    if options.phase_conditions:
        rows.append(phase_modes(problem, q))
    if options.near_symmetry_gauge and options.gauge == "integral":
        modes = sliding_phase_modes(problem, q)
        if modes.size:
            rows.append(modes / np.linalg.norm(modes, axis=1, keepdims=True))
    elif options.near_symmetry_gauge:
        dofs = near_symmetry_gauge(problem, q)
        gauge = np.zeros((dofs.size, problem.n_dofs))
        gauge[np.arange(dofs.size), dofs] = 1.0 / np.asarray(problem.mass, float)[dofs]
        rows.append(gauge)
    modes = np.vstack(rows) if rows else np.zeros((0, problem.n_dofs))
    return modes if modes.shape[0] else None


def phase_modes(problem: ConstrainedEnergy, q: np.ndarray, relative: float = 1e-8) -> np.ndarray:
    """The problem's symmetry modes at ``q`` that do not vanish there, ``(r, n_dofs)``."""
    getter = getattr(problem, "symmetry_modes", None)
    if getter is None:
        return np.zeros((0, problem.n_dofs))
    modes = np.atleast_2d(np.asarray(getter(q), dtype=float))
    if modes.size == 0:
        return np.zeros((0, problem.n_dofs))
    scale = max(1.0, float(np.max(np.abs(q))))
    norms = np.linalg.norm(modes, axis=1)
    return modes[norms > relative * scale]


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


class _Tracer:
    """Follows one branch from a corrected point and tangent; collects points and events."""

    def __init__(self, system: ExtendedSystem, options: ContinuationOptions, name: str,
                 parent: str | None, origin: SpecialPoint | None,
                 records: RecordFunction | None, events: Sequence[UserEvent],
                 on_point: PointCallback | None = None):
        self.system = system
        self.on_point = on_point
        self.stop: Callable[[np.ndarray], str | None] | None = None  # see continuation()
        # see continuation(); by default the problem's own admissible(q), if it has one
        self.admissible: Callable[[np.ndarray], bool] | None = getattr(
            system.problem, "admissible", None)
        self.opts = options
        self.name, self.parent, self.origin = name, parent, origin
        self.records_fn = records
        self.events = tuple(events)
        self.xs: list[np.ndarray] = []
        self.ts: list[np.ndarray] = []
        self.stabs = []
        self.s: list[float] = []
        self.recs: list[dict] = []
        self.user: list[list[dict]] = []
        self.specials: list[SpecialPoint] = []
        # (tangent, step) of the point before the first one, for the quadratic
        # predictor of a resumed branch (set by resume_branch)
        self.before: tuple[np.ndarray, float] | None = None
        # (x, full Hessian) of the last point added, assembled after its accept: the
        # rephase tangent there needs no new one (phase rows are linear)
        self._accepted_hessian: tuple[np.ndarray, object] | None = None
        # converted per point and per record for branch() (the recorded values are only
        # ever appended)
        self._rows: list[tuple] = []
        self._columns: dict[str, list] = {}

    def _previous_tangent(self) -> tuple[np.ndarray, float] | None:
        """The tangent at the point before the last and the arclength between the two."""
        if len(self.xs) >= 2:
            return self.ts[-2], self.s[-1] - self.s[-2]
        return self.before if len(self.xs) == 1 else None

    # -- per point ------------------------------------------------------------------------
    def _records(self, x):
        if self.records_fn is None:
            return {}
        self.system.set_parameter(x[-1])
        return dict(self.records_fn(self.system.q(x), self.system.multipliers(x), float(x[-1])))

    def add_point(self, x: np.ndarray, t: np.ndarray, search_events: bool = True,
                  full_hessian=None) -> None:
        """Keep ``x``: stability, records and user values first (an exception leaves the
        branch as it was), then the point, then the events since the previous one.

        ``full_hessian``: the Hessian on all DOFs at ``x`` if known (a converged
        :class:`~supercoil.continuation.corrector.Correction`'s), for the stability
        and the rephase tangent. It was assembled before ``accept``, which carries
        the rod's reference frames to ``x``: that changes the Hessian by round-off
        only (measured on the ring's alpha branch at N = 200: at most 3e-16 of its
        largest entry, as much as assembling it twice at ``x`` with other states
        evaluated in between does).
        """
        system = self.system
        system.set_parameter(x[-1])
        system.problem.accept(system.q(x))
        self._accepted_hessian = None
        full = system.full_hessian(x) if full_hessian is None else full_hessian
        stability = point_stability(system, x, self.opts.zero_tolerance, self.opts.n_modes,
                                    full)
        records = self._records(x)
        user = [user_values(ev, system, x) for ev in self.events]
        self.s.append(0.0 if not self.xs else self.s[-1] + system.norm(x - self.xs[-1]))
        self.xs.append(x)
        self.ts.append(t)
        self.stabs.append(stability)
        self.recs.append(records)
        self.user.append(user)
        self._accepted_hessian = (x, full)
        if len(self.xs) >= 2 and search_events:
            self._search_events()
        if self.on_point is not None:
            self.on_point(self.branch(ContinuationStatus.MAX_POINTS, PARTIAL_MESSAGE))

    # -- events between the last two points -------------------------------------------------
    def _search_events(self) -> None:
        opts, k = self.opts, len(self.xs) - 2
        x_a, x_b = self.xs[k], self.xs[k + 1]
        segment = Segment(self.system, x_a, x_b, opts.tolerance, opts.max_corrector_iterations,
                          opts.zero_tolerance)
        xtol = opts.event_tolerance / segment.length
        found = []
        fold = (opts.detect_folds and self.ts[k][-1] * self.ts[k + 1][-1] < 0)
        fold_u = None
        if fold:
            found.append(locate_fold(segment, xtol))
            fold_u = found[-1].u if found[-1].located else None
        jump = self.stabs[k + 1].unstable_count - self.stabs[k].unstable_count
        if opts.detect_bifurcations and jump != 0 and not (fold and abs(jump) == 1):
            # each change of the count on the segment, one after the other; a change by
            # one where the fold is, is the fold's own (its eigenvalue crosses there)
            start = 0.0
            for _ in range(abs(jump) + 2):
                located = locate_count_change(segment, xtol, opts.switch_below, start)
                if located is None:
                    break
                at_fold = (fold_u is not None and located.located
                           and abs(located.count_after - located.count_before) == 1
                           and abs(located.u - fold_u) <= max(opts.switch_below, 100 * xtol))
                if not at_fold:
                    found.append(located)
                if located.resume is None or located.resume >= 1.0:
                    break
                start = located.resume
        for event, before, after in zip(self.events, self.user[k], self.user[k + 1]):
            for label in before:
                if label in after and before[label] * after[label] < 0:
                    found.append(locate_user_event(segment, event, label, xtol,
                                                   (before, after)))
        for ev in sorted(found, key=lambda e: e.u):
            self.specials.append(self._special(ev, k, segment))
            self.system.set_parameter(x_b[-1])

    def _special(self, ev, k: int, segment: Segment) -> SpecialPoint:
        system, opts = self.system, self.opts
        x = ev.x
        t = ev.tangent if ev.tangent is not None else self.ts[k + 1]
        stab = point_stability(system, x, opts.zero_tolerance, opts.n_modes)
        values = modes = np.zeros(0)
        if ev.kind in ("bifurcation", "fold"):
            n_critical = max(1, abs(ev.count_after - ev.count_before))
            values, modes = stab.critical_modes(n_critical)
        else:
            modes = np.zeros((0, system.problem.n_dofs))
        return SpecialPoint(
            kind=ev.kind, label=ev.label, branch=self.name, index=k,
            parameter=float(x[-1]), arclength=self.s[k] + ev.u * segment.length,
            q=system.q(x), multipliers=system.multipliers(x), tangent=system.full_tangent(t),
            unstable_count=stab.unstable_count,
            count_before=ev.count_before if ev.kind == "bifurcation" else
            self.stabs[k].unstable_count,
            count_after=ev.count_after if ev.kind == "bifurcation" else
            self.stabs[k + 1].unstable_count,
            critical_eigenvalues=values, critical_modes=modes, located=ev.located,
            tolerance=(opts.event_tolerance if ev.accuracy is None
                       else max(ev.accuracy, opts.event_tolerance)),
            records=self._records(x))

    def _regauge(self) -> bool:
        """Move the phase rows to those :func:`branch_phase_modes` gives at the last point
        (re-anchored there), correct that point in the new gauge at its parameter value
        and recompute its tangent; False (gauge unchanged) if the rows are the same or
        the correction fails.

        The last point is an equilibrium of the old gauge: the new row's reaction
        differs (the discretisation's force along the sliding moves from one
        node or mode to another), so the state moves a little. A moved point is
        added to the branch (at the same parameter value); a step from the
        uncorrected one could not converge, however short."""
        system, opts = self.system, self.opts
        x = self.xs[-1]
        q = system.q(x)
        modes = branch_phase_modes(system.problem, q, opts)
        if modes is None or modes.shape != system.phase_modes.shape:
            return False
        if opts.gauge == "node" and np.array_equal(modes != 0, system.phase_modes != 0):
            return False
        if opts.gauge == "integral" and np.allclose(modes, system.phase_modes, rtol=0,
                                                    atol=1e-12):
            return False
        old = (system.phase_modes, system.q_phase_full)
        system.set_phase(modes, q)
        e_lam = np.zeros(system.size)
        e_lam[-1] = 1.0
        corr = correct(system, x, e_lam, x, 0.0, opts.tolerance,
                       4 * opts.max_corrector_iterations)
        try:
            if not corr.ok:
                raise SingularMatrixError(corr.message)
            t = tangent(system, corr.x, self._orientation(corr.x, self.ts[-1]))
        except SingularMatrixError:
            system.set_phase(*old)
            system.set_parameter(x[-1])
            return False
        if system.norm(corr.x - x) > opts.min_step:
            # the same equilibrium up to the gauge's slide: no events between the two
            # (their counts and values come from different gauges)
            self.add_point(corr.x, t, search_events=False)
        else:
            self.xs[-1], self.ts[-1] = corr.x, t
        if opts.rephase:
            self._rephase()
        return True

    def _rephase(self, factor: BorderedFactor | None = None) -> None:
        """Re-anchor the integral phase condition at the last point (``ContinuationOptions.rephase``).

        The point satisfies the new condition (``q - q_k = 0``); only its tangent
        is recomputed, oriented along the old one. ``factor``: the bordered factor
        of the step's corrector (``ContinuationOptions.factor_refinement``): the
        tangent is then solved by iterative refinement with it, under its own border
        row (the kernel of ``[K, F_lambda]`` is one direction, whichever row
        normalises it), and oriented by the sign of its product with the
        orientation row; a new factor only when refinement does not converge.
        """
        system = self.system
        x = self.xs[-1]
        q = system.q(x)
        modes = branch_phase_modes(system.problem, q, self.opts)
        if modes is None or modes.shape != system.phase_modes.shape:
            return
        system.set_phase(modes, q)
        known = self._accepted_hessian
        hessian = known[1].restrict(system.free) if known and known[0] is x else None
        orientation = self._orientation(x, self.ts[-1])
        if factor is not None and hessian is not None:
            e_last = np.zeros(system.size)
            e_last[-1] = 1.0
            z = factor.refined_solve(hessian, system.jacobian(x),
                                     system.parameter_derivative(x), factor.row, e_last)
            if z is not None and np.all(np.isfinite(z)) and z @ orientation != 0.0:
                self.ts[-1] = np.sign(z @ orientation) * z / system.norm(z)
                return
        self.ts[-1] = tangent(system, x, orientation, hessian)

    def _orientation(self, x: np.ndarray, t_old: np.ndarray) -> np.ndarray:
        """The row that orients a tangent recomputed in a new gauge: ``W t_old`` with the
        approximate-symmetry motions (:func:`goldstone_modes` at ``x``) projected out of
        its state part (M-orthogonally).

        Each gauge adds to the tangent the slide that keeps its own condition, so
        the two tangents can disagree along the slide while they agree on the
        rest: measured on the ring's alpha branch (N = 200, integral contact, node
        gauge, dLk 4.069), the plain product oriented the new tangent with dLk
        decreasing, and the branch turned back at a spurious fold, then snaked.
        """
        system = self.system
        v = np.array(t_old, dtype=float)
        modes = goldstone_modes(system.problem, system.q(x))
        if modes.size:
            g = modes[:, system.free]
            mass = system.weights[:system.n]
            gram = (g * mass) @ g.T
            v[:system.n] -= g.T @ np.linalg.solve(gram, (g * mass) @ v[:system.n])
        return system.weights * v

    def _returned_to(self) -> int | None:
        """Index of an earlier point the last step passed through (see
        ``ContinuationOptions.detect_closed_loops``), or None."""
        k = len(self.xs) - 1
        if k < 4:
            return None
        system, opts = self.system, self.opts
        a, b = self.xs[-2], self.xs[-1]
        chord = b - a
        length = system.norm(chord)
        if length == 0.0:
            return None
        reach = opts.closed_loop_tolerance * length
        # The metric weighs the parameter by w (its last weight is w^2), so a point whose
        # parameter lies farther than reach / w from the chord's is not within reach:
        # only the others are stacked (this runs at every point).
        lam = np.array([x[-1] for x in self.xs[:k - 2]])
        low, high = sorted((a[-1], b[-1]))
        off = np.maximum(np.maximum(low - lam, lam - high), 0.0)
        near = np.flatnonzero(off * np.sqrt(system.weights[-1]) <= reach)
        if near.size == 0:
            return None
        earlier = np.array([self.xs[j] for j in near])
        w = system.weights
        u = np.clip(((earlier - a) * w) @ chord / length**2, 0.0, 1.0)
        gaps = np.sqrt(np.einsum("ij,ij->i", (a + u[:, None] * chord - earlier) ** 2,
                                 np.broadcast_to(w, earlier.shape)))
        cos_limit = math.cos(math.radians(15.0))
        close = np.flatnonzero(gaps <= reach)
        if close.size == 0:
            return None
        count = self.stabs[-1].unstable_count
        for i in close:
            j = int(near[i])
            if (self.ts[j] @ (w * self.ts[-1]) >= cos_limit
                    and self.stabs[j].unstable_count == count and self._closes_at(a, chord,
                                                                                u[i], j)):
                return j
        return None

    def _closes_at(self, a: np.ndarray, chord: np.ndarray, u: float, j: int) -> bool:
        """Whether the branch really passes through point ``j``: the point of the last
        chord nearest to it, corrected on the hyperplane through it orthogonal to its
        tangent, must land on it (a branch that only passes near it, e.g. a helix of
        small pitch, lands elsewhere on that hyperplane)."""
        system, opts = self.system, self.opts
        x_j = self.xs[j]
        corr = correct(system, a + u * chord, system.weights * self.ts[j], x_j, 0.0,
                       opts.tolerance, opts.max_corrector_iterations)
        system.set_parameter(self.xs[-1][-1])
        if not corr.ok:
            return False
        scale = max(1.0, system.norm(x_j))
        return system.norm(corr.x - x_j) <= CLOSURE_TOLERANCE * scale

    # -- the stepping loop ------------------------------------------------------------------
    def run(self, step: float) -> tuple[ContinuationStatus, str]:
        """Step from the last point until a bound, a stop or a failure; ``(status, message)``."""
        try:
            return self._run(step)
        except (SingularMatrixError, InertiaError) as exc:
            return self._stability_failed(exc)

    def _stability_failed(self, exc: Exception) -> tuple[ContinuationStatus, str]:
        return ContinuationStatus.STEP_TOO_SMALL, (
            f"stability at point {len(self.xs)} failed: {exc}")

    def _run(self, step: float) -> tuple[ContinuationStatus, str]:
        system, opts = self.system, self.opts
        low, high = opts.parameter_bounds
        cos_turn = math.cos(math.radians(opts.max_turn_degrees))
        ds = step
        regauged = False
        while len(self.xs) < opts.max_points:
            if self.s[-1] >= opts.max_arclength:
                return ContinuationStatus.MAX_ARCLENGTH, (
                    f"arclength {self.s[-1]:.4g} reached max_arclength after {len(self.xs)} points")
            x_k, t_k = self.xs[-1], self.ts[-1]
            d = t_k
            if opts.predictor == "secant" and len(self.xs) >= 2:
                d = x_k - self.xs[-2]
                d = d / system.norm(d)
            row = system.weights * d
            problem = system.problem
            q_k = system.q(x_k)
            start = x_k + ds * d
            if opts.predictor == "quadratic":
                previous = self._previous_tangent()
                if previous is not None:
                    start = start + quadratic_term(system, previous[0], t_k, previous[1], ds)
            predicted = start
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
            failure = None if corr.ok else corr.message
            x_new = t_new = full = None
            if failure is None:
                x_new = corr.x
                # one assembly at the new point for its tangent, count and eigenpairs (the
                # corrector's if it made one there)
                full = corr.full_hessian if corr.full_hessian is not None else \
                    system.full_hessian(x_new)
                hessian = corr.hessian if corr.hessian is not None else \
                    full.restrict(system.free)
                try:
                    t_new = tangent(system, x_new, system.weights * t_k, hessian,
                                    corr.factor if opts.factor_refinement else None)
                except SingularMatrixError as exc:
                    failure = f"tangent: {exc}"
            if failure is None and self.admissible is not None and \
                    not self.admissible(system.q(x_new)):
                failure = "the corrected state is inadmissible (e.g. its linking number changed)"
            if failure is None and t_new @ (system.weights * t_k) < cos_turn:
                failure = (f"the tangent turned by more than {opts.max_turn_degrees} degrees "
                           f"(a jump to another branch?)")
            if failure is None and self.stop is not None:
                refusal = self.stop(system.q(x_new))
                if refusal:
                    return ContinuationStatus.STOPPED, (
                        f"stopped after {len(self.xs)} points at {system.parameter} = "
                        f"{x_k[-1]:.10g}: {refusal}")
            bound = None
            if failure is None and not low <= x_new[-1] <= high:
                bound = low if x_new[-1] < low else high
                if x_k[-1] == bound:  # started on the bound, heading out
                    return ContinuationStatus.PARAMETER_BOUND, (
                        f"{system.parameter} = {bound:.10g} is a bound and the branch leaves "
                        f"the interval there ({len(self.xs)} points)")
                u = (bound - x_k[-1]) / (x_new[-1] - x_k[-1])
                e_lam = np.zeros(system.size)
                e_lam[-1] = 1.0
                landing = correct(system, x_k + u * (x_new - x_k), e_lam, x_k, bound - x_k[-1],
                                  opts.tolerance, opts.max_corrector_iterations)
                if landing.ok:
                    x_new = landing.x
                    x_new[-1] = bound
                    try:
                        t_new = tangent(system, x_new, system.weights * t_k)
                    except SingularMatrixError as exc:
                        failure = f"tangent at the bound: {exc}"
                else:
                    failure = f"landing on the bound {bound:.6g}: {landing.message}"
            if failure is not None:
                log.debug("step %.3g rejected: %s", ds, failure)
                if opts.regauge and system.r and not regauged:
                    try:
                        moved = self._regauge()
                    except (SingularMatrixError, InertiaError) as exc:
                        return ContinuationStatus.STEP_TOO_SMALL, (
                            f"stability at the point corrected in a moved gauge failed: {exc}")
                    if moved:
                        regauged = True  # retry the same step once with the moved gauge
                        log.debug("gauge moved at point %d", len(self.xs) - 1)
                        continue
                if ds <= opts.min_step:
                    return ContinuationStatus.STEP_TOO_SMALL, (
                        f"stopped after {len(self.xs)} points at {system.parameter} = "
                        f"{x_k[-1]:.10g}: {failure} at the minimum step {opts.min_step:.1e}")
                ds = max(ds * opts.shrink, opts.min_step)
                continue
            regauged = False
            try:
                self.add_point(x_new, t_new, full_hessian=full if bound is None else None)
                if opts.rephase and system.r:
                    self._rephase(corr.factor if opts.factor_refinement and bound is None
                                  else None)
            except (SingularMatrixError, InertiaError) as exc:
                return self._stability_failed(exc)
            if bound is None and x_new[-1] in (low, high):
                bound = x_new[-1]  # the step ended exactly on the bound
            if bound is not None:
                return ContinuationStatus.PARAMETER_BOUND, (
                    f"reached {system.parameter} = {bound:.10g} after {len(self.xs)} points")
            if opts.detect_closed_loops:
                try:
                    j = self._returned_to()
                except (SingularMatrixError, InertiaError) as exc:
                    return self._stability_failed(exc)
                if j is not None:
                    return ContinuationStatus.CLOSED_LOOP, (
                        f"the branch closed on itself: after {len(self.xs)} points it came "
                        f"back to point {j} ({system.parameter} = {self.xs[j][-1]:.6g}; "
                        f"arclength {self.s[-1] - self.s[j]:.4g} per lap)")
            if corr is not None and corr.iterations <= opts.fast_iterations:
                ds = min(ds * opts.growth, opts.max_step)
        return ContinuationStatus.MAX_POINTS, f"{len(self.xs)} points computed (max_points)"

    # -- result -------------------------------------------------------------------------------
    def branch(self, status: ContinuationStatus, message: str) -> Branch:
        """The branch so far (also the partial branch handed to ``on_point`` at every
        point): each point's full-DOF rows and each record's values are converted once
        and kept (:meth:`_point_rows`, :attr:`_columns`), so that a partial branch costs
        the arrays' stacking, not a conversion of every point."""
        system = self.system
        n_dofs, m = system.problem.n_dofs, system.m
        k = len(self.xs)
        records = {}
        if k and self.recs[0]:
            for name in self.recs[0]:
                column = self._columns.setdefault(name, [])
                column.extend(np.asarray(r[name]) for r in self.recs[len(column):k])
            records = {name: np.array(self._columns[name][:k]) for name in self.recs[0]}
        if k:
            system.set_parameter(self.xs[k - 1][-1])
        rows = self._point_rows(k)
        stabs = self.stabs[:k]
        return Branch(
            name=self.name, parent=self.parent, origin=self.origin,
            parameter=system.parameter,
            parameter_values=np.array([x[-1] for x in self.xs[:k]]),
            states=np.array([row[3] for row in rows]).reshape(k, n_dofs),
            multipliers=np.array([row[4] for row in rows]).reshape(k, m),
            unstable_count=np.array([s.unstable_count for s in stabs], dtype=np.int64),
            zero_modes=np.array([s.zero_modes for s in stabs], dtype=np.int64),
            determinant_sign=np.array([s.determinant_sign for s in stabs], dtype=np.int64),
            nearest_eigenvalue=np.array([row[6] for row in rows]),
            tangents=np.array([row[5] for row in rows]).reshape(k, n_dofs + m + 1),
            arclength=np.array(self.s[:k]),
            special_points=tuple(self.specials), status=status, message=message,
            records=records, phase_modes=system.phase_modes,
            phase_state=system.q_phase_full)

    def _point_rows(self, count: int) -> list[tuple]:
        """Per point of the first ``count``, ``(x, t, stability, q, multipliers, full
        tangent, nearest eigenvalue)``, converted when the point's ``x``, ``t`` or
        stability object is new (a regauged point's ``x`` and a rephased point's tangent
        are replaced)."""
        system, rows = self.system, self._rows
        for i, (x, t, stab) in enumerate(zip(self.xs[:count], self.ts, self.stabs)):
            if i < len(rows) and rows[i][0] is x and rows[i][1] is t and rows[i][2] is stab:
                continue
            row = (x, t, stab, system.q(x), system.multipliers(x), system.full_tangent(t),
                   stab.nearest_eigenvalue)
            if i < len(rows):
                rows[i] = row
            else:
                rows.append(row)
        return rows[:count]


def continuation(problem: ConstrainedEnergy, q0: np.ndarray,
                 multipliers0: np.ndarray | None = None, parameter: str = "parameter",
                 options: ContinuationOptions | None = None, *, name: str = "branch",
                 records: RecordFunction | None = None,
                 events: Sequence[UserEvent] = (),
                 on_point: PointCallback | None = None,
                 stop: Callable[[np.ndarray], str | None] | None = None,
                 admissible: Callable[[np.ndarray], bool] | None = None) -> Branch:
    """Follow the equilibria of ``problem`` through ``q0`` as ``problem.<parameter>`` varies.

    ``q0`` (n_dofs,) is a (near-)equilibrium at the current parameter value;
    it is first corrected at fixed parameter. ``multipliers0`` (m,) default to
    least squares. ``records(q, multipliers, parameter)`` returns named
    per-point values kept in ``Branch.records``; ``events`` are
    :class:`UserEvent` s. ``on_point(partial_branch)``, if given, is called
    after each accepted point (events between it and the previous point
    located) with the branch so far (status ``MAX_POINTS``, message
    ``PARTIAL_MESSAGE``), e.g. to save it; an exception it raises (a
    KeyboardInterrupt) propagates. ``stop(q)``, if given, is asked about each corrected
    state before it is accepted: a non-empty message refuses it and ends the run at
    the point before (status ``STOPPED``), e.g. when a problem's gauge pins lose their
    grip there and must be picked again. ``admissible(q)``, if given, replaces the
    problem's own ``admissible`` (if any): a corrected state it refuses is not
    accepted, and the step is retried shorter (e.g. a contact-free ring that would
    pass through itself). Returns a :class:`Branch` whose ``status`` says how
    the run ended; numerical failures never raise. The problem is left at the
    last point's parameter value and state (accepted).
    """
    opts = options or ContinuationOptions()
    if not hasattr(problem, parameter):
        raise ValueError(f"the problem has no parameter attribute {parameter!r}")
    lam0 = float(getattr(problem, parameter))
    low, high = opts.parameter_bounds
    if not low <= lam0 <= high:
        raise ValueError(f"the starting {parameter} = {lam0} is outside the bounds {low, high}")
    q0 = np.array(q0, dtype=float)
    modes = branch_phase_modes(problem, q0, opts)
    system = ExtendedSystem(problem, parameter, q0, modes, q0, opts.parameter_weight,
                            opts.finite_difference_step)
    mu0 = (least_squares_multipliers(problem, q0, system.free) if multipliers0 is None
           else np.asarray(multipliers0, dtype=float))
    tracer = _Tracer(system, opts, name, None, None, records, events, on_point)
    tracer.stop = stop
    if admissible is not None:
        tracer.admissible = admissible
    x0 = system.pack(q0, mu0, lam0)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    corr = correct(system, x0, e_lam, x0, 0.0, opts.tolerance, 4 * opts.max_corrector_iterations)
    if not corr.ok:
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"the starting point did not converge: {corr.message}")
    try:
        t0 = opts.direction * tangent(system, corr.x, e_lam, corr.hessian)
        tracer.add_point(corr.x, t0)
    except (SingularMatrixError, InertiaError) as exc:
        return tracer.branch(ContinuationStatus.START_FAILED,
                             f"the starting point is singular ({exc}): start away from folds "
                             f"and bifurcation points")
    status, message = tracer.run(opts.initial_step)
    return tracer.branch(status, message)
