"""Segment–segment distance and its derivatives (supercoil.contact.distance).

Oracles: a dense 400 x 400 grid of (s, t), an exact bounded least-squares
solve (scipy's BVLS) and the squared distance in exact rational arithmetic
(``fractions``) for the distance; central finite differences of
``segment_distance`` and JAX autodiff of each type's closed-form formula for
the derivatives; analytic values for the special configurations.
"""

import math
from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

from supercoil.contact.distance import segment_distance, segment_distance_derivatives
from supercoil.contact.distance_kernels import DistanceKind

jax.config.update("jax_enable_x64", True)  # as supercoil.rod.kernels does

K = DistanceKind


# --------------------------------------------------------------------------
# oracles
# --------------------------------------------------------------------------


def grid_distance(p0, p1, q0, q1, n=400):
    """Smallest distance over an n x n grid of parameters (an upper bound on d)."""
    s = np.linspace(0.0, 1.0, n)
    p = p0 + s[:, None] * (p1 - p0)
    q = q0 + s[:, None] * (q1 - q0)
    return np.sqrt(((p[:, None, :] - q[None, :, :]) ** 2).sum(-1).min())


def bvls_distance(p0, p1, q0, q1):
    """min |w + s e_p - t e_q| over [0, 1]^2 by scipy's bounded-variable least squares."""
    a = np.stack([p1 - p0, -(q1 - q0)], axis=1)
    result = lsq_linear(a, -(p0 - q0), bounds=(0.0, 1.0), method="bvls", tol=1e-15)
    return np.linalg.norm(a @ result.x + (p0 - q0))


def exact_distance_squared(p0, p1, q0, q1) -> Fraction:
    """``d^2`` in exact rational arithmetic.

    The float coordinates are exact rationals and ``|r(s, t)|^2`` is a quadratic with
    rational coefficients, so its minimum over the square is rational: the interior
    critical point when it lies in the square, else the best of the four endpoint-to-
    segment projections clamped to ``[0, 1]`` (the textbook formulas, here without
    rounding).
    """
    p0, p1, q0, q1 = ([Fraction(float(c)) for c in x] for x in (p0, p1, q0, q1))
    u = [b - a for a, b in zip(p0, p1)]
    v = [b - a for a, b in zip(q0, q1)]
    w = [b - a for a, b in zip(q0, p0)]

    def dot(x, y):
        return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]

    def h(s, t):
        r = [w[k] + s * u[k] - t * v[k] for k in range(3)]
        return dot(r, r)

    def clamp(x):
        return min(max(x, Fraction(0)), Fraction(1))

    a, b, c, dw, ew = dot(u, u), dot(u, v), dot(v, v), dot(u, w), dot(v, w)
    candidates = []
    det = a * c - b * b
    if det > 0:
        s, t = (b * ew - c * dw) / det, (a * ew - b * dw) / det
        if 0 <= s <= 1 and 0 <= t <= 1:
            candidates.append(h(s, t))
    for s in (Fraction(0), Fraction(1)):
        candidates.append(h(s, clamp((ew + s * b) / c) if c > 0 else Fraction(0)))
    for t in (Fraction(0), Fraction(1)):
        candidates.append(h(clamp((t * b - dw) / a) if a > 0 else Fraction(0), t))
    return min(candidates)


EPS = np.finfo(float).eps


def rounding_scale(p0, p1, q0, q1) -> float:
    """``|p0 - q0| + |p1 - p0| + |q1 - q0|``: the size of the differences the kernel rounds."""
    return float(np.linalg.norm(np.subtract(p0, q0)) + np.linalg.norm(np.subtract(p1, p0))
                 + np.linalg.norm(np.subtract(q1, q0)))


def assert_near_exact(d, p0, p1, q0, q1, tolerance):
    """``|d - sqrt(exact d^2)| <= tolerance``, decided in exact arithmetic."""
    exact = exact_distance_squared(p0, p1, q0, q1)
    d, tolerance = Fraction(float(d)), Fraction(float(tolerance))
    assert max(d - tolerance, Fraction(0)) ** 2 <= exact <= (d + tolerance) ** 2, (
        f"d = {float(d)!r}, exact {math.sqrt(exact)!r}, tolerance {float(tolerance)!r}")


