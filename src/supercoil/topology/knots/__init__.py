"""Knot types of closed curves: diagrams, Alexander and Jones polynomials, a knot table, builders.

- :func:`identify`: the :class:`KnotType` of a closed polygon ``(n, 3)``: the
  table's name (prime knots up to 10 crossings and their connected sums),
  chirality from the Jones polynomial, Alexander polynomial, determinant and
  the crossings of the simplified diagram.
- :func:`project`, :class:`Diagram`: a generic projection's signed Gauss code,
  Reidemeister I/II simplification, PD code.
- :func:`alexander_polynomial`, :func:`jones_polynomial`: exact integer
  invariants of a diagram.
- :func:`knot_curve`, :func:`torus_knot`: smooth embeddings as equally spaced
  polygons of perimeter 1.
- :class:`KnotGuard`: whether a closed rod kept its knot type, the per-step guard;
  :class:`StrandPassageGuard`: whether a closed rod without contact kept its linking
  number and knot type.
"""

from supercoil.topology.knots.alexander import alexander_polynomial, knot_determinant
from supercoil.topology.knots.builders import KNOT_CURVES, knot_curve, torus_knot
from supercoil.topology.knots.diagram import Diagram
from supercoil.topology.knots.guard import KnotGuard
from supercoil.topology.knots.jones import jones_polynomial
from supercoil.topology.knots.knot_type import (
    KnotType,
    classify,
    identify,
    identify_diagram,
    simplified_diagram,
)
from supercoil.topology.knots.passage import StrandPassageGuard
from supercoil.topology.knots.projection import project
from supercoil.topology.knots.table import KNOTS, TableKnot

__all__ = [
    "KNOTS",
    "KNOT_CURVES",
    "Diagram",
    "KnotGuard",
    "KnotType",
    "StrandPassageGuard",
    "TableKnot",
    "alexander_polynomial",
    "classify",
    "identify",
    "identify_diagram",
    "jones_polynomial",
    "knot_curve",
    "knot_determinant",
    "project",
    "simplified_diagram",
    "torus_knot",
]
