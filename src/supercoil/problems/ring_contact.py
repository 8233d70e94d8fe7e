"""The supercoiled ring: a twisted ring of diameter D that cannot pass through itself.

Below Michell's threshold the twisted circle is stable and is the answer.
Above it the circle is an unstable equilibrium; the ring is then pushed off
it along the lowest unstable mode and relaxed by Newton minimisation with
self-contact until it lands on a stable equilibrium with contact (Coleman &
Swigon 2000).

Perturbation: the M-normalised lowest eigenmode of the circle (symmetry
modes removed), scaled so that the largest node displacement is
``PERTURBATION_AMPLITUDE * L`` (1 % of the length: large enough to leave the
circle in a few Newton steps, far below the ring's radius ``L / 2 pi``), with
the sign that makes its largest component positive. Every step is guarded by
continuous collision detection, and the result reports whether the linking
number was kept (independent double-sum writhe plus frame twist).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from supercoil import checks
from supercoil.contact.problem import (
    DEFAULT_TREATMENT,
    TREATMENTS,
    ContactOptions,
    ContactProblem,
)
from supercoil.contact.report import contact_summary
from supercoil.contact.solve import solve_contact
from supercoil.geometry.curves import resample_closed
from supercoil.problems.ring import (
    RingResult,
    check_ring_inputs,
    ring_result,
    twisted_circle_problem,
)
from supercoil.rod.closed import ClosedRodEnergy, Rod
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import DEFAULT_ZERO_TOLERANCE, analyse

PERTURBATION_AMPLITUDE = 1e-2
RESTART_AMPLITUDE = 5e-2  # of D, see solve_supercoiled_ring
MAX_RESTARTS = 3


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


def perturb_along_lowest_mode(problem, q: np.ndarray, multipliers: np.ndarray,
                              amplitude: float = PERTURBATION_AMPLITUDE,
                              report=None) -> np.ndarray:
    """``q`` displaced along the lowest eigenmode (see the module docstring).

    ``report``: the stability report of ``q`` if the caller has one.
    """
    stab = report if report is not None else analyse(problem, q, multipliers, n_modes=2)
    mode = stab.lowest_modes[0].reshape(-1, 3)
    norms = np.linalg.norm(mode, axis=1)
    k = int(np.argmax(np.abs(mode.ravel())))
    sign = 1.0 if mode.ravel()[k] >= 0 else -1.0
    return q + sign * amplitude * problem.rod.length * (mode / norms.max()).ravel()


def solve_supercoiled_ring(twist_ratio: float, excess_link: float, length_over_diameter: float,
                           n_nodes: int = 100, treatment: str = DEFAULT_TREATMENT,
                           curvature: str = "angle", tolerance: float = 1e-9,
                           zero_tolerance: float = DEFAULT_ZERO_TOLERANCE, n_modes: int = 6,
                           max_iterations: int = 1000,
                           initial_points: np.ndarray | None = None) -> RingResult:
    """Stable equilibrium of the ring with self-contact (see the module docstring).

    ``initial_points`` ``(m, 3)``: start from this closed curve instead of the
    circle (scaled to length L = 1 and resampled at ``n_nodes`` equally spaced
    points; its knot type is kept). The excess link keeps its meaning,
    ``dLk = Tw + Wr`` with ``Tw`` the excess twist: the rod starts with the
    uniform twist ``dLk - Wr(curve)`` (a trefoil at ``dLk = 0`` carries about
    3 turns of twist, opposite to its writhe). A curve that already penetrates
    itself is an :class:`~supercoil.errors.InputError`.
    """
    check_ring_inputs(twist_ratio, excess_link, n_nodes)
    diameter = validate_diameter(length_over_diameter)
    checks.choice("treatment", treatment, TREATMENTS, meaning="contact treatment")
    if initial_points is not None:
        initial_points = check_initial_curve(initial_points)
    if initial_points is None:
        base, q0 = twisted_circle_problem(twist_ratio, excess_link, n_nodes, curvature)
        circle = newton(base, q0, NewtonOptions(tolerance=tolerance, mode="stationary"))
        start = circle.q
        note = "circle stable: no perturbation"
        circle_stability = analyse(base, circle.q, circle.multipliers, n_modes=2)
        if circle_stability.unstable_count > 0:
            start = perturb_along_lowest_mode(base, circle.q, circle.multipliers,
                                              report=circle_stability)
            note = (f"circle unstable: perturbed along its lowest mode by "
                    f"{PERTURBATION_AMPLITUDE:g} L")
    else:
        rod = Rod(n_nodes=n_nodes, twist_stiffness=twist_ratio, curvature=curvature)
        points = resample_closed(initial_points, n_nodes, rod.length)
        base = ClosedRodEnergy(rod, points, excess_link)
        start = points.ravel()
        note = "started from the given curve"
    options = ContactOptions(diameter=diameter * base.rod.length, treatment=treatment)
    problem = ContactProblem(base, options)
    d0 = problem.min_distance(start)
    if not d0 > diameter * (1 - options.tolerance):
        what = "initial_points" if initial_points is not None else "length_over_diameter"
        raise checks.refuse(what, f"gives a starting curve that already penetrates itself: "
                            f"closest approach of non-neighbouring points "
                            f"{d0 / diameter:.4f} D < D (L/D = {length_over_diameter:g}, "
                            f"{n_nodes} nodes); a thinner tube (larger L/D) or a curve whose "
                            "non-neighbouring points are farther apart is valid")
    options_newton = NewtonOptions(tolerance=tolerance, mode="minimize",
                                   max_iterations=max_iterations)
    res = solve_contact(problem, start, options_newton)
    stab = analyse(problem.stability_view(), res.q, res.multipliers, n_modes=n_modes,
                   zero_tolerance=zero_tolerance)
    # Minimisation can stop on a saddle whose unstable direction is blocked a
    # tiny distance away by a contact about to form; push off along the
    # unstable mode (largest node displacement RESTART_AMPLITUDE * D) and
    # minimise again.
    restarts, iterations = 0, res.newton_iterations
    while res.converged and stab.unstable_count > 0 and restarts < MAX_RESTARTS:
        restarts += 1
        mode = stab.lowest_modes[0].reshape(-1, 3)
        step = mode / np.linalg.norm(mode, axis=1).max() * RESTART_AMPLITUDE * problem.diameter
        gradient = problem.gradient(res.q)
        # (at an equilibrium the gradient is the constraint reaction, so this
        # sign is a deterministic choice rather than a descent direction)
        sign = -1.0 if float(gradient @ step.ravel()) > 0 else 1.0
        trial = solve_contact(problem, res.q + sign * step.ravel(), options_newton)
        if not trial.converged:
            break
        res = trial
        iterations += res.newton_iterations
        stab = analyse(problem.stability_view(), res.q, res.multipliers, n_modes=n_modes,
                       zero_tolerance=zero_tolerance)
    if restarts:
        note += f"; left {restarts} saddle(s) along the unstable mode"
    if res.converged and stab.unstable_count > 0:
        note += (f"; warning: the state is unstable ({stab.unstable_count} negative "
                 f"eigenvalue(s)) after {restarts} restart(s) along the unstable mode")
    if not res.converged:
        note += "; the stability reported is that of a state that is not an equilibrium"
    if base.rod.edge_length > options.diameter:
        note += (f"; warning: segments ({base.rod.edge_length:.3g} L) are longer than the tube "
                 f"diameter ({options.diameter:.3g} L): contact lines are under-resolved, use "
                 f"--nodes >= {int(np.ceil(base.rod.length / options.diameter))}")
    contact = contact_summary(problem, res.q, res.multipliers)
    message = note + "; " + res.message
    if contact["negative_contact_forces"]:
        message += (f"; warning: {contact['negative_contact_forces']} contact force(s) are "
                    "negative: not an admissible equilibrium")
    if not res.admissible:
        message += "; warning: the state is not admissible (penetration beyond tolerance)"
    result = ring_result(problem, res.q, res.multipliers, stab,
                         converged=(res.converged and res.admissible
                                    and not contact["negative_contact_forces"]),
                         status=res.status,
                         message=message, residual=res.residual,
                         iterations=iterations, zero_tolerance=zero_tolerance,
                         length_over_diameter=float(length_over_diameter),
                         contact_treatment=treatment, contact=contact)
    # The writhe the energy uses (carried continuously from the circle through
    # the reference twist) must equal the double-sum writhe of the final state:
    # a strand passing through another would make them differ by 2.
    if result.writhe_error > 1e-6 or result.link_error > 1e-6:
        result = dataclasses.replace(
            result, converged=False,
            message=result.message + f"; error: Lk not conserved (continuous writhe differs "
            f"from the double sum by {result.writhe_error:.2e}, |Tw + Wr - dLk| = "
            f"{result.link_error:.2e})")
    return result
