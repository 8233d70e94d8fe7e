"""Tests of supercoil.topology: writhe, linking number, twist. Every test has an oracle.

Oracles used here:

- exact values: planar curves (Wr = 0), the Hopf link (Lk = ±1 by Ampère's
  right-hand rule), the (2,4) torus link (Lk = ±2), a framed circle (Tw = m);
- tensor Gauss–Legendre quadrature of the Gauss integrand for one pair of
  edges and for an edge with a semi-infinite tail;
- Fuller's theorem for polygons (Fuller 1978, in its spherical-area form): the
  writhe of a polygon closed by axial tails equals (1/2π) × the signed area
  between its tangent indicatrix (a geodesic polygon) and the pole, exactly when
  the curve is monotone along the axis; for a closed polygon
  Wr ≡ 1 + A/2π (mod 2) for any pole;
- Fuller's helix formula n(1 − cos θ) and a spectrally accurate Fuller integral
  for a smooth trefoil, with the observed order of convergence;
- invariances (rigid motions, subdivision, relabelling, reversal, mirror);
- the fast numba kernel against the plain numpy double sum;
- Călugăreanu–White, Lk = Tw + Wr, with all three computed independently.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial.legendre import leggauss

from supercoil._numba import njit as _njit
from supercoil.errors import InputError
from supercoil.topology import (
    linking_number,
    parallel_transport,
    twist_from_frames,
    writhe,
    writhe_reference,
)
from supercoil.topology.solid_angles import branch_free_atan2
from supercoil.topology.writhe_reference import solid_angle_triangles

Z = np.array([0.0, 0.0, 1.0])


# ---------------------------------------------------------------- helpers


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random proper rotation matrix (3, 3)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def random_walk(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3) random-walk polygon (generic: no three vertices collinear)."""
    return np.cumsum(rng.normal(size=(n, 3)), axis=0)


def helix(radius: float, rise: float, turns: int, per_turn: int) -> np.ndarray:
    """(turns·per_turn + 1, 3) vertices of a right-handed helix r(t) = (R cos t, R sin t, c t)."""
    t = np.linspace(0.0, 2.0 * np.pi * turns, turns * per_turn + 1)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t), rise * t])


def torus_knot(p: int, q: int, n: int, big: float = 2.0, small: float = 0.7) -> np.ndarray:
    """(n, 3) vertices of the (p, q) torus curve at φ_k = 2πk/n."""
    phi = 2.0 * np.pi * np.arange(n) / n
    return torus_curve(p, q, phi, big, small)


def torus_curve(
    p: int, q: int, phi: np.ndarray, big: float = 2.0, small: float = 0.7
) -> np.ndarray:
    rho = big + small * np.cos(q * phi)
    return np.column_stack([rho * np.cos(p * phi), rho * np.sin(p * phi), small * np.sin(q * phi)])


def tube_normal(p: int, q: int, phi: np.ndarray) -> np.ndarray:
    """(n, 3) unit normal of the torus surface at the (p, q) torus curve point φ."""
    return np.column_stack(
        [np.cos(q * phi) * np.cos(p * phi), np.cos(q * phi) * np.sin(p * phi), np.sin(q * phi)]
    )


def unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def edge_tangents(points: np.ndarray, closed: bool) -> np.ndarray:
    following = np.roll(points, -1, axis=0) if closed else points[1:]
    return unit(following - points[: following.shape[0]])


def discrete_fuller(points: np.ndarray, pole: np.ndarray, closed: bool) -> float:
    """(1/2π) Σ Ω(pole, t_k, t_{k+1}): signed area between the tantrix polygon and the pole."""
    tangents = edge_tangents(points, closed)
    following = np.roll(tangents, -1, axis=0) if closed else tangents[1:]
    previous = tangents if closed else tangents[:-1]
    poles = np.broadcast_to(pole, previous.shape)
    return float(np.sum(solid_angle_triangles(poles, previous, following))) / (2.0 * np.pi)


def gauss_integrand_quadrature(r1, t1, r2, t2, w1, w2) -> float:
    """Σ w1 w2 (t1 × t2)·(r1 − r2)/|r1 − r2|³ over quadrature nodes r1 (n1, 3), r2 (n2, 3)."""
    difference = r1[:, None, :] - r2[None, :, :]
    numerator = np.einsum("k,ijk->ij", np.cross(t1, t2), difference)
    return float(w1 @ (numerator / np.linalg.norm(difference, axis=2) ** 3) @ w2)


def observed_order(sizes, errors) -> float:
    """Slope of log|error| against log(1/size) (least squares)."""
    slope, _ = np.polyfit(np.log(sizes), np.log(np.abs(errors)), 1)
    return -slope


# ---------------------------------------------------------------- pair integrals


