"""The sample points of the double-integral contact energy, and their closest pairs.

The points are ``weights`` ``(k, q, w)`` on ``stencil`` ``(k, w)``
(:mod:`supercoil.contact.sample_weights`) summed over the nodes. Beside them: the
bounding sphere of each segment's points, their largest distance from the
segment's chord (what the broad phase on the segments must add to its cutoff),
and the closest sample points of segment pairs (the integral formulation sees the
curve only there, :mod:`supercoil.contact.integral`). Every kernel that calls
another lives in this module (numba caches a kernel with the code of the compiled
functions it calls).
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit
from supercoil.contact.distance import within_buffers


@njit()
def _sample_points_kernel(x, stencil, weights, out):
    # the three coordinates' sums side by side (each over l in order from 0.0, as
    # before): independent chains, 11 -> 6 us at N = 100 (spline, 10 samples)
    k, q, w = weights.shape
    for i in range(k):
        for a in range(q):
            t0 = 0.0
            t1 = 0.0
            t2 = 0.0
            for l in range(w):
                weight = weights[i, a, l]
                node = stencil[i, l]
                t0 += weight * x[node, 0]
                t1 += weight * x[node, 1]
                t2 += weight * x[node, 2]
            out[i, a, 0] = t0
            out[i, a, 1] = t1
            out[i, a, 2] = t2


def sample_points(x: np.ndarray, stencil: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``(k, q, 3)`` sample points of every segment (or piece), summed over the stencil in
    the order of the integral kernel (:mod:`supercoil.contact.integral`)."""
    out = np.empty((weights.shape[0], weights.shape[1], 3))
    _sample_points_kernel(np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3),
                          np.ascontiguousarray(stencil, dtype=np.int64),
                          np.ascontiguousarray(weights, dtype=np.float64), out)
    return out


@njit()
def bounding_spheres(points, centre, radius):
    """Centroid ``(k, 3)`` of every segment's samples and their largest distance ``(k,)``."""
    k, q, _ = points.shape
    for i in range(k):
        for c in range(3):
            total = 0.0
            for a in range(q):
                total += points[i, a, c]
            centre[i, c] = total / q
        largest = 0.0
        for a in range(q):
            d0 = points[i, a, 0] - centre[i, 0]
            d1 = points[i, a, 1] - centre[i, 1]
            d2 = points[i, a, 2] - centre[i, 2]
            dd = d0 * d0 + d1 * d1 + d2 * d2
            largest = max(largest, dd)
        radius[i] = math.sqrt(largest)


@njit(inline="always")
def _chord_deviation_of(points, i, s0, s1, s2, end0, end1, end2):
    """Largest distance of segment ``i``'s sample points from the segment ``s -> end``."""
    e0 = end0 - s0
    e1 = end1 - s1
    e2 = end2 - s2
    length2 = max(e0 * e0 + e1 * e1 + e2 * e2, 1e-300)
    largest = 0.0
    for a in range(points.shape[1]):
        r0 = points[i, a, 0] - s0
        r1 = points[i, a, 1] - s1
        r2 = points[i, a, 2] - s2
        t = min(1.0, max(0.0, (r0 * e0 + r1 * e1 + r2 * e2) / length2))
        f0 = r0 - t * e0
        f1 = r1 - t * e1
        f2 = r2 - t * e2
        dd = f0 * f0 + f1 * f1 + f2 * f2
        largest = max(largest, dd)
    return math.sqrt(largest)


