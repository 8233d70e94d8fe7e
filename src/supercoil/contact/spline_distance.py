"""Distance between two pieces of a uniform cubic B-spline, with exact derivatives.

Why a spline. A polygon's chord sags inside the smooth curve through its
nodes by up to ``h^2 kappa / 8``, and by nothing at the nodes, so a contact
distance measured between chords depends on where the nodes sit relative to
the contact: a ripple of period ``h`` that locks contacts to the mesh and
breaks the material-sliding symmetry of a closed homogeneous rod
(:mod:`supercoil.problems.ring_diagram.contact_branches`, "Material sliding"). The uniform
cubic B-spline whose control points are the nodes has discrete moments that
are shift invariant up to degree 3: for nodes ``x_k = x(s_0 + k h)`` sampled
from a smooth curve, ``c(s) = x(s) + (h^2 / 6) x''(s) + O(h^4)`` whatever the
sampling phase ``s_0``, so the ripple falls to ``O(h^4)`` (measured in
``tests/test_contact_spline.py``: observed orders about 4 for the spline and 2
for the chords). An interpolating (Catmull–Rom) spline has no phase-independent
leading error and is not used.

Pieces. Piece ``i`` (the segment from node ``a_i`` to node ``b_i``) is

    c_i(u) = sum_{k=0..3} B_k(u) P_{i,k},  u in [0, 1],

``B_0 = (1-u)^3/6``, ``B_1 = (3u^3 - 6u^2 + 4)/6``, ``B_2 = (-3u^3 + 3u^2 +
3u + 1)/6``, ``B_3 = u^3/6``, with control points ``P_i = (x_{i-1}, x_i,
x_{i+1}, x_{i+2})`` on a closed rod (indices wrap). Each control point is a
fixed linear combination of at most four *stencil nodes*: :class:`CurvePieces`
holds the stencil ``(k, 4)`` and the matrix ``control`` ``(k, 4, 4)`` with
``P_{i,j} = sum_l control[i, j, l] x[stencil[i, l]]``. Open (clamped) rods
have ghost control points by reflection, ``x_{-1} = 2 x_0 - x_1`` and
``x_n = 2 x_{n-1} - x_{n-2}``: the end piece then starts exactly at the end
node with the chord's direction and zero curvature (``c(0) = x_0``,
``c'(0) = x_1 - x_0``, ``c''(0) = 0``). A chord is the same form with
collinear, equally spaced control points ``(2a - b, a, b, 2b - a)``
(:func:`chord_pieces`), which the B-spline reproduces exactly: the tests use
it to reduce to :mod:`supercoil.contact.distance`.

Sag. ``c_i(u) - ((1-u) x_i + u x_{i+1}) = B_0(u) Δ_i + B_3(u) Δ_{i+1}`` with the
second differences ``Δ_i = P_{i,0} - 2 P_{i,1} + P_{i,2}``, ``Δ_{i+1} =
P_{i,1} - 2 P_{i,2} + P_{i,3}`` (linear reproduction fixes the form), and
``B_0 + B_3 <= 1/6``; so a piece lies within ``max(|Δ_i|, |Δ_{i+1}|) / 6``
(:func:`sag_bound`, about ``h^2 kappa / 6``) of its chord, and a broad phase on
the chords with the cutoff widened by twice that bound misses no pair.

Distance. ``d = min |c_p(s) - c_q(t)|`` over ``(s, t)`` in ``[0, 1]^2``. The
function ``h = |r|^2 / 2``, ``r = c_p(s) - c_q(t)``, is a polynomial of degree
six, nearly convex when the pieces are short against their radii of
curvature but not always (a point inside the osculating circle of the other
piece, e.g. tight plectonemes, has a local maximum of the distance along it).
The minimiser is searched globally:

* on each side of the square (one endpoint of a piece against the other
  piece, a one-dimensional problem): the sign of ``h'`` at 9 equally spaced
  parameters brackets every local minimum that is not closer than 1/8 to
  another critical point, and each is refined by Newton safeguarded by
  bisection; the ends of the side (corners) are candidates when ``h'``
  points inwards;
* in the interior: damped Newton from the pieces' chord solution and from
  the best point of the sides; a converged point inside the square with a
  positive definite ``h_uu`` is a candidate.

The smallest candidate is the distance, and its type (:class:`DistanceKind`:
interior, one free parameter, corner) says which parameters ``u`` are free.

Derivatives. ``r = C(s, t) X`` is linear in the 24 coordinates ``X`` of the
8 stencil nodes, ``C = c ⊗ I_3`` with ``c = (w_p(s), -w_q(t))``, ``w`` the
nodes' weights ``w_l(u) = sum_j B_j(u) control[j, l]``. By the envelope and
implicit function theorems, over the free parameters ``u``,

    grad h = C^T r,      hess h = C^T C - h_xu h_uu^{-1} h_ux,

with ``h_ss = |r_s|^2 + r.r_ss``, ``h_tt = |r_t|^2 + r.r_tt``, ``h_st =
r_s.r_t`` (``r_s = c_p'``, ``r_t = -c_q'``, ``r_ss = c_p''``, ``r_tt = -c_q''``)
and ``d h_s / dX = C_s^T r + C^T r_s`` (``C_s = (w_p', 0) ⊗ I``), likewise for
``t``; then ``grad d = c ⊗ r̂`` and ``hess d = (hess h - grad d grad d^T) / d``
as in :mod:`supercoil.contact.distance` (checked against finite differences
in ``tests/test_contact_spline.py``).

Near-parallel pieces (line contacts). The interior type's ``h_uu^{-1}`` blows
up where the valley of ``h`` is flat, i.e. where two pieces run parallel at a
constant distance (two strands of a plectoneme). As for the chords, when
``det h_uu <= parallel_tolerance h_ss h_tt`` (``sin^2`` of the angle between
the pieces for chords) :func:`piece_distance_derivatives` drops the interior
candidate and uses the best side or corner instead: exact when the valley is
flat, bounded derivatives, and above the interior minimum by at most about
``lambda_min / (2 d)`` with ``lambda_min <= parallel_tolerance h_ss h_tt /
(h_ss + h_tt)`` the valley's curvature (the valley leaves the square within a
unit parameter step): ``5e-7 ℓ^2 / d`` for ``ℓ`` the piece length at the
default tolerance. :func:`piece_distance` never drops it.

Degenerate cases. When ``d <= 1e-12`` times the larger piece length the
gradient and Hessian are returned as zeros (crossing pieces), as in
:mod:`supercoil.contact.distance`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

from supercoil._numba import njit
from supercoil.contact.distance import CROSSING_RELATIVE_DISTANCE, DistanceKind

__all__ = [
    "BSPLINE_BASIS",
    "CurvePieces",
    "bspline_pieces",
    "chord_pieces",
    "local_minimum_pairs",
    "piece_distance",
    "piece_distance_derivatives",
    "piece_distance_of_nodes",
    "sag_bound",
]

# B_j(u) = sum_p BSPLINE_BASIS[j, p] u^p (uniform cubic B-spline, module docstring)
BSPLINE_BASIS = np.array([[1.0, -3.0, 3.0, -1.0],
                          [4.0, 0.0, -6.0, 3.0],
                          [1.0, 3.0, 3.0, -3.0],
                          [0.0, 0.0, 0.0, 1.0]]) / 6.0

_EE = 0
_P0_EQ, _P1_EQ, _Q0_EP, _Q1_EP = 1, 2, 3, 4
_P0_Q0, _P0_Q1, _P1_Q0, _P1_Q1 = 5, 6, 7, 8
_SAMPLES = 8  # intervals in which h' is sampled on a side of the square
_NEWTON_ITERATIONS = 40


@dataclass(frozen=True)
class CurvePieces:
    """Cubic B-spline pieces of a polygon: ``stencil`` ``(k, 4)`` node indices and
    ``control`` ``(k, 4, 4)``, control point ``j`` of piece ``i`` being
    ``sum_l control[i, j, l] x[stencil[i, l]]`` (module docstring)."""

    stencil: np.ndarray
    control: np.ndarray
    # (k, 2): whether the piece continues into a neighbour at u = 0 and at u = 1
    joined: np.ndarray | None = None

    def joined_ends(self) -> np.ndarray:
        return (np.zeros((len(self.stencil), 2), dtype=bool) if self.joined is None
                else np.asarray(self.joined, dtype=bool))

    @cached_property
    def coefficients(self) -> np.ndarray:
        """``(k, 4, 4)``: weight of stencil node ``l`` on ``u^p`` is ``[i, l, p]``."""
        return np.einsum("ijl,jp->ilp", self.control, BSPLINE_BASIS)

    def control_points(self, points: np.ndarray) -> np.ndarray:
        """``(k, 4, 3)`` control points of the pieces for nodes ``points`` ``(n, 3)``."""
        x = np.asarray(points, dtype=float)[self.stencil]  # (k, 4, 3)
        return np.einsum("ijl,ilx->ijx", self.control, x)

    def evaluate(self, points: np.ndarray, piece: npt.ArrayLike, u: npt.ArrayLike) -> np.ndarray:
        """Points ``c_piece(u)`` ``(..., 3)`` of the curve."""
        piece = np.asarray(piece)
        u = np.asarray(u, dtype=float)
        basis = np.stack([u**p for p in range(4)], axis=-1) @ BSPLINE_BASIS.T  # (..., 4)
        return np.einsum("...j,...jx->...x", basis, self.control_points(points)[piece])


def bspline_pieces(segments: np.ndarray, closed: bool) -> CurvePieces:
    """The uniform cubic B-spline pieces of the segments ``(k, 2)`` (node indices).

    Segment ``i`` runs from ``segments[i, 0]`` to ``segments[i, 1]``; it is
    joined to segment ``i + 1`` when ``segments[i + 1, 0] == segments[i, 1]``
    (and the last to the first when ``closed``). The control points of piece
    ``i`` are the nodes ``(a_{i-1}, a_i, b_i, b_{i+1})``; at a free end (no
    joined neighbour: the ends of an open rod, or of each strand of a set of
    strands) the missing one is a ghost by reflection (module docstring).
    """
    seg = np.asarray(segments, dtype=np.int64)
    k = len(seg)
    if seg.ndim != 2 or seg.shape[1] != 2 or k < 1:
        raise ValueError(f"segments must have shape (k, 2) with k >= 1, got {seg.shape}")
    stencil = np.empty((k, 4), dtype=np.int64)
    control = np.zeros((k, 4, 4))
    joined = np.zeros((k, 2), dtype=bool)
    eye = np.eye(4)
    for i in range(k):
        a, b = seg[i]
        prev = (i - 1) % k if (closed or i > 0) else None
        succ = (i + 1) % k if (closed or i < k - 1) else None
        before = seg[prev, 0] if prev is not None and seg[prev, 1] == a and prev != i else None
        after = seg[succ, 1] if succ is not None and seg[succ, 0] == b and succ != i else None
        stencil[i] = (a, b, before if before is not None else a,
                      after if after is not None else b)
        # control points in terms of the stencil (a, b, before, after)
        control[i, 0] = eye[2] if before is not None else 2 * eye[0] - eye[1]
        control[i, 1] = eye[0]
        control[i, 2] = eye[1]
        control[i, 3] = eye[3] if after is not None else 2 * eye[1] - eye[0]
        joined[i] = (before is not None, after is not None)
    return CurvePieces(stencil, control, joined)


def chord_pieces(segments: np.ndarray) -> CurvePieces:
    """The segments themselves as B-spline pieces (control points ``2a - b, a, b, 2b - a``)."""
    seg = np.asarray(segments, dtype=np.int64)
    stencil = np.concatenate([seg, seg], axis=1)
    rows = np.array([[2.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0],
                     [0.0, 1.0, 0.0, 0.0], [-1.0, 2.0, 0.0, 0.0]])
    return CurvePieces(stencil, np.broadcast_to(rows, (len(seg), 4, 4)).copy())


def sag_bound(points: np.ndarray, pieces: CurvePieces) -> np.ndarray:
    """``(k,)`` bound on the distance of each piece from its chord (module docstring)."""
    ctrl = pieces.control_points(points)
    second = ctrl[:, :2] - 2 * ctrl[:, 1:3] + ctrl[:, 2:]  # (k, 2, 3)
    return np.linalg.norm(second, axis=-1).max(axis=1) / 6.0


# --------------------------------------------------------------------------
# per-pair kernels (numba): pieces as polynomial coefficient vectors a[p] (4, 3)
# --------------------------------------------------------------------------


@njit()
def _weights(coef, u, w, w1, w2):
    """Stencil weights of c(u), c'(u), c''(u) of one piece: coef (4 nodes, 4 powers)."""
    for k in range(4):
        c0, c1, c2, c3 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3]
        w[k] = c0 + u * (c1 + u * (c2 + u * c3))
        w1[k] = c1 + u * (2.0 * c2 + 3.0 * u * c3)
        w2[k] = 2.0 * c2 + 6.0 * u * c3


