"""The special Cosserat (Simo-Reissner) rod: bending, torsion, shear and extension.

A second rod model beside the Kirchhoff rod of :mod:`supercoil.rod`, discretised by
two-node elements with geodesic rotation interpolation and one-point shear
(:mod:`supercoil.cosserat.element`). :class:`CosseratEnergy` and
:class:`ClampedCosseratEnergy` are :class:`~supercoil.solvers.problem.ConstrainedEnergy`
problems, so Newton, stability and continuation work on them unchanged;
:func:`solve_equilibrium` is Newton on the configuration manifold itself.
"""

from supercoil.cosserat.clamped import ClampedCosseratEnergy
from supercoil.cosserat.newton import (
    ManifoldNewtonOptions,
    ManifoldNewtonResult,
    solve_equilibrium,
    solve_incrementally,
)
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod, retract

__all__ = [
    "ClampedCosseratEnergy",
    "CosseratEnergy",
    "CosseratRod",
    "ManifoldNewtonOptions",
    "ManifoldNewtonResult",
    "retract",
    "solve_equilibrium",
    "solve_incrementally",
]