# The kernel's error bound (module docstring of supercoil.contact.distance, "Accuracy"):
# the differences w, e_p, e_q are rounded once (eps/2 relative), r(s, t) = w + s e_p - t e_q
# is rounded a few more times, and the error of (s, t) along the valley of |r|^2 is
# O(eps ℓ): a few eps times rounding_scale, i.e. the exact distance of segments moved by a
# few units in the last place. Measured: at most 0.93 eps * rounding_scale on 48000 random
# nearly parallel, coplanar crossing, rotated crossing and generic pairs. Below
# sqrt(tiny) ≈ 1.5e-154 the squares of the coordinates of r underflow (hypothesis found
# coordinates of 7e-228): an absolute error of a few sqrt(tiny) comes on top.
ROUNDING = 4 * EPS
UNDERFLOW = 4 * np.sqrt(np.finfo(float).tiny)


def check_against_oracles(p0, p1, q0, q1, grid=400):
    p0, p1, q0, q1 = (np.asarray(x, dtype=float) for x in (p0, p1, q0, q1))
    d, s, t = segment_distance(p0, p1, q0, q1)
    scale = max(1.0, *(np.abs(x).max() for x in (p0, p1, q0, q1)))
    assert_near_exact(d, p0, p1, q0, q1, ROUNDING * rounding_scale(p0, p1, q0, q1) + UNDERFLOW)
    assert 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
    # the returned points realise d
    np.testing.assert_allclose(np.linalg.norm(p0 + s * (p1 - p0) - q0 - t * (q1 - q0)), d,
                               rtol=1e-12, atol=1e-14 * scale)
    # never worse than any sampled pair of points, equal to the exact solve
    assert d <= grid_distance(p0, p1, q0, q1, grid) + 1e-14 * scale
    np.testing.assert_allclose(d, bvls_distance(p0, p1, q0, q1), rtol=1e-9, atol=1e-12 * scale)
    return d, s, t


def random_rigid(rng):
    rotation = Rotation.random(random_state=rng).as_matrix()
    shift = rng.normal(size=3)
    return lambda x: np.asarray(x, dtype=float) @ rotation.T + shift


def _type_formula(kind):
    """Closed-form distance of one type as a function of the 12 coordinates (JAX)."""

    def point_line(x, a, b):
        e = b - a
        return jnp.linalg.norm(jnp.cross(x - a, e)) / jnp.linalg.norm(e)

    def value(x):
        p0, p1, q0, q1 = x[0:3], x[3:6], x[6:9], x[9:12]
        if kind == K.EDGE_EDGE:
            n = jnp.cross(p1 - p0, q1 - q0)
            return jnp.abs(jnp.dot(p0 - q0, n)) / jnp.linalg.norm(n)
        if kind == K.P0_EDGE_Q:
            return point_line(p0, q0, q1)
        if kind == K.P1_EDGE_Q:
            return point_line(p1, q0, q1)
        if kind == K.Q0_EDGE_P:
            return point_line(q0, p0, p1)
        if kind == K.Q1_EDGE_P:
            return point_line(q1, p0, p1)
        a = {K.P0_Q0: p0, K.P0_Q1: p0, K.P1_Q0: p1, K.P1_Q1: p1}[kind]
        b = {K.P0_Q0: q0, K.P0_Q1: q1, K.P1_Q0: q0, K.P1_Q1: q1}[kind]
        return jnp.linalg.norm(a - b)

    return value


_JAX_ORACLES = {}


def jax_oracle(kind):
    """``(value, gradient, hessian)`` of the type formula by JAX autodiff."""
    kind = K(int(kind))
    if kind not in _JAX_ORACLES:
        f = _type_formula(kind)
        _JAX_ORACLES[kind] = (jax.jit(f), jax.jit(jax.grad(f)), jax.jit(jax.hessian(f)))
    return _JAX_ORACLES[kind]


def fd_gradient(x12, h=1e-6):
    g = np.empty(12)
    for i in range(12):
        e = np.zeros(12)
        e[i] = h
        g[i] = (segment_distance(*(x12 + e).reshape(4, 3))[0]
                - segment_distance(*(x12 - e).reshape(4, 3))[0]) / (2 * h)
    return g