@njit()
def _point(a, u, out, out1, out2):
    """c(u), c'(u), c''(u) of a piece with power coefficients a (4, 3)."""
    for x in range(3):
        out[x] = a[0, x] + u * (a[1, x] + u * (a[2, x] + u * a[3, x]))
        out1[x] = a[1, x] + u * (2.0 * a[2, x] + 3.0 * u * a[3, x])
        out2[x] = 2.0 * a[2, x] + 6.0 * u * a[3, x]


@njit()
def _side_slope(a, q, u, c, c1, c2):
    """(f, f', f'') of f(u) = |c(u) - q|^2 / 2."""
    _point(a, u, c, c1, c2)
    f = 0.0
    g = 0.0
    gg = 0.0
    for x in range(3):
        r = c[x] - q[x]
        f += r * r
        g += r * c1[x]
        gg += c1[x] * c1[x] + r * c2[x]
    return 0.5 * f, g, gg


@njit()
def _refine(a, q, lo, hi, c, c1, c2):
    """Root of f' in [lo, hi] with f'(lo) < 0 < f'(hi): Newton safeguarded by bisection."""
    u = 0.5 * (lo + hi)
    for _ in range(60):
        _f, g, gg = _side_slope(a, q, u, c, c1, c2)
        if g < 0.0:
            lo = u
        else:
            hi = u
        if g == 0.0 or hi - lo <= 1e-15:
            break
        step = -g / gg if gg > 0.0 else 0.0
        trial = u + step
        if gg > 0.0 and lo < trial < hi:
            if abs(step) <= 1e-15:
                u = trial
                break
            u = trial
        else:
            u = 0.5 * (lo + hi)
    return u


