"""A tube's radius of curvature kept at least D/2 in the knotted computations.

Oracles:

- the discrete radius of curvature ``h / (2 tan(phi / 2))``: exact on the regular
  n-gon (its inscribed radius), and on a sampled ellipse converging at second order
  to the exact ``b^2 / a`` at the ends of its major axis;
- ``ContactProblem.admissible`` with ``curvature_limit``: an ellipse with semi-axes
  a > b, whose thickness is set by its curvature (``b^2 / a < b``, half its smallest
  doubly critical chord), is refused with ``D/2`` above its radius of curvature
  though no contact pair is closer than D, admitted below;
- the tight unknot (Carlen et al. 2005: the ideal unknot is the round circle,
  ropelength pi): tightening an ellipse with the condition imposed ends at the
  regular n-gon's ``L/D = n tan(pi / n)``, where only the curvature is active (no
  pair of points lies beyond the contact's neighbour exclusion); without the
  condition the tube would thicken without bound.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.geometry.curves import circle, min_radius_of_curvature
from supercoil.problems.knot_tighten import tighten
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod


def ellipse(n: int, a: float, b: float) -> np.ndarray:
    """``n`` points of the ellipse of semi-axes ``a`` (x) and ``b`` (y), equally spaced in
    its angle parameter, the first at the end of the major axis."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.stack([a * np.cos(t), b * np.sin(t), np.zeros(n)], axis=1)


@pytest.mark.parametrize("n", [5, 12, 40])
def test_the_regular_polygon_has_its_inscribed_radius(n):
    x = circle(n, 1.0)
    radius, _vertex = min_radius_of_curvature(x)
    assert radius == pytest.approx((1.0 / n) / (2 * np.tan(np.pi / n)), rel=1e-12)


def test_the_ellipse_radius_converges_at_second_order():
    a, b = 1.0, 0.6
    errors = []
    for n in (100, 200, 400):
        radius, vertex = min_radius_of_curvature(ellipse(n, a, b))
        assert vertex in (0, n // 2)
        errors.append(abs(radius - b * b / a))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.1), orders


def test_a_state_bent_below_half_the_diameter_is_refused():
    n, a, b = 120, 1.0, 0.6
    x = ellipse(n, a, b)
    radius, _ = min_radius_of_curvature(x)
    rod = Rod(n_nodes=n, twist_stiffness=1.0, length=float(np.sum(
        np.linalg.norm(np.roll(x, -1, 0) - x, axis=1))))
    base = ClosedRodEnergy(rod, x, 0.0)
    for factor, admitted in ((0.98, True), (1.02, False)):
        D = 2 * radius * factor
        problem = ContactProblem(base, ContactOptions(diameter=D, treatment="barrier"))
        problem.curvature_limit = 0.5 * D
        assert problem.min_distance(x.ravel()) > D  # no contact sees it
        assert problem.admissible(x.ravel()) is admitted
        if not admitted:
            assert "radius of curvature" in problem.refusal
    problem.curvature_limit = None  # the contact alone admits it
    assert problem.admissible(x.ravel())


@pytest.mark.parametrize("n", [16, 24])
def test_the_tight_unknot_is_the_regular_polygon(n):
    tight = tighten(ellipse(200, 1.0, 0.8), n, twist_ratio=1e-3)
    assert tight.status == "tight"
    assert tight.length_over_diameter == pytest.approx(n * np.tan(np.pi / n), rel=3e-4)
    radius, _ = min_radius_of_curvature(tight.points)
    assert 0.5 <= radius / (1.0 / tight.length_over_diameter) < 0.5 * (1 + 3e-4)
    assert "radius of curvature 0.5 D" in tight.message