@pytest.mark.parametrize("seed", range(4))
def test_edge_pair_equals_quadrature_of_gauss_integrand(seed: int) -> None:
    # Open 4-vertex polygon: edges 0 and 2 are the only non-adjacent pair, so
    # writhe(..., "none") = Ω_02 / 2π, with Ω_02 the Gauss integral of the two segments.
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(2, 3))
    c, d = rng.normal(size=(2, 3)) + rng.normal(size=3) * 2.0
    nodes, weights = leggauss(160)
    s, w = (nodes + 1.0) / 2.0, weights / 2.0
    oracle = gauss_integrand_quadrature(
        a + np.outer(s, b - a), b - a, c + np.outer(s, d - c), d - c, w, w
    )
    points = np.array([a, b, c, d])
    assert writhe(points, "none") * 2.0 * np.pi == pytest.approx(oracle, abs=1e-10)
    assert writhe_reference(points, "none") * 2.0 * np.pi == pytest.approx(oracle, abs=1e-10)


@pytest.mark.parametrize("seed", range(4))
def test_axial_tails_equal_quadrature_of_gauss_integrand(seed: int) -> None:
    # Three vertices: Wr_axis = [G(edge 0, upper tail) + G(edge 1, lower tail)] / 2π,
    # each by Gauss–Legendre in (s, τ) with the tail parameter σ = τ/(1 − τ) ∈ [0, ∞).
    rng = np.random.default_rng(100 + seed)
    points = rng.normal(size=(3, 3))
    axis = unit(rng.normal(size=3))
    nodes, weights = leggauss(200)
    s, w = (nodes + 1.0) / 2.0, weights / 2.0
    sigma, w_sigma = s / (1.0 - s), w / (1.0 - s) ** 2
    upper = gauss_integrand_quadrature(
        points[0] + np.outer(s, points[1] - points[0]),
        points[1] - points[0],
        points[2] + np.outer(sigma, axis),
        axis,
        w,
        w_sigma,
    )
    lower = gauss_integrand_quadrature(
        points[1] + np.outer(s, points[2] - points[1]),
        points[2] - points[1],
        points[0] - np.outer(sigma, axis),
        axis,
        w,
        w_sigma,
    )
    oracle = (upper + lower) / (2.0 * np.pi)
    assert writhe(points, "axis", axis) == pytest.approx(oracle, abs=1e-9)
    assert writhe_reference(points, "axis", axis) == pytest.approx(oracle, abs=1e-9)


def test_vectorised_atan2_matches_libm() -> None:
    rng = np.random.default_rng(7)
    y = rng.normal(size=20_000) * 10.0 ** rng.uniform(-12, 6, 20_000)
    x = rng.normal(size=20_000) * 10.0 ** rng.uniform(-12, 6, 20_000)
    special = [
        (0.0, 0.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (1.0, 1.0),
        (3.0, -3.0),
    ]
    values = [branch_free_atan2(float(yi), float(xi)) for yi, xi in zip(y, x)]
    assert np.max(np.abs(np.array(values) - np.arctan2(y, x))) < 2e-15
    for yi, xi in special:
        assert branch_free_atan2(yi, xi) == pytest.approx(math.atan2(yi, xi), abs=1e-15)


# ---------------------------------------------------------------- exact values and sign


@pytest.mark.parametrize("closure", ["closed", "chord", "none"])
def test_planar_curve_has_zero_writhe_even_after_rotation(closure: str) -> None:
    rng = np.random.default_rng(11)
    n = 400
    angle = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
    radius = 1.0 + 0.5 * rng.uniform(size=n)
    planar = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(n)])
    assert writhe(planar, closure) == 0.0
    # a rigid rotation makes it only near-planar in floating point
    tilted = planar @ random_rotation(rng).T + np.array([0.3, -2.0, 5.0])
    assert abs(writhe(tilted, closure)) < 1e-12
    assert abs(writhe_reference(tilted, closure)) < 1e-12


def test_planar_open_curve_with_tails_in_its_plane_has_zero_writhe() -> None:
    # x-monotone planar curve in the xy-plane, tails along x: the closed curve is planar
    x = np.linspace(0.0, 3.0, 50)
    planar = np.column_stack([x, np.sin(3.0 * x), np.zeros_like(x)])
    rotation = random_rotation(np.random.default_rng(12))
    tilted = planar @ rotation.T
    assert abs(writhe(tilted, "axis", rotation @ np.array([1.0, 0.0, 0.0]))) < 1e-12


def test_right_handed_helix_has_positive_writhe() -> None:
    right = helix(1.0, 0.3, 3, 32)
    left = right * np.array([1.0, -1.0, 1.0])
    assert writhe(right, "axis") > 0.5
    assert writhe(right, "none") > 0.5
    assert writhe(left, "axis") == pytest.approx(-writhe(right, "axis"), abs=1e-12)