@njit()
def _side_minimum(a, q, c, c1, c2):
    """Global minimiser ``(u, f)`` of |c(u) - q|^2/2 on [0, 1] (module docstring)."""
    best_u = 0.0
    best_f = np.inf
    u_prev = 0.0
    f_prev, g_prev, _ = _side_slope(a, q, 0.0, c, c1, c2)
    if g_prev >= 0.0:
        best_u, best_f = 0.0, f_prev
    for j in range(1, _SAMPLES + 1):
        u = j / _SAMPLES
        f, g, _ = _side_slope(a, q, u, c, c1, c2)
        if g_prev < 0.0 <= g:
            root = _refine(a, q, u_prev, u, c, c1, c2)
            fr, _, _ = _side_slope(a, q, root, c, c1, c2)
            if fr < best_f:
                best_u, best_f = root, fr
        u_prev, f_prev, g_prev = u, f, g
    if g_prev <= 0.0 and f_prev < best_f:
        best_u, best_f = 1.0, f_prev
    if best_f == np.inf:  # cannot happen for a polynomial; keep a valid answer
        f0, _, _ = _side_slope(a, q, 0.0, c, c1, c2)
        f1, _, _ = _side_slope(a, q, 1.0, c, c1, c2)
        best_u, best_f = (0.0, f0) if f0 <= f1 else (1.0, f1)
    return best_u, best_f


