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
g_hat)`` of the region where ``psi`` acts
(:func:`~supercoil.contact.sample_weights.default_samples`).

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
    ``(k, q, 3)`` (:func:`~supercoil.contact.samples.sample_points`, the same sums)
    instead of formed again for every pair. ``dofs[p]`` ``(6 w,)`` gets the DOFs
    ``3 node + xyz`` of the stencil nodes of segment ``i``, then of segment ``j``.
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


