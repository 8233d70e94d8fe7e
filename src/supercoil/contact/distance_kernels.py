"""Compiled kernels of the segment–segment distance (:mod:`supercoil.contact.distance`).

The formulas, the candidates and their accuracy are described there. Every kernel
that calls another lives in this module (numba caches a kernel with the code of the
compiled functions it calls); :mod:`supercoil.contact.ccd` calls
:func:`closest_pair` too.
"""

from __future__ import annotations

import enum
import math

import numpy as np

from supercoil._numba import njit

# Below this fraction of the longer segment length the pair counts as crossing.
CROSSING_RELATIVE_DISTANCE = 1e-12


class DistanceKind(enum.IntEnum):
    """Type of the closest pair (the ``kind`` codes of
    :func:`~supercoil.contact.distance.segment_distance_derivatives`)."""

    EDGE_EDGE = 0  # interior points of both segments: distance of the two lines
    P0_EDGE_Q = 1  # endpoint p0 and the interior of segment q
    P1_EDGE_Q = 2
    Q0_EDGE_P = 3  # endpoint q0 and the interior of segment p
    Q1_EDGE_P = 4
    P0_Q0 = 5  # two endpoints
    P0_Q1 = 6
    P1_Q0 = 7
    P1_Q1 = 8


_EE = 0
_P0_EQ, _P1_EQ, _Q0_EP, _Q1_EP = 1, 2, 3, 4
_P0_Q0, _P0_Q1, _P1_Q0, _P1_Q1 = 5, 6, 7, 8
# A segment whose squared length is at most this is a point (and 1 / _SHORT is finite).
_SHORT = 1e-300
# sin^2 θ from which an interior minimum is accurate alone (supercoil.contact.distance,
# "Accuracy").
_WELL_CONDITIONED = 1e-2


@njit()
def _clamp01(x):
    return min(max(x, 0.0), 1.0)


@njit()
def _r2(wx, wy, wz, ux, uy, uz, vx, vy, vz, s, t):
    rx = wx + s * ux - t * vx
    ry = wy + s * uy - t * vy
    rz = wz + s * uz - t * vz
    return rx * rx + ry * ry + rz * rz


@njit()
def _norm2(x, y, z):
    return x * x + y * y + z * z


@njit()
def _foot_kind(t, interior, at0, at1):
    if t <= 0.0:
        return at0
    if t >= 1.0:
        return at1
    return interior


