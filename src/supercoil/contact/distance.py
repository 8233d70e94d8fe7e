"""Segment–segment distance with exact first and second derivatives.

Notation. Two segments ``p(s) = p0 + s e_p`` and ``q(t) = q0 + t e_q`` with
``e_p = p1 - p0``, ``e_q = q1 - q0`` and ``s, t`` in ``[0, 1]``; ``w = p0 - q0``,
``r(s, t) = p(s) - q(t)``. The distance is ``d = min |r(s, t)|`` over the unit
square.

Classification (Li et al., *Incremental Potential Contact*, SIGGRAPH 2020,
supplementary "edge-edge distance"). The minimum of the convex quadratic
``|r|^2`` over the square is attained either

* in the interior: the *edge–edge* type, the distance of the two infinite
  lines ``|w . n| / |n|`` with ``n = e_p x e_q``;
* on a side of the square with the foot strictly inside the other segment:
  one of four *point–edge* types, the distance of an endpoint to the infinite
  line of the other segment, ``|(x - a) x e| / |e|``;
* at a corner: one of four *point–point* types, ``|x - y|``.

So ``d`` is the minimum over five candidates — the interior critical point
(when it lies in the square) and the four endpoint-to-segment distances — and
the type is the candidate that attains it (``DistanceKind``). Each type is
a smooth function of the 12 coordinates where it is active, and ``d`` is C¹
across the boundaries between types (at a boundary the stationarity condition
of the free parameter holds for both neighbouring types, so their gradients
agree); the Hessian jumps there.

Derivatives. Write ``h = |r|^2 / 2 = |C(s, t) x|^2 / 2`` with ``x`` the 12
coordinates ``(p0, p1, q0, q1)`` and ``C = c ⊗ I_3``,
``c = (1 - s, s, -(1 - t), -t)``. A type minimises ``h`` over its free
parameters ``u`` (``(s, t)``, ``t``, ``s`` or none), so by the envelope
theorem and the implicit function theorem

    grad h = C^T r,      hess h = C^T C - h_xu h_uu^{-1} h_ux,

with ``h_uu = [[e_p.e_p, -e_p.e_q], [-e_p.e_q, e_q.e_q]]`` (restricted to the
free parameters), ``d h_s / d x_k = c_k e_p + dp_k r`` and
``d h_t / d x_k = -(c_k e_q + dq_k r)`` where ``dp = (-1, 1, 0, 0)``,
``dq = (0, 0, -1, 1)``. Then with ``r̂ = r / d``

    grad d = c ⊗ r̂,      hess d = (hess h - grad d grad d^T) / d.

These are the exact derivatives of the closed-form type functions (checked
against JAX autodiff and finite differences in ``tests/test_contact_distance.py``).

Near-parallel segments. The edge–edge Hessian contains ``h_uu^{-1}``, which
grows like ``1 / sin^2 θ`` (the distance's Hessian like ``1 / sin θ``); for
exactly parallel segments the line distance is not even differentiable. When
``|e_p x e_q|^2 <= parallel_tolerance |e_p|^2 |e_q|^2`` (``sin^2 θ`` below the
tolerance) :func:`segment_distance_derivatives` therefore drops the edge–edge
candidate and uses the minimum over the point–edge / point–point types. That is
exact for parallel segments (some minimiser then lies on the boundary of the
square), and its derivatives stay bounded (``O(1/d + 1/ℓ)``), which keeps line
contacts — two parallel strands of a plectoneme — smooth enough for Newton.
For a near-parallel pair whose exact minimiser is interior, the fallback
over-estimates the distance: along the valley of ``|r|^2`` the distance from a
point of one line to the other line is ``sqrt(d^2 + (δs ℓ_p sin θ)^2)``, and the
valley leaves the square within ``|δs| <= 1`` (and ``|δt| <= 1``), so

    0 <= d_fallback - d <= sqrt(d^2 + ℓ_min^2 sin^2 θ) - d
                         <= min(ℓ_min sin θ, ℓ_min^2 sin^2 θ / (2 d)),

``ℓ_min = min(|e_p|, |e_q|)``. With the default ``parallel_tolerance = 1e-6``
this is at most ``ℓ_min^2 / (2e6 d)`` (``5e-7 ℓ`` for ``d ≈ ℓ``). The returned
function therefore jumps by at most this amount where ``sin^2 θ`` crosses the
tolerance; elsewhere it is C¹ as above. :func:`segment_distance` never uses the
fallback: it is exact in all cases.

What the fallback does not fix: at exactly parallel overlapping segments the
exact distance itself is not differentiable (its minimisers form a segment, so
only directional derivatives exist), and the fallback's gradient is that of one
end of the overlap. Where two endpoint types are equally close — the two ends
of the overlap of two exactly parallel segments — the fallback is the minimum of
two smooth functions: bounded Hessian, but a gradient that switches between
them (the contact force moves from one end of the overlap to the other).
Smoothing that (e.g. summing the endpoint–segment terms in the energy) belongs
to the contact potential, not to this distance.

Accuracy. The textbook closest parameters of the two lines,
``s* = (b e_w - c d_w) / (ac - b^2)`` and ``t* = (a e_w - b d_w) / (ac - b^2)``
(``a, b, c = e_p.e_p, e_p.e_q, e_q.e_q``, ``d_w, e_w = e_p.w, e_q.w``), fail for
nearly parallel segments: the numerators are differences of products of size
``ℓ^3 |w|`` that cancel down to ``ℓ^4 sin^2 θ s*``, so ``s*`` carries an error
``~ ε |w| / (ℓ sin^2 θ)`` (``ε`` the machine epsilon). With them a pair 1.2e-8
apart at ``sin θ ≈ 1e-8`` came out 1.4 times too far, and coplanar segments
crossing at small angles came out up to ``4e9 ε (|w| + |e_p| + |e_q|)`` (1e-6 of
that size) apart instead of 0. By Lagrange's identity the
numerators are the triple products ``n.(e_q x w)`` and ``n.(e_p x w)``, whose
factors are formed from the coordinates directly: ``s*`` is then accurate to
``~ ε (1 + δ / (ℓ sin θ)) / sin θ`` (``δ`` the distance of the two lines).
Independent errors in ``s`` and ``t`` would still move the pair across the
narrow valley of ``|r|^2`` (by ``ℓ δs``), so the interior candidate takes ``t``
as the foot of ``p(s)`` on segment ``q`` (a well-conditioned projection): the
error is then along the valley, where the distance grows only like
``sqrt(d^2 + (δs ℓ sin θ)^2)``, i.e. ``O(ε ℓ)`` when ``sin θ >= δ / ℓ``. For
smaller angles the best endpoint candidate is within ``ℓ^2 sin^2 θ / (2 d)`` of
the exact distance (the fallback bound above) and the interior one within
``ε^2 δ / (2 sin^2 θ)``; the product of the two is ``(ε ℓ / 2)^2``, so the
smaller is ``O(ε ℓ)`` too. When the interior point lies in the square and
``sin^2 θ >= 1e-2`` it is the minimum (``|r|^2`` is convex) and accurate alone
(the error ``ε δ / sin θ`` stays ``O(ε δ)``): the endpoint candidates are then
skipped. Each candidate is the distance of two actual points,
so :func:`segment_distance` returns ``|d - d_exact| = O(ε (|w| + |e_p| + |e_q|))``
(plus a few ``1.5e-154``, where the squares underflow):
the exact distance of segments whose endpoints moved by a few units in the last
place, which is all that rounded coordinates allow (two segments of length 0.4
crossing in the plane z = 0 come out 6e-17 apart, not 0).
``tests/test_contact_distance.py`` checks this against exact rational arithmetic
on nearly parallel, crossing and generic pairs (at most ``0.93 ε (|w| + |e_p| +
|e_q|)`` measured on 48000 random pairs).

Degenerate cases. Zero-length segments, and segments whose squared length is
at most 1e-300, are points (their foot parameter is 0).
When ``d <= 1e-12 max(|e_p|, |e_q|)`` (crossing or touching segments, or two
coincident points) the distance is not differentiable: the gradient and the
Hessian returned are **zero** (finite), ``d`` is the computed value (tiny or 0)
and ``kind`` the type found. Callers refuse such states.

Speed. The kernels (:mod:`supercoil.contact.distance_kernels`, with
:class:`~supercoil.contact.distance_kernels.DistanceKind`) are compiled with numba
(one pass over the pairs, no temporary arrays per pair); no recompilation when the
number of pairs changes.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from supercoil.contact.distance_kernels import (
    derivative_kernel,
    distance_kernel,
    pairs_within_kernel,
)

__all__ = [
    "segment_distance",
    "segment_distance_derivatives",
    "segment_pairs_within",
]






def within_buffers(pairs) -> tuple[np.ndarray, ...]:
    """``(pairs, kept, d, s, t)`` of a within-cutoff pass over candidate ``pairs``: the
    pairs as ``(m, 2)`` int64 and the empty buffers of ``m`` rows it fills in order
    (the kept pairs, their distances and parameters)."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    m = len(pairs)
    return pairs, np.empty((m, 2), dtype=np.int64), np.empty(m), np.empty(m), np.empty(m)