def fd_hessian(x12, h=1e-4):
    """Second central differences of segment_distance."""
    def d(x):
        return segment_distance(*x.reshape(4, 3))[0]

    hess = np.empty((12, 12))
    eye = np.eye(12) * h
    for i in range(12):
        for j in range(i, 12):
            hess[i, j] = hess[j, i] = (d(x12 + eye[i] + eye[j]) - d(x12 + eye[i] - eye[j])
                                       - d(x12 - eye[i] + eye[j]) + d(x12 - eye[i] - eye[j])
                                       ) / (4 * h * h)
    return hess


def derivatives(x12, **options):
    d, g, hess, kind = segment_distance_derivatives(*np.asarray(x12).reshape(4, 3), **options)
    return float(d), g, hess, K(int(kind))


# --------------------------------------------------------------------------
# distance, s, t
# --------------------------------------------------------------------------


def test_crossing_at_right_angles_is_exact():
    d, s, t = segment_distance([0, 0, 0], [1, 0, 0], [0.25, -1, 2], [0.25, 3, 2])
    assert (float(d), float(s), float(t)) == (2.0, 0.25, 0.25)


def test_random_pairs_match_grid_and_exact_solve(rng):
    for _ in range(40):
        p0, p1, q0, q1 = rng.normal(size=(4, 3))
        check_against_oracles(p0, p1, q0, q1)


def test_vectorised_equals_one_by_one(rng):
    x = rng.normal(size=(4, 200, 3))
    d, s, t = segment_distance(*x)
    assert d.shape == s.shape == t.shape == (200,)
    for i in range(0, 200, 17):
        di, si, ti = segment_distance(*x[:, i])
        assert (di, si, ti) == (d[i], s[i], t[i])
    # (3,) broadcasts against (m, 3)
    d_b, _, _ = segment_distance(x[0, 0], x[1, 0], x[2], x[3])
    np.testing.assert_array_equal(d_b, segment_distance(*np.broadcast_arrays(*x[:2, :1], *x[2:]))[0])


@pytest.mark.parametrize("offset", [-1.5, -0.3, 0.0, 0.4, 0.999, 1.0, 2.5])
@pytest.mark.parametrize("reverse", [False, True])
def test_parallel_and_antiparallel(rng, offset, reverse):
    transform = random_rigid(rng)
    q0, q1 = [offset, 0.3, 0.4], [offset + 0.7, 0.3, 0.4]
    if reverse:
        q0, q1 = q1, q0
    p = [transform([0, 0, 0]), transform([1, 0, 0])]
    d, _, _ = check_against_oracles(*p, transform(q0), transform(q1))
    gap = max(0.0, offset - 1.0, -(offset + 0.7))  # along the common direction
    np.testing.assert_allclose(d, np.hypot(0.5, gap), rtol=1e-12)


@pytest.mark.parametrize("offset", [-1.5, -0.5, 0.2, 0.999, 1.0, 1.0 + 1e-9, 2.5])
def test_collinear(rng, offset):
    transform = random_rigid(rng)
    p0, p1, q0, q1 = (transform(x) for x in ([0, 0, 0], [1, 0, 0], [offset, 0, 0],
                                              [offset + 0.7, 0, 0]))
    d, _, _ = segment_distance(p0, p1, q0, q1)
    gap = max(0.0, offset - 1.0, -(offset + 0.7))
    np.testing.assert_allclose(d, gap, atol=1e-14)
    check_against_oracles(p0, p1, q0, q1)


def test_zero_length_segments(rng):
    for _ in range(10):
        a, b, c = rng.normal(size=(3, 3))
        # point against segment, both orders, and point against point
        d, s, _ = check_against_oracles(a, a, b, c)
        assert s == 0.0
        d2, _, t2 = check_against_oracles(b, c, a, a)
        assert t2 == 0.0 and d2 == pytest.approx(d, rel=1e-12)
        d3, _, _ = check_against_oracles(a, a, b, b)
        assert d3 == pytest.approx(np.linalg.norm(a - b), rel=1e-15)
    assert segment_distance(a, a, a, a)[0] == 0.0
    # below a squared length of 1e-300 a segment is a point (its foot parameter 0)
    d4, s4, _ = check_against_oracles(a, a + 1e-160, b, c)
    assert s4 == 0.0 and d4 == pytest.approx(d, rel=1e-12)