@njit()
def closest_pair(P0, P1, Q0, Q1, i, parallel_tolerance, exact):
    """Closest parameters of pair ``i``: ``(d, s, t, kind)``.

    ``exact=True``: the interior candidate is used whenever the lines are not
    exactly parallel and its value is the distance between two actual points
    (``s`` clamped, ``t`` the clamped foot of ``p(s)`` on ``q``), so ``d`` is always
    attained by real points; a well-conditioned interior minimum skips the
    endpoint candidates.
    ``exact=False``: the interior candidate needs ``sin^2 θ > parallel_tolerance``
    and its value is the line distance ``|w.n|/|n|`` (the smooth type function).
    """
    ux = P1[i, 0] - P0[i, 0]
    uy = P1[i, 1] - P0[i, 1]
    uz = P1[i, 2] - P0[i, 2]
    vx = Q1[i, 0] - Q0[i, 0]
    vy = Q1[i, 1] - Q0[i, 1]
    vz = Q1[i, 2] - Q0[i, 2]
    wx = P0[i, 0] - Q0[i, 0]
    wy = P0[i, 1] - Q0[i, 1]
    wz = P0[i, 2] - Q0[i, 2]
    a = ux * ux + uy * uy + uz * uz
    b = ux * vx + uy * vy + uz * vz
    c = vx * vx + vy * vy + vz * vz
    dw = ux * wx + uy * wy + uz * wz
    ew = vx * wx + vy * wy + vz * wz
    nx = uy * vz - uz * vy
    ny = uz * vx - ux * vz
    nz = ux * vy - uy * vx
    big_d = nx * nx + ny * ny + nz * nz  # |e_p x e_q|^2 = ac - b^2, without cancellation
    inv_a = 1.0 / a if a > _SHORT else 0.0
    inv_c = 1.0 / c if c > _SHORT else 0.0

    best = np.inf
    s_best = 0.0
    t_best = 0.0
    kind = _P0_Q0

    if exact:
        use_interior = big_d > 0.0
    else:
        use_interior = big_d > parallel_tolerance * a * c and big_d > 0.0
    if use_interior:
        # The numerators b ew - c dw and a ew - b dw, by Lagrange's identity, as the triple
        # products n.(e_q x w) and n.(e_p x w) (module docstring, "Accuracy"): as dot
        # products they cancel catastrophically for nearly parallel segments.
        s = (nx * (vy * wz - vz * wy) + ny * (vz * wx - vx * wz) + nz * (vx * wy - vy * wx)) / big_d
        if exact:
            # s and t would each carry an error ~ eps / sin θ, and independent errors move r
            # across the valley of |r|^2: t is the foot of p(s) on q instead (a
            # well-conditioned projection), which keeps (s, t) in the valley.
            inside = 0.0 <= s <= 1.0
            s = _clamp01(s)
            t = (ew + s * b) * inv_c
            inside = inside and 0.0 <= t <= 1.0
            t = _clamp01(t)
            best = _r2(wx, wy, wz, ux, uy, uz, vx, vy, vz, s, t)
            s_best = s
            t_best = t
            kind = _EE
            if inside and big_d >= _WELL_CONDITIONED * a * c:
                # |r|^2 is convex: an interior critical point is the minimum, and at this
                # angle it is accurate, so the endpoint candidates cannot do better
                return np.sqrt(best), s, t, kind
        else:
            t = (nx * (uy * wz - uz * wy) + ny * (uz * wx - ux * wz)
                 + nz * (ux * wy - uy * wx)) / big_d
            if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
                wn = wx * nx + wy * ny + wz * nz
                best = wn * wn / big_d
                s_best = s
                t_best = t
                kind = _EE

    # The four endpoint-to-segment candidates: r = (w + s e_p) - t e_q with s or t in {0, 1},
    # written out without the products by 0 and 1 (measured 2-3 % faster than a loop).
    # p0 against segment q
    t = ew * inv_c
    k = _foot_kind(t, _P0_EQ, _P0_Q0, _P0_Q1)
    t = _clamp01(t)
    value = _norm2(wx - t * vx, wy - t * vy, wz - t * vz)
    if value < best:
        best = value
        s_best = 0.0
        t_best = t
        kind = k
    # p1 against segment q
    t = (ew + b) * inv_c
    k = _foot_kind(t, _P1_EQ, _P1_Q0, _P1_Q1)
    t = _clamp01(t)
    value = _norm2((wx + ux) - t * vx, (wy + uy) - t * vy, (wz + uz) - t * vz)
    if value < best:
        best = value
        s_best = 1.0
        t_best = t
        kind = k
    # q0 against segment p
    s = -dw * inv_a
    k = _foot_kind(s, _Q0_EP, _P0_Q0, _P1_Q0)
    s = _clamp01(s)
    value = _norm2(wx + s * ux, wy + s * uy, wz + s * uz)
    if value < best:
        best = value
        s_best = s
        t_best = 0.0
        kind = k
    # q1 against segment p
    s = (b - dw) * inv_a
    k = _foot_kind(s, _Q1_EP, _P0_Q1, _P1_Q1)
    s = _clamp01(s)
    value = _norm2((wx + s * ux) - vx, (wy + s * uy) - vy, (wz + s * uz) - vz)
    if value < best:
        best = value
        s_best = s
        t_best = 1.0
        kind = k
    return np.sqrt(best), s_best, t_best, kind


@njit()
def distance_kernel(P0, P1, Q0, Q1, d, s, t):
    for i in range(P0.shape[0]):
        d[i], s[i], t[i], _ = closest_pair(P0, P1, Q0, Q1, i, 0.0, True)


@njit()
def pairs_within_kernel(x, segments, pairs, cutoff, pairs_out, d_out, s_out, t_out):
    """The pairs of ``pairs`` whose segments (``x[segments[i]]``) are within ``cutoff``,
    written in order to the first ``count`` rows of the outputs; returns ``count``, or
    -1 when an end of a pair's segments is not finite.

    A pair whose midpoints lie farther apart than ``cutoff`` plus the two half lengths
    (every point of a segment lies within its half length of its midpoint), by a margin
    far above the rounding of that bound, is dropped without its distance; the others
    get :func:`closest_pair` on their own ends, the values :func:`distance_kernel` gives.
    """
    k = segments.shape[0]
    mid = np.empty((k, 3))
    half = np.empty(k)
    finite = np.empty(k, dtype=np.bool_)
    scale = 0.0
    for i in range(k):
        a = segments[i, 0]
        b = segments[i, 1]
        e2 = 0.0
        finite[i] = True
        for c in range(3):
            mid[i, c] = 0.5 * (x[a, c] + x[b, c])
            e = x[b, c] - x[a, c]
            e2 += e * e
            finite[i] = finite[i] and np.isfinite(x[a, c]) and np.isfinite(x[b, c])
            scale = max(scale, abs(x[a, c]), abs(x[b, c]))
        half[i] = 0.5 * math.sqrt(e2)
    P0 = np.empty((1, 3))
    P1 = np.empty((1, 3))
    Q0 = np.empty((1, 3))
    Q1 = np.empty((1, 3))
    count = 0
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        if not (finite[i] and finite[j]):
            return -1
        m0 = mid[i, 0] - mid[j, 0]
        m1 = mid[i, 1] - mid[j, 1]
        m2 = mid[i, 2] - mid[j, 2]
        apart = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
        radii = half[i] + half[j]
        if apart - radii > cutoff + 1e-9 * (cutoff + apart + radii) + 1e-12 * scale:
            continue
        for c in range(3):
            P0[0, c] = x[segments[i, 0], c]
            P1[0, c] = x[segments[i, 1], c]
            Q0[0, c] = x[segments[j, 0], c]
            Q1[0, c] = x[segments[j, 1], c]
        d, s, t, _ = closest_pair(P0, P1, Q0, Q1, 0, 0.0, True)
        if d <= cutoff:
            pairs_out[count, 0] = i
            pairs_out[count, 1] = j
            d_out[count] = d
            s_out[count] = s
            t_out[count] = t
            count += 1
    return count


