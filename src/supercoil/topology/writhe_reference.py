"""The writhe of a polygon by a plain numpy double sum: the oracle of
:func:`supercoil.topology.writhe` (same closures; ``O(N^2)`` memory, for tests and
small curves). Each pair of edges contributes the signed solid angle of its
quadrilateral, split into two Van Oosterom & Strackee (1983) triangles.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from supercoil.topology.polygon import Closure, extended_vertices, prepare_polygon


def solid_angle_triangles(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Signed solid angles (shape ``a.shape[:-1]``) of triangles ``(a, b, c)``, arrays ``(..., 3)``.

    Van Oosterom & Strackee (1983): ``Ω = 2 atan2(a·(b×c), |a||b||c| + (a·b)|c| +
    (a·c)|b| + (b·c)|a|)``, in ``(−2π, 2π]``.
    """
    la = np.linalg.norm(a, axis=-1)
    lb = np.linalg.norm(b, axis=-1)
    lc = np.linalg.norm(c, axis=-1)
    numerator = np.einsum("...k,...k->...", a, np.cross(b, c))
    denominator = (
        la * lb * lc
        + np.einsum("...k,...k->...", a, b) * lc
        + np.einsum("...k,...k->...", a, c) * lb
        + np.einsum("...k,...k->...", b, c) * la
    )
    return 2.0 * np.arctan2(numerator, denominator)


def quadrilateral_angles(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Gauss integrals of the segment pairs ``a→b``, ``c→d`` (arrays broadcasting to ``(..., 3)``).

    The signed area of the spherical quadrilateral ``(c−a, c−b, d−b, d−a)`` as two
    Van Oosterom–Strackee triangles, clipped to ``[−2π, 2π]``.

    The two triangles share the sign of their (mathematically equal) numerators
    and ``|Ω| < 2π``, so their sum needs no reduction modulo 4π; near
    ``|Ω| = 2π`` (nearly crossing edges) rounding can push it just past ``±2π``,
    and wrapping it to ``∓2π`` there would flip the sign of a nearly crossing
    pair (an error of ±2 in the writhe), so it is clipped instead.
    """
    v1, v2, v3, v4 = c - a, c - b, d - b, d - a
    omega = solid_angle_triangles(v1, v2, v3) + solid_angle_triangles(v1, v3, v4)
    return np.clip(omega, -2.0 * np.pi, 2.0 * np.pi)


def tail_angles_reference(vertices: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Gauss integrals of every edge with the two axial tails, shape ``(n_vertices − 1,)``."""
    starts, ends = vertices[:-1], vertices[1:]
    omega = np.zeros(starts.shape[0])
    first, last = vertices[0], vertices[-1]
    # Ray from the last vertex to +∞ along +axis: triangle (P − A, P − B, axis).
    upper = slice(0, starts.shape[0] - 1)
    omega[upper] += solid_angle_triangles(
        last - starts[upper], last - ends[upper], np.broadcast_to(axis, starts[upper].shape)
    )
    # Ray from −∞ to the first vertex along +axis: −(triangle (Q − A, Q − B, −axis)).
    lower = slice(1, starts.shape[0])
    omega[lower] -= solid_angle_triangles(
        first - starts[lower], first - ends[lower], np.broadcast_to(-axis, starts[lower].shape)
    )
    return omega


def writhe_reference(
    points: npt.ArrayLike,
    closure: Closure = "closed",
    axis: npt.ArrayLike = (0.0, 0.0, 1.0),
) -> float:
    """Writhe of a polygon by a plain vectorized numpy double sum (oracle and baseline).

    Same contract as :func:`writhe`; ``O(N²)`` time, ``O(N)`` memory per row
    block. Each edge pair is the sum of two Van Oosterom–Strackee triangles
    computed from the four vertex differences (no shared numerator, no carried
    distances), so it is an independent check of the fast kernel.
    """
    vertices, closed, unit_axis = prepare_polygon(points, closure, axis)
    nodes = extended_vertices(vertices, closed)
    starts, ends = nodes[:-1], nodes[1:]
    n_edges = starts.shape[0]
    total = 0.0
    block = max(1, 200_000 // max(n_edges, 1))
    columns = np.arange(n_edges)
    for row0 in range(0, n_edges, block):
        rows = np.arange(row0, min(row0 + block, n_edges))
        first_col = row0 + 2
        if first_col >= n_edges:
            break
        cols = columns[first_col:]
        keep = cols[None, :] >= rows[:, None] + 2
        if closed:
            keep &= ~((rows[:, None] == 0) & (cols[None, :] == n_edges - 1))
        omega = quadrilateral_angles(
            starts[rows][:, None, :],
            ends[rows][:, None, :],
            starts[cols][None, :, :],
            ends[cols][None, :, :],
        )
        total += float(np.sum(omega[keep]))
    if unit_axis is not None:
        total += float(np.sum(tail_angles_reference(vertices, unit_axis)))
    return total / (2.0 * np.pi)