@pytest.mark.parametrize("closure", ["closed", "none", "axis"])
def test_mirror_image_flips_the_sign(closure: str) -> None:
    rng = np.random.default_rng(13)
    points = random_walk(rng, 60)
    axis = unit(rng.normal(size=3))
    mirror = np.diag([1.0, 1.0, -1.0]) @ random_rotation(rng)  # an improper orthogonal map
    value = writhe(points, closure, axis)
    assert abs(value) > 0.05
    assert writhe(points @ mirror.T, closure, mirror @ axis) == pytest.approx(-value, abs=1e-12)


def test_hopf_link_by_amperes_right_hand_rule() -> None:
    u = np.linspace(0.0, 2.0 * np.pi, 120, endpoint=False)
    ring = np.column_stack([np.cos(u), np.sin(u), np.zeros_like(u)])  # normal +z
    # passes through the ring's disc at the origin going up (+z): Lk = +1
    upward = np.column_stack([1.0 - np.cos(u), np.zeros_like(u), np.sin(u)])
    assert linking_number(ring, upward) == pytest.approx(1.0, abs=1e-12)
    assert linking_number(upward, ring) == pytest.approx(1.0, abs=1e-12)
    assert linking_number(ring, upward[::-1]) == pytest.approx(-1.0, abs=1e-12)
    far = upward + np.array([5.0, 0.0, 0.0])
    assert linking_number(ring, far) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("handedness", [1, -1])
def test_two_four_torus_link_has_linking_number_two(handedness: int) -> None:
    # Two (1, 2) curves on a torus, half a meridian apart: the strands wind about each
    # other twice. The tube angle ψ = −2φ turns right-handedly about the core tangent
    # φ̂ (φ̂ × ẑ = ρ̂ takes ẑ towards ρ̂), so that link has Lk = +2; its mirror −2.
    phi = np.linspace(0.0, 2.0 * np.pi, 240, endpoint=False)
    components = []
    for offset in (0.0, np.pi):
        psi = -handedness * 2.0 * phi + offset
        rho = 2.0 + 0.7 * np.cos(psi)
        components.append(
            np.column_stack([rho * np.cos(phi), rho * np.sin(phi), 0.7 * np.sin(psi)])
        )
    assert linking_number(*components) == pytest.approx(2.0 * handedness, abs=1e-11)


# ---------------------------------------------------------------- invariances


@pytest.mark.parametrize("closure", ["closed", "none", "axis"])
def test_invariance_under_rigid_motion_and_scaling(closure: str) -> None:
    rng = np.random.default_rng(21)
    points = random_walk(rng, 80)
    axis = unit(rng.normal(size=3))
    rotation = random_rotation(rng)
    moved = 3.7 * points @ rotation.T + np.array([40.0, -25.0, 13.0])
    expected = writhe(points, closure, axis)
    assert writhe(moved, closure, rotation @ axis) == pytest.approx(expected, abs=1e-11)
    assert writhe_reference(moved, closure, rotation @ axis) == pytest.approx(expected, abs=1e-11)


def test_linking_number_invariant_under_rigid_motion() -> None:
    rng = np.random.default_rng(22)
    phi = np.linspace(0.0, 2.0 * np.pi, 200, endpoint=False)
    first = torus_curve(1, 3, phi)
    second = torus_curve(1, 3, phi + np.pi / 3.0) * 1.0001
    rotation = random_rotation(rng)
    value = linking_number(first, second)
    moved = linking_number(first @ rotation.T + 7.0, second @ rotation.T + 7.0)
    assert moved == pytest.approx(value, abs=1e-11)
    assert abs(value - round(value)) < 1e-10 and round(value) != 0


@pytest.mark.parametrize("closure", ["closed", "none", "axis"])
def test_subdividing_edges_leaves_polygon_writhe_unchanged(closure: str) -> None:
    rng = np.random.default_rng(31)
    points = random_walk(rng, 40)
    refined = []
    for k in range(points.shape[0]):
        refined.append(points[k])
        if k < points.shape[0] - 1 and k % 3 == 0:
            refined.append(0.5 * (points[k] + points[k + 1]))
    if closure == "closed":
        refined.append(0.3 * points[-1] + 0.7 * points[0])  # on the closing edge
    refined = np.array(refined)
    assert refined.shape[0] > points.shape[0] + 10
    assert writhe(refined, closure) == pytest.approx(writhe(points, closure), abs=1e-12)


