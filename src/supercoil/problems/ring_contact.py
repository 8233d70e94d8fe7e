"""The supercoiled ring: a twisted ring of diameter D that cannot pass through itself.

The answer at an excess link ``dLk`` is the state an experiment reaches that
winds the ring slowly from ``dLk = 0`` (quasi-static path, as the tweezers'
protocols do):

* below the discrete Michell threshold (:func:`~supercoil.problems.ring.michell_threshold`)
  the twisted circle is stable and is the answer (branch ``circle``);
* at the threshold the circle loses stability (Michell's bifurcation is
  subcritical: no equilibrium is near): just beyond it, at ``dLk_c (1 +
  SNAP_OFFSET)``, the circle is pushed along its critical mode and the energy is
  minimised with self-contact (the snap);
* from there ``dLk`` is raised in steps of at most ``winding_step``, the energy
  minimised at each from the previous state (Newton in minimisation mode, every
  step guarded by continuous collision detection). A step that changes the
  writhe by more than ``WRITHE_STEP``, leaves a saddle, or whose minimisation
  fails (``STEP_ITERATIONS``) is halved, down to ``winding_step / 2**MAX_HALVINGS``;
  after a smooth step the step doubles again. A writhe change that stays larger
  at the smallest step is a jump (the branch folded; the writhe, not the node
  displacements, measures it: the material slides along the ring almost freely).
  A smallest step whose minimisation does not settle within ``STEP_ITERATIONS``
  is retried with the full iteration budget; if it still fails, the path stops
  there and the result says so (not converged). A state that is not stable (a
  saddle) is pushed along its unstable mode and minimised again
  (``MAX_RESTARTS`` times at most). Before each step the six rigid pins are
  picked again where their grip fell below ``PIN_QUALITY``
  (:meth:`~supercoil.rod.closed.ClosedRodEnergy.pin_quality`), as the contact
  branches of the ring diagram do;
* the state at the requested ``dLk`` is the answer (branch ``contact``). If it is
  still a saddle, its status says ``unstable``, never ``converged``.

The path keeps the two-fold axis through node 0 that the push off the circle
gives it (to round-off), unless a state on it is unstable and the restart along
the unstable mode breaks it. Sliding the material along the ring is a symmetry
of the continuous ring only: an axis that slid off the mesh's symmetric
positions (a node or an edge midpoint) meets the discretisation's sliding ripple,
on which minimisation crawls (measured where a contact forms under the barrier).
Newton's saddle escape leaves the material sliding alone for that reason
(:mod:`supercoil.solvers.newton`).

Critical modes of the circle: the circle's O(2) symmetry makes them pairs
(``cos m theta``, ``sin m theta``), and an eigensolver returns any basis of the
pair (which one depends on round-off). The perturbation is the combination
invariant under the two-fold axis through node 0
(:func:`~supercoil.geometry.symmetry.axis_invariant_combination`), a symmetry
of the discrete circle, with node 0 moving outward; its largest node
displacement is ``PERTURBATION_AMPLITUDE * L`` (1 % of the length: large enough
to leave the circle in a few Newton steps, far below its radius ``L / 2 pi``).
The unstable mode of a saddle is a simple eigenvector; its sign is the one with
a positive projection on a fixed pseudo-random vector (a choice that does not
hang on round-off). Eigenpairs are computed with one BLAS thread
(:mod:`supercoil.stability.analysis`), so the answer does not depend on the
number of threads.

Mirror symmetry: an isotropic rod's energy is invariant under the reflection
``z -> -z``, which maps a state at ``dLk`` to one at ``-dLk`` (twist and writhe
change sign). The ring at ``dLk < 0`` is computed at ``|dLk|`` (from the
reflected initial curve, if one is given) and reflected: exactly the mirror
image, with the same energy and stability and the opposite twist and writhe.

Every result reports whether the linking number was kept (independent
double-sum writhe plus frame twist) and the penetration reached.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from supercoil import checks
from supercoil.contact.options import DEFAULT_TREATMENT, TREATMENTS, ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import solve_contact, solved_contact_report
from supercoil.geometry.curves import resample_closed
from supercoil.geometry.symmetry import axis_invariant_combination
from supercoil.problems.ring import (
    RingResult,
    check_ring_inputs,
    michell_threshold,
    ring_result,
    twisted_circle_problem,
)
from supercoil.problems.segments import set_pin
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import DEFAULT_ZERO_TOLERANCE, analyse

PERTURBATION_AMPLITUDE = 1e-2  # of L, the push off the circle
RESTART_AMPLITUDE = 5e-2  # of D, the push off a saddle
MAX_RESTARTS = 3
SNAP_OFFSET = 1e-3  # the snap off the circle at dLk_c (1 + SNAP_OFFSET)
WINDING_STEP = 0.1  # largest step of dLk along the path
MAX_HALVINGS = 5  # a step is halved at most this many times before a move is a jump
WRITHE_STEP = 0.15  # a step changing the writhe by more is halved
STEP_ITERATIONS = 300  # Newton iterations of a step (a step that needs more is halved)
PIN_QUALITY = 0.5  # the rigid pins are re-picked below this (ClosedRodEnergy.pin_quality)
_SIGN_SEED = 20_000_101  # the fixed vector that signs a saddle's unstable mode

log = logging.getLogger(__name__)


def validate_diameter(length_over_diameter: float) -> float:
    """The tube diameter D (units of L) of a ring, or an InputError saying what is valid."""
    lod = checks.number("length_over_diameter", length_over_diameter, math.pi,
                        checks.MAX_MAGNITUDE, low_open=True, meaning="L/D")
    return 1.0 / lod


def check_initial_curve(points) -> np.ndarray:
    """The vertices ``(m, 3)`` of a closed starting curve, or an InputError: at least 3
    finite vertices, at most ``MAX_CURVE_VERTICES``, consecutive vertices distinct
    (the last is joined to the first), not all on one straight line."""
    x = np.asarray(points, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3:
        raise checks.refuse("initial_points", f"must be vertices (x, y, z) of a closed curve, "
                            f"an (m, 3) array; got shape {x.shape}")
    if not 3 <= len(x) <= checks.MAX_CURVE_VERTICES:
        raise checks.refuse("initial_points", f"has {len(x)} vertices; a closed curve needs "
                            f"at least 3 vertices 'x y z' and at most "
                            f"{checks.MAX_CURVE_VERTICES}")
    if not np.all(np.isfinite(x)):
        raise checks.refuse("initial_points", "has a non-finite coordinate; all must be "
                            "finite")
    edges = np.roll(x, -1, axis=0) - x
    lengths = np.linalg.norm(edges, axis=1)
    zero = np.flatnonzero(lengths == 0.0)
    if zero.size:
        k = int(zero[0])
        hint = (" (do not repeat the first vertex at the end: the last vertex is joined "
                "to the first)" if k == len(x) - 1 else "")
        raise checks.refuse("initial_points", f"has vertices {k} and {(k + 1) % len(x)} "
                            f"equal; consecutive vertices must be distinct{hint}")
    spread = x - x.mean(axis=0)
    singular = np.linalg.svd(spread, compute_uv=False)
    if singular[1] <= 1e-9 * singular[0]:
        raise checks.refuse("initial_points", "has all its vertices on one straight line; a "
                            "closed curve needs vertices that span a plane or space")
    return x


def circle_perturbation(problem, q: np.ndarray, report, amplitude: float = PERTURBATION_AMPLITUDE
                        ) -> np.ndarray:
    """The displacement off the circle ``q`` along its lowest mode (module docstring).

    ``report``: the stability report of ``q`` (its lowest modes). A double lowest
    eigenvalue (relative gap below 1e-6) gives the axis-invariant combination.
    """
    values = np.asarray(report.lowest_eigenvalues, float)
    modes = np.asarray(report.lowest_modes, float)
    x = np.asarray(q, float).reshape(-1, 3)
    if len(values) >= 2 and abs(values[1] - values[0]) <= 1e-6 * max(abs(values[0]), 1e-300):
        fields = modes[:2].reshape(2, -1, 3)
        mass = np.asarray(problem.mass, float).reshape(-1, 3)[:, 0]
        direction = axis_invariant_combination(x, 0.0, fields, mass) @ modes[:2]
    else:
        direction = modes[0]
    field = direction.reshape(-1, 3)
    if field[0] @ (x[0] - x.mean(axis=0)) < 0:  # node 0 outward
        field = -field
    return (amplitude * problem.rod.length * field / np.linalg.norm(field, axis=1).max()).ravel()


def signed_mode(mode: np.ndarray) -> np.ndarray:
    """``mode`` with the sign of its projection on a fixed pseudo-random vector."""
    v = np.asarray(mode, float)
    reference = np.random.default_rng(_SIGN_SEED).standard_normal(v.size)
    return v if float(v @ reference) >= 0 else -v


def reflected(points: np.ndarray) -> np.ndarray:
    """The mirror image ``z -> -z`` of ``(n, 3)`` points."""
    out = np.array(points, dtype=float)
    out[..., 2] = -out[..., 2]
    return out


def mirror_result(result: RingResult) -> RingResult:
    """The mirror image of a ring state (module docstring): the same energy, stability,
    tensions and contacts (distances and arc lengths are kept), the opposite excess
    link, twist, writhe and chirality (the knot type's name is kept), the points
    reflected."""
    path = None if result.path is None else {
        **result.path, "excess_link": -result.path["excess_link"],
        "snap_at": None if result.path.get("snap_at") is None else -result.path["snap_at"],
        "jumps": [-j for j in result.path.get("jumps", [])]}
    message = (f"computed at dLk = {result.excess_link:+.6g} and reflected (z -> -z), the "
               f"mirror image: " + result.message)
    return dataclasses.replace(result, excess_link=-result.excess_link,
                               points=reflected(result.points), twist=-result.twist,
                               writhe=-result.writhe, chirality=-result.chirality,
                               path=path, message=message)


def solve_supercoiled_ring(twist_ratio: float, excess_link: float, length_over_diameter: float,
                           n_nodes: int = 100, treatment: str = DEFAULT_TREATMENT,
                           curvature: str = "angle", tolerance: float = 1e-9,
                           zero_tolerance: float = DEFAULT_ZERO_TOLERANCE, n_modes: int = 6,
                           max_iterations: int = 1000,
                           initial_points: np.ndarray | None = None,
                           winding_step: float = WINDING_STEP) -> RingResult:
    """The ring with self-contact at ``excess_link`` (see the module docstring).

    ``initial_points`` ``(m, 3)``: instead of winding from the circle, minimise from
    this closed curve (scaled to length L = 1 and resampled at ``n_nodes`` equally
    spaced points; its knot type is kept). The excess link keeps its meaning,
    ``dLk = Tw + Wr`` with ``Tw`` the excess twist: the rod starts with the
    uniform twist ``dLk - Wr(curve)`` (a trefoil at ``dLk = 0`` carries about
    3 turns of twist, opposite to its writhe). A curve that already penetrates
    itself is an :class:`~supercoil.errors.InputError`. ``winding_step``: the largest step of ``dLk`` along
    the quasi-static path.
    """
    check_ring_inputs(twist_ratio, excess_link, n_nodes)
    checks.number("winding_step", winding_step, 0.0, checks.MAX_MAGNITUDE, low_open=True,
                  meaning="the largest step of dLk, in turns")
    validate_diameter(length_over_diameter)
    checks.choice("treatment", treatment, TREATMENTS, meaning="contact treatment")
    if initial_points is not None:
        initial_points = check_initial_curve(initial_points)
    if excess_link < 0:
        mirrored = None if initial_points is None else reflected(initial_points)
        return mirror_result(solve_supercoiled_ring(
            twist_ratio, -excess_link, length_over_diameter, n_nodes, treatment, curvature,
            tolerance, zero_tolerance, n_modes, max_iterations, mirrored, winding_step))
    return _Winding(twist_ratio, float(excess_link), length_over_diameter, n_nodes, treatment,
                    curvature, tolerance, zero_tolerance, n_modes, max_iterations,
                    winding_step).solve(initial_points)


class _Winding:
    """One solve of :func:`solve_supercoiled_ring` at ``excess_link >= 0``."""

    def __init__(self, twist_ratio, excess_link, length_over_diameter, n_nodes, treatment,
                 curvature, tolerance, zero_tolerance, n_modes, max_iterations, winding_step):
        self.twist_ratio, self.excess_link = twist_ratio, excess_link
        self.length_over_diameter = float(length_over_diameter)
        self.diameter = validate_diameter(length_over_diameter)
        self.n_nodes, self.treatment, self.curvature = n_nodes, treatment, curvature
        self.tolerance, self.zero_tolerance, self.n_modes = tolerance, zero_tolerance, n_modes
        self.step = winding_step
        self.newton = NewtonOptions(tolerance=tolerance, mode="minimize",
                                    max_iterations=max_iterations)
        self.iterations, self.restarts, self.steps = 0, 0, 0
        self.jumps: list[float] = []
        self.notes: list[str] = []

    # ------------------------------------------------------------------ set-up
    def _contact_problem(self, base) -> ContactProblem:
        options = ContactOptions(diameter=self.diameter * base.rod.length,
                                 treatment=self.treatment)
        return ContactProblem(base, options)

    def _check_start(self, problem, start, given: bool) -> None:
        d0 = problem.min_distance(start)
        if not d0 > problem.diameter * (1 - problem.options.tolerance):
            what = "initial_points" if given else "length_over_diameter"
            raise checks.refuse(what, f"gives a starting curve that already penetrates itself: "
                                f"closest approach of non-neighbouring points "
                                f"{d0 / problem.diameter:.4f} D < D (L/D = "
                                f"{self.length_over_diameter:g}, {self.n_nodes} nodes); a "
                                "thinner tube (larger L/D) or a curve whose non-neighbouring "
                                "points are farther apart is valid")

    def solve(self, initial_points) -> RingResult:
        if initial_points is not None:
            rod = Rod(n_nodes=self.n_nodes, twist_stiffness=self.twist_ratio,
                      curvature=self.curvature)
            points = resample_closed(initial_points, self.n_nodes, rod.length)
            base = ClosedRodEnergy(rod, points, self.excess_link)
            problem = self._contact_problem(base)
            # a knotted (or given) curve: its radius of curvature kept at least D/2 too
            problem.curvature_limit = 0.5 * problem.diameter
            self._check_start(problem, points.ravel(), True)
            self.notes.append("started from the given curve")
            res, stab = self._accept_relaxed(problem, points.ravel())
            path = {"branch": "given curve", "excess_link": self.excess_link,
                    "snap_at": None, "steps": 0, "jumps": [], "restarts": self.restarts}
            return self._result(problem, res, stab, path)
        base, q0 = twisted_circle_problem(self.twist_ratio, self.excess_link, self.n_nodes,
                                          self.curvature)
        circle = newton(base, q0, NewtonOptions(tolerance=self.tolerance, mode="stationary"))
        self.iterations += circle.iterations
        problem = self._contact_problem(base)
        self._check_start(problem, circle.q, False)
        report = analyse(base, circle.q, circle.multipliers, n_modes=2)
        if report.unstable_count == 0:
            self.notes.append("circle stable: no perturbation")
            res, stab = self._accept_relaxed(problem, circle.q)
            path = {"branch": "circle", "excess_link": self.excess_link, "snap_at": None,
                    "steps": 0, "jumps": [], "restarts": self.restarts}
            return self._result(problem, res, stab, path)
        return self._wind(base, problem, q0)

    # ------------------------------------------------------------------ the path
    def _wind(self, base, problem, q0) -> RingResult:
        threshold = michell_threshold(self.twist_ratio, self.n_nodes, curvature=self.curvature,
                                      rtol=1e-9)
        snap_at = min(self.excess_link, threshold * (1 + SNAP_OFFSET))
        # the path's problem at each level: a new one, carrying on what the last one
        # holds (frames, pins, contact state)
        problem = problem.at(excess_link=snap_at)
        base = problem.base
        circle = newton(base, q0, NewtonOptions(tolerance=self.tolerance, mode="stationary"))
        self.iterations += circle.iterations
        report = analyse(base, circle.q, circle.multipliers, n_modes=2)
        if report.unstable_count == 0:  # the threshold's round-off: a little further
            snap_at = min(self.excess_link, threshold * (1 + 10 * SNAP_OFFSET))
            problem = problem.at(excess_link=snap_at)
            base = problem.base
            report = analyse(base, circle.q, circle.multipliers, n_modes=2)
        start = circle.q + circle_perturbation(base, circle.q, report)
        base.accept(start)
        self.notes.append(f"wound from the circle: it lost stability at dLk = {threshold:.6g} "
                          f"and was pushed along its critical mode by "
                          f"{PERTURBATION_AMPLITUDE:g} L at dLk = {snap_at:.6g}")
        res, stab = self._accept_relaxed(problem, start)
        log.debug("snap at dLk %.6g: %s, writhe %.4g, unstable %d", snap_at, res.status,
                  problem.base.writhe_local(res.q), stab.unstable_count)
        level, size, jumped = snap_at, self.step, False
        stepping = dataclasses.replace(self.newton, max_iterations=min(
            self.newton.max_iterations, STEP_ITERATIONS))
        while res.converged and level < self.excess_link:
            if base.pin_quality(res.q) < PIN_QUALITY:
                # the pins chosen on the circle lose their grip as the ring coils: a
                # rigid rotation is then nearly free and minimisation stalls on it
                set_pin(problem, base, res.q)
            stop = min(self.excess_link, level + size)
            problem = problem.at(excess_link=stop)
            base = problem.base
            # the reference frames at the last accepted state, restored after a refused
            # step (carrying them back by transport can slip the tracked writhe by a turn)
            frames = base.frames
            trial, trial_stab, restarts = self._relax(problem, res.q, stepping)
            change = abs(problem.base.writhe_local(trial.q) - problem.base.writhe_local(res.q))
            smooth = trial.converged and change <= WRITHE_STEP and restarts == 0
            log.debug("dLk %.6g -> %.6g: %s, %d Newton iterations, writhe %+.3g, "
                      "%d restart(s), unstable %d", level, stop, trial.status,
                      trial.newton_iterations, change, restarts, trial_stab.unstable_count)
            if not smooth and stop - level > self.step / 2**MAX_HALVINGS:
                size = 0.5 * (stop - level)
                problem = problem.at(excess_link=level).with_frames(frames)
                base = problem.base
                continue
            if not trial.converged:
                # the smallest step did not settle within STEP_ITERATIONS: the same
                # step with the full iteration budget (a jump, if it lands far)
                problem = problem.with_frames(frames)
                base = problem.base
                trial, trial_stab, restarts = self._relax(problem, res.q)
                log.debug("dLk %.6g -> %.6g with the full budget: %s, %d Newton iterations",
                          level, stop, trial.status, trial.newton_iterations)
                if not trial.converged:
                    self.notes.append(f"the step from dLk = {level:.6g} to {stop:.6g} did not "
                                      f"converge")
                    res, stab = trial, trial_stab
                    break
                change = abs(base.writhe_local(trial.q) - base.writhe_local(res.q))
                smooth = change <= WRITHE_STEP and restarts == 0
            if trial.converged and not smooth and not jumped:
                self.jumps.append(float(stop))  # one jump, however many steps it spans
            jumped = trial.converged and not smooth
            self.steps += 1
            self.restarts += restarts
            res, stab, level = trial, trial_stab, stop
            if smooth:
                size = min(self.step, 2.0 * size)
        if not res.converged:
            self.notes.append(f"the path stopped at dLk = {level:.6g}")
        path = {"branch": "contact", "excess_link": level, "snap_at": snap_at,
                "steps": self.steps, "jumps": list(self.jumps), "restarts": self.restarts}
        return self._result(problem, res, stab, path)

    def _accept_relaxed(self, problem, start):
        res, stab, restarts = self._relax(problem, start)
        self.restarts += restarts
        return res, stab

    def _relax(self, problem, start, options=None):
        """``(result, stability, restarts)``: minimise from ``start``; off a saddle along its unstable mode (module docstring)."""
        problem.accept(start)
        options = options or self.newton
        res = solve_contact(problem, start, options)
        self.iterations += res.newton_iterations
        stab = self._analyse(problem, res)
        restarts = 0
        while res.converged and stab.unstable_count > 0 and restarts < MAX_RESTARTS:
            restarts += 1
            mode = signed_mode(stab.lowest_modes[0]).reshape(-1, 3)
            step = mode / np.linalg.norm(mode, axis=1).max()
            amplitude = RESTART_AMPLITUDE * problem.diameter
            trial = res.q + amplitude * step.ravel()
            # a push into a contact (the barrier needs a gap) is made shorter
            while (problem.min_distance(trial) <= problem.diameter
                   and amplitude > 1e-4 * problem.diameter):
                amplitude *= 0.5
                trial = res.q + amplitude * step.ravel()
            problem.accept(trial)
            again = solve_contact(problem, trial, options)
            if not again.converged:
                break
            res = again
            self.iterations += res.newton_iterations
            stab = self._analyse(problem, res)
        return res, stab, restarts

    def _analyse(self, problem, res):
        return analyse(problem.stability_view(), res.q, res.multipliers, n_modes=self.n_modes,
                       zero_tolerance=self.zero_tolerance)

    # ------------------------------------------------------------------ the result
    def _result(self, problem, res, stab, path) -> RingResult:
        note = "; ".join(self.notes)
        if self.restarts:
            note += f"; left {self.restarts} saddle(s) along the unstable mode"
        if path["jumps"]:
            note += (f"; jumped at dLk = {', '.join(f'{j:.4g}' for j in path['jumps'])} "
                     f"(folds of the branch)")
        unstable = res.converged and stab.unstable_count > 0
        if unstable:
            note += (f"; the state is unstable ({stab.unstable_count} negative "
                     f"eigenvalue(s)) after {self.restarts} restart(s) along the unstable mode")
        if not res.converged:
            note += "; the stability reported is that of a state that is not an equilibrium"
        base = problem.base
        if base.rod.edge_length > problem.diameter:
            note += (f"; warning: segments ({base.rod.edge_length:.3g} L) are longer than the "
                     f"tube diameter ({problem.diameter:.3g} L): contact lines are "
                     f"under-resolved, use --nodes >= "
                     f"{math.ceil(base.rod.length / problem.diameter)}")
        contact, message, converged = solved_contact_report(problem, res, note)
        # (ring_result adds "unstable equilibrium (k unstable directions)" to the status)
        result = ring_result(problem.base, res.q, res.multipliers, stab, converged=converged,
                             status=res.status, message=message, residual=res.residual,
                             iterations=self.iterations, zero_tolerance=self.zero_tolerance,
                             known_knot=problem.knot_guard.reference,
                             length_over_diameter=self.length_over_diameter,
                             contact_treatment=self.treatment, contact=contact,
                             branch=path["branch"], path=path)
        # The writhe the energy uses (carried continuously from the circle through
        # the reference twist) must equal the double-sum writhe of the final state:
        # a strand passing through another would make them differ by 2.
        if result.writhe_error > 1e-6 or result.link_error > 1e-6:
            result = dataclasses.replace(
                result, converged=False,
                message=result.message + f"; error: Lk not conserved (continuous writhe "
                f"differs from the double sum by {result.writhe_error:.2e}, |Tw + Wr - dLk| = "
                f"{result.link_error:.2e})")
        return result
