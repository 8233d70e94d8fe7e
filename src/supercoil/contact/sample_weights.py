"""Where the sample points of the double-integral contact energy sit: quadrature weights.

Each segment (or curve piece) carries ``q`` sample points at the midpoint-rule
parameters ``u_a = (a + 1/2) / q``; each point is a fixed linear combination of
the nodes of a stencil (two on the polygon, four on the cubic B-spline, six on
the quintic), given by ``weights`` ``(k, q, w)`` on ``stencil`` ``(k, w)``
(:mod:`supercoil.contact.integral`). The points themselves are formed by
:mod:`supercoil.contact.samples`.
"""

from __future__ import annotations

import math

import numpy as np

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
    (:attr:`supercoil.contact.spline_pieces.CurvePieces.coefficients`).
    """
    u = sample_parameters(samples)
    powers = u[:, None] ** np.arange(4)[None, :]  # (q, 4)
    return np.ascontiguousarray(np.einsum("ilp,ap->ial", coefficients, powers))


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
    (as the cubic pieces' ghosts, :func:`~supercoil.contact.spline_pieces.bspline_pieces`),
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