def test_crossing_segments_have_zero_distance(rng):
    for _ in range(20):
        transform = random_rigid(rng)
        s, t = rng.uniform(0.05, 0.95, size=2)
        u, v = rng.normal(size=(2, 3))
        x = rng.normal(size=3)  # the common point
        d, s_found, t_found = segment_distance(*(transform(y) for y in (x - s * u, x + (1 - s) * u,
                                                                         x - t * v, x + (1 - t) * v)))
        assert d < 1e-14 * 10
        np.testing.assert_allclose([s_found, t_found], [s, t], atol=1e-12)


@pytest.mark.parametrize("height", [0.0, 1e-8, 0.3])
def test_t_configurations(rng, height):
    # the endpoint q0 sits above the interior of p; q leaves perpendicularly
    transform = random_rigid(rng)
    d, s, t = check_against_oracles(*(transform(x) for x in ([-1, 0, 0], [1, 0, 0],
                                                              [0.3, 0, height], [0.3, 0, 2])))
    np.testing.assert_allclose([d, s, t], [height, 0.65, 0.0], atol=1e-14)


# Nearly antiparallel, overlapping, EPS_AP = 1.19e-8 apart: p(s) = (ε(1 - s), 1 - s, εs) and
# q(t) = (0, t, 0), so |p(s) - q(1 - s)|^2 = ε^2 ((1 - s)^2 + s^2) (t = 1 - s is the foot), least
# at s = t = 1/2: d = ε / sqrt(2) ≈ 8.41e-9 (the textbook numerators cancelled to garbage and
# the kernel returned the endpoint distance ε, hypothesis found it).
EPS_AP = 1.19e-8
ANTIPARALLEL = np.array([[EPS_AP, 1, 0], [0, 0, EPS_AP], [0, 0, 0], [0, 1, 0]], dtype=float)
# Coplanar (z = 0) segments crossing at s ≈ 0.66, t ≈ 0.42 at 0.58°: the exact distance is 0
# (exact_distance_squared says so); the kernel returned 1.52e-12.
COPLANAR_CROSSING = np.array([[-0.018, -0.104, 0], [-0.28, 0.271, 0], [-0.389, 0.421, 0],
                              [0.085, -0.243, 0]], dtype=float)


def test_nearly_antiparallel_overlap_is_exact(rng):
    assert exact_distance_squared(*ANTIPARALLEL) == Fraction(EPS_AP) ** 2 / 2  # the closed form
    d, s, t = segment_distance(*ANTIPARALLEL)
    scale = rounding_scale(*ANTIPARALLEL)
    assert abs(d - EPS_AP / np.sqrt(2)) <= ROUNDING * scale
    # the minimiser is unique (the lines are skew): s = t = 1/2. Along the valley the distance
    # grows like d (1 + 2 δs^2), so an error of ROUNDING · scale in d pins s and t only to
    # δs ≈ sqrt(ROUNDING · scale / (2 d)) ≈ 4e-4
    np.testing.assert_allclose([s, t], [0.5, 0.5], atol=1e-3)
    # rigid motions: the exact distance of the rounded images is the oracle, and it is within
    # the rounding of the images (~ eps |x|) of the closed form
    for _ in range(20):
        transform = random_rigid(rng)
        x = [transform(y) for y in ANTIPARALLEL]
        d_moved = segment_distance(*x)[0]
        assert_near_exact(d_moved, *x, ROUNDING * rounding_scale(*x))
        assert abs(d_moved - EPS_AP / np.sqrt(2)) < 1e-14