@njit()
def _interior_terms(ap, aq, s, t, p, p1, p2, q, q1, q2):
    """h, gradient (h_s, h_t) and h_uu entries at (s, t)."""
    _point(ap, s, p, p1, p2)
    _point(aq, t, q, q1, q2)
    h = 0.0
    hs = 0.0
    ht = 0.0
    hss = 0.0
    htt = 0.0
    hst = 0.0
    for x in range(3):
        r = p[x] - q[x]
        h += r * r
        hs += r * p1[x]
        ht -= r * q1[x]
        hss += p1[x] * p1[x] + r * p2[x]
        htt += q1[x] * q1[x] - r * q2[x]
        hst -= p1[x] * q1[x]
    return 0.5 * h, hs, ht, hss, htt, hst


@njit()
def _interior_minimum(ap, aq, s, t, p, p1, p2, q, q1, q2):
    """Damped Newton for an interior local minimum from (s, t).

    Returns ``(ok, s, t, h, det_ratio)``: ``ok`` when it converged inside the
    square with ``h_uu`` positive definite; ``det_ratio = det h_uu / (h_ss h_tt)``.
    """
    h, hs, ht, hss, htt, hst = _interior_terms(ap, aq, s, t, p, p1, p2, q, q1, q2)
    converged = False
    for _ in range(_NEWTON_ITERATIONS):
        det = hss * htt - hst * hst
        newton = hss > 0.0 and det > 0.0
        if newton:
            ds = -(htt * hs - hst * ht) / det
            dt = -(hss * ht - hst * hs) / det
        else:
            scale = abs(hss) + abs(htt)
            if not scale > 0.0:
                return False, s, t, h, 0.0
            ds = -hs / scale
            dt = -ht / scale
        alpha = 1.0
        accepted = False
        for _ls in range(30):
            s_new = s + alpha * ds
            t_new = t + alpha * dt
            h_new, hs_n, ht_n, hss_n, htt_n, hst_n = _interior_terms(
                ap, aq, s_new, t_new, p, p1, p2, q, q1, q2)
            # near the minimum h stops decreasing in floating point long before
            # the parameters are accurate (at sqrt(eps)): a Newton step that
            # reduces the gradient is then taken
            if h_new < h or (newton and alpha == 1.0
                             and max(abs(hs_n), abs(ht_n)) < max(abs(hs), abs(ht))):
                accepted = True
                break
            alpha *= 0.5
        step = max(abs(alpha * ds), abs(alpha * dt))
        if not accepted:
            converged = True  # no decrease at any scale: at the minimum to round-off
            break
        s, t, h, hs, ht, hss, htt, hst = s_new, t_new, h_new, hs_n, ht_n, hss_n, htt_n, hst_n
        if s < -0.5 or s > 1.5 or t < -0.5 or t > 1.5:
            return False, s, t, h, 0.0  # the minimum lies beyond a side
        if step <= 1e-14:
            converged = True
            break
    det = hss * htt - hst * hst
    inside = 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
    if not (converged and inside and hss > 0.0 and htt > 0.0 and det > 0.0):
        return False, s, t, h, 0.0
    return True, s, t, h, det / (hss * htt)


