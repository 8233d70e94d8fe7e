"""The starting curve of a knotted ring: a named knot or a torus knot, free of overlap at L/D.

:func:`knot_start` builds a smooth embedding of the knot
(:func:`~supercoil.topology.knots.knot_curve`, :func:`~supercoil.topology.knots.torus_knot`)
of length L = 1 at the ring's nodes. If its tube of diameter D = L / (L/D)
overlaps itself, it is tightened (:func:`~supercoil.problems.knot_tighten.tighten`:
continuation in L/D downward, the knot type kept at every step) until it is
free at the requested L/D; an L/D below what the tightening reaches (the knot's
ropelength, about 16.4 for the trefoil) is refused.
"""

from __future__ import annotations

import re

import numpy as np

from supercoil import checks
from supercoil.errors import InputError
from supercoil.problems.knot_tighten import Tightening, tighten
from supercoil.topology.knots import KNOT_CURVES, knot_curve, torus_knot

_TORUS = re.compile(r"^\s*T?\(?\s*(-?\d+)\s*,\s*(-?\d+)\s*\)?\s*$")
FINE_NODES = 400  # vertices of the built curve before it is resampled at the ring's nodes


def parse_knot(knot) -> tuple[str, tuple[int, int] | None]:
    """``(name, torus)`` of a knot given as a table name of the builders (``"3_1"``, a
    trailing ``*`` for the mirror image), ``"T(p,q)"`` / ``"p,q"`` or a pair ``(p, q)``;
    ``torus`` is ``(p, q)`` for a torus knot, else None. Raises InputError."""
    if isinstance(knot, (tuple, list)) and len(knot) == 2:
        p, q = (int(v) for v in knot)
        return f"T({p},{q})", (p, q)
    if not isinstance(knot, str):
        raise checks.refuse("knot", f"got {knot!r}; valid: a name "
                            f"({', '.join(sorted(KNOT_CURVES))}, '*' for the mirror image) or "
                            "a torus knot (p, q) / 'T(p,q)'")
    match = _TORUS.match(knot)
    if match:
        p, q = int(match.group(1)), int(match.group(2))
        return f"T({p},{q})", (p, q)
    name = knot.strip()
    if name.rstrip("*") not in KNOT_CURVES:
        raise checks.refuse("knot", f"got {knot!r}; valid: "
                            f"{', '.join(sorted(KNOT_CURVES))} (a trailing '*' for the mirror "
                            "image), or a torus knot 'T(p,q)' with coprime p, q")
    return name, None


def knot_points(knot, n_nodes: int = FINE_NODES) -> np.ndarray:
    """The built curve ``(n_nodes, 3)`` of ``knot`` (:func:`parse_knot`), perimeter 1."""
    name, torus = parse_knot(knot)
    if torus is not None:
        p, q = torus
        mirror = (p < 0) != (q < 0)
        try:
            return torus_knot(abs(p), abs(q), n_nodes, mirror=mirror)
        except InputError as exc:
            raise checks.refuse("knot", str(exc)) from None
    return knot_curve(name.rstrip("*"), n_nodes, mirror=name.endswith("*"))


def knot_start(knot, n_nodes: int, length_over_diameter: float,
               twist_ratio: float = 1.0) -> tuple[np.ndarray, str]:
    """``(points, note)``: the curve of ``knot`` at ``n_nodes`` equally spaced points,
    length 1, free of overlap at ``length_over_diameter`` (module doc); ``note`` says
    whether it was tightened."""
    fine = knot_points(knot, max(FINE_NODES, 4 * n_nodes))
    result = tighten(fine, n_nodes, length_over_diameter=length_over_diameter,
                     twist_ratio=twist_ratio)
    name, _ = parse_knot(knot)
    if not result.reached:
        raise checks.refuse("length_over_diameter", f"is {length_over_diameter:g}, but the "
                            f"knot {name} at {n_nodes} nodes could only be tightened to L/D = "
                            f"{result.length_over_diameter:.4g} ({result.message}); valid: "
                            "a larger L/D (a thinner tube)")
    if result.status == "free":
        return result.points, (f"the built {name} is free of overlap at L/D = "
                               f"{length_over_diameter:g}")
    return result.points, (f"the built {name} was tightened to L/D = "
                           f"{length_over_diameter:g} in {len(result.history)} steps")


def tight_knot(knot, n_nodes: int = 60, *, twist_ratio: float = 1e-3,
               min_relative_step: float = 1e-4) -> Tightening:
    """The tight limit of ``knot`` (:func:`parse_knot`) at ``n_nodes``: the tube thickened
    until it cannot thicken by more than ``min_relative_step`` (its ``length_over_diameter``
    is then the ropelength, from above). ``twist_ratio``: C/A of the rod, small by
    default so that the excess link (the start's writhe) hardly constrains the writhe
    (an ideal knot has no twist)."""
    checks.integer("n_nodes", n_nodes, checks.MIN_NODES, checks.MAX_NODES,
                   meaning="nodes of the ring")
    checks.number("twist_ratio", twist_ratio, 0.0, checks.MAX_MAGNITUDE, low_open=True,
                  meaning="C/A")
    checks.number("min_relative_step", min_relative_step, 0.0, 0.1, low_open=True,
                  meaning="the relative thickening below which the tube is tight")
    fine = knot_points(knot, max(FINE_NODES, 4 * n_nodes))
    return tighten(fine, n_nodes, twist_ratio=twist_ratio, min_relative_step=min_relative_step)
