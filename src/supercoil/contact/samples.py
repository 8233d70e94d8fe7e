"""The sample points of the double-integral contact energy.

Each segment (or curve piece) carries ``q`` sample points at the midpoint-rule
parameters ``u_a = (a + 1/2) / q``; each point is a fixed linear combination of
the nodes of a stencil (two on the polygon, four on the cubic B-spline, six on
the quintic), given by ``weights`` ``(k, q, w)`` on ``stencil`` ``(k, w)``
(:mod:`supercoil.contact.integral`). Beside the weights: the points themselves,
the bounding sphere of each segment's points, and their largest distance from
the segment's chord (what the broad phase on the segments must add to its
cutoff).
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit

# quadrature spacing over the width sqrt(2 D g_hat) of a point contact's region
SPACING_OVER_WIDTH = 0.25


MIN_SAMPLES = 2


def default_samples(edge_length: float, diameter: float, activation: float) -> int:
    """Points per segment so that their spacing is ``SPACING_OVER_WIDTH sqrt(2 D g_hat)``.

    ``activation`` is ``g_hat`` (a length). At least ``MIN_SAMPLES``.
    """
    width = math.sqrt(2.0 * diameter * activation)
    return max(MIN_SAMPLES, math.ceil(edge_length / (SPACING_OVER_WIDTH * width)))


def sample_parameters(samples: int) -> np.ndarray:
    """Midpoint-rule parameters ``(a + 1/2) / q`` ``(q,)`` along a segment."""
    return (np.arange(samples) + 0.5) / samples


def polygon_weights(n_segments: int, samples: int) -> np.ndarray:
    """``(k, q, 2)`` weights of a segment's two end nodes at its sample points."""
    u = sample_parameters(samples)
    w = np.stack([1.0 - u, u], axis=1)
    return np.ascontiguousarray(np.broadcast_to(w, (n_segments, samples, 2)))


def spline_weights(coefficients: np.ndarray, samples: int) -> np.ndarray:
    """``(k, q, 4)`` weights of a B-spline piece's stencil nodes at its sample points.

    ``coefficients`` ``(k, 4, 4)``: weight of stencil node ``l`` on ``u^p``
    (:attr:`supercoil.contact.spline_distance.CurvePieces.coefficients`).
    """
    u = sample_parameters(samples)
    powers = u[:, None] ** np.arange(4)[None, :]  # (q, 4)
    return np.ascontiguousarray(np.einsum("ilp,ap->ial", coefficients, powers))


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


# Uniform quintic B-spline: weight of control point k (of six) on u^p, times 120.
QUINTIC_BASIS = np.array([
    [1.0, -5.0, 10.0, -10.0, 5.0, -1.0],
    [26.0, -50.0, 20.0, 20.0, -20.0, 5.0],
    [66.0, 0.0, -60.0, 0.0, 30.0, -10.0],
    [26.0, 50.0, 20.0, -20.0, -20.0, 10.0],
    [1.0, 5.0, 10.0, 10.0, 5.0, -5.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
]) / 120.0


def _quintic_controls(segments: np.ndarray, closed: bool) -> list[list[dict[int, float]]]:
    """The six control points of every piece as ``{node: coefficient}`` combinations.

    Piece ``i`` spans segment ``i = (a, b)``; its control points are the nodes
    ``x_{-2}, x_{-1}, a, b, x_{+1}, x_{+2}`` along the chain of joined segments
    (segment ``j`` follows ``i`` when ``segments[j, 0] == segments[i, 1]``, the
    last follows the first when ``closed``). Past a free end the chain is
    continued by odd reflection about the end node, ``x_{-k} = 2 x_0 - x_k``
    (as the cubic pieces' ghosts, :func:`~supercoil.contact.spline_distance.bspline_pieces`),
    so a straight end stays straight.
    """
    seg = np.asarray(segments, dtype=np.int64)
    k = len(seg)

    def prev_of(i):
        j = (i - 1) % k if (closed or i > 0) else None
        return j if j is not None and j != i and seg[j, 1] == seg[i, 0] else None

    def next_of(i):
        j = (i + 1) % k if (closed or i < k - 1) else None
        return j if j is not None and j != i and seg[j, 0] == seg[i, 1] else None

    def combo(*terms):
        out: dict[int, float] = {}
        for coefficient, node in terms:
            out[int(node)] = out.get(int(node), 0.0) + coefficient
        return out

    def chain(i, step, toward):
        """Nodes beyond the end ``toward`` (0: before a, 1: after b) of piece i, two deep,
        as combinations; ``step`` finds the joined neighbour."""
        near = seg[i, toward]
        far = seg[i, 1 - toward]
        j = step(i)
        if j is None:  # near is a free end: reflect the chain through it
            beyond = chain_inward(i, toward)
            return [combo((2.0, near), (-1.0, far)), combo((2.0, near), *[(-c, n) for n, c in
                                                                         beyond.items()])]
        first = seg[j, toward]
        jj = step(j)
        if jj is None:  # first is a free end: x_{-2} = 2 first - near
            return [combo((1.0, first)), combo((2.0, first), (-1.0, near))]
        return [combo((1.0, first)), combo((1.0, seg[jj, toward]))]

    def chain_inward(i, toward):
        """The node two steps inward from the free end ``toward`` of piece i."""
        step = next_of if toward == 0 else prev_of
        j = step(i)
        if j is None:  # a single-segment chain: continue the line
            a, b = seg[i, toward], seg[i, 1 - toward]
            return combo((2.0, b), (-1.0, a))
        return combo((1.0, seg[j, 1 - toward]))

    controls = []
    for i in range(k):
        a, b = seg[i]
        before = chain(i, prev_of, 0)
        after = chain(i, next_of, 1)
        controls.append([before[1], before[0], combo((1.0, a)), combo((1.0, b)), after[0],
                         after[1]])
    return controls


def quintic_samples(segments: np.ndarray, closed: bool, samples: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(stencil (k, 6), weights (k, q, 6))`` of the uniform quintic B-spline pieces.

    Its sampling-phase ripple is O(h⁶) against the cubic's O(h⁴): the
    approximation error of a uniform B-spline of degree ``p`` depends on where
    the nodes sit along the curve only at order ``h^{p+1}``. Nodes of a piece
    beyond six (none) are impossible; fewer are padded with zero weights.
    """
    u = sample_parameters(samples)
    basis = (u[:, None] ** np.arange(6)[None, :]) @ QUINTIC_BASIS.T  # (q, 6 controls)
    controls = _quintic_controls(segments, closed)
    k = len(controls)
    stencil = np.zeros((k, 6), dtype=np.int64)
    weights = np.zeros((k, samples, 6))
    for i, ctrl in enumerate(controls):
        nodes = sorted({n for c in ctrl for n in c})
        if len(nodes) > 6:
            raise ValueError(f"piece {i} depends on {len(nodes)} nodes (at most 6)")
        index = {n: j for j, n in enumerate(nodes)}
        matrix = np.zeros((6, 6))  # control c -> stencil slot
        for c, terms in enumerate(ctrl):
            for n, coefficient in terms.items():
                matrix[c, index[n]] += coefficient
        stencil[i, :len(nodes)] = nodes
        stencil[i, len(nodes):] = nodes[0]
        weights[i] = basis @ matrix
    return stencil, np.ascontiguousarray(weights)


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
    :func:`~supercoil.contact.sample_pairs.closest_samples_within`)."""
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