@njit()
def _chord_start(ap, aq):
    """Closest parameters of the infinite lines through the pieces' ends, clamped."""
    ux = ap[1, 0] + ap[2, 0] + ap[3, 0]
    uy = ap[1, 1] + ap[2, 1] + ap[3, 1]
    uz = ap[1, 2] + ap[2, 2] + ap[3, 2]
    vx = aq[1, 0] + aq[2, 0] + aq[3, 0]
    vy = aq[1, 1] + aq[2, 1] + aq[3, 1]
    vz = aq[1, 2] + aq[2, 2] + aq[3, 2]
    wx = ap[0, 0] - aq[0, 0]
    wy = ap[0, 1] - aq[0, 1]
    wz = ap[0, 2] - aq[0, 2]
    a = ux * ux + uy * uy + uz * uz
    b = ux * vx + uy * vy + uz * vz
    c = vx * vx + vy * vy + vz * vz
    dw = ux * wx + uy * wy + uz * wz
    ew = vx * wx + vy * wy + vz * wz
    det = a * c - b * b
    if det > 1e-12 * a * c and det > 0.0:
        s = (b * ew - c * dw) / det
        t = (a * ew - b * dw) / det
    else:
        s = 0.5
        t = 0.5
    return min(max(s, 0.0), 1.0), min(max(t, 0.0), 1.0)


