"""The first time of approach of sample points along a step (conservative advancement).

The integral formulation (:mod:`supercoil.contact.integral`) sees the curve only
at its sample points (:mod:`supercoil.contact.samples`): the barrier's step guard
keeps every sample gap above a fraction of its value along the step
(:func:`first_time_of_approach_samples`).
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit
from supercoil.contact.samples import sample_points


@njit(inline="always")
def sample_pair_time(p0, v, i, a, j, b, t2):
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
    return float(_first_time_kernel(p0, v, pairs, float(threshold)))


# Relative margin of the culling bound of _first_time_kernel (see there).
_CULL_MARGIN = 1e-6


@njit()
def _first_time_kernel(p0, v, pairs, threshold):
    """Smallest root of :func:`sample_pair_time` over the sample pairs of ``pairs`` (see
    :func:`first_time_of_approach_samples`): 0.0 as soon as one pair is within
    ``threshold``, 1.0 when none comes that close; the sample pairs that provably stay
    farther than ``threshold`` during the step are skipped (the same value as the loop
    over every pair: ``tests/test_contact_samples_fast.py``).

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
                tau = sample_pair_time(p0, v, i, a, j, b, t2)
                if tau < 0.0:
                    return 0.0
                best = min(best, tau)
    return best
