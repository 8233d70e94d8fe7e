"""A generic planar projection of a closed polygon and its knot diagram.

The polygon ``(n, 3)`` is turned by a random rotation (a fixed seed, so the
result is reproducible) and projected on the ``xy``-plane, viewed from ``+z``.
Every pair of non-adjacent edges is tested for a crossing of the projected
segments (a compiled double loop with a bounding-box test first; cost
``O(n^2)``, about 0.1 ms at n = 200). At a crossing the edge whose point above
the crossing has the larger ``z`` passes over; the crossing's sign is that of
``(t_over × t_under) · z`` with the projected edge directions.

A projection is generic when every crossing is transversal and lies well
inside both edges, no vertex lies on or near another edge, no two crossings on
one edge are too close to be ordered, and the strands are apart in ``z`` at
every crossing. These are tested with tolerances relative to the size of the
curve; a projection that fails them is discarded and another rotation tried.
A curve that fails them in every direction (strands that meet) is refused.
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit
from supercoil.errors import InputError
from supercoil.topology.knots.diagram import Diagram

# Relative tolerances of a generic projection (fractions of the curve's size or
# of an edge): far above rounding (1e-16), far below any physical gap.
_PARAMETER_MARGIN = 1e-9  # crossing parameter within an edge, and apart on it
_NEAR_MISS = 1e-9  # a vertex this close to another projected edge is degenerate
_HEIGHT_GAP = 1e-10  # strands closer than this in z at a crossing: not decidable


@njit()
def _crossing_kernel(x, y, z, near, capacity):  # pragma: no cover - compiled
    """Crossings of the projected closed polygon ``(x, y)``: arrays of the two edges
    ``i < j``, the parameters ``s``, ``u`` on them, and whether the point on ``i`` is
    above; ``count`` (> capacity: call again larger) and ``degenerate`` (True if a
    pair is not in general position within ``near``, a fraction of edge lengths)."""
    n = x.shape[0]
    ei = np.empty(capacity, np.int64)
    ej = np.empty(capacity, np.int64)
    es = np.empty(capacity, np.float64)
    eu = np.empty(capacity, np.float64)
    above = np.empty(capacity, np.bool_)
    count = 0
    degenerate = False
    for i in range(n):
        i1 = (i + 1) % n
        ax, ay = x[i], y[i]
        dx, dy = x[i1] - ax, y[i1] - ay
        li = math.sqrt(dx * dx + dy * dy)
        xmin_i, xmax_i = min(ax, x[i1]), max(ax, x[i1])
        ymin_i, ymax_i = min(ay, y[i1]), max(ay, y[i1])
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            j1 = (j + 1) % n
            bx, by = x[j], y[j]
            if max(bx, x[j1]) < xmin_i or min(bx, x[j1]) > xmax_i:
                continue
            if max(by, y[j1]) < ymin_i or min(by, y[j1]) > ymax_i:
                continue
            ex, ey = x[j1] - bx, y[j1] - by
            lj = math.sqrt(ex * ex + ey * ey)
            denom = dx * ey - dy * ex
            rx, ry = bx - ax, by - ay
            if abs(denom) <= near * li * lj:
                # (nearly) parallel: degenerate if the two lines nearly coincide
                if li > 0 and abs(rx * dy - ry * dx) <= near * li * (li + lj):
                    degenerate = True
                continue
            s = (rx * ey - ry * ex) / denom
            u = (rx * dy - ry * dx) / denom
            m_s = near * (1.0 + lj / li) if li > 0 else 1.0
            m_u = near * (1.0 + li / lj) if lj > 0 else 1.0
            if s < -m_s or s > 1.0 + m_s or u < -m_u or u > 1.0 + m_u:
                continue
            if s < m_s or s > 1.0 - m_s or u < m_u or u > 1.0 - m_u:
                degenerate = True
                continue
            if count < capacity:
                ei[count] = i
                ej[count] = j
                es[count] = s
                eu[count] = u
                above[count] = z[i] + s * (z[i1] - z[i]) > z[j] + u * (z[j1] - z[j])
            count += 1
    return ei, ej, es, eu, above, count, degenerate


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A rotation matrix ``(3, 3)`` drawn uniformly (QR of a Gaussian matrix)."""
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def _diagram_from_view(v: np.ndarray) -> Diagram | None:
    """The diagram of the polygon ``v`` ``(n, 3)`` seen from ``+z``, or None if this
    view is not generic (module doc)."""
    x = np.ascontiguousarray(v[:, 0])
    y = np.ascontiguousarray(v[:, 1])
    z = np.ascontiguousarray(v[:, 2])
    n = len(v)
    capacity = 4 * n
    while True:
        ei, ej, es, eu, above, count, degenerate = _crossing_kernel(
            x, y, z, _PARAMETER_MARGIN, capacity)
        if count <= capacity:
            break
        capacity = count
    if degenerate:
        return None
    ei, ej, es, eu, above = ei[:count], ej[:count], es[:count], eu[:count], above[:count]
    nxt = (np.arange(n) + 1) % n
    size = float(np.max(np.ptp(v, axis=0)))
    zi = z[ei] + es * (z[nxt[ei]] - z[ei])
    zj = z[ej] + eu * (z[nxt[ej]] - z[ej])
    if count and np.min(np.abs(zi - zj)) <= _HEIGHT_GAP * size:
        return None
    # passes along the curve: position = edge index + parameter
    position = np.concatenate([ei + es, ej + eu])
    crossing = np.concatenate([np.arange(count), np.arange(count)])
    over = np.concatenate([above, ~above])
    order = np.argsort(position, kind="stable")
    if count and np.min(np.diff(position[order])) <= _PARAMETER_MARGIN:
        return None  # two crossings too close on one edge to be ordered reliably
    di = np.stack([x[nxt[ei]] - x[ei], y[nxt[ei]] - y[ei]], axis=1)
    dj = np.stack([x[nxt[ej]] - x[ej], y[nxt[ej]] - y[ej]], axis=1)
    cross_ij = di[:, 0] * dj[:, 1] - di[:, 1] * dj[:, 0]  # t_i × t_j
    signs = np.where(above, np.sign(cross_ij), -np.sign(cross_ij)).astype(int)
    return Diagram(tuple(int(c) for c in crossing[order]),
                   tuple(bool(o) for o in over[order]),
                   tuple(int(s) for s in signs))