def test_coplanar_crossing_is_round_off_from_zero(rng):
    assert exact_distance_squared(*COPLANAR_CROSSING) == 0
    d, s, t = segment_distance(*COPLANAR_CROSSING)
    # backward error: d is the exact distance of the pair with q moved by d normal to the
    # plane, so d <= a few ulps of the coordinates (ROUNDING · scale) is all rounding allows
    assert d <= ROUNDING * rounding_scale(*COPLANAR_CROSSING)
    p0, p1, q0, q1 = COPLANAR_CROSSING
    u, v = p1 - p0, q1 - q0
    n = np.cross(u, v)[2]  # the crossing parameters in closed form (2D Cramer)
    w = q0 - p0
    np.testing.assert_allclose([s, t], [np.cross(w, v)[2] / n, np.cross(w, u)[2] / n], atol=1e-12)
    # the same crossing with generic coordinates: rotated and shifted, no longer exactly
    # coplanar, checked against the exact distance of the rounded images
    for _ in range(20):
        transform = random_rigid(rng)
        x = [transform(y) for y in COPLANAR_CROSSING]
        assert_near_exact(segment_distance(*x)[0], *x, ROUNDING * rounding_scale(*x))


finite = st.floats(-10.0, 10.0, allow_nan=False, allow_subnormal=False)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=finite))
@example(ANTIPARALLEL)
@example(COPLANAR_CROSSING)
def test_hypothesis_distance_matches_oracles(x):
    check_against_oracles(*x, grid=120)


@st.composite
def nearly_parallel_pairs(draw):
    """Overlapping, nearly parallel or antiparallel segments (4, 3), 1e-12 … 1e-3 of their
    length apart, at an angle 0 or 1e-16 … 1e-2, then rotated and shifted."""
    length = draw(st.floats(0.1, 10.0))
    other_length = length * draw(st.floats(0.3, 3.0))
    separation = length * 10.0 ** draw(st.floats(-12.0, -3.0))
    angle = draw(st.sampled_from([0.0]) | st.floats(-16.0, -2.0).map(lambda e: 10.0**e))
    tilt = draw(st.floats(0.0, 2 * np.pi))  # the plane of the angle
    overlap = draw(st.floats(0.0, 1.0))  # where the middle of q sits along p
    euler = draw(arrays(np.float64, 3, elements=st.floats(-np.pi, np.pi)))
    shift = draw(arrays(np.float64, 3, elements=st.floats(-10.0, 10.0)))
    half = 0.5 * other_length * np.array([np.cos(angle), np.sin(angle) * np.cos(tilt),
                                          np.sin(angle) * np.sin(tilt)])
    middle = np.array([overlap * length, separation, 0.0])
    q0, q1 = middle - half, middle + half
    if draw(st.booleans()):
        q0, q1 = q1, q0
    rotation = Rotation.from_euler("zyx", euler).as_matrix()
    return np.array([[0.0, 0.0, 0.0], [length, 0.0, 0.0], q0, q1]) @ rotation.T + shift


@settings(max_examples=200, deadline=None)
@given(nearly_parallel_pairs())
def test_hypothesis_nearly_parallel_matches_exact(x):
    d, s, t = segment_distance(*x)
    assert 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
    assert_near_exact(d, *x, ROUNDING * rounding_scale(*x) + UNDERFLOW)
    # the returned points realise d (up to the rounding of this recomputation)
    p0, p1, q0, q1 = x
    np.testing.assert_allclose(np.linalg.norm(p0 + s * (p1 - p0) - q0 - t * (q1 - q0)), d,
                               rtol=0, atol=8 * EPS * max(np.abs(x).max(), 1.0))


# --------------------------------------------------------------------------
# derivatives in each region
# --------------------------------------------------------------------------

# canonical configurations, the closest pair well inside one region
_POINT_EDGE = {  # endpoint A above the interior of segment B; A's segment leaves B
    K.P0_EDGE_Q: lambda a, b: (a[0], a[1], b[0], b[1]),
    K.P1_EDGE_Q: lambda a, b: (a[1], a[0], b[0], b[1]),
    K.Q0_EDGE_P: lambda a, b: (b[0], b[1], a[0], a[1]),
    K.Q1_EDGE_P: lambda a, b: (b[1], b[0], a[1], a[0]),
}
_POINT_POINT = {
    K.P0_Q0: lambda a, b: (a[0], a[1], b[0], b[1]),
    K.P0_Q1: lambda a, b: (a[0], a[1], b[1], b[0]),
    K.P1_Q0: lambda a, b: (a[1], a[0], b[0], b[1]),
    K.P1_Q1: lambda a, b: (a[1], a[0], b[1], b[0]),
}