def test_cyclic_relabelling_and_reversal_leave_writhe_unchanged() -> None:
    rng = np.random.default_rng(41)
    points = random_walk(rng, 70)
    axis = unit(rng.normal(size=3))
    expected = writhe(points)
    assert writhe(np.roll(points, 17, axis=0)) == pytest.approx(expected, abs=1e-12)
    assert writhe(points[::-1]) == pytest.approx(expected, abs=1e-12)
    assert writhe(points[::-1], "none") == pytest.approx(writhe(points, "none"), abs=1e-12)
    # reversing an open curve reverses its tails: the same closed curve, run backwards
    assert writhe(points[::-1], "axis", -axis) == pytest.approx(
        writhe(points, "axis", axis), abs=1e-12
    )
    assert writhe(points, "chord") == writhe(points, "closed")


# ---------------------------------------------------------------- fast path vs reference


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(min_value=3, max_value=60),
    seed=st.integers(min_value=0, max_value=2**32 - 1),
    closure=st.sampled_from(["closed", "chord", "none", "axis"]),
)
def test_numba_kernel_matches_numpy_reference(n: int, seed: int, closure: str) -> None:
    rng = np.random.default_rng(seed)
    points = random_walk(rng, n) * 10.0 ** rng.uniform(-3, 3)
    axis = rng.normal(size=3)
    assert writhe(points, closure, axis) == pytest.approx(
        writhe_reference(points, closure, axis), abs=1e-12
    )


def test_numba_kernel_matches_numpy_reference_on_a_long_curve() -> None:
    points = random_walk(np.random.default_rng(51), 1500)
    for closure in ("closed", "none", "axis"):
        assert writhe(points, closure) == pytest.approx(
            writhe_reference(points, closure), abs=1e-11
        )


@pytest.mark.parametrize("n", [3, 4, 50, 101, 1200])
@pytest.mark.parametrize("closed", [True, False])
def test_serial_writhe_rows_equal_the_parallel_ones_bit_for_bit(n: int, closed: bool) -> None:
    # writhe() sums small polygons on one thread (_SERIAL_BELOW); the rows must not change
    from supercoil.topology.polygon import coordinate_columns, extended_vertices
    from supercoil.topology.solid_angles import self_half_angle_rows, self_half_angle_rows_serial

    points = random_walk(np.random.default_rng(n), n)
    nx, ny, nz = coordinate_columns(extended_vertices(points, closed))
    assert np.array_equal(self_half_angle_rows_serial(nx, ny, nz, closed),
                          self_half_angle_rows(nx, ny, nz, closed))


def nearly_crossing_quadrilateral(eps: float) -> np.ndarray:
    """Closed (4, 3) polygon whose edges 0 and 2 pass each other at height ``eps/2``: Wr ≈ sign(eps)."""
    return np.array([[1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, eps], [-1.0, 1.0, 0.0]])


NEAR_CROSSING_EPS = [sign * 10.0**-k for k in range(6, 14) for sign in (1.0, -1.0)]


@pytest.mark.parametrize("eps", NEAR_CROSSING_EPS)
def test_nearly_crossing_edges_keep_the_sign_of_their_solid_angle(eps: float) -> None:
    # |Ω| → 2π for the crossing pair: the combined atan2 of the two triangles used to
    # pick the wrong branch there and return Wr = +1 for eps < 0 (an error of 2)
    points = nearly_crossing_quadrilateral(eps)
    mirror = points * np.array([1.0, 1.0, -1.0])
    value = writhe(points)
    assert value == pytest.approx(writhe_reference(points), abs=1e-9)
    assert value == pytest.approx(math.copysign(1.0, eps), abs=1e-5)
    assert writhe(mirror) == pytest.approx(-value, abs=1e-12)
    assert writhe(mirror) == pytest.approx(writhe_reference(mirror), abs=1e-9)
    for closure in ("chord", "none"):
        assert writhe(points, closure) == pytest.approx(writhe_reference(points, closure), abs=1e-9)


@pytest.mark.parametrize("eps", [1e-8, -1e-8, 1e-10, -1e-10, 1e-12, -1e-12])
def test_nearly_crossing_edges_under_random_rotations(eps: float) -> None:
    # After a rotation the rounded coordinates perturb the crossing distance by ~1e-16,
    # and the two-triangle split of this symmetric quadrilateral (diagonal endpoints
    # nearly antipodal) amplifies that by ~1/eps in both kernels; a wrong branch
    # would be an error of 2, far above the tolerance (at most 1e-2).
    rng = np.random.default_rng(2024)
    points = nearly_crossing_quadrilateral(eps)
    tolerance = max(1e-9, 1e-14 / abs(eps))
    for _ in range(200):
        rotated = points @ random_rotation(rng).T
        fast, reference = writhe(rotated), writhe_reference(rotated)
        assert fast == pytest.approx(reference, abs=tolerance)
        assert fast == pytest.approx(math.copysign(1.0, eps), abs=tolerance)
        assert reference == pytest.approx(math.copysign(1.0, eps), abs=tolerance)