def segment_pairs_within(x: np.ndarray, segments: np.ndarray, pairs: np.ndarray,
                         cutoff: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(pairs, d, s, t)`` of the segment pairs ``pairs`` ``(m, 2)`` within ``cutoff``,
    in their order: :func:`segment_distance` of the pairs' ends (``x`` ``(n, 3)`` the
    nodes, ``segments`` ``(k, 2)`` their end nodes) filtered by ``d <= cutoff``, the
    same values, in one compiled pass that skips the distance of pairs whose bounding
    spheres are apart. Measured at the tweezers' contact states (N = 100, some 1000
    candidate pairs, none within ``D/2`` plus a step): the step bound's polygon pair
    state took 92 us with the gathering, distances and filter as numpy steps, 12 us so.
    The arrays are views of buffers of ``m`` rows.
    Raises ValueError, as :func:`segment_distance`, when an end is not finite.
    """
    pairs, kept, d, s, t = within_buffers(pairs)
    m = len(pairs)
    count = pairs_within_kernel(np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3),
                                 np.ascontiguousarray(segments, dtype=np.int64), pairs,
                                 float(cutoff), kept, d, s, t) if m else 0
    if count < 0:
        raise ValueError("segment endpoints must be finite")
    return kept[:count], d[:count], s[:count], t[:count]


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------


def _as_segment_pairs(p0, p1, q0, q1) -> tuple[list[np.ndarray], tuple[int, ...]]:
    """Broadcast the four endpoint arrays to ``(..., 3)``; return them flat ``(m, 3)``."""
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (p0, p1, q0, q1)))
    shape = arrays[0].shape
    if len(shape) == 0 or shape[-1] != 3:
        raise ValueError(f"segment endpoints must have shape (m, 3) or (3,), got {shape}")
    flat = [np.ascontiguousarray(x.reshape(-1, 3)) for x in arrays]
    if not all(np.isfinite(x).all() for x in flat):
        raise ValueError("segment endpoints must be finite")
    return flat, shape[:-1]


def segment_distance(
    p0: npt.ArrayLike, p1: npt.ArrayLike, q0: npt.ArrayLike, q1: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest distance between the segments ``[p0, p1]`` and ``[q0, q1]``.

    The endpoints are arrays of shape ``(m, 3)`` (or ``(3,)``, or anything that
    broadcasts to a common ``(..., 3)``). Returns ``d, s, t`` of shape ``(m,)``
    (the broadcast batch shape) with ``d = |p0 + s (p1 - p0) - q0 - t (q1 - q0)|``
    and ``s, t`` in ``[0, 1]``: ``d`` is always attained by the returned points.

    Exact in every case up to rounding (within a few ``ε (|p0 - q0| + |p1 - p0|
    + |q1 - q0|)``, module docstring, "Accuracy"): the minimum over the interior
    critical point of the two lines (``s`` clamped, ``t`` the foot of ``p(s)`` on
    segment ``q``) and the four endpoint-to-segment distances (see the module
    docstring). For parallel or collinear
    overlapping segments, where the closest pair is not unique, one valid pair
    is returned (an endpoint of one segment); a zero-length segment has foot
    parameter 0.
    """
    (P0, P1, Q0, Q1), batch = _as_segment_pairs(p0, p1, q0, q1)
    m = P0.shape[0]
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    distance_kernel(P0, P1, Q0, Q1, d, s, t)
    _rescale_tiny_pairs(P0, P1, Q0, Q1, d, s, t)
    return d.reshape(batch), s.reshape(batch), t.reshape(batch)