@njit()
def _closest_pieces(ap, aq, parallel_tolerance, exact, work):
    """``(d, s, t, kind)`` of two pieces with power coefficients ``ap``, ``aq`` (4, 3)."""
    p = work[0]
    p1 = work[1]
    p2 = work[2]
    q = work[3]
    q1 = work[4]
    q2 = work[5]
    best = np.inf
    s_best = 0.0
    t_best = 0.0
    kind = _P0_Q0
    # sides: an end of p against piece q, an end of q against piece p
    for end in range(2):
        _point(ap, float(end), p, p1, p2)
        t, f = _side_minimum(aq, p, q, q1, q2)
        if f < best:
            best, s_best, t_best = f, float(end), t
            if t <= 0.0:
                kind = _P0_Q0 if end == 0 else _P1_Q0
            elif t >= 1.0:
                kind = _P0_Q1 if end == 0 else _P1_Q1
            else:
                kind = _P0_EQ if end == 0 else _P1_EQ
    for end in range(2):
        _point(aq, float(end), q, q1, q2)
        s, f = _side_minimum(ap, q, p, p1, p2)
        if f < best:
            best, s_best, t_best = f, s, float(end)
            if s <= 0.0:
                kind = _P0_Q0 if end == 0 else _P0_Q1
            elif s >= 1.0:
                kind = _P1_Q0 if end == 0 else _P1_Q1
            else:
                kind = _Q0_EP if end == 0 else _Q1_EP
    s0, t0 = _chord_start(ap, aq)
    for start in range(2):
        if start == 0:
            ok, s, t, f, ratio = _interior_minimum(ap, aq, s0, t0, p, p1, p2, q, q1, q2)
        else:
            ok, s, t, f, ratio = _interior_minimum(ap, aq, s_best, t_best, p, p1, p2, q, q1, q2)
        if ok and (exact or ratio > parallel_tolerance) and f < best:
            best, s_best, t_best, kind = f, s, t, _EE
    return np.sqrt(2.0 * best), s_best, t_best, kind


@njit()
def _power_coefficients(nodes, coef, a):
    """a[p, x] = sum_l coef[l, p] nodes[l, x] for one piece."""
    for pw in range(4):
        for x in range(3):
            v = 0.0
            for k in range(4):
                v += coef[k, pw] * nodes[k, x]
            a[pw, x] = v


@njit()
def _distance_kernel(nodes, coef, d, s, t, kinds):
    """Exact distances of pairs: nodes (m, 8, 3), coef (m, 2, 4, 4)."""
    ap = np.empty((4, 3))
    aq = np.empty((4, 3))
    work = np.empty((6, 3))
    for i in range(nodes.shape[0]):
        _power_coefficients(nodes[i, :4], coef[i, 0], ap)
        _power_coefficients(nodes[i, 4:], coef[i, 1], aq)
        d[i], s[i], t[i], kinds[i] = _closest_pieces(ap, aq, 0.0, True, work)


@njit()
def _shadow_kernel(nodes, coef, joined, s, t, shadow):
    """Whether each pair's minimiser lies on a side where its piece continues into
    the next one with the distance still falling (see :func:`local_minimum_pairs`)."""
    ap = np.empty((4, 3))
    aq = np.empty((4, 3))
    p = np.empty(3)
    p1 = np.empty(3)
    p2 = np.empty(3)
    q = np.empty(3)
    q1 = np.empty(3)
    q2 = np.empty(3)
    for i in range(nodes.shape[0]):
        _power_coefficients(nodes[i, :4], coef[i, 0], ap)
        _power_coefficients(nodes[i, 4:], coef[i, 1], aq)
        _point(ap, s[i], p, p1, p2)
        _point(aq, t[i], q, q1, q2)
        hs = 0.0
        ht = 0.0
        rr = 0.0
        lp = 0.0
        lq = 0.0
        for x in range(3):
            r = p[x] - q[x]
            hs += r * p1[x]
            ht -= r * q1[x]
            rr += r * r
            lp += p1[x] * p1[x]
            lq += q1[x] * q1[x]
        tol_s = 1e-10 * np.sqrt(rr * lp)
        tol_t = 1e-10 * np.sqrt(rr * lq)
        out = False
        if s[i] >= 1.0 and joined[i, 0, 1]:
            out = out or hs < tol_s
        if s[i] <= 0.0 and joined[i, 0, 0]:
            out = out or hs > tol_s
        if t[i] >= 1.0 and joined[i, 1, 1]:
            out = out or ht < tol_t
        if t[i] <= 0.0 and joined[i, 1, 0]:
            out = out or ht > tol_t
        shadow[i] = out


