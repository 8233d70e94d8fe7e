"""Smooth embeddings of knots from exact parametrisations, as equally spaced polygons of length 1.

* :func:`torus_knot` ``(p, q)``: the curve on the torus of radii 2 and 1

      r(φ) = ((2 + cos qφ) cos pφ, (2 + cos qφ) sin pφ, -sin qφ),   0 <= φ < 2π,

  winding ``p`` times around the torus' axis and ``q`` times around its core
  (Rolfsen 1976, 3.C). For ``p, q > 0`` it is the positive torus knot (all
  crossings of its standard diagram positive): T(2, 3) is the right-handed
  trefoil, the table's 3_1; ``q < 0`` gives the mirror image.
* :func:`knot_curve` by name: ``0_1`` (a circle), the torus knots 3_1 = T(2, 3),
  5_1 = T(2, 5), 7_1 = T(2, 7), 8_19 = T(3, 4); 4_1 from the Fourier knot
  ``((2 + cos 2φ) cos 3φ, (2 + cos 2φ) sin 3φ, sin 4φ)`` (a Fourier knot:
  trigonometric polynomials in every coordinate); 5_2 from the Lissajous knot of frequencies
  (3, 2, 7) and phases (0.7, 0.2, 0) (Bogle, Hearst, Jones & Stoilov 1994),
  its coordinates scaled by (1, 1.5, 0.3): a linear map of positive determinant,
  so the same knot, with its turns much less sharp (the largest turning angle
  between chords at 300 nodes drops from about 1.2 to 0.36 rad).
  Every chiral knot is built in the table's chirality (the tests check it with
  the Jones polynomial, and with the sign of the writhe, positive for these
  positive knots); ``mirror=True`` reflects it ``z -> -z``.

The polygon has ``n_nodes`` vertices on the exact curve at equal arc length
(arc length from the exact derivative, by a fine trapezoidal sum, inverted by
interpolation), centred at the origin and scaled so that the polygon's
perimeter is 1.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from supercoil.errors import InputError

Curve = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]

MIN_NODES = 16


def torus_curve(p: int, q: int) -> Curve:
    """``φ -> (r(φ), r'(φ))`` ``(m, 3)`` each, of the torus knot T(p, q) (module doc)."""

    def curve(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rho = 2.0 + np.cos(q * phi)
        drho = -q * np.sin(q * phi)
        c, s = np.cos(p * phi), np.sin(p * phi)
        r = np.stack([rho * c, rho * s, -np.sin(q * phi)], axis=1)
        dr = np.stack([drho * c - p * rho * s, drho * s + p * rho * c,
                       -q * np.cos(q * phi)], axis=1)
        return r, dr

    return curve


def _figure_eight(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rho = 2.0 + np.cos(2 * phi)
    drho = -2.0 * np.sin(2 * phi)
    c, s = np.cos(3 * phi), np.sin(3 * phi)
    r = np.stack([rho * c, rho * s, np.sin(4 * phi)], axis=1)
    dr = np.stack([drho * c - 3 * rho * s, drho * s + 3 * rho * c, 4 * np.cos(4 * phi)],
                  axis=1)
    return r, dr


def _lissajous(frequencies, phases, amplitudes=(1.0, 1.0, 1.0)) -> Curve:
    n = np.asarray(frequencies, dtype=float)
    ph = np.asarray(phases, dtype=float)
    a = np.asarray(amplitudes, dtype=float)

    def curve(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        arg = np.outer(phi, n) + ph
        return a * np.cos(arg), -a * n * np.sin(arg)

    return curve


def _circle(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    zero = np.zeros_like(phi)
    return (np.stack([np.cos(phi), np.sin(phi), zero], axis=1),
            np.stack([-np.sin(phi), np.cos(phi), zero], axis=1))


KNOT_CURVES: dict[str, Curve] = {
    "0_1": _circle,
    "3_1": torus_curve(2, 3),
    "4_1": _figure_eight,
    "5_1": torus_curve(2, 5),
    "5_2": _lissajous((3, 2, 7), (0.7, 0.2, 0.0), amplitudes=(1.0, 1.5, 0.3)),
    "7_1": torus_curve(2, 7),
    "8_19": torus_curve(3, 4),
}
"""The knots :func:`knot_curve` builds, each in the table's chirality."""


def sample_equal_arc_length(curve: Curve, n_nodes: int, fine: int | None = None) -> np.ndarray:
    """``n_nodes`` points of the closed curve ``curve`` (period 2π) at equal arc length,
    centred at the origin and scaled so that the polygon through them has perimeter 1."""
    fine = fine or max(64 * n_nodes, 20_000)
    phi = np.linspace(0.0, 2.0 * np.pi, fine + 1)
    _, dr = curve(phi)
    speed = np.linalg.norm(dr, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(phi))])
    target = np.arange(n_nodes) * arc[-1] / n_nodes
    points, _ = curve(np.interp(target, arc, phi))
    points = points - points.mean(axis=0)
    perimeter = float(np.sum(np.linalg.norm(points - np.roll(points, -1, axis=0), axis=1)))
    return points / perimeter


def _check_nodes(n_nodes) -> int:
    if isinstance(n_nodes, bool) or not isinstance(n_nodes, (int, np.integer)) or \
            n_nodes < MIN_NODES:
        raise InputError(f"n_nodes {n_nodes!r}: give an integer of at least {MIN_NODES}")
    return int(n_nodes)


def torus_knot(p: int, q: int, n_nodes: int, *, mirror: bool = False) -> np.ndarray:
    """The torus knot T(p, q) (module doc) as a polygon ``(n_nodes, 3)`` of perimeter 1.

    ``p >= 2`` and ``|q| >= 2`` coprime integers; ``q < 0`` (or ``mirror``) gives
    the mirror image. Its curve needs enough nodes to resolve ``p·|q|`` windings.
    """
    for label, value in (("p", p), ("q", q)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise InputError(f"torus knot {label} {value!r}: give an integer")
    if p < 2 or abs(q) < 2 or math.gcd(int(p), int(q)) != 1:
        raise InputError(f"torus knot ({p}, {q}): give coprime integers p >= 2 and |q| >= 2 "
                         "(other values give the unknot or a link)")
    n_nodes = _check_nodes(n_nodes)
    if n_nodes < 4 * p * abs(q):
        raise InputError(f"n_nodes {n_nodes}: the torus knot ({p}, {q}) needs at least "
                         f"{4 * p * abs(q)} nodes (4 per winding p·|q|)")
    points = sample_equal_arc_length(torus_curve(int(p), int(q)), n_nodes)
    if mirror:
        points = points * np.array([1.0, 1.0, -1.0])
    return points


def knot_curve(name: str, n_nodes: int, *, mirror: bool = False) -> np.ndarray:
    """A smooth embedding of the knot ``name`` (one of :data:`KNOT_CURVES`, module doc)
    as a polygon ``(n_nodes, 3)`` of perimeter 1, in the table's chirality
    (``mirror=True``: its mirror image)."""
    if name not in KNOT_CURVES:
        raise InputError(f"knot {name!r}: not one this builds; give one of "
                         f"{', '.join(KNOT_CURVES)} (or a torus knot by its p, q)")
    n_nodes = _check_nodes(n_nodes)
    points = sample_equal_arc_length(KNOT_CURVES[name], n_nodes)
    if mirror:
        points = points * np.array([1.0, 1.0, -1.0])
    return points