def check_polygon(points) -> np.ndarray:
    """``points`` as a float array ``(n, 3)``, n >= 3, finite; InputError otherwise."""
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InputError("points: not an array of numbers; give the vertices of a closed "
                         "polygon as an array (n, 3)") from None
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 3:
        raise InputError(f"points: shape {p.shape}; give the vertices of a closed polygon "
                         "as an array (n, 3) with n >= 3, each vertex once")
    if not np.all(np.isfinite(p)):
        raise InputError("points: non-finite coordinates; give finite numbers")
    if float(np.max(np.ptp(p, axis=0))) == 0.0:
        raise InputError("points: all vertices coincide; give a closed polygon")
    return p


def project(points, seed: int = 0, attempts: int = 20) -> Diagram:
    """The knot diagram of the closed polygon ``points`` ``(n, 3)`` (each vertex once)
    in a generic projection (module doc): the first of up to ``attempts`` rotations
    drawn from ``seed`` whose projection is generic.

    Raises :class:`~supercoil.errors.InputError` if none is (the strands meet, or
    consecutive vertices coincide).
    """
    p = check_polygon(points)
    p = p - p.mean(axis=0)
    rng = np.random.default_rng(seed)
    for _ in range(attempts):
        diagram = _diagram_from_view(p @ random_rotation(rng).T)
        if diagram is not None:
            return diagram
    raise InputError(
        f"points: no generic projection in {attempts} directions; the curve passes "
        "through itself (two strands meet, or repeated vertices); give a closed polygon "
        "without self-intersections")