TINY_EXTENT = 2.0**-200  # ~6e-61: below it the kernel's fourth-order products underflow


def _rescale_tiny_pairs(P0, P1, Q0, Q1, d, s, t) -> None:
    """Recompute, in place, the pairs whose whole extent (the differences from ``p0``)
    is below :data:`TINY_EXTENT`, on copies translated to ``p0`` and scaled to unit
    size: the triple products of the kernel are of fourth order in the lengths and
    underflow there (segments of 1e-127 came out 15 % off). Distances scale exactly
    with the coordinates and ``s, t`` do not change, so the result is the exact one
    up to rounding."""
    diffs = np.stack([P1 - P0, Q0 - P0, Q1 - P0])
    extent = np.abs(diffs).max(axis=(0, 2))
    rows = np.flatnonzero((extent > 0.0) & (extent < TINY_EXTENT))
    if rows.size == 0:
        return
    scale = extent[rows, None]
    zero = np.zeros((rows.size, 3))
    scaled = [np.ascontiguousarray(diffs[k, rows] / scale) for k in range(3)]
    dd, ss, tt = np.empty(rows.size), np.empty(rows.size), np.empty(rows.size)
    distance_kernel(zero, scaled[0], scaled[1], scaled[2], dd, ss, tt)
    d[rows], s[rows], t[rows] = dd * scale[:, 0], ss, tt


