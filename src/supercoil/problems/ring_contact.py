"""The supercoiled ring: a twisted ring of diameter D that cannot pass through itself.

Below Michell's threshold the twisted circle is stable and is the answer.
Above it the circle is an unstable equilibrium; the ring is then pushed off
it along the lowest unstable mode and relaxed by Newton minimisation with
self-contact until it lands on a stable equilibrium with contact (seed 001).

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

import numpy as np

from supercoil.contact.problem import DEFAULT_TREATMENT, ContactOptions, ContactProblem
from supercoil.contact.report import contact_summary
from supercoil.contact.solve import solve_contact
from supercoil.geometry.curves import resample_closed
from supercoil.problems.ring import RingResult, ring_result, twisted_circle_problem
from supercoil.rod.closed import ClosedRodEnergy, Rod
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import DEFAULT_ZERO_TOLERANCE, analyse

PERTURBATION_AMPLITUDE = 1e-2
RESTART_AMPLITUDE = 5e-2  # of D, see solve_supercoiled_ring
MAX_RESTARTS = 3


def validate_diameter(length_over_diameter: float) -> float:
    """The tube diameter D (units of L) of a ring, or a ValueError saying what is valid."""
    lod = length_over_diameter
    if not np.isfinite(lod) or lod <= 0:
        raise ValueError(f"length_over_diameter (L/D) must be a positive finite number, got {lod!r}")
    if lod <= np.pi:
        raise ValueError(f"length_over_diameter (L/D) = {lod:g} is too small: a ring of "
                         f"diameter D must have L > pi D (L/D > {np.pi:.4f})")
    return 1.0 / lod


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
    itself is a ValueError.
    """
    if not np.isfinite(twist_ratio) or twist_ratio <= 0:
        raise ValueError(f"twist_ratio (C/A) must be a positive finite number, got {twist_ratio!r}")
    if not np.isfinite(excess_link):
        raise ValueError(f"excess_link must be a finite number, got {excess_link!r}")
    diameter = validate_diameter(length_over_diameter)
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
        what = "the initial curve" if initial_points is not None else "the starting ring"
        raise ValueError(f"{what} already penetrates itself: closest approach of "
                         f"non-neighbouring points {d0 / diameter:.4f} D < D "
                         f"(L/D = {length_over_diameter:g}, {n_nodes} nodes)")
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