@njit()
def _sample_state_kernel(x, stencil, weights, segments, points, centre, radius):
    """:func:`_sample_points_kernel`, :func:`bounding_spheres` and the largest of
    :func:`_chord_deviation_kernel` (segment ``i`` from ``x[segments[i, 0]]`` to
    ``x[segments[i, 1]]``) in one pass, the same sums; returns that largest deviation
    (0.0 without segments, nan if one is nan, as ``np.max(..., initial=0.0)``)."""
    _sample_points_kernel(x, stencil, weights, points)
    bounding_spheres(points, centre, radius)
    overall = 0.0
    for i in range(points.shape[0]):
        s = segments[i, 0]
        e = segments[i, 1]
        deviation = _chord_deviation_of(points, i, x[s, 0], x[s, 1], x[s, 2], x[e, 0], x[e, 1],
                                        x[e, 2])
        if math.isnan(deviation):
            return deviation
        overall = max(overall, deviation)
    return overall


def sample_state(x: np.ndarray, stencil: np.ndarray, weights: np.ndarray,
                 segments: np.ndarray):
    """``(points (k, q, 3), largest chord deviation, centre (k, 3), radius (k,))`` at the
    nodes ``x`` ``(n, 3)``: :func:`sample_points`, ``max(chord_deviation(points, starts,
    ends), initial=0)`` with the segments' end nodes ``segments`` ``(k, 2)``, and the
    bounding spheres of each segment's samples (centroid, largest distance), the same
    values as those functions, from one compiled call (four calls and numpy steps cost
    25 us at N = 100; the spheres serve
    :func:`closest_samples_within`)."""
    k, q = weights.shape[0], weights.shape[1]
    points = np.empty((k, q, 3))
    centre = np.empty((k, 3))
    radius = np.empty(k)
    # a writable x (a copy of a read-only one): one compiled specialisation
    deviation = _sample_state_kernel(np.require(x, np.float64, "CW").reshape(-1, 3),
                                     stencil, weights, segments, points, centre, radius)
    return points, float(deviation), centre, radius


@njit()
def _chord_deviation_kernel(points, starts, ends, out):
    for i in range(points.shape[0]):
        out[i] = _chord_deviation_of(points, i, starts[i, 0], starts[i, 1], starts[i, 2],
                                     ends[i, 0], ends[i, 1], ends[i, 2])


