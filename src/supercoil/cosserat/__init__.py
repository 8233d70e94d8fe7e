"""The special Cosserat (Simo-Reissner) rod: bending, torsion, shear and extension.

A second rod model beside the Kirchhoff rod of :mod:`supercoil.rod`, discretised by
two-node elements with geodesic rotation interpolation and one-point shear
(:mod:`supercoil.cosserat.element`). :class:`CosseratEnergy` and
:class:`ClampedCosseratEnergy` are :class:`~supercoil.solvers.problem.ConstrainedEnergy`
problems, so Newton, stability and continuation work on them unchanged;
:func:`solve_equilibrium` is Newton on the configuration manifold itself.
:class:`ClosedCosseratEnergy` is the ring at fixed excess link and
:func:`solve_cosserat_ring` its entry point (:mod:`supercoil.cosserat.circle`: the
continuous twisted circle, exact).
"""

from supercoil.cosserat.clamped import ClampedCosseratEnergy
from supercoil.cosserat.closed import ClosedCosseratEnergy, LinkingError
from supercoil.cosserat.newton import (
    ManifoldNewtonOptions,
    ManifoldNewtonResult,
    solve_equilibrium,
    solve_incrementally,
)
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.ring import CosseratRingResult, solve_cosserat_ring
from supercoil.cosserat.rod import CosseratRod, retract

__all__ = [
    "ClampedCosseratEnergy",
    "ClosedCosseratEnergy",
    "CosseratEnergy",
    "CosseratRingResult",
    "CosseratRod",
    "LinkingError",
    "ManifoldNewtonOptions",
    "ManifoldNewtonResult",
    "retract",
    "solve_cosserat_ring",
    "solve_equilibrium",
    "solve_incrementally",
]
