"""Tightening a knotted ring: continuation in L/D downward, the tube thickened step by step.

A closed curve of length L = 1 is a tube of diameter D without overlap when
non-neighbouring points are at least D apart. Starting from a diameter at
which the given curve is free (half its closest approach), each step:

1. minimises the ring's elastic energy plus a barrier on the gaps (barrier
   active below ``TIGHTEN_ACTIVATION`` D, a wider cushion than an equilibrium's,
   so that the minimiser leaves room to thicken), every Newton step bounded by
   continuous collision detection and refused if it changed the linking number
   or the knot type (:meth:`~supercoil.contact.problem.ContactProblem.admissible`);
2. thickens the tube to ``D + THICKEN (d_min - D)`` (``d_min`` the closest
   approach of the relaxed curve), or to the requested diameter if that is
   less.

With a requested L/D the run stops there (the curve is then free of overlap at
it, with a positive gap: the start of a ring computation). Without one it goes
on until the tube cannot thicken any more (a relative step below
``min_relative_step``) or the minimisation fails: the last diameter is then the
tight limit, ``L/D`` its ropelength (Pieranski 1998; Carlen, Laurie, Maddocks &
Smutny 2005), reached from above.

A tube of diameter D must not overlap itself locally either: its radius of
curvature stays at least D/2 (Carlen et al. 2005; the discrete radius
``h / (2 tan(phi / 2))`` at a vertex turning by ``phi``,
:func:`~supercoil.geometry.curves.min_radius_of_curvature`). The neighbour
exclusion of the contact hides such an overlap, so the condition is imposed
on its own: a Newton step to a state bent more tightly is refused
(``ContactProblem.curvature_limit``), and the tube thickens by the same
fraction of the smaller of the free gap and of the radius of curvature's room
above D/2. At the tight limit either may be the active one: the round circle
(the ideal unknot, L/D = pi; for the regular ``n``-gon ``n tan(pi / n)``) has
both, the tight trefoil at these resolutions the contacts only
(``min_radius_of_curvature_over_diameter`` about 0.65-0.73).
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import solve_contact
from supercoil.geometry.curves import min_radius_of_curvature as curvature_radius
from supercoil.geometry.curves import resample_closed
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions
from supercoil.topology import writhe

TIGHTEN_ACTIVATION = 0.1  # of D: the barrier's cushion while tightening
THICKEN = 0.8  # fraction of the free gap taken by the next diameter
MIN_RELATIVE_STEP = 1e-4  # a thickening below this (relative) is the tight limit
MAX_STEPS = 400
STEP_ITERATIONS = 40  # Newton iterations of a step; a step that needs more keeps its state

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Tightening:
    """The result of :func:`tighten`.

    ``points`` ``(n, 3)``: the last relaxed curve (length 1), free of overlap at
    ``length_over_diameter`` (its ``min_gap_over_diameter`` > 0); ``history``: the
    L/D of every accepted step; ``reached``: the requested L/D was reached (or,
    without one, the tight limit was); ``status``, ``message``: why it stopped.
    """

    points: np.ndarray
    length_over_diameter: float
    min_gap_over_diameter: float
    history: tuple[float, ...]
    reached: bool
    status: str
    message: str
    excess_link: float
    problem: ContactProblem

    @property
    def writhe(self) -> float:
        return float(writhe(self.points))

    def __repr__(self) -> str:
        return (f"Tightening({self.status}: L/D = {self.length_over_diameter:.6g}, "
                f"{len(self.points)} nodes, {len(self.history)} steps, "
                f"min gap {self.min_gap_over_diameter:.3g} D)")

    def record(self) -> dict:
        """The JSON keys of ``supercoil tighten``: L/D (the ropelength at the tight
        limit), writhe, the smallest radius of curvature over D, the contact keys
        (:func:`~supercoil.contact.report.contact_summary`: the pairs the barrier
        pushes apart, those within its cushion) and the knot type."""
        from supercoil.contact.report import contact_summary
        from supercoil.topology.knots import identify

        knot = identify(self.points)
        summary = contact_summary(self.problem, self.points.ravel())
        return {
            "length_over_diameter": self.length_over_diameter,
            "tight": self.status == "tight",
            "writhe": self.writhe,
            "knot_type": knot.name,
            "chirality": knot.chirality,
            "min_radius_of_curvature_over_diameter":
                min_radius_of_curvature(self.points) * self.length_over_diameter,
            **summary,
            "min_gap_over_diameter": self.min_gap_over_diameter,
            "barrier_activation_over_diameter": TIGHTEN_ACTIVATION,
            "excess_link": self.excess_link,
            "steps": len(self.history),
            "status": self.status,
            "message": self.message,
            "n_nodes": len(self.points),
        }


def min_radius_of_curvature(points: np.ndarray) -> float:
    """Smallest discrete radius of curvature of the closed polygon ``points`` ``(n, 3)``
    (:func:`supercoil.geometry.curves.min_radius_of_curvature`)."""
    return curvature_radius(points)[0]


def _problem(base: ClosedRodEnergy, diameter: float, reference: np.ndarray,
             activation: float) -> ContactProblem:
    problem = ContactProblem(base, ContactOptions(diameter=diameter, treatment="barrier",
                                                  barrier_activation=activation))
    problem.keep_knot_type(reference)
    problem.curvature_limit = 0.5 * diameter
    return problem


def tighten(points: np.ndarray, n_nodes: int, *, length_over_diameter: float | None = None,
            twist_ratio: float = 1.0, excess_link: float | None = None,
            tolerance: float = 1e-8, min_relative_step: float = MIN_RELATIVE_STEP,
            max_steps: int = MAX_STEPS) -> Tightening:
    """Thicken the tube around the closed curve ``points`` ``(m, 3)`` (module doc).

    The curve is scaled to length 1 and resampled at ``n_nodes`` equally spaced
    points. ``excess_link``: default the curve's writhe, so that it starts without
    twist. ``length_over_diameter``: stop there (None: go to the tight limit).
    """
    rod = Rod(n_nodes=n_nodes, twist_stiffness=twist_ratio)
    x = resample_closed(np.asarray(points, float), n_nodes, rod.length)
    dlk = float(writhe(x)) if excess_link is None else float(excess_link)
    base = ClosedRodEnergy(rod, x, dlk)
    target = None if length_over_diameter is None else 1.0 / float(length_over_diameter)
    # a starting diameter at which the curve is free: half the closest approach,
    # whose neighbour exclusion (pi D / 2 along the rod) depends on D itself
    diameter = 0.5 * rod.length / math.pi
    for _ in range(20):
        d = _problem(base, diameter, x, TIGHTEN_ACTIVATION).min_distance(x.ravel(), polygon=True)
        if d > 1.5 * diameter:
            break
        diameter = 0.5 * d
    diameter = min(diameter, min_radius_of_curvature(x))  # and a radius of curvature >= D
    if target is not None and target <= diameter:
        problem = _problem(base, target, x, TIGHTEN_ACTIVATION)
        gap = problem.min_distance(x.ravel(), polygon=True) / target - 1.0
        return Tightening(x, 1.0 / target, gap, (1.0 / target,), True, "free",
                          "the curve is free of overlap at the requested L/D", dlk, problem)
    newton = NewtonOptions(mode="minimize", tolerance=tolerance, max_iterations=STEP_ITERATIONS)
    q = x.ravel()
    history: list[float] = []
    status, message, reached = "max_steps", f"{max_steps} thickening steps", False
    problem = None
    for step in range(max_steps):
        if target is not None:
            diameter = min(diameter, target)
        trial = _problem(base, diameter, x, TIGHTEN_ACTIVATION)
        trial.accept(q)
        res = solve_contact(trial, q, newton)
        # a step's minimisation need not converge: its last state, free of overlap,
        # is where the tube thickens from
        relaxed = res.admissible and trial.min_distance(res.q, polygon=True) > diameter
        if not relaxed:
            status = "stopped"
            message = (f"the minimisation at L/D = {1 / diameter:.6g} failed ({res.message}); "
                       f"the last free state is at L/D = "
                       f"{history[-1] if history else float('nan'):.6g}")
            base.accept(q)
            break
        q, problem = res.q, trial
        history.append(1.0 / diameter)
        d = problem.min_distance(q, polygon=True)
        radius = min_radius_of_curvature(q.reshape(-1, 3))
        log.debug("tighten step %d: L/D %.6g, gap %.3e D, radius of curvature %.4g D", step,
                  1 / diameter, d / diameter - 1, radius / diameter)
        if target is not None and diameter == target:
            status, message, reached = "reached", "reached the requested L/D", True
            break
        # the free room: the gap, and the radius of curvature above D/2
        following = diameter + THICKEN * (min(d, 2.0 * radius) - diameter)
        if following <= diameter * (1.0 + min_relative_step):
            status, reached = "tight", target is None
            message = (f"the tube cannot thicken by more than {min_relative_step:g} of D "
                       f"(gap {d / diameter - 1:.2e} D, radius of curvature "
                       f"{radius / diameter:.4g} D): the tight limit")
            break
        diameter = following
    if problem is None:
        problem = _problem(base, diameter, x, TIGHTEN_ACTIVATION)
    points_out = np.asarray(q, float).reshape(-1, 3)
    gap = problem.min_distance(q, polygon=True) / problem.diameter - 1.0
    return Tightening(points_out, 1.0 / problem.diameter, gap, tuple(history), reached, status,
                      message, dlk, problem)
