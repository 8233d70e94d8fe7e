"""The sample-point kernels of supercoil.contact.integral against brute force.

The sample points, the chords' deviation, the closest sample points (with and
without the bounding-sphere cut-off) and the sample collision time are numba
loops; each is checked here against the plain numpy expression it replaced.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
from contact_toys import integral_pair_hessians_loop

from supercoil.contact.sample_ccd import first_time_of_approach_samples, sample_pair_time
from supercoil.contact.sample_weights import polygon_weights, spline_weights
from supercoil.contact.samples import chord_deviation, closest_samples, sample_points
from supercoil.contact.spline_pieces import bspline_pieces


def _coil(n: int, seed: int):
    """Nodes ``(n, 3)`` of a closed, self-approaching coil (two turns of a squashed
    helix, so that many segment pairs are near), its segments and spline samples."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = np.stack([np.cos(2 * t) * (1 + 0.3 * np.cos(t)), np.sin(2 * t) * (1 + 0.3 * np.cos(t)),
                  0.05 * np.sin(t)], axis=1) + 0.002 * rng.standard_normal((n, 3))
    segments = np.stack([np.arange(n), (np.arange(n) + 1) % n], axis=1)
    pieces = bspline_pieces(segments, True)
    return x, segments, pieces


def _all_pairs(k: int, exclusion: int):
    i, j = np.triu_indices(k, exclusion)
    keep = (j - i) <= k - exclusion
    return np.stack([i[keep], j[keep]], axis=1)


def _reference_points(x, stencil, weights):
    return np.einsum("kal,klx->kax", weights, x[stencil])