@njit()
def derivative_kernel(P0, P1, Q0, Q1, parallel_tolerance, d_out, grad, hess, kinds):
    u = np.empty(3)
    v = np.empty(3)
    r = np.empty(3)
    cc = np.empty(4)
    dp = np.array([-1.0, 1.0, 0.0, 0.0])
    dq = np.array([0.0, 0.0, -1.0, 1.0])
    js = np.empty(12)
    jt = np.empty(12)
    for i in range(P0.shape[0]):
        d, s, t, kind = closest_pair(P0, P1, Q0, Q1, i, parallel_tolerance, False)
        d_out[i] = d
        kinds[i] = kind
        for x in range(3):
            u[x] = P1[i, x] - P0[i, x]
            v[x] = Q1[i, x] - Q0[i, x]
        a = u[0] * u[0] + u[1] * u[1] + u[2] * u[2]
        b = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
        c = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        scale = np.sqrt(max(a, c))
        if not d > CROSSING_RELATIVE_DISTANCE * scale:
            for m in range(12):
                grad[i, m] = 0.0
                for n in range(12):
                    hess[i, m, n] = 0.0
            continue
        if kind == _EE:
            # r is along n = e_p x e_q: take its direction from n (accurate), its length d
            nx = u[1] * v[2] - u[2] * v[1]
            ny = u[2] * v[0] - u[0] * v[2]
            nz = u[0] * v[1] - u[1] * v[0]
            wn = ((P0[i, 0] - Q0[i, 0]) * nx + (P0[i, 1] - Q0[i, 1]) * ny
                  + (P0[i, 2] - Q0[i, 2]) * nz)
            factor = d / np.sqrt(nx * nx + ny * ny + nz * nz)
            if wn < 0.0:
                factor = -factor
            r[0] = factor * nx
            r[1] = factor * ny
            r[2] = factor * nz
        else:
            for x in range(3):
                r[x] = P0[i, x] + s * u[x] - Q0[i, x] - t * v[x]
        cc[0] = 1.0 - s
        cc[1] = s
        cc[2] = t - 1.0
        cc[3] = -t
        inv_d = 1.0 / d
        # gradient c ⊗ r̂ and the point-point part (c c^T) ⊗ (I - r̂ r̂^T) / d
        for k in range(4):
            for x in range(3):
                grad[i, 3 * k + x] = cc[k] * r[x] * inv_d
        for k in range(4):
            for x in range(3):
                row = 3 * k + x
                for m in range(4):
                    ckm = cc[k] * cc[m]
                    for y in range(3):
                        delta = 1.0 if x == y else 0.0
                        hess[i, row, 3 * m + y] = ckm * (delta - r[x] * r[y] * inv_d * inv_d)
        free_s = kind == _EE or kind == _Q0_EP or kind == _Q1_EP
        free_t = kind == _EE or kind == _P0_EQ or kind == _P1_EQ
        if free_s:
            for k in range(4):
                for x in range(3):
                    js[3 * k + x] = cc[k] * u[x] + dp[k] * r[x]
        if free_t:
            for k in range(4):
                for x in range(3):
                    jt[3 * k + x] = -(cc[k] * v[x] + dq[k] * r[x])
        # - h_xu h_uu^{-1} h_ux with h_uu = [[a, -b], [-b, c]]
        if free_s and free_t:
            nx = u[1] * v[2] - u[2] * v[1]
            ny = u[2] * v[0] - u[0] * v[2]
            nz = u[0] * v[1] - u[1] * v[0]
            det = nx * nx + ny * ny + nz * nz
            mss = c / det
            mst = b / det
            mtt = a / det
            for m in range(12):
                for n in range(12):
                    hess[i, m, n] -= (mss * js[m] * js[n] + mst * (js[m] * jt[n] + jt[m] * js[n])
                                      + mtt * jt[m] * jt[n])
        elif free_s:
            inv_a = 1.0 / a
            for m in range(12):
                for n in range(12):
                    hess[i, m, n] -= inv_a * js[m] * js[n]
        elif free_t:
            inv_c = 1.0 / c
            for m in range(12):
                for n in range(12):
                    hess[i, m, n] -= inv_c * jt[m] * jt[n]
        for m in range(12):
            for n in range(12):
                hess[i, m, n] *= inv_d