@pytest.mark.parametrize("eps", [1e-6, -1e-6, 1e-10, -1e-10, 1e-12, -1e-12])
def test_linking_number_of_nearly_touching_polygons(eps: float) -> None:
    # an edge of the second square passes the edge x = 1 of the first at distance |eps|:
    # through the first square (Lk = 1) for eps < 0, beside it (Lk = 0) for eps > 0
    ring = np.array([[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]])
    other = np.array(
        [[1.0 + eps, 0.0, -1.0], [1.0 + eps, 0.0, 1.0], [3.0, 0.0, 1.0], [3.0, 0.0, -1.0]]
    )
    expected = 1.0 if eps < 0 else 0.0
    rng = np.random.default_rng(2025)
    assert linking_number(ring, other) == pytest.approx(expected, abs=1e-3)
    for _ in range(200):
        rotation = random_rotation(rng)
        assert linking_number(ring @ rotation.T, other @ rotation.T) == pytest.approx(
            expected, abs=1e-3
        )


# ---------------------------------------------------------------- Fuller's theorem


@settings(max_examples=40, deadline=None)
@given(n=st.integers(min_value=2, max_value=50), seed=st.integers(min_value=0, max_value=2**32 - 1))
def test_axis_closure_equals_discrete_fuller_for_monotone_curves(n: int, seed: int) -> None:
    # Every edge rises along the axis, so the curve and its tails never cross and the
    # tantrix stays in the upper hemisphere while the curve is flattened onto the axis:
    # Fuller's theorem then holds exactly (no mod 2), and the tail kinks are meridian arcs
    # of the tantrix, which enclose no area.
    rng = np.random.default_rng(seed)
    steps = np.column_stack([rng.normal(size=(n - 1, 2)), rng.uniform(0.05, 1.0, n - 1)])
    points = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    rotation = random_rotation(rng)
    oracle = discrete_fuller(points, Z, closed=False) if n > 2 else 0.0
    assert writhe(points @ rotation.T, "axis", rotation @ Z) == pytest.approx(oracle, abs=1e-11)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(min_value=4, max_value=40), seed=st.integers(min_value=0, max_value=2**32 - 1))
def test_closed_polygon_satisfies_fuller_mod_two(n: int, seed: int) -> None:
    # Fuller (1978): Wr ≡ 1 + A/2π (mod 2), A the area enclosed by the tantrix (a geodesic
    # polygon for a polygon), measured here from an arbitrary pole.
    rng = np.random.default_rng(seed)
    points = random_walk(rng, n)
    pole = unit(rng.normal(size=3))
    half_integer = (writhe(points) - 1.0 - discrete_fuller(points, pole, closed=True)) / 2.0
    assert abs(half_integer - round(half_integer)) < 1e-10


def test_helix_with_tails_fuller_formula_and_convergence() -> None:
    # Oracle. Smooth helix r(t) = (R cos t, R sin t, c t), t ∈ [0, 2πn], closed by tails
    # along z from its ends: Fuller gives Wr = n(1 − cos θ), cos θ = c/√(R² + c²), with no
    # end effect (the tangent turns to ẑ along meridians of the tantrix).
    # The inscribed polygon (m vertices per turn) has, by the discrete Fuller formula,
    # exactly Wr_m = (mn − 1) Ω_m / 2π, Ω_m = Ω(ẑ, t_0, t_1), and
    # Wr_m = n(1 − cos θ) − (1 − cos θ)/m + O(m⁻²): its first and last edges lag half an
    # edge behind the helix ends (first order), the rest converges at second order.
    radius, rise, turns = 1.0, 0.3, 3
    fuller = 1.0 - rise / math.hypot(radius, rise)
    per_turn = np.array([32, 64, 128, 256])
    errors, corrected, turn_errors = [], [], []
    for m in per_turn:
        polygon_writhe = writhe(helix(radius, rise, turns, m), "axis")
        tangents = edge_tangents(helix(radius, rise, 1, m), closed=False)
        omega = solid_angle_triangles(Z, tangents[0], tangents[1])
        assert polygon_writhe == pytest.approx((m * turns - 1) * omega / (2 * np.pi), abs=1e-12)
        # more turns add exactly one turn's worth, m Ω_m / 2π → (1 − cos θ) at O(m⁻²)
        per_turn_writhe = writhe(helix(radius, rise, turns + 1, m), "axis") - polygon_writhe
        assert per_turn_writhe == pytest.approx(m * omega / (2 * np.pi), abs=1e-12)
        turn_errors.append(per_turn_writhe - fuller)
        errors.append(polygon_writhe - turns * fuller)
        corrected.append(polygon_writhe - (turns - 1.0 / m) * fuller)
    assert observed_order(per_turn, errors) == pytest.approx(1.0, abs=0.1)
    assert errors[-1] * per_turn[-1] == pytest.approx(-fuller, rel=0.05)  # + O(1/m)
    assert observed_order(per_turn, corrected) == pytest.approx(2.0, abs=0.1)
    assert observed_order(per_turn, turn_errors) == pytest.approx(2.0, abs=0.1)


