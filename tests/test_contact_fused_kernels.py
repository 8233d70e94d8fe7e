"""The fused contact kernels against the numpy steps they replaced.

Each compiled call returns what a chain of numba calls and numpy steps returned
before; the oracle is that chain, and the values must agree bit for bit:

* ``segment_pairs_within``: ``segment_distance`` of every candidate pair, then the
  filter ``d <= cutoff`` (the bounding-sphere cut must not drop a pair within);
* ``closest_samples_within``: ``closest_samples`` with the cutoff, then the filter;
* ``sample_state``: ``sample_points``, ``max(chord_deviation, initial=0)`` and the
  bounding spheres of each segment's samples;
* ``verlet_displacement``: ``np.max(np.abs(x))`` and the largest node displacement;
* ``largest_displacement``: ``np.max(np.linalg.norm(dx, axis=1))``;
* the DOFs of ``integral_terms``, now written by its kernel.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.contact.broadphase import candidate_pairs, verlet_displacement
from supercoil.contact.ccd import largest_displacement
from supercoil.contact.distance import segment_distance, segment_pairs_within
from supercoil.contact.integral import integral_terms
from supercoil.contact.sample_weights import polygon_weights, spline_weights
from supercoil.contact.samples import (
    bounding_spheres,
    chord_deviation,
    closest_samples,
    closest_samples_within,
    sample_points,
    sample_state,
)
from supercoil.contact.spline_pieces import bspline_pieces


def _coil(n: int, seed: int):
    """Nodes ``(n, 3)`` of a closed coil that comes close to itself (two turns of a
    squashed helix with noise), and its segments."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = np.stack([np.cos(2 * t) * (1 + 0.3 * np.cos(t)), np.sin(2 * t) * (1 + 0.3 * np.cos(t)),
                  0.05 * np.sin(t)], axis=1) + 0.002 * rng.standard_normal((n, 3))
    segments = np.stack([np.arange(n), (np.arange(n) + 1) % n], axis=1)
    return x, segments


