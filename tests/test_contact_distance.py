"""Segment–segment distance and its derivatives (supercoil.contact.distance).

Oracles: a dense 400 x 400 grid of (s, t) plus an exact bounded least-squares
solve (scipy's BVLS) for the distance; central finite differences of
``segment_distance`` and JAX autodiff of each type's closed-form formula for
the derivatives; analytic values for the special configurations.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

from supercoil.contact.distance import (
    DistanceKind,
    segment_distance,
    segment_distance_derivatives,
)

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


def check_against_oracles(p0, p1, q0, q1, grid=400):
    p0, p1, q0, q1 = (np.asarray(x, dtype=float) for x in (p0, p1, q0, q1))
    d, s, t = segment_distance(p0, p1, q0, q1)
    scale = max(1.0, *(np.abs(x).max() for x in (p0, p1, q0, q1)))
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


finite = st.floats(-10.0, 10.0, allow_nan=False, allow_subnormal=False)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=finite))
def test_hypothesis_distance_matches_oracles(x):
    check_against_oracles(*x, grid=120)


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


def _twisted_parallel(theta, rng, offset=0.3, length=1.0):
    """p along x; q of length ``length`` above it at height 0.5, rotated by theta about z at its
    midpoint: the exact minimiser is interior whenever theta != 0."""
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    mid = np.array([offset + length / 2, 0.0, 0.5])
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


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=finite))
@example(np.array([[0.125, 0, 0], [0, 0, 0], [0, 1, 0], [0, 2, 0]], dtype=float))
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
        # scale^2 bounds both (the jax oracle above checks the gradient to 1e-9).
        np.testing.assert_allclose(g, fd_gradient(x12),
                                   atol=1e-6 * scale + 2e-6 * max(np.abs(hess).max(), scale**2))


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