def smooth_fuller_area(p: int, q: int, samples: int, pole: np.ndarray) -> float:
    """(1/2π) ∮ (pole × t)·dt / (1 + pole·t) for the smooth (p, q) torus curve.

    Derivatives by FFT and the periodic trapezoidal rule: spectrally accurate.
    """
    points = torus_knot(p, q, samples)
    wavenumber = np.fft.fftfreq(samples, 1.0 / samples)[:, None]
    spectrum = np.fft.fft(points, axis=0)
    first = np.real(np.fft.ifft(1j * wavenumber * spectrum, axis=0))
    second = np.real(np.fft.ifft(-(wavenumber**2) * spectrum, axis=0))
    speed = np.linalg.norm(first, axis=1)
    tangent = first / speed[:, None]
    tangent_rate = second - tangent * np.einsum("ij,ij->i", tangent, second)[:, None]
    integrand = np.einsum("ij,ij->i", np.cross(pole, tangent), tangent_rate / speed[:, None])
    return float(np.sum(integrand / (1.0 + tangent @ pole))) / samples


def test_closed_trefoil_converges_at_second_order_to_smooth_writhe() -> None:
    # Oracle: the smooth curve's writhe modulo 2 from Fuller, Wr ≡ 1 + A/2π, with A from
    # a spectral quadrature (converged to 1e-14 between 1024 and 2048 samples); the
    # representative nearest the finest polygon fixes the even integer.
    area = smooth_fuller_area(2, 3, 2048, Z)
    assert area == pytest.approx(smooth_fuller_area(2, 3, 1024, Z), abs=1e-13)
    sizes = np.array([64, 128, 256, 512])
    values = np.array([writhe(torus_knot(2, 3, n)) for n in sizes])
    shift = 2.0 * round((values[-1] - 1.0 - area) / 2.0)
    smooth = 1.0 + area + shift
    errors = values - smooth
    assert abs(errors[-1]) < 1e-3
    assert observed_order(sizes, errors) == pytest.approx(2.0, abs=0.05)
    richardson = (4.0 * values[-1] - values[-2]) / 3.0
    assert abs(richardson - smooth) < abs(errors[-1]) / 50.0


# ---------------------------------------------------------------- twist and Lk = Tw + Wr


def test_parallel_transport_is_the_minimal_rotation() -> None:
    rng = np.random.default_rng(61)
    a = unit(rng.normal(size=(50, 3)))
    b = unit(rng.normal(size=(50, 3)))
    v = rng.normal(size=(50, 3))
    moved = parallel_transport(v, a, b)
    np.testing.assert_allclose(parallel_transport(a, a, b), b, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(moved, axis=1), np.linalg.norm(v, axis=1), rtol=1e-14)
    binormal = np.cross(a, b)
    np.testing.assert_allclose(parallel_transport(binormal, a, b), binormal, atol=1e-14)
    np.testing.assert_allclose(parallel_transport(moved, b, a), v, atol=1e-13)
    with pytest.raises(ValueError, match="opposite"):
        parallel_transport(v[:1], a[:1], -a[:1])


def test_twist_of_a_straight_rod_with_uniformly_turning_frame() -> None:
    n, step = 30, 0.4
    points = np.column_stack([np.zeros(n), np.zeros(n), np.linspace(0.0, 2.0, n)])
    angle = step * np.arange(n - 1)
    d1 = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n - 1)])  # right-handed about z
    assert twist_from_frames(points, d1, closed=False) == pytest.approx(
        (n - 2) * step / (2 * np.pi), abs=1e-14
    )
    # each vertex angle is taken in (−π, π]: a 3π/2 step counts as −π/2
    angle = 1.5 * np.pi * np.arange(n - 1)
    d1 = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n - 1)])
    assert twist_from_frames(points, d1, closed=False) == pytest.approx(-(n - 2) / 4.0, abs=1e-12)