def _candidates(x, segments, reach):
    k = len(segments)
    s = np.arange(k, dtype=float) / k
    return candidate_pairs(x[segments[:, 0]], x[segments[:, 1]], s, s + 1.0 / k, reach,
                           3.0 / k, period=1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("cutoff", [0.0, 0.12, 0.2, 0.3, np.inf])
def test_segment_pairs_within_equals_distances_then_filter(seed, cutoff):
    x, segments = _coil(120, seed)
    pairs = _candidates(x, segments, 0.4)
    assert len(pairs) > 100
    a, b = x[segments[:, 0]], x[segments[:, 1]]
    d, s, t = segment_distance(a[pairs[:, 0]], b[pairs[:, 0]], a[pairs[:, 1]], b[pairs[:, 1]])
    keep = d <= cutoff
    kept, d_kept, s_kept, t_kept = segment_pairs_within(x, segments, pairs, cutoff)
    np.testing.assert_array_equal(kept, pairs[keep])
    for fast, slow in ((d_kept, d[keep]), (s_kept, s[keep]), (t_kept, t[keep])):
        assert fast.tobytes() == slow.tobytes()
    if 0.0 < cutoff < np.inf:  # the cut meets pairs on both sides
        assert 0 < keep.sum() < len(pairs)


def test_segment_pairs_within_keeps_a_pair_exactly_at_the_cutoff_and_refuses_nan():
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.25, -1.0], [0.5, 0.25, 1.0]])
    segments = np.array([[0, 1], [2, 3]])
    pairs = np.array([[0, 1]])
    kept, d, s, t = segment_pairs_within(x, segments, pairs, 0.25)
    assert kept.tolist() == [[0, 1]] and d.tolist() == [0.25] and (s[0], t[0]) == (0.5, 0.5)
    assert len(segment_pairs_within(x, segments, pairs, np.nextafter(0.25, 0.0))[0]) == 0
    assert len(segment_pairs_within(x, segments, np.zeros((0, 2), np.int64), 1.0)[0]) == 0
    x[3, 2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        segment_pairs_within(x, segments, pairs, 0.25)
    with pytest.raises(ValueError, match="finite"):
        segment_distance(x[0], x[1], x[2], x[3])


@pytest.mark.parametrize("spline", [False, True])
@pytest.mark.parametrize("seed", [0, 3])
def test_sample_state_equals_points_deviation_and_spheres(spline, seed):
    x, segments = _coil(90, seed)
    pieces = bspline_pieces(segments, True)
    stencil = np.ascontiguousarray(pieces.stencil) if spline else segments
    weights = spline_weights(pieces.coefficients, 9) if spline else polygon_weights(90, 9)
    points, deviation, centre, radius = sample_state(x, stencil, weights, segments)
    slow = sample_points(x, stencil, weights)
    assert points.tobytes() == slow.tobytes()
    # the kernels' sums: over the stencil in order, from 0.0 (as numpy steps)
    summed = np.zeros_like(slow)
    for node in range(stencil.shape[1]):
        summed = summed + weights[:, :, node, None] * x[stencil[:, node]][:, None, :]
    assert points.tobytes() == summed.tobytes()
    expected = float(np.max(chord_deviation(slow, x[segments[:, 0]], x[segments[:, 1]]),
                            initial=0.0))
    assert deviation == expected and (deviation > 1e-12) == spline  # chords: round-off
    # the kernels' arithmetic written out in numpy, operation by operation
    a, e = x[segments[:, 0]], x[segments[:, 1]] - x[segments[:, 0]]
    length2 = np.maximum(e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1] + e[:, 2] * e[:, 2], 1e-300)
    r = slow - a[:, None, :]
    t = np.minimum(1.0, np.maximum(0.0, (r[..., 0] * e[:, None, 0] + r[..., 1] * e[:, None, 1]
                                         + r[..., 2] * e[:, None, 2]) / length2[:, None]))
    f = r - t[..., None] * e[:, None, :]
    dd = f[..., 0] * f[..., 0] + f[..., 1] * f[..., 1] + f[..., 2] * f[..., 2]
    assert deviation == float(np.sqrt(np.max(dd)))
    centre_slow, radius_slow = np.empty((90, 3)), np.empty(90)
    bounding_spheres(slow, centre_slow, radius_slow)
    assert centre.tobytes() == centre_slow.tobytes()
    assert radius.tobytes() == radius_slow.tobytes()
    # and the spheres themselves, against numpy: the samples' mean, the farthest sample
    assert np.allclose(centre, slow.mean(axis=1), rtol=0.0, atol=1e-15)
    farthest = np.sqrt(np.max(np.sum((slow - centre[:, None, :]) ** 2, axis=2), axis=1))
    assert np.allclose(radius, farthest, rtol=1e-14, atol=1e-16)
    for row in (5, 89):  # a nan node: the same deviation as the former steps
        y = x.copy()
        y[row, 1] = np.nan
        slow = sample_points(y, stencil, weights)
        expected = float(np.max(chord_deviation(slow, y[segments[:, 0]], y[segments[:, 1]]),
                                initial=0.0))
        found = sample_state(y, stencil, weights, segments)[1]
        assert found == expected or (np.isnan(found) and np.isnan(expected))


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("cutoff", [0.12, 0.2, 0.3, 0.45])
def test_closest_samples_within_equals_closest_samples_then_filter(seed, cutoff):
    x, segments = _coil(100, seed)
    pieces = bspline_pieces(segments, True)
    stencil = np.ascontiguousarray(pieces.stencil)
    weights = spline_weights(pieces.coefficients, 7)
    points, _deviation, centre, radius = sample_state(x, stencil, weights, segments)
    pairs = _candidates(x, segments, 0.6)
    d, s, t = closest_samples(points, pairs, cutoff)
    keep = d <= cutoff
    kept, d_kept, s_kept, t_kept = closest_samples_within(points, centre, radius, pairs, cutoff)
    np.testing.assert_array_equal(kept, pairs[keep])
    for fast, slow in ((d_kept, d[keep]), (s_kept, s[keep]), (t_kept, t[keep])):
        assert fast.tobytes() == slow.tobytes()
    assert 0 < keep.sum() < len(pairs)
    empty = closest_samples_within(points, centre, radius, np.zeros((0, 2), np.int64), cutoff)
    assert all(len(a) == 0 for a in empty) and empty[0].shape == (0, 2)