def region_configuration(kind, rng):
    if kind == K.EDGE_EDGE:
        x = ([-1, 0, 0], [1, 0.2, 0], [0.1, -1, 0.5], [-0.2, 1, 0.7])
    elif kind in _POINT_EDGE:
        x = _POINT_EDGE[kind](([0.2, 0.1, 0.6], [0.5, 0.5, 1.5]), ([-1, 0, 0], [1, 0.1, 0]))
    else:
        x = _POINT_POINT[kind](([0, 0, 0.5], [0.3, 0.2, 1.5]), ([0.2, -0.1, 0], [0.5, -0.6, -1]))
    transform = random_rigid(rng)
    return np.concatenate([transform(y) for y in x])


@pytest.mark.parametrize("kind", list(K))
def test_derivatives_in_each_region(rng, kind):
    x = region_configuration(kind, rng)
    d, g, hess, found = derivatives(x)
    assert found == kind
    assert d == pytest.approx(segment_distance(*x.reshape(4, 3))[0], rel=1e-13)
    np.testing.assert_allclose(g, fd_gradient(x), atol=1e-8)
    np.testing.assert_allclose(hess, fd_hessian(x), atol=2e-6)
    value, grad_jax, hess_jax = jax_oracle(kind)
    assert d == pytest.approx(float(value(x)), rel=1e-13)
    np.testing.assert_allclose(g, grad_jax(x), atol=1e-12)
    np.testing.assert_allclose(hess, hess_jax(x), atol=1e-10)
    np.testing.assert_allclose(hess, hess.T, atol=1e-14)


def _twisted_parallel(theta, rng, offset=0.3, length=1.0, height=0.5):
    """p along x; q of length ``length`` above it at ``height``, rotated by theta/2 about z at its
    midpoint: the exact minimiser is interior whenever theta != 0."""
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    mid = np.array([offset + length / 2, 0.0, height])
    half = 0.5 * length * np.array([c, s, 0.0])
    transform = random_rigid(rng)
    return np.concatenate([transform(y) for y in ([0, 0, 0], [1, 0, 0], mid - half, mid + half)])


@pytest.mark.parametrize("theta", [0.0, 1e-9, 1e-6, 1e-4])
def test_near_parallel_fallback(rng, theta):
    x = _twisted_parallel(theta, rng)
    d, g, hess, kind = derivatives(x)
    assert kind != K.EDGE_EDGE
    d_exact = segment_distance(*x.reshape(4, 3))[0]
    ell = 1.0
    bound = min(ell * abs(np.sin(theta)), (ell * np.sin(theta)) ** 2 / (2 * d_exact))
    assert -1e-15 <= d - d_exact <= bound + 1e-15  # the documented fallback error
    # exact derivatives of the fallback's own formula
    value, grad_jax, hess_jax = jax_oracle(kind)
    assert d == pytest.approx(float(value(x)), rel=1e-13)
    np.testing.assert_allclose(g, grad_jax(x), atol=1e-12)
    np.testing.assert_allclose(hess, hess_jax(x), atol=1e-10)
    # The exact distance is not differentiable at parallel overlapping pairs (a min over a
    # segment of minimisers: only directional derivatives exist), so the fallback, an upper
    # bound within `bound`, has a gradient g with D(x + h v) <= d + h g.v + O(h^2).
    directions = rng.normal(size=(20, 12))
    for h in (1e-3, 1e-5):
        d_moved = segment_distance(*(x + h * directions).reshape(20, 4, 3).transpose(1, 0, 2))[0]
        assert (d_moved <= d + h * directions @ g + 20 * h * h + bound).all()
    # a rigid translation moves every type alike: there g is the exact derivative
    shift = np.tile(rng.normal(size=3), 4)
    np.testing.assert_allclose(g @ shift, fd_gradient(x) @ shift, atol=1e-8)
    # bounded Hessian: O(1/d + 1/length), whatever theta
    assert np.abs(np.linalg.eigvalsh(hess)).max() < 10.0 * (1 / d + 1 / ell)


def test_near_parallel_hessian_is_continuous_at_parallel(rng):
    seed = int(rng.integers(2**31))
    hessians = [derivatives(_twisted_parallel(theta, np.random.default_rng(seed)))[2]
                for theta in (0.0, 1e-9)]
    np.testing.assert_allclose(hessians[1], hessians[0], atol=1e-7)