@pytest.mark.parametrize("turns", [0, 1, -2, 5])
def test_twist_of_a_framed_circle_is_its_number_of_turns(turns: int) -> None:
    n = 90
    phi = 2.0 * np.pi * (np.arange(n) + 0.5) / n  # edge midpoints of the regular polygon
    points = np.column_stack([np.cos(phi - np.pi / n), np.sin(phi - np.pi / n), np.zeros(n)])
    radial = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)])
    tangent = edge_tangents(points, closed=True)
    binormal = np.cross(tangent, radial)
    d1 = np.cos(turns * phi)[:, None] * radial + np.sin(turns * phi)[:, None] * binormal
    twist = twist_from_frames(points, d1)
    assert twist == pytest.approx(turns, abs=1e-12)
    # rigid motions and reversal of the curve (with its frame) leave the twist unchanged
    rotation = random_rotation(np.random.default_rng(62))
    assert twist_from_frames(points @ rotation.T + 3.0, d1 @ rotation.T) == pytest.approx(
        twist, abs=1e-12
    )
    reversed_points = points[::-1]
    reversed_frame = np.roll(d1[::-1], -1, axis=0)  # edge k of the reversed polygon
    assert twist_from_frames(reversed_points, reversed_frame) == pytest.approx(twist, abs=1e-12)