@njit()
def _derivative_kernel(nodes, coef, parallel_tolerance, d_out, s_out, t_out, grad, hess, kinds):
    ap = np.empty((4, 3))
    aq = np.empty((4, 3))
    work = np.empty((6, 3))
    wp = np.empty(4)
    wp1 = np.empty(4)
    wp2 = np.empty(4)
    wq = np.empty(4)
    wq1 = np.empty(4)
    wq2 = np.empty(4)
    cc = np.empty(8)
    cs = np.zeros(8)
    ct = np.zeros(8)
    r = np.empty(3)
    rs = np.empty(3)
    rt = np.empty(3)
    js = np.empty(24)
    jt = np.empty(24)
    for i in range(nodes.shape[0]):
        _power_coefficients(nodes[i, :4], coef[i, 0], ap)
        _power_coefficients(nodes[i, 4:], coef[i, 1], aq)
        d, s, t, kind = _closest_pieces(ap, aq, parallel_tolerance, False, work)
        d_out[i] = d
        s_out[i] = s
        t_out[i] = t
        kinds[i] = kind
        _weights(coef[i, 0], s, wp, wp1, wp2)
        _weights(coef[i, 1], t, wq, wq1, wq2)
        hss = 0.0
        htt = 0.0
        hst = 0.0
        lp = 0.0
        lq = 0.0
        for x in range(3):
            px = 0.0
            p1 = 0.0
            p2 = 0.0
            qx = 0.0
            q1 = 0.0
            q2 = 0.0
            for k in range(4):
                px += wp[k] * nodes[i, k, x]
                p1 += wp1[k] * nodes[i, k, x]
                p2 += wp2[k] * nodes[i, k, x]
                qx += wq[k] * nodes[i, 4 + k, x]
                q1 += wq1[k] * nodes[i, 4 + k, x]
                q2 += wq2[k] * nodes[i, 4 + k, x]
            r[x] = px - qx
            rs[x] = p1
            rt[x] = -q1
            hss += p1 * p1 + r[x] * p2
            htt += q1 * q1 - r[x] * q2
            hst -= p1 * q1
            lp += (ap[1, x] + ap[2, x] + ap[3, x]) ** 2
            lq += (aq[1, x] + aq[2, x] + aq[3, x]) ** 2
        scale = np.sqrt(max(lp, lq))
        if not d > CROSSING_RELATIVE_DISTANCE * scale:
            for m in range(24):
                grad[i, m] = 0.0
                for n in range(24):
                    hess[i, m, n] = 0.0
            continue
        for k in range(4):
            cc[k] = wp[k]
            cc[4 + k] = -wq[k]
            cs[k] = wp1[k]
            ct[4 + k] = -wq1[k]
        inv_d = 1.0 / d
        for k in range(8):
            for x in range(3):
                grad[i, 3 * k + x] = cc[k] * r[x] * inv_d
        for k in range(8):
            for x in range(3):
                row = 3 * k + x
                for m in range(8):
                    ckm = cc[k] * cc[m]
                    for y in range(3):
                        delta = 1.0 if x == y else 0.0
                        hess[i, row, 3 * m + y] = ckm * (delta - r[x] * r[y] * inv_d * inv_d)
        free_s = kind == _EE or kind == _Q0_EP or kind == _Q1_EP
        free_t = kind == _EE or kind == _P0_EQ or kind == _P1_EQ
        if free_s:
            for k in range(8):
                for x in range(3):
                    js[3 * k + x] = cs[k] * r[x] + cc[k] * rs[x]
        if free_t:
            for k in range(8):
                for x in range(3):
                    jt[3 * k + x] = ct[k] * r[x] + cc[k] * rt[x]
        det = hss * htt - hst * hst
        if free_s and free_t and det > 0.0:
            mss = htt / det
            mst = -hst / det
            mtt = hss / det
            for m in range(24):
                for n in range(24):
                    hess[i, m, n] -= (mss * js[m] * js[n] + mst * (js[m] * jt[n] + jt[m] * js[n])
                                      + mtt * jt[m] * jt[n])
        elif free_s and not free_t and hss > 0.0:
            inv = 1.0 / hss
            for m in range(24):
                for n in range(24):
                    hess[i, m, n] -= inv * js[m] * js[n]
        elif free_t and not free_s and htt > 0.0:
            inv = 1.0 / htt
            for m in range(24):
                for n in range(24):
                    hess[i, m, n] -= inv * jt[m] * jt[n]
        for m in range(24):
            for n in range(24):
                hess[i, m, n] *= inv_d
        for k in range(4):
            cs[k] = 0.0
            ct[4 + k] = 0.0


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------