def test_line_formula_hessian_blows_up_without_fallback(rng):
    # why the fallback exists: the edge-edge Hessian grows like 1/theta
    x = _twisted_parallel(1e-4, rng)
    _, _, hess, kind = derivatives(x, parallel_tolerance=0.0)
    assert kind == K.EDGE_EDGE
    assert np.abs(np.linalg.eigvalsh(hess)).max() > 1e3
    _, _, hess_fallback, _ = derivatives(x)
    assert np.abs(np.linalg.eigvalsh(hess_fallback)).max() < 100


@pytest.mark.parametrize("height", [1e-6, 1e-4, 1e-2])
@pytest.mark.parametrize("theta", [0.01, 0.1])
def test_near_parallel_edge_edge_derivatives(rng, theta, height):
    # nearly parallel and close, but above the fallback tolerance: the edge-edge type, whose
    # weights (1 - s, s, t - 1, -t) use the interior (s, t) of the kernel
    x = _twisted_parallel(theta, rng, height=height)
    d, g, hess, kind = derivatives(x)
    assert kind == K.EDGE_EDGE
    sin = abs(np.sin(theta / 2))  # the angle between the segments
    points = x.reshape(4, 3)
    # the line formula |w.n| / |n| has the direction of n to ~eps / sin θ
    assert_near_exact(d, *points, ROUNDING * rounding_scale(*points) / sin)
    _, grad_jax, hess_jax = jax_oracle(kind)
    # s and t carry errors ~eps / sin θ (the textbook numerators gave ~eps / sin^2 θ: 2e-12
    # here at theta = 0.01)
    np.testing.assert_allclose(g, grad_jax(x), atol=10 * EPS / sin)
    # central differences of the exact distance, step h: round-off ~ ROUNDING · scale / h
    h = 1e-7
    np.testing.assert_allclose(g, fd_gradient(x, h),
                               atol=10 * ROUNDING * rounding_scale(*points) / h)
    # hess d = (hess h - grad d grad d^T) / d, with |hess h| ~ 1 / sin^2 θ, cancels to an
    # error ~eps / (d sin^2 θ)
    cancellation = 10 * EPS / (d * sin**2)
    np.testing.assert_allclose(hess, hess_jax(x), atol=cancellation)
    hess_fd = np.array([(derivatives(x + h * e)[1] - derivatives(x - h * e)[1]) / (2 * h)
                        for e in np.eye(12)])
    np.testing.assert_allclose(hess, hess_fd, atol=cancellation + 1e-8 * np.abs(hess).max())


def _slide(kind_boundary, lam):
    """Configurations crossing a region boundary at lam = 0 (no rigid motion: exact values)."""
    if kind_boundary == "edge-edge|point-edge":
        # q crosses over p; its closest point on the line of p is s* = 1 + lam
        return np.array([0, 0, 0, 1, 0, 0, 0.85 + lam, -1, 0.5, 1.15 + lam, 1, 0.5], dtype=float)
    # point-edge|point-point: the foot of p1 on q is t* = -lam / 2
    return np.array([0.2, 0.3, -0.4, 1, 0, 0, 1, -1 + 1 + lam, 0.5, 1, 1 + 1 + lam, 0.5],
                    dtype=float)


@pytest.mark.parametrize(("boundary", "kinds"), [
    ("edge-edge|point-edge", (K.EDGE_EDGE, K.P1_EDGE_Q)),
    ("point-edge|point-point", (K.P1_EDGE_Q, K.P1_Q0)),
])
def test_gradient_is_continuous_across_region_boundary(boundary, kinds):
    jumps = []
    for delta in (1e-2, 1e-4, 1e-6):
        d_minus, g_minus, h_minus, k_minus = derivatives(_slide(boundary, -delta))
        d_plus, g_plus, h_plus, k_plus = derivatives(_slide(boundary, delta))
        assert (k_minus, k_plus) == kinds
        jumps.append(np.abs(g_plus - g_minus).max() / delta)
        assert abs(d_plus - d_minus) < 2 * delta
    # the gradient changes in O(delta) (C^1), with a bounded ratio ...
    assert max(jumps) < 10.0
    # ... while the Hessian does jump (C^1, not C^2)
    assert np.abs(h_plus - h_minus).max() > 1e-2