def framed_torus_knot(
    p: int, q: int, n: int, turns: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Polygon (n, 3), edge frame d1 (n, 3) and vertex frame (n, 3) of a (p, q) torus knot.

    The frame is the torus surface normal, made normal to the tangent, then turned by
    ``turns`` full right-handed turns about the tangent along the knot.
    """
    phi = 2.0 * np.pi * np.arange(n) / n
    points = torus_curve(p, q, phi)
    tangent = edge_tangents(points, closed=True)

    def frame(directions: np.ndarray, where: np.ndarray) -> np.ndarray:
        normal = tube_normal(p, q, where)
        normal = unit(normal - np.einsum("ij,ij->i", normal, directions)[:, None] * directions)
        binormal = np.cross(directions, normal)
        angle = turns * where
        return np.cos(angle)[:, None] * normal + np.sin(angle)[:, None] * binormal

    d1 = frame(tangent, phi + np.pi / n)
    vertex_tangent = unit(tangent + np.roll(tangent, 1, axis=0))
    return points, d1, frame(vertex_tangent, phi)


@pytest.mark.parametrize(("p", "q"), [(2, 3), (3, 2), (2, 5)])
@pytest.mark.parametrize("turns", [0, 1, -3])
def test_calugareanu_white_for_twisted_torus_knot_ribbons(p: int, q: int, turns: int) -> None:
    # Oracles: (i) Tw + Wr is an integer (Călugăreanu–White); (ii) it equals the Gauss
    # linking number of the knot with its push-off along the frame; (iii) the torus
    # surface framing of a (p, q) torus knot has linking number ±pq (here −pq: with ψ = qφ
    # increasing this parametrisation is left-handed, cf. the (2,4) link test), and each
    # added right-handed turn of the frame adds +1.
    points, d1, vertex_frame = framed_torus_knot(p, q, 300, turns)
    total = twist_from_frames(points, d1) + writhe(points)
    expected = -p * q + turns
    assert total == pytest.approx(expected, abs=1e-9)
    assert linking_number(points, points + 0.01 * vertex_frame) == pytest.approx(expected, abs=1e-9)
    mirror = np.array([1.0, 1.0, -1.0])
    assert twist_from_frames(points * mirror, d1 * mirror) + writhe(points * mirror) == (
        pytest.approx(-expected, abs=1e-9)
    )


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("points", "closure", "message"),
    [
        (np.zeros((5, 2)), "closed", "points has shape (5, 2); expected an (n_vertices, 3)"),
        (
            np.array([[0.0, 0, 0], [1, 0, 0], [np.nan, 0, 1]]),
            "closed",
            "non-finite coordinate at vertex 2",
        ),
        (
            np.array([[0.0, 0, 0], [1, 0, 0]]),
            "closed",
            "2 vertices; a closed polygon needs at least 3",
        ),
        (np.array([[0.0, 0, 0]]), "none", "1 vertex; an open polygon needs at least 2"),
        (
            np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0]]),
            "closed",
            "zero-length edge between vertices 1 and 2",
        ),
        (
            np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0]]),
            "closed",
            "do not repeat the first vertex",
        ),
        (np.eye(3), "loop", "closure 'loop' is unknown; expected one of closed, chord, none, axis"),
        ("abc", "closed", "points: cannot be read as a float array"),
    ],
)
def test_bad_writhe_input_raises_a_clear_value_error(points, closure: str, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        writhe(points, closure)
    with pytest.raises(ValueError, match=re.escape(message)):
        writhe_reference(points, closure)


def test_bad_axis_and_bad_linking_input_raise() -> None:
    with pytest.raises(ValueError, match="axis is the zero vector"):
        writhe(np.eye(3), "axis", (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="not a finite 3-vector"):
        writhe(np.eye(3), "axis", (0.0, 1.0))
    with pytest.raises(ValueError, match=re.escape("curve2 has shape (4,)")):
        linking_number(np.eye(3), np.zeros(4))


def test_bad_frame_input_raises() -> None:
    points, d1, _ = framed_torus_knot(2, 3, 30, 0)
    with pytest.raises(ValueError, match=re.escape("d1 has shape (29, 3); expected (30, 3)")):
        twist_from_frames(points, d1[:-1])
    with pytest.raises(ValueError, match=re.escape("d1[0] has length 2")):
        twist_from_frames(points, d1 * 2.0)
    tangent = edge_tangents(points, closed=True)
    with pytest.raises(ValueError, match=re.escape("d1[0] makes cosine")):
        twist_from_frames(points, np.vstack([tangent[:1], d1[1:]]))
    cusp = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0, 0]])
    with pytest.raises(ValueError, match="antiparallel"):
        twist_from_frames(cusp, np.array([[0.0, 1, 0], [0, 1, 0]]), closed=False)


def test_jit_decorator_falls_back_without_a_cache_location() -> None:
    # A function compiled from a string has no source file: numba finds no cache
    # locator and raises at decoration time; _njit must then compile without a cache.
    namespace: dict[str, object] = {}
    source = compile("def double(x):\n    return 2.0 * x\n", "<string>", "exec")
    exec(source, namespace)  # noqa: S102 - a constant string, to get a function without a file
    assert _njit()(namespace["double"])(1.5) == 3.0


# ------------------------------------------------ undefined writhe and linking number


def figure_eight(n: int = 40, lift: float = 0.0) -> np.ndarray:
    """(n, 3) lemniscate ``(sin 2t, sin t, lift cos t)``: with ``lift = 0`` its two
    lobes cross at the origin (vertices 0 and n/2)."""
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([np.sin(2 * t), np.sin(t), lift * np.cos(t)], axis=1)


def test_writhe_of_a_self_intersecting_polygon_is_refused() -> None:
    """Oracle: the writhe jumps by 2 across a crossing, so at the crossing it is undefined.
    Lifted by +eps and -eps the lemniscate's writhes differ by 2 (the limits on either
    side); at eps = 0 the input is refused instead of returning one of them."""
    from supercoil.errors import InputError

    above, below = writhe(figure_eight(lift=1e-9)), writhe(figure_eight(lift=-1e-9))
    assert abs(above - below) == pytest.approx(2.0, abs=1e-6)
    for closure in ("closed", "chord"):
        with pytest.raises(InputError, match="meet .*writhe is undefined"):
            writhe(figure_eight(), closure)
    with pytest.raises(InputError, match="intersects itself"):
        writhe_reference(figure_eight())
    # an open polygon that retraces its last edge (a fold back onto itself)
    retrace = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 0.5, 0]])
    with pytest.raises(InputError, match="edges 1 and 2"):
        writhe(retrace, "none")


def test_linking_number_of_a_curve_with_itself_or_a_crossing_curve_is_refused() -> None:
    """Oracle: the Hopf link has Lk = 1 and an unlinked pair 0; the curve with itself, and
    two circles through each other's points, are refused (Lk jumps by 1 there)."""
    from supercoil.errors import InputError

    t = 2 * np.pi * np.arange(60) / 60
    ring = np.stack([np.cos(t), np.sin(t), 0 * t], axis=1)
    hopf = np.stack([1 + np.cos(t), 0 * t, np.sin(t)], axis=1)
    assert abs(linking_number(ring, hopf)) == pytest.approx(1.0, abs=1e-9)
    assert linking_number(ring, ring + [5.0, 0, 0]) == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(InputError, match="same vertices.*with itself is undefined"):
        linking_number(ring, ring)
    with pytest.raises(InputError, match="same vertices"):
        linking_number(ring, ring.copy())
    through = np.stack([np.cos(t), 0 * t, np.sin(t)], axis=1)  # shares two points with ring
    with pytest.raises(InputError, match="meets edge .* undefined"):
        linking_number(ring, through)


def test_writhe_of_a_self_crossing_polygon_is_nan_when_asked():
    """A figure eight lying in a plane meets itself: an error by default, NaN on request
    (the records of a rod that may pass through itself)."""
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    eight = np.c_[np.sin(t), np.sin(t) * np.cos(t), 0 * t]
    with pytest.raises(InputError):
        writhe(eight)
    assert np.isnan(writhe(eight, self_crossing="nan"))
    lifted = eight + np.c_[0 * t, 0 * t, 0.1 * np.cos(t)]
    assert writhe(lifted, self_crossing="nan") == writhe(lifted)