def _reference_closest(points, pairs):
    diff = points[pairs[:, 0]][:, :, None, :] - points[pairs[:, 1]][:, None, :, :]
    dist = np.linalg.norm(diff, axis=-1).reshape(len(pairs), -1)
    flat = np.argmin(dist, axis=1)  # first among equals, row-major as the kernel
    q = points.shape[1]
    return dist[np.arange(len(pairs)), flat], (flat // q + 0.5) / q, (flat % q + 0.5) / q


def _reference_time(x0, dx, stencil, weights, pairs, threshold):
    """The vectorised quadratic of the sample collision time (the former implementation)."""
    p0 = _reference_points(x0, stencil, weights)
    v = _reference_points(dx, stencil, weights)
    r0 = p0[pairs[:, 0]][:, :, None, :] - p0[pairs[:, 1]][:, None, :, :]
    rv = v[pairs[:, 0]][:, :, None, :] - v[pairs[:, 1]][:, None, :, :]
    a = np.sum(rv * rv, axis=-1)
    b = 2.0 * np.sum(r0 * rv, axis=-1)
    c = np.sum(r0 * r0, axis=-1) - threshold * threshold
    if np.any(c <= 0.0):
        return 0.0
    disc = b * b - 4.0 * a * c
    hit = (a > 0.0) & (b < 0.0) & (disc >= 0.0)
    if not hit.any():
        return 1.0
    tau = 2.0 * c[hit] / (-b[hit] + np.sqrt(disc[hit]))
    return float(min(1.0, np.min(tau)))


@pytest.mark.parametrize("spline", [False, True])
@pytest.mark.parametrize("seed", [0, 1])
def test_sample_points_and_chord_deviation_match_numpy(spline, seed):
    x, segments, pieces = _coil(80, seed)
    q = 7
    stencil = pieces.stencil if spline else segments
    weights = spline_weights(pieces.coefficients, q) if spline else polygon_weights(80, q)
    points = sample_points(x, stencil, weights)
    np.testing.assert_allclose(points, _reference_points(x, stencil, weights), rtol=0,
                               atol=1e-15)
    a, b = x[segments[:, 0]], x[segments[:, 1]]
    e = b - a
    t = np.clip(np.einsum("kqx,kx->kq", points - a[:, None], e) / np.sum(e * e, 1)[:, None],
                0, 1)
    expected = np.sqrt(np.max(np.sum((points - a[:, None] - t[..., None] * e[:, None]) ** 2,
                                     axis=-1), axis=1))
    np.testing.assert_allclose(chord_deviation(points, a, b), expected, rtol=0, atol=1e-15)
    if not spline:
        assert np.max(chord_deviation(points, a, b)) < 1e-15


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_closest_samples_match_brute_force_with_and_without_cutoff(seed):
    x, _, pieces = _coil(80, seed)
    points = sample_points(x, pieces.stencil, spline_weights(pieces.coefficients, 9))
    pairs = _all_pairs(80, 3)
    d_ref, s_ref, t_ref = _reference_closest(points, pairs)
    d, s, t = closest_samples(points, pairs)
    np.testing.assert_allclose(d, d_ref, rtol=1e-14, atol=0)
    assert np.array_equal(s, s_ref) and np.array_equal(t, t_ref)
    for cutoff in np.quantile(d_ref, [0.0, 0.01, 0.1, 0.5]):
        dc, sc, tc = closest_samples(points, pairs, cutoff)
        near = d_ref <= cutoff
        assert near.any()
        np.testing.assert_array_equal(dc <= cutoff, near)
        assert np.all(np.isinf(dc[~near]))
        assert np.array_equal(dc[near], d[near])
        assert np.array_equal(sc[near], s[near]) and np.array_equal(tc[near], t[near])


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_sample_collision_time_matches_the_vectorised_quadratic(seed):
    rng = np.random.default_rng(seed)
    x, _, pieces = _coil(60, seed)
    stencil = pieces.stencil
    weights = spline_weights(pieces.coefficients, 6)
    pairs = _all_pairs(60, 3)
    d, _, _ = closest_samples(sample_points(x, stencil, weights), pairs)
    dx = -0.8 * x + 0.02 * rng.standard_normal(x.shape)  # contracts: the strands approach
    hits = 0
    for threshold in (0.3 * d.min(), 0.6 * d.min(), 0.9 * d.min(), d.min() + 1e-12):
        expected = _reference_time(x, dx, stencil, weights, pairs, threshold)
        got = first_time_of_approach_samples(x, dx, stencil, weights, pairs, threshold)
        assert got == pytest.approx(expected, rel=1e-13, abs=1e-15)
        hits += 0.0 < got < 1.0
    assert hits >= 2  # the roots, not only the two early exits, are compared
    assert first_time_of_approach_samples(x, dx, stencil, weights, pairs[:0], 1.0) == 1.0


@pytest.mark.parametrize("curve", ["polygon", "spline"])
def test_integral_hessian_equals_the_former_loop_bit_for_bit(curve):
    from supercoil.contact.integral import integral_terms

    x, segments, pieces = _coil(40, 2)
    samples = 5
    if curve == "spline":
        stencil = np.ascontiguousarray(pieces.stencil)
        weights = spline_weights(pieces.coefficients, samples)
    else:
        stencil = np.ascontiguousarray(segments)
        weights = polygon_weights(len(segments), samples)
    points = sample_points(x, stencil, weights)
    pairs = _all_pairs(len(segments), 4)
    d, _s, _t = closest_samples(points, pairs, np.inf)
    diameter = float(np.min(d)) * 0.9  # the closest samples just inside the barrier's reach
    activation = 0.5 * diameter
    pairs = pairs[d < diameter + activation][:12]
    assert len(pairs) >= 4
    terms = integral_terms(x, stencil, weights, pairs, diameter, "barrier", 3.0, activation,
                           0.1, order=2)
    scale = (0.1 / samples) ** 2 / (2.0 * diameter * activation)
    former = integral_pair_hessians_loop(x, stencil, weights, pairs, diameter, 3.0, activation, scale)
    assert np.abs(former).max() > 0
    assert np.array_equal(terms[2], former)


@numba.njit
def _first_time_every_pair(p0, v, pairs, threshold):
    """The first time of approach by the loop over every sample pair (no culling)."""
    q = p0.shape[1]
    t2 = threshold * threshold
    best = 1.0
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        for a in range(q):
            for b in range(q):
                tau = sample_pair_time(p0, v, i, a, j, b, t2)
                if tau < 0.0:
                    return 0.0
                best = min(best, tau)
    return best


@pytest.mark.parametrize("seed", range(4))
def test_culled_sample_collision_time_equals_the_full_loop(seed):
    """first_time_of_approach_samples (sample pairs that provably stay apart skipped)
    against the loop over every sample pair: the same time, bit for bit, for steps from
    far below to far above the gaps, thresholds below and above the closest samples."""

    x, segments, pieces = _coil(60, 10 + seed)
    rng = np.random.default_rng(seed)
    stencil = np.ascontiguousarray(pieces.stencil)
    weights = spline_weights(pieces.coefficients, 7)
    pairs = _all_pairs(len(segments), 5)
    p0 = sample_points(x, stencil, weights)
    closest = float(np.min(closest_samples(p0, pairs, np.inf)[0]))
    times = []
    for size in (1e-3, 1e-2, 0.05, 0.2, 1.0):
        for factor in (0.5, 0.9, 0.999, 1.01):
            dx = size * rng.standard_normal(x.shape)
            v = sample_points(dx, stencil, weights)
            threshold = factor * closest
            full = _first_time_every_pair(p0, v, pairs, threshold)
            assert first_time_of_approach_samples(x, dx, stencil, weights, pairs,
                                                  threshold) == full
            times.append(full)
    times = np.array(times)
    assert np.any(times == 1.0) and np.any((times > 0) & (times < 1)) and np.any(times == 0)


@pytest.mark.parametrize("order", [0, 1, 2])
def test_integral_terms_from_given_sample_points_are_the_same(order):
    """integral_terms with the sample points passed (ContactProblem's remembered ones)
    against the kernel forming them per pair: every output bit for bit."""
    from supercoil.contact.integral import integral_terms

    x, _segments, pieces = _coil(50, 4)
    stencil = np.ascontiguousarray(pieces.stencil)
    weights = spline_weights(pieces.coefficients, 6)
    points = sample_points(x, stencil, weights)
    pairs = _all_pairs(len(stencil), 4)
    d, _s, _t = closest_samples(points, pairs, np.inf)
    diameter = float(np.min(d)) * 0.95
    pairs = pairs[d < 1.5 * diameter]
    args = (x, stencil, weights, pairs, diameter, "barrier", 2.0, 0.5 * diameter, 0.1, order)
    given, formed = integral_terms(*args, points=points), integral_terms(*args)
    assert np.abs(given[0]).max() > 0
    for mine, reference in zip(given, formed):
        assert np.array_equal(mine, reference)