def _hessian_near(x12, h=1e-6) -> float:
    """The largest Hessian entry at the points of :func:`fd_gradient`'s differences."""
    largest = 0.0
    for i in range(12):
        for sign in (1.0, -1.0):
            e = np.zeros(12)
            e[i] = sign * h
            largest = max(largest, float(np.abs(derivatives(x12 + e)[2]).max()))
    return largest


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=finite))
@example(np.array([[0.125, 0, 0], [0, 0, 0], [0, 1, 0], [0, 2, 0]], dtype=float))
# a corner whose other side's Hessian (about 27) is six times scale^2
@example(np.array([[0.0, -7.02667459, -1.0], [1.6328125, 3.0, -1.0],
                   [1.6328125, 1.6328125, 1.6328125], [1.6328125, 3.0, 1.6328125]]))
def test_hypothesis_derivatives_are_exact(x):
    x12 = x.ravel()
    d, g, hess, kind = derivatives(x12)
    lengths = np.linalg.norm(x[1] - x[0]), np.linalg.norm(x[3] - x[2])
    assume(d > 1e-3 * max(1.0, *lengths) and min(lengths) > 1e-3)
    value, grad_jax, hess_jax = jax_oracle(kind)
    scale = 1.0 + 1.0 / d + 1.0 / min(lengths)
    assert d == pytest.approx(float(value(x12)), rel=1e-10)
    np.testing.assert_allclose(g, grad_jax(x12), atol=1e-9 * scale)
    np.testing.assert_allclose(hess, hess_jax(x12), atol=1e-8 * scale**2)
    u, v = x[1] - x[0], x[3] - x[2]
    sin2 = np.linalg.norm(np.cross(u, v)) ** 2 / (lengths[0] * lengths[1]) ** 2
    if sin2 > 1e-6:  # no fallback: the exact distance and its gradient
        assert d == pytest.approx(segment_distance(*x)[0], rel=1e-10)
        # a central difference of step h across a region boundary (the Hessian
        # jumps there: C^1, not C^2) is off by up to h |H| with H the Hessian on
        # the *other* side, which is not the one returned: at the corner of two
        # perpendicular segments (p1 - q0 of length 1, |p| = 1/8) the edge-type
        # side has |H| ~ 1/|p|^2 = 64 while the corner's is ~1 (hypothesis found it).
        # The Hessians at the difference's own points bound it on both sides (the
        # jax oracle above checks the gradient to 1e-9).
        np.testing.assert_allclose(g, fd_gradient(x12),
                                   atol=1e-6 * scale + 2e-6 * max(np.abs(hess).max(), scale**2,
                                                                  _hessian_near(x12)))


def test_crossing_returns_finite_zeros():
    d, g, hess, kind = segment_distance_derivatives([0, 0, 0], [1, 0, 0], [0.5, -1, 0], [0.5, 1, 0])
    assert d == 0.0 and kind == K.EDGE_EDGE
    assert not g.any() and not hess.any()
    # coincident points
    d, g, hess, _ = segment_distance_derivatives(*np.ones((4, 3)))
    assert d == 0.0 and not g.any() and not hess.any()


def test_derivatives_vectorised_shapes(rng):
    x = rng.normal(size=(4, 300, 3))
    d, g, hess, kind = segment_distance_derivatives(*x)
    assert (d.shape, g.shape, hess.shape, kind.shape) == ((300,), (300, 12), (300, 12, 12), (300,))
    d1, g1, h1, k1 = segment_distance_derivatives(*x[:, 123])
    assert (d1, k1) == (d[123], kind[123])
    np.testing.assert_array_equal(g1, g[123])
    np.testing.assert_array_equal(h1, hess[123])


def test_invalid_input():
    with pytest.raises(ValueError, match="shape"):
        segment_distance(np.zeros((5, 2)), np.zeros((5, 2)), np.zeros((5, 2)), np.zeros((5, 2)))
    with pytest.raises(ValueError, match="finite"):
        segment_distance([np.nan, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0])
    with pytest.raises(ValueError, match="parallel_tolerance"):
        segment_distance_derivatives([0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0],
                                     parallel_tolerance=-1.0)