def segment_distance_derivatives(
    p0: npt.ArrayLike,
    p1: npt.ArrayLike,
    q0: npt.ArrayLike,
    q1: npt.ArrayLike,
    parallel_tolerance: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Distance, gradient and Hessian of the segment–segment distance.

    Returns ``d`` ``(m,)``, ``gradient`` ``(m, 12)``, ``hessian`` ``(m, 12, 12)``
    with respect to ``(p0, p1, q0, q1)`` flattened in that order (index
    ``3 k + xyz``, ``k = 0..3``), and ``kind`` ``(m,)`` int, the
    :class:`~supercoil.contact.distance_kernels.DistanceKind` of the smooth formula
    evaluated.

    Each type's closed-form distance (line–line, point–line or point–point,
    module docstring) is differentiated exactly. Segments with
    ``sin^2 θ <= parallel_tolerance`` never use the line–line type: the
    minimum over the point–edge and point–point types is used instead, exact
    for parallel segments, with bounded derivatives, and at most
    ``min(ℓ sin θ, ℓ^2 sin^2 θ / (2 d))`` above the true distance otherwise.
    For crossing pairs (``d <= 1e-12 max(|e_p|, |e_q|)``) the gradient and
    Hessian are returned as zeros.
    """
    if not (np.isfinite(parallel_tolerance) and 0.0 <= parallel_tolerance < 1.0):
        raise ValueError(f"parallel_tolerance must be in [0, 1), got {parallel_tolerance!r}")
    (P0, P1, Q0, Q1), batch = _as_segment_pairs(p0, p1, q0, q1)
    m = P0.shape[0]
    d = np.empty(m)
    gradient = np.empty((m, 12))
    hessian = np.empty((m, 12, 12))
    kind = np.empty(m, dtype=np.int64)
    derivative_kernel(P0, P1, Q0, Q1, float(parallel_tolerance), d, gradient, hessian, kind)
    return (d.reshape(batch), gradient.reshape(batch + (12,)),
            hessian.reshape(batch + (12, 12)), kind.reshape(batch))
