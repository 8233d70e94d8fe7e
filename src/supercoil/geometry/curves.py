"""Discrete curves: edges, tangents, parallel transport and simple test curves.

All functions are plain numpy and vectorised over vertices or edges. A polygon
is an array ``points`` of shape ``(n_nodes, 3)``; for a closed polygon the edge
``i`` joins vertex ``i`` to vertex ``(i + 1) % n_nodes`` so there are
``n_nodes`` edges, for an open one ``n_nodes - 1``.
"""

from __future__ import annotations

import numpy as np


def edges(points: np.ndarray, closed: bool) -> np.ndarray:
    """Edge vectors ``e_i = x_{i+1} - x_i``, shape ``(n_edges, 3)``."""
    if closed:
        return np.roll(points, -1, axis=0) - points
    return np.diff(points, axis=0)


def unit(v: np.ndarray) -> np.ndarray:
    """Normalise the rows of ``v`` (shape ``(M, 3)``)."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def parallel_transport(v: np.ndarray, t_from: np.ndarray, t_to: np.ndarray) -> np.ndarray:
    """Discrete parallel transport of ``v`` from unit tangent ``t_from`` to ``t_to``.

    The rotation about ``t_from x t_to`` through the angle between them
    (Bergou et al. 2008, sec. 4.1), written without trigonometry:
    ``P v = c v + n x v + (n.v) n / (1 + c)`` with ``n = a x b``, ``c = a.b``.
    Shapes ``(M, 3)``; undefined for antiparallel tangents.
    """
    n = np.cross(t_from, t_to)
    c = np.sum(t_from * t_to, axis=-1, keepdims=True)
    return c * v + np.cross(n, v) + n * np.sum(n * v, axis=-1, keepdims=True) / (1.0 + c)


def signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Signed angle in (-pi, pi] from ``a`` to ``b`` about ``axis`` (rows, shape ``(M, 3)``)."""
    return np.arctan2(np.sum(np.cross(a, b) * axis, axis=-1), np.sum(a * b, axis=-1))


def perpendicular(t: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each unit row of ``t`` (shape ``(M, 3)``)."""
    trial = np.where(np.abs(t[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    return unit(trial - np.sum(trial * t, axis=-1, keepdims=True) * t)


def circle(n_nodes: int, length: float = 1.0) -> np.ndarray:
    """Regular polygon with ``n_nodes`` vertices and perimeter ``length`` in the xy-plane.

    Counter-clockwise about +z, centred at the origin; shape ``(n_nodes, 3)``.
    """
    angle = 2.0 * np.pi * np.arange(n_nodes) / n_nodes
    radius = length / (2.0 * n_nodes * np.sin(np.pi / n_nodes))
    return np.stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(n_nodes)], axis=1)


def resample_closed(points: np.ndarray, n_nodes: int, length: float = 1.0) -> np.ndarray:
    """A closed polygon scaled to perimeter ``length`` and resampled at ``n_nodes``
    points equally spaced in arc length (linear interpolation along its edges).

    ``points`` ``(m, 3)``, each vertex once (the closing edge is implied);
    returns ``(n_nodes, 3)``. The chords of the result are slightly shorter than
    ``length / n_nodes`` where the input turns; an inextensible rod set up on it
    restores them in its first Newton step.
    """
    x = np.asarray(points, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or len(x) < 3:
        raise ValueError(f"a closed curve needs at least 3 points of shape (m, 3), got {x.shape}")
    closed = np.vstack([x, x[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    total = float(seg.sum())
    if not np.isfinite(total) or total <= 0:
        raise ValueError("the curve has zero or non-finite length")
    s = np.concatenate([[0.0], np.cumsum(seg)])
    target = np.arange(n_nodes) * total / n_nodes
    out = np.stack([np.interp(target, s, closed[:, k]) for k in range(3)], axis=1)
    return (out - out.mean(axis=0)) * (length / total)


def min_radius_of_curvature(points: np.ndarray) -> tuple[float, int]:
    """``(radius, vertex)``: the smallest discrete radius of curvature ``h / (2 tan(phi / 2))``
    over the vertices of the closed polygon ``points`` ``(n, 3)`` (``phi`` the turning
    angle at the vertex, ``h`` the mean of its two edges; ``inf`` where it does not
    turn) and where it is. A regular ``n``-gon of edge ``h`` has ``h / (2 tan(pi / n))``,
    the radius of its inscribed circle; on a smooth curve sampled with edges ``h`` it
    tends to the radius of curvature as ``h^2``."""
    x = np.asarray(points, float)
    e = np.roll(x, -1, axis=0) - x
    prev = np.roll(e, 1, axis=0)
    cos = np.einsum("ij,ij->i", prev, e) / (np.linalg.norm(prev, axis=1)
                                            * np.linalg.norm(e, axis=1))
    phi = np.arccos(np.clip(cos, -1.0, 1.0))
    h = 0.5 * (np.linalg.norm(prev, axis=1) + np.linalg.norm(e, axis=1))
    with np.errstate(divide="ignore"):
        radius = h / (2.0 * np.tan(0.5 * phi))
    k = int(np.argmin(radius))
    return float(radius[k]), k