def test_verlet_displacement_equals_the_numpy_reductions():
    rng = np.random.default_rng(7)
    for n in (1, 2, 7, 100):
        x = rng.standard_normal((n, 3)) * np.exp(3 * rng.standard_normal((n, 3)))
        x_ref = x + 1e-3 * rng.standard_normal((n, 3))
        scale, moved = verlet_displacement(x, x_ref)
        assert scale == float(np.max(np.abs(x)))
        assert moved == float(np.sqrt(np.max(np.sum((x - x_ref) ** 2, axis=1))))
        assert verlet_displacement(x, x) == (scale, 0.0)
    for row in (0, 50, 99):  # a nan anywhere, as numpy's max, makes both nan
        y = x.copy()
        y[row, 1] = np.nan
        assert all(np.isnan(v) for v in verlet_displacement(y, x_ref))
        assert np.isnan(verlet_displacement(x, y)[1])


def test_largest_displacement_equals_the_numpy_norm():
    rng = np.random.default_rng(11)
    for n in (1, 3, 100):
        dx = rng.standard_normal((n, 3)) * np.exp(4 * rng.standard_normal((n, 3)))
        assert largest_displacement(dx) == float(np.max(np.linalg.norm(dx, axis=1)))
    dx[40, 2] = np.nan
    assert np.isnan(largest_displacement(dx))


@pytest.mark.parametrize("spline", [False, True])
def test_integral_terms_dofs_are_the_stencils_dofs(spline):
    x, segments = _coil(60, 4)
    pieces = bspline_pieces(segments, True)
    stencil = np.ascontiguousarray(pieces.stencil) if spline else segments
    weights = spline_weights(pieces.coefficients, 5) if spline else polygon_weights(60, 5)
    pairs = _candidates(x, segments, 0.3)
    dofs = integral_terms(x, stencil, weights, pairs, 0.2, "barrier", 1.0, 0.05, 1 / 60, 1)[5]
    nodes = np.concatenate([stencil[pairs[:, 0]], stencil[pairs[:, 1]]], axis=1)
    expected = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(pairs), -1)
    assert dofs.dtype == expected.dtype and np.array_equal(dofs, expected)
    empty = integral_terms(x, stencil, weights, pairs[:0], 0.2, "barrier", 1.0, 0.05, 1 / 60, 1)
    assert empty[5].shape == (0, 6 * stencil.shape[1])


def _former_first_time(x0, dx, pairs, threshold, max_iterations=100, tolerance=1e-3):
    """first_time_of_approach before residual13: ccd._advance on ccd._pair_distance."""
    from supercoil.contact import ccd

    pair_x0, pair_dx = x0[pairs], dx[pairs]
    relative = pair_dx[:, :2, None, :] - pair_dx[:, None, 2:, :]
    speed = np.linalg.norm(relative, axis=-1).max(axis=(1, 2))
    threshold = np.broadcast_to(np.asarray(threshold, dtype=float), (len(pairs),))
    return ccd._advance(lambda idx, tau: ccd._pair_distance(pair_x0[idx], pair_dx[idx], tau),
                        speed, threshold, max_iterations, tolerance)


@pytest.mark.parametrize("seed", range(6))
def test_first_time_of_approach_equals_the_vectorised_advancement(seed):
    from supercoil.contact.ccd import first_time_of_approach

    rng = np.random.default_rng(seed)
    x0, segments = _coil(80, seed)
    pairs = _candidates(x0, segments, 0.3)
    nodes = np.concatenate([segments[pairs[:, 0]], segments[pairs[:, 1]]], axis=1)
    d0 = segment_distance(x0[nodes[:, 0]], x0[nodes[:, 1]], x0[nodes[:, 2]], x0[nodes[:, 3]])[0]
    outcomes = set()
    for size in (0.01, 0.05, 0.2, 1.0):
        dx = size * rng.standard_normal(x0.shape)
        dx[::7] = 0.0  # some pairs at rest relative to each other
        for threshold, iterations, tolerance in ((0.5 * d0, 100, 1e-3), (0.9 * d0, 100, 1e-3),
                                                 (0.05, 3, 1e-3), (0.5 * d0, 100, 0.3),
                                                 (np.maximum(d0 - 0.01, 0.0), 100, 1e-3),
                                                 (np.where(np.arange(d0.size) == 3, d0 + 0.01,
                                                           0.5 * d0), 100, 1e-3)):
            found = first_time_of_approach(x0, dx, nodes, threshold, iterations, tolerance)
            expected = _former_first_time(x0, dx, nodes, threshold, iterations, tolerance)
            assert found == expected
            assert type(found[0]) is float and type(found[1]) is int
            outcomes.add("clear" if found[1] < 0 else "now" if found[0] == 0.0 else "hit")
    assert outcomes == {"clear", "now", "hit"}