def chord_deviation(points: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``(k,)`` largest distance of a segment's sample points ``(k, q, 3)`` from the
    segment ``starts[i] -> ends[i]`` (zero on the polygon)."""
    out = np.zeros(points.shape[0])
    _chord_deviation_kernel(np.ascontiguousarray(points, dtype=np.float64),
                            np.ascontiguousarray(starts, dtype=np.float64),
                            np.ascontiguousarray(ends, dtype=np.float64), out)
    return out


@njit(inline="always")
def _closest_sample_pair(points, centre, radius, i, j, cutoff, bounded):
    """``(d, a, b)``: the closest sample points ``a`` of segment ``i`` and ``b`` of ``j``
    (first in row-major order among equals) and their distance; with ``bounded``,
    ``d = inf`` when all lie farther apart than ``cutoff`` (see
    :func:`_closest_samples_kernel`)."""
    q = points.shape[1]
    best = np.inf
    ba = 0
    bb = 0
    reach = np.inf
    margin = 0.0
    if bounded:
        margin = 1e-9 * (cutoff + radius[i] + radius[j])
        c0 = centre[i, 0] - centre[j, 0]
        c1 = centre[i, 1] - centre[j, 1]
        c2 = centre[i, 2] - centre[j, 2]
        if math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) - radius[i] - radius[j] > cutoff + margin:
            return np.inf, 0, 0
        reach = cutoff + margin  # rows farther than this from sphere j hold no pair within it
    for a in range(q):
        if bounded:
            e0 = points[i, a, 0] - centre[j, 0]
            e1 = points[i, a, 1] - centre[j, 1]
            e2 = points[i, a, 2] - centre[j, 2]
            row_bound = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2) - radius[j]
            limit = reach if best == np.inf else min(reach, math.sqrt(best) + margin)
            if row_bound > limit:
                continue
        for b in range(q):
            d0 = points[i, a, 0] - points[j, b, 0]
            d1 = points[i, a, 1] - points[j, b, 1]
            d2 = points[i, a, 2] - points[j, b, 2]
            dd = d0 * d0 + d1 * d1 + d2 * d2
            if dd < best:
                best = dd
                ba = a
                bb = b
    d = math.sqrt(best)
    if bounded and d > cutoff:
        d = np.inf
    return d, ba, bb


@njit()
def _closest_samples_kernel(points, pairs, cutoff, d_out, a_out, b_out):
    """Closest sample points of each pair (first in row-major order among equals).

    With a finite ``cutoff``, pairs whose samples all lie farther apart report
    ``inf``: a bounding sphere of each segment's samples rules out whole pairs, and
    rows ``a`` whose distance to the other sphere exceeds the best distance so far,
    with a margin far above round-off so that no row that could hold a closer (or
    equally close, earlier) sample pair is skipped.
    """
    k = points.shape[0]
    centre = np.empty((k, 3))
    radius = np.empty(k)
    bounded = cutoff < np.inf
    if bounded:
        bounding_spheres(points, centre, radius)
    for p in range(pairs.shape[0]):
        d_out[p], a_out[p], b_out[p] = _closest_sample_pair(points, centre, radius, pairs[p, 0],
                                                            pairs[p, 1], cutoff, bounded)


@njit()
def _closest_samples_within_kernel(points, centre, radius, pairs, cutoff, pairs_out, d_out,
                                   s_out, t_out):
    """The pairs of ``pairs`` whose closest sample points are within the finite ``cutoff``,
    in their order, written to the first ``count`` rows of the outputs (``s``, ``t``
    the sample parameters ``(a + 1/2) / q``); returns ``count``. ``centre``, ``radius``:
    :func:`bounding_spheres` of ``points``."""
    q = points.shape[1]
    count = 0
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        d, a, b = _closest_sample_pair(points, centre, radius, i, j, cutoff, True)
        if d <= cutoff:
            pairs_out[count, 0] = i
            pairs_out[count, 1] = j
            d_out[count] = d
            s_out[count] = (a + 0.5) / q
            t_out[count] = (b + 0.5) / q
            count += 1
    return count


def closest_samples(points: np.ndarray, pairs: np.ndarray, cutoff: float = np.inf):
    """``(d, s, t)`` ``(m,)``: the closest sample points of each pair of segments, their
    distance and parameters along the segments; ``points`` ``(k, q, 3)``.

    With a finite ``cutoff`` only pairs within it are resolved: the others report
    ``d = inf`` (and parameters of no meaning), and are found faster (bounding spheres).
    """
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    m = len(pairs)
    d = np.zeros(m)
    a = np.zeros(m, dtype=np.int64)
    b = np.zeros(m, dtype=np.int64)
    if m:
        _closest_samples_kernel(np.ascontiguousarray(points, dtype=np.float64), pairs,
                                float(cutoff), d, a, b)
    q = points.shape[1]
    return d, (a + 0.5) / q, (b + 0.5) / q


def closest_samples_within(points: np.ndarray, centre: np.ndarray, radius: np.ndarray,
                           pairs: np.ndarray, cutoff: float):
    """``(pairs, d, s, t)`` of the pairs of ``pairs`` ``(m, 2)`` whose closest sample points
    are within the finite ``cutoff``, in their order: the rows of :func:`closest_samples`
    with ``d <= cutoff``, the same values, in one compiled pass (the filter and the
    parameters as numpy steps cost about as much as the search at N = 100).
    ``centre``, ``radius``: the bounding spheres of
    :func:`sample_state`. The arrays are
    views of buffers of ``m`` rows."""
    pairs, kept, d, s, t = within_buffers(pairs)
    m = len(pairs)
    count = _closest_samples_within_kernel(points, centre, radius, pairs, float(cutoff), kept,
                                           d, s, t) if m else 0
    return kept[:count], d[:count], s[:count], t[:count]