def _pair_arrays(points, pieces: CurvePieces, pairs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = np.asarray(points, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or not np.isfinite(x).all():
        raise ValueError(f"points must be a finite array of shape (n, 3), got {x.shape}")
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    stencil = pieces.stencil[pairs].reshape(len(pairs), 8)  # (m, 8) node indices
    coef = pieces.coefficients[pairs]  # (m, 2, 4, 4)
    return np.ascontiguousarray(x[stencil]), np.ascontiguousarray(coef), stencil


def piece_distance(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distances ``d``, ``s``, ``t`` ``(m,)`` of the piece pairs ``pairs`` ``(m, 2)``.

    ``d = |c_i(s) - c_j(t)|`` is attained by the returned parameters; the
    interior candidate is never dropped (module docstring).
    """
    nodes, coef, _ = _pair_arrays(points, pieces, pairs)
    return piece_distance_of_nodes(nodes, coef)


def local_minimum_pairs(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike,
                        s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(m,)`` bool: whether pair ``(i, j)``'s minimiser ``(s, t)`` is a local minimum of
    the distance between the whole curves, not a *shadow* of a neighbouring pair.

    A minimiser on a side of the square where the piece continues into its
    neighbour (``u = 1`` with the distance still falling into the next piece,
    or ``u = 0`` with it falling into the previous one) is the end of a piece
    that a neighbouring pair sees closer: the same contact counted twice.
    Keeping only the other pairs counts each local minimum of the curve
    distance once (a minimum exactly at a junction belongs to the piece that
    starts there, up to a relative tolerance of 1e-10 on the slope).
    """
    nodes, coef, _ = _pair_arrays(points, pieces, pairs)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    joined = np.ascontiguousarray(pieces.joined_ends()[pairs])  # (m, 2, 2)
    shadow = np.empty(len(pairs), dtype=np.bool_)
    _shadow_kernel(nodes, coef, joined, np.ascontiguousarray(s, dtype=np.float64),
                   np.ascontiguousarray(t, dtype=np.float64), shadow)
    return ~shadow


def piece_distance_of_nodes(nodes: np.ndarray, coef: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`piece_distance` of gathered stencils ``(m, 8, 3)`` with coefficients
    ``(m, 2, 4, 4)`` (``CurvePieces.coefficients`` of the two pieces)."""
    m = nodes.shape[0]
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    kinds = np.empty(m, dtype=np.int64)
    _distance_kernel(np.ascontiguousarray(nodes, dtype=np.float64),
                     np.ascontiguousarray(coef, dtype=np.float64), d, s, t, kinds)
    return d, s, t


def piece_distance_derivatives(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike,
                               parallel_tolerance: float = 1e-6):
    """Distance, parameters, gradient, Hessian and type of piece pairs.

    Returns ``d, s, t`` ``(m,)``, ``gradient`` ``(m, 24)`` and ``hessian``
    ``(m, 24, 24)`` with respect to the coordinates of the 8 stencil nodes
    (index ``3 k + xyz``; nodes ``0..3`` those of ``pairs[:, 0]``, ``4..7``
    those of ``pairs[:, 1]``, given by ``nodes`` ``(m, 8)``), ``kind`` ``(m,)``
    (:class:`~supercoil.contact.distance.DistanceKind`) and ``nodes``. A
    stencil that repeats a node (ghost ends) has its entries summed by the
    caller's scatter. Near-parallel pieces use the sides (module docstring).
    """
    if not (np.isfinite(parallel_tolerance) and 0.0 <= parallel_tolerance < 1.0):
        raise ValueError(f"parallel_tolerance must be in [0, 1), got {parallel_tolerance!r}")
    x_nodes, coef, stencil = _pair_arrays(points, pieces, pairs)
    m = x_nodes.shape[0]
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    gradient = np.empty((m, 24))
    hessian = np.empty((m, 24, 24))
    kind = np.empty(m, dtype=np.int64)
    _derivative_kernel(x_nodes, coef, float(parallel_tolerance), d, s, t, gradient, hessian,
                       kind)
    return d, s, t, gradient, hessian, kind, stencil


assert DistanceKind.EDGE_EDGE == _EE and DistanceKind.P1_Q1 == _P1_Q1
