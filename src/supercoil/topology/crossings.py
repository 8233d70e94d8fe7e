"""Where polygons meet: the first pair of edges that touch, within rounding.

The writhe of a polygon is Gauss's integral over pairs of its edges; where two
edges meet, the integrand is singular and the writhe jumps by 2 across that
configuration, so it is undefined there. The same holds for the linking number
of two polygons that meet. :func:`first_self_crossing` and :func:`first_crossing`
find such a pair (two edges whose closest distance is below ``1e-15`` of the
curves' extent, or two consecutive edges folding back onto each other) so that
:func:`~supercoil.topology.writhe.writhe` and
:func:`~supercoil.topology.linking.linking_number` refuse the input instead of
returning a number that depends on rounding.

Each pair is tested first on the edges' bounding boxes (six comparisons), then
by the closest distance of two segments (Ericson 2005, "Real-Time Collision
Detection", section 5.1.9); ``O(n1 n2)`` work, small next to the Gauss sum itself.
"""

from __future__ import annotations

import numpy as np

from supercoil._numba import njit

__all__ = ["RELATIVE_TOLERANCE", "closest_approach", "first_crossing", "first_self_crossing"]

RELATIVE_TOLERANCE = 1e-15  # edges closer than this times the curves' extent meet (a few ulps)


@njit()
def _distance2(px, py, pz, qx, qy, qz, rx, ry, rz, sx, sy, sz) -> float:
    """Squared closest distance of the segments p->q and r->s (both of non-zero length)."""
    d1x, d1y, d1z = qx - px, qy - py, qz - pz
    d2x, d2y, d2z = sx - rx, sy - ry, sz - rz
    wx, wy, wz = px - rx, py - ry, pz - rz
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    b = d1x * d2x + d1y * d2y + d1z * d2z
    c = d1x * wx + d1y * wy + d1z * wz
    f = d2x * wx + d2y * wy + d2z * wz
    denom = a * e - b * b
    s = 0.0
    if denom > 0.0:
        s = min(max((b * f - c * e) / denom, 0.0), 1.0)
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0)
    dx = wx + s * d1x - t * d2x
    dy = wy + s * d1y - t * d2y
    dz = wz + s * d1z - t * d2z
    return dx * dx + dy * dy + dz * dz


@njit()
def _first_pair(a: np.ndarray, b: np.ndarray, same: bool, closed: bool,
                tolerance: float) -> tuple[int, int]:
    """First edge pair ``(i, j)`` of the extended vertex arrays ``a`` (``(n1 + 1, 3)``) and
    ``b`` that meet, or ``(-1, -1)``. ``same``: ``b`` is ``a`` (pairs ``i < j``, neighbours
    tested for folding back only; ``closed``: edges 0 and n - 1 are neighbours too)."""
    n1 = a.shape[0] - 1
    n2 = b.shape[0] - 1
    lo1 = np.minimum(a[:-1], a[1:]) - tolerance
    hi1 = np.maximum(a[:-1], a[1:]) + tolerance
    lo2 = np.minimum(b[:-1], b[1:])
    hi2 = np.maximum(b[:-1], b[1:])
    tol2 = tolerance * tolerance
    for i in range(n1):
        first = i + 1 if same else 0
        for j in range(first, n2):
            if same and (j == i + 1 or (closed and i == 0 and j == n1 - 1)):
                # neighbours share a vertex: they meet elsewhere only by folding back
                k0, k1 = (i, j) if j == i + 1 else (j, i)
                ux = a[k0 + 1, 0] - a[k0, 0]
                uy = a[k0 + 1, 1] - a[k0, 1]
                uz = a[k0 + 1, 2] - a[k0, 2]
                vx = a[k1 + 1, 0] - a[k1, 0]
                vy = a[k1 + 1, 1] - a[k1, 1]
                vz = a[k1 + 1, 2] - a[k1, 2]
                cx = uy * vz - uz * vy
                cy = uz * vx - ux * vz
                cz = ux * vy - uy * vx
                dot = ux * vx + uy * vy + uz * vz
                uu = ux * ux + uy * uy + uz * uz
                vv = vx * vx + vy * vy + vz * vz
                if dot < 0.0 and cx * cx + cy * cy + cz * cz <= (
                        RELATIVE_TOLERANCE * RELATIVE_TOLERANCE * uu * vv):
                    return i, j
                continue
            if (lo1[i, 0] > hi2[j, 0] or lo2[j, 0] > hi1[i, 0] or lo1[i, 1] > hi2[j, 1]
                    or lo2[j, 1] > hi1[i, 1] or lo1[i, 2] > hi2[j, 2] or lo2[j, 2] > hi1[i, 2]):
                continue
            if _distance2(a[i, 0], a[i, 1], a[i, 2], a[i + 1, 0], a[i + 1, 1], a[i + 1, 2],
                          b[j, 0], b[j, 1], b[j, 2], b[j + 1, 0], b[j + 1, 1],
                          b[j + 1, 2]) <= tol2:
                return i, j
    return -1, -1


