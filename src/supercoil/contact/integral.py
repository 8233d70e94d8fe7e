"""Contact energy as a double integral over the two touching strands.

The pair formulation (:mod:`supercoil.contact.problem`, ``formulation =
"pairs"``) sums the potential of the closest distance of every segment pair.
A contact point then counts once when it lies inside a segment pair and twice
(four times) when it lies at a node of one (both) strands, where the two pairs
sharing that node see the same closest points: as the material slides along a
contact its energy jumps by up to a factor of four with period ``h``. Those
jumps are the sawtooth, the artefact folds and the stalls of the contact
branches (docs/model.md, "Contact energy").

The integral formulation counts every stretch of contact once by
construction:

    E_c = 1 / (2 D g_hat) ∫∫ psi(|r(s) - r(t)| - D) ds dt,

over pairs of points farther apart along the rod than the neighbour
exclusion, ``psi`` the scalar potential of the gap (a barrier that is C⁴
where it vanishes, see ``_psi``, or the penalty) and ``r``
the contact curve (the polygon, or the cubic or quintic B-spline of the
nodes). It is a
functional of the curve alone: it does not depend on where the nodes sit
along it, up to the quadrature error. This is the interaction-potential
approach of beam contact (Grill, Meier & Wall, "A computational model for
molecular interactions between curved slender fibers undergoing large 3D
deformations with a focus on electrostatic, van der Waals and repulsive
steric forces", IJNME 2020), with the steric potential replaced by the
barrier. The normalisation ``1 / (2 D g_hat)`` makes a point contact weigh
about one pair term: two strands crossing at a right angle at the gap ``g``
interact over an area of about ``2 pi D (g_hat - g)`` of the ``(s, t)``
plane, where ``psi`` is non-zero.

Quadrature: the midpoint rule with ``q`` points per segment (``u_a = (a +
1/2) / q``), weight ``(h / q)^2`` per pair of points. Each sample point is a
fixed linear combination of at most six nodes (two on the polygon, four on
the cubic B-spline, six on the quintic), so the discrete energy is a smooth
function of the nodes wherever every sample gap is positive: no closest-point
search, no distance regions, exact gradient and Hessian by the chain rule,

    grad = sum psi'(g) c ⊗ n,
    Hess = sum c c^T ⊗ (psi''(g) n n^T + psi'(g) / d (I - n n^T)),

``n`` the unit vector between the two sample points, ``c`` their stencil
weights (the second strand's negated). The quadrature resolves a point
contact when its spacing ``h / q`` is small against the width ``sqrt(2 D
g_hat)`` of the region where ``psi`` acts (:func:`default_samples`).

The barrier only sees the sample points, and so do the formulation's pair
states and the reported ``min_gap_over_diameter``: between samples the curve
may come closer than ``D``, by at most about ``(h / 2q)^2 / D`` for crossing
strands (3e-4 D at h = 0.6 D with the default 18 samples). The polygon's
collision guard (segments stay ``D / 2`` apart) keeps the topology whatever
the curve.
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit

POTENTIALS = {"barrier": 0, "penalty": 1}
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
def _psi(kind, g, stiffness, activation):
    """``(psi, psi', psi'')`` of the gap.

    ``kind`` 0: the barrier ``-kappa (g - g_hat)^4 / g_hat^2 log(g / g_hat)`` on
    ``0 < g < g_hat``, ``inf`` for ``g <= 0``. Near ``g = 0`` it is the IPC
    barrier of Li et al. 2020 (:func:`supercoil.contact.potentials.barrier`,
    ``-kappa (g - g_hat)^2 log(g / g_hat)``), both ``~ kappa g_hat^2 log(g_hat /
    g)``; at ``g_hat`` it is C⁴ instead of C², so that the midpoint rule's
    error, set by the first derivative that jumps there, falls faster with the
    sampling: at 32 points per segment the force ripples 3-10 times less
    (measured in tests/test_contact_integral.py; a C-infinity cut-off, steeper
    near ``g_hat``, rippled more). ``kind`` 1: the penalty ``k/2 min(g, 0)^2``.
    """
    if kind == 0:
        if g <= 0.0:
            return np.inf, 0.0, 0.0
        if g >= activation:
            return 0.0, 0.0, 0.0
        diff = g - activation
        log = math.log(g / activation)
        k = stiffness / (activation * activation)
        d2 = diff * diff
        value = -k * d2 * d2 * log
        first = -k * (4.0 * d2 * diff * log + d2 * d2 / g)
        second = -k * (12.0 * d2 * log + 8.0 * d2 * diff / g - d2 * d2 / (g * g))
        return value, first, second
    if g >= 0.0:
        return 0.0, 0.0, 0.0
    return 0.5 * stiffness * g * g, stiffness * g, stiffness


@njit()
def _integral_kernel(x, stencil, weights, pairs, diameter, kind, stiffness, activation,
                     scale, order, energy_out, grad, hess, force, param, points, have_points,
                     dofs):
    """Per-pair terms of the double integral (see the module docstring).

    ``order`` 0: energy only; 1: and gradients; 2: and Hessians. Per pair ``p``:
    ``energy_out[p]``, ``grad[p]`` ``(2 w 3,)``, ``hess[p]`` ``(2 w 3, 2 w 3)``
    over the stencil nodes of both segments (``w`` per segment), ``force[p]`` the
    magnitude of the resultant of the pair's normal forces ``-psi' n * scale`` and
    ``param[p]`` the mean sample parameters on both segments, weighted by
    ``-psi'``. With ``have_points``, the sample points are read from ``points``
    ``(k, q, 3)`` (:func:`sample_points`, the same sums) instead of formed again
    for every pair. ``dofs[p]`` ``(6 w,)`` gets the DOFs ``3 node + xyz`` of the
    stencil nodes of segment ``i``, then of segment ``j``.
    """
    m = pairs.shape[0]
    q = weights.shape[1]
    w = weights.shape[2]
    for p in range(m):
        for side in range(2):
            segment = pairs[p, side]
            for l in range(w):
                for k in range(3):
                    dofs[p, 3 * (side * w + l) + k] = 3 * stencil[segment, l] + k
    cutoff = diameter + activation if kind == 0 else diameter
    pi = np.empty((q, 3))
    pj = np.empty((q, 3))
    c = np.empty(2 * w)
    cc_row = np.empty(6 * w)
    h3 = np.empty((3, 3))
    h3_row = np.empty((3, 6 * w))
    u = np.empty(q)
    for a in range(q):
        u[a] = (a + 0.5) / q
    for p in range(m):
        i = pairs[p, 0]
        j = pairs[p, 1]
        for a in range(q):
            for k in range(3):
                if have_points:
                    pi[a, k] = points[i, a, k]
                    pj[a, k] = points[j, a, k]
                    continue
                si = 0.0
                sj = 0.0
                for l in range(w):
                    si += weights[i, a, l] * x[stencil[i, l], k]
                    sj += weights[j, a, l] * x[stencil[j, l], k]
                pi[a, k] = si
                pj[a, k] = sj
        e = 0.0
        f_sum = 0.0
        f0 = 0.0
        f1 = 0.0
        f2 = 0.0
        ui = 0.0
        uj = 0.0
        for a in range(q):
            for b in range(q):
                d0 = pi[a, 0] - pj[b, 0]
                d1 = pi[a, 1] - pj[b, 1]
                d2 = pi[a, 2] - pj[b, 2]
                d = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                if d >= cutoff:
                    continue
                value, first, second = _psi(kind, d - diameter, stiffness, activation)
                e += value
                if order == 0 or value == np.inf:
                    continue
                first *= scale
                f_sum -= first
                ui -= first * u[a]
                uj -= first * u[b]
                n0 = d0 / d
                n1 = d1 / d
                n2 = d2 / d
                f0 -= first * n0
                f1 -= first * n1
                f2 -= first * n2
                for l in range(w):
                    c[l] = weights[i, a, l]
                    c[w + l] = -weights[j, b, l]
                for l in range(2 * w):
                    grad[p, 3 * l] += first * c[l] * n0
                    grad[p, 3 * l + 1] += first * c[l] * n1
                    grad[p, 3 * l + 2] += first * c[l] * n2
                if order < 2:
                    continue
                second *= scale
                tang = first / d
                nv = (n0, n1, n2)
                for r in range(3):
                    for s in range(3):
                        h3[r, s] = (second - tang) * nv[r] * nv[s]
                    h3[r, r] += tang
                # entry (3 l1 + r, 3 l2 + s) gains (c[l1] c[l2]) h3[r, s], one term per
                # sample pair in the sample pairs' order; the row's 6w columns in one
                # contiguous run (measured 2x faster than the (l1, l2, r, s) nest that
                # skipped zero weights; a zero weight adds +-0, which leaves every
                # entry as it was), its factors laid out along the row first
                # (cc_row[3 l2 + s] = c[l1] c[l2], h3_row[r, 3 l2 + s] = h3[r, s]) so
                # that the update is one vectorisable loop: the same products and sums,
                # 12-17 % faster than three strided updates per l2 (13-79 pairs, N = 100)
                for r in range(3):
                    for l2 in range(2 * w):
                        h3_row[r, 3 * l2] = h3[r, 0]
                        h3_row[r, 3 * l2 + 1] = h3[r, 1]
                        h3_row[r, 3 * l2 + 2] = h3[r, 2]
                for l1 in range(2 * w):
                    c1 = c[l1]
                    if c1 == 0.0:
                        continue
                    for l2 in range(2 * w):
                        cc = c1 * c[l2]
                        cc_row[3 * l2] = cc
                        cc_row[3 * l2 + 1] = cc
                        cc_row[3 * l2 + 2] = cc
                    for r in range(3):
                        row = hess[p, 3 * l1 + r]
                        hr = h3_row[r]
                        for t in range(6 * w):
                            row[t] += cc_row[t] * hr[t]
        energy_out[p] = e * scale
        force[p] = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
        if f_sum > 0.0:
            param[p, 0] = ui / f_sum
            param[p, 1] = uj / f_sum
        else:
            param[p, 0] = 0.5
            param[p, 1] = 0.5


def barrier(gap: np.ndarray, stiffness: float, activation: float):
    """The integral formulation's barrier (``_psi`` kind 0) and its two derivatives."""
    out = np.array([_psi(0, float(g), stiffness, activation) for g in np.ravel(gap)])
    return out[:, 0], out[:, 1], out[:, 2]


def integral_terms(x: np.ndarray, stencil: np.ndarray, weights: np.ndarray, pairs: np.ndarray,
                   diameter: float, potential: str, stiffness: float, activation: float,
                   edge_length: float, order: int = 2, points: np.ndarray | None = None):
    """Terms of the double-integral contact energy for segment pairs ``pairs`` ``(m, 2)``.

    ``x`` ``(n, 3)`` nodes; ``stencil`` ``(k, w)`` node indices and ``weights``
    ``(k, q, w)`` their weights at each segment's ``q`` sample points.
    ``activation`` is the barrier's ``g_hat`` (a length; it also sets the
    normalisation ``1 / (2 D g_hat)`` of both potentials). Returns ``(energy
    (m,), gradient (m, 6w), Hessian (m, 6w, 6w), force (m,), parameters (m,
    2), dofs (m, 6w))``; the gradient and Hessian are zero when ``order`` is
    below 1 and 2. ``energy`` is ``inf`` for a pair with a sample gap ``<= 0``
    (barrier). ``points``: ``sample_points(x, stencil, weights)`` if the caller has
    them (the same values; otherwise each pair's are formed in the kernel).
    """
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    m = len(pairs)
    q, w = weights.shape[1], weights.shape[2]
    samples_weight = (edge_length / q) ** 2 / (2.0 * diameter * activation)
    energy = np.zeros(m)
    # the kernel writes the gradient (Hessian) only when order >= 1 (2)
    grad = np.zeros((m if order >= 1 else 1, 6 * w))
    hess = np.zeros((m if order >= 2 else 1, 6 * w, 6 * w))
    force = np.zeros(m)
    param = np.zeros((m, 2))
    # the DOFs of (3 nodes[:, :, None] + arange(3)).reshape(m, 6 w), nodes the pairs'
    # stencils side by side, written by the kernel (7 us as numpy steps at N = 100)
    dofs = np.empty((m, 6 * w), dtype=np.int64)
    if m:
        _integral_kernel(np.ascontiguousarray(x, dtype=np.float64), stencil, weights, pairs,
                         float(diameter), POTENTIALS[potential], float(stiffness),
                         float(activation), samples_weight, int(order), energy, grad, hess,
                         force, param,
                         np.zeros((1, 1, 3)) if points is None
                         else np.ascontiguousarray(points, dtype=np.float64),
                         points is not None, dofs)
    return energy, grad, hess, force, param, dofs


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
    the order of :func:`_integral_kernel`."""
    out = np.empty((weights.shape[0], weights.shape[1], 3))
    _sample_points_kernel(np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3),
                          np.ascontiguousarray(stencil, dtype=np.int64),
                          np.ascontiguousarray(weights, dtype=np.float64), out)
    return out


@njit(inline="always")
def _sample_pair_time(p0, v, i, a, j, b, t2):
    """Smaller root ``tau`` of ``|r0 + tau v|^2 = t2`` for sample point ``a`` of ``i``
    and ``b`` of ``j`` (positions ``p0``, displacements ``v``): -1.0 when they are
    already within (``c <= 0``), inf when they do not approach that close."""
    r0 = p0[i, a, 0] - p0[j, b, 0]
    r1 = p0[i, a, 1] - p0[j, b, 1]
    r2 = p0[i, a, 2] - p0[j, b, 2]
    v0 = v[i, a, 0] - v[j, b, 0]
    v1 = v[i, a, 1] - v[j, b, 1]
    v2 = v[i, a, 2] - v[j, b, 2]
    c = r0 * r0 + r1 * r1 + r2 * r2 - t2
    if c <= 0.0:
        return -1.0
    aa = v0 * v0 + v1 * v1 + v2 * v2
    bb = 2.0 * (r0 * v0 + r1 * v1 + r2 * v2)
    if aa <= 0.0 or bb >= 0.0:
        return math.inf
    disc = bb * bb - 4.0 * aa * c
    if disc < 0.0:
        return math.inf
    # smaller root of aa tau^2 + bb tau + c, in the stable form
    return 2.0 * c / (-bb + math.sqrt(disc))


@njit()
def _first_time_kernel(p0, v, pairs, threshold):
    """Smallest root over the sample pairs of ``pairs`` (see
    :func:`first_time_of_approach_samples`); 0.0 as soon as one pair is within
    ``threshold``, 1.0 when none comes that close."""
    q = p0.shape[1]
    t2 = threshold * threshold
    best = 1.0
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        for a in range(q):
            for b in range(q):
                tau = _sample_pair_time(p0, v, i, a, j, b, t2)
                if tau < 0.0:
                    return 0.0
                best = min(best, tau)
    return best


def first_time_of_approach_samples(x0: np.ndarray, dx: np.ndarray, stencil: np.ndarray,
                                   weights: np.ndarray, pairs: np.ndarray,
                                   threshold: float, points0: np.ndarray | None = None) -> float:
    """Earliest ``tau`` in ``[0, 1]`` at which two sample points of ``pairs`` come
    within ``threshold`` of each other, the nodes moving as ``x0 + tau dx``.

    Sample points are linear in the nodes, so each pair of them moves on a
    straight line relative to the other and ``|r0 + tau v|^2 = threshold^2`` is
    a quadratic in ``tau``: the time is exact (no conservative advancement,
    which crawls when strands slide along each other at small gaps). Returns
    1.0 when no pair gets that close, 0.0 when one already is. ``points0``: the sample
    points at ``x0`` if the caller has them (``sample_points(x0, stencil, weights)``,
    the same values).
    """
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return 1.0
    p0 = sample_points(x0, stencil, weights) if points0 is None else points0
    v = sample_points(dx, stencil, weights)
    return float(_first_time_kernel_culled(p0, v, pairs, float(threshold)))


# Relative margin of the culling bound of _first_time_kernel_culled (see there).
_CULL_MARGIN = 1e-6


@njit()
def _first_time_kernel_culled(p0, v, pairs, threshold):
    """:func:`_first_time_kernel` skipping the sample pairs that provably stay farther
    than ``threshold`` during the step; the same value.

    Segment ``i``'s sample points lie in the ball of centre ``c_i`` (their mean) and
    radius ``rho_i`` and move at most ``V_i = max_a |v_a|``; two of them, one of
    ``i`` and one of ``j``, stay at least ``|c_i - c_j| - rho_i - rho_j - V_i - V_j``
    apart for ``tau`` in ``[0, 1]``, and a sample point ``p_a`` of ``i`` at least
    ``|p_a - c_j| - rho_j - |v_a| - V_j`` from those of ``j``. Where that bound
    exceeds the threshold by ``m = 1e-6 (threshold + max rho + max V)``, no sample
    pair is within the threshold now (no early 0.0) and the first root of its
    quadratic lies beyond ``tau = 1`` by far more than its rounding (at least about
    ``sqrt(2 m threshold) / |v|`` after 1 where the approach is tangential, against
    a relative rounding of ``sqrt(eps)`` there), so it could only have returned
    ``min(best, tau) = best``: the pairs left give the same result. Measured at a
    late state of the ring (N = 200, 18 samples a segment, random steps): 1.01 ->
    0.36 ms for a step of one edge length (886 pairs within reach), 0.63 -> 0.31 ms
    for 0.3 h (552 pairs), 0.23 -> 0.25 ms for 0.03 h (136 pairs in contact, none
    culled: the pre-pass costs a tenth).
    """
    k, q = p0.shape[0], p0.shape[1]
    centre = np.zeros((k, 3))
    radius = np.zeros(k)
    speed = np.zeros(k)
    for i in range(k):
        for a in range(q):
            for c in range(3):
                centre[i, c] += p0[i, a, c]
        for c in range(3):
            centre[i, c] /= q
        for a in range(q):
            e0 = p0[i, a, 0] - centre[i, 0]
            e1 = p0[i, a, 1] - centre[i, 1]
            e2 = p0[i, a, 2] - centre[i, 2]
            radius[i] = max(radius[i], math.sqrt(e0 * e0 + e1 * e1 + e2 * e2))
            speed[i] = max(speed[i], math.sqrt(v[i, a, 0] ** 2 + v[i, a, 1] ** 2
                                               + v[i, a, 2] ** 2))
    far = threshold + _CULL_MARGIN * (threshold + np.max(radius) + np.max(speed))
    t2 = threshold * threshold
    best = 1.0
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        g0 = centre[i, 0] - centre[j, 0]
        g1 = centre[i, 1] - centre[j, 1]
        g2 = centre[i, 2] - centre[j, 2]
        if math.sqrt(g0 * g0 + g1 * g1 + g2 * g2) - radius[i] - radius[j] - speed[i] \
                - speed[j] > far:
            continue
        for a in range(q):
            h0 = p0[i, a, 0] - centre[j, 0]
            h1 = p0[i, a, 1] - centre[j, 1]
            h2 = p0[i, a, 2] - centre[j, 2]
            va = math.sqrt(v[i, a, 0] ** 2 + v[i, a, 1] ** 2 + v[i, a, 2] ** 2)
            if math.sqrt(h0 * h0 + h1 * h1 + h2 * h2) - radius[j] - va - speed[j] > far:
                continue
            for b in range(q):
                tau = _sample_pair_time(p0, v, i, a, j, b, t2)
                if tau < 0.0:
                    return 0.0
                best = min(best, tau)
    return best


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
def _bounding_spheres(points, centre, radius):
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
        _bounding_spheres(points, centre, radius)
    for p in range(pairs.shape[0]):
        d_out[p], a_out[p], b_out[p] = _closest_sample_pair(points, centre, radius, pairs[p, 0],
                                                            pairs[p, 1], cutoff, bounded)


@njit()
def _closest_samples_within_kernel(points, centre, radius, pairs, cutoff, pairs_out, d_out,
                                   s_out, t_out):
    """The pairs of ``pairs`` whose closest sample points are within the finite ``cutoff``,
    in their order, written to the first ``count`` rows of the outputs (``s``, ``t``
    the sample parameters ``(a + 1/2) / q``); returns ``count``. ``centre``, ``radius``:
    :func:`_bounding_spheres` of ``points``."""
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
    ``centre``, ``radius``: the bounding spheres of :func:`sample_state`. The arrays are
    views of buffers of ``m`` rows."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    m = len(pairs)
    kept = np.empty((m, 2), dtype=np.int64)
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    count = _closest_samples_within_kernel(points, centre, radius, pairs, float(cutoff), kept,
                                           d, s, t) if m else 0
    return kept[:count], d[:count], s[:count], t[:count]


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
    """:func:`_sample_points_kernel`, :func:`_bounding_spheres` and the largest of
    :func:`_chord_deviation_kernel` (segment ``i`` from ``x[segments[i, 0]]`` to
    ``x[segments[i, 1]]``) in one pass, the same sums; returns that largest deviation
    (0.0 without segments, nan if one is nan, as ``np.max(..., initial=0.0)``)."""
    _sample_points_kernel(x, stencil, weights, points)
    _bounding_spheres(points, centre, radius)
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
    25 us at N = 100; the spheres serve :func:`closest_samples_within`)."""
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