@njit()
def _closest_approach(a: np.ndarray, closed: bool) -> float:
    """Smallest distance between edges of the extended vertex array ``a`` that share no
    vertex (``inf`` if there are none)."""
    n = a.shape[0] - 1
    best = np.inf
    for i in range(n):
        for j in range(i + 2, n):
            if closed and i == 0 and j == n - 1:
                continue
            d2 = _distance2(a[i, 0], a[i, 1], a[i, 2], a[i + 1, 0], a[i + 1, 1], a[i + 1, 2],
                            a[j, 0], a[j, 1], a[j, 2], a[j + 1, 0], a[j + 1, 1], a[j + 1, 2])
            best = min(best, d2)
    return np.sqrt(best)


def _extent(*arrays: np.ndarray) -> float:
    points = np.vstack(arrays)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def _extended(vertices: np.ndarray, closed: bool) -> np.ndarray:
    if closed:
        return np.ascontiguousarray(np.vstack([vertices, vertices[:1]]))
    return np.ascontiguousarray(vertices)


def first_self_crossing(vertices: np.ndarray, closed: bool) -> tuple[int, int] | None:
    """The first pair ``(i, j)`` of edges of a polygon (``(n, 3)`` finite vertices, edges of
    non-zero length; ``closed``: the edge from the last vertex to the first is edge
    ``n - 1``) that meet other than at a shared vertex, or None."""
    nodes = _extended(np.asarray(vertices, dtype=np.float64), closed)
    tolerance = RELATIVE_TOLERANCE * _extent(nodes)
    i, j = _first_pair(nodes, nodes, True, closed, tolerance)
    return None if i < 0 else (int(i), int(j))


def closest_approach(vertices: np.ndarray, closed: bool = True) -> float:
    """The smallest distance between two edges of a polygon (``(n, 3)`` finite vertices,
    edges of non-zero length) that share no vertex, ``inf`` if no two edges are so.

    No motion of the vertices by at most ``d`` each brings two edges closer by more than
    ``2 d`` (a point of an edge is a convex combination of its vertices), so a polygon
    moved by less than half of this cannot have passed an edge through another.
    """
    return float(_closest_approach(_extended(np.asarray(vertices, dtype=np.float64), closed),
                                   closed))


def first_crossing(first: np.ndarray, second: np.ndarray) -> tuple[int, int] | None:
    """The first pair ``(i, j)``, edge ``i`` of closed polygon ``first`` and edge ``j`` of
    closed polygon ``second`` (``(n, 3)`` finite vertices each), that meet, or None."""
    a = _extended(np.asarray(first, dtype=np.float64), True)
    b = _extended(np.asarray(second, dtype=np.float64), True)
    tolerance = RELATIVE_TOLERANCE * _extent(a, b)
    i, j = _first_pair(a, b, False, True, tolerance)
    return None if i < 0 else (int(i), int(j))
