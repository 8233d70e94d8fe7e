"""Broad phase of self-contact: the segment pairs that may be closer than a cutoff.

A rod is a tube of diameter ``D`` around a polygonal centreline. Self-contact
needs the pairs of segments ``(i, j)`` whose distance is at most a cutoff
(``D`` plus a margin) and that lie far enough apart *along the rod* (the
arc-length neighbour exclusion; Coleman & Swigon 2002 exclude points closer
than about ``πD/2`` along the rod, which can never touch without a kink). The narrow phase
(`supercoil.contact.distance.segment_distance`) then measures the candidates.

Segments are described generically, so closed rods, open rods and rods whose
end segments are half-edges all fit: segment ``i`` runs from ``starts[i]`` to
``ends[i]`` in space and from ``s_start[i]`` to ``s_end[i]`` in arc length.

Bounding test. With midpoint ``m_i = (starts[i] + ends[i]) / 2`` and half chord
``r_i = |ends[i] − starts[i]| / 2``, every point of segment ``i`` lies in the
ball of radius ``r_i`` about ``m_i``, so by the triangle inequality

    dist(seg_i, seg_j) ≤ cutoff   ⇒   |m_i − m_j| ≤ cutoff + r_i + r_j.

The pairs that pass the right-hand test are therefore a superset of the pairs
within the cutoff. The test is widened by ``1e-12 × scale`` (``scale`` = the
largest of the coordinates' magnitudes and the cutoff) so that the superset
property also holds under rounding, for both methods alike.

Arc-length separation. Two segments are separated by the arc length between
their nearest points along the rod: ``max(0, s_start[j] − s_end[i],
s_start[i] − s_end[j])`` on an open rod. On a closed rod of length ``P``
(``period``) the arcs live on a circle; with ``δ = (s_start[j] − s_start[i])
mod P`` and arc lengths ``ℓ = s_end − s_start`` the separation is

    max(0, min(δ − ℓ_i, P − δ − ℓ_j)),

the shorter of the two gaps around the loop (zero when the arcs overlap or
touch, e.g. the last and the first segment of a closed polygon). A pair is kept
when its separation is at least ``exclusion − 1e-12 × s_scale`` (``s_scale`` =
the period or the largest ``|s|``): a pair exactly at the exclusion, such as
segments ``i`` and ``i + 3`` of a uniform polygon with ``exclusion = 2h``, is
kept even if rounding puts it an ulp short.

Methods. ``"kdtree"`` and ``"brute"`` differ in the prefilter that proposes
block pairs (:mod:`supercoil.contact.broadphase_blocks`, which says why blocks
and a KD tree); one compiled loop (numba) then applies the exact per-pair tests
to the segment pairs of the remaining block pairs. Both apply the same exact
tests to a superset of the answer, so they return the same array; ``"brute"`` is
the reference the tests compare against.

Cost. The tree is O(N log N) to build and query plus the output. At a fixed
geometry refined with N, the output itself grows faster than N: where two
strands are in line contact (a plectoneme) the bounding test, which is ``h``
wider than the cutoff, holds for O(sqrt(cutoff / h)) segments of the other
strand per segment (the strands separate quadratically away from the closest
point), so the answer has O(N^1.5) pairs (docs/performance.md, "Contact
detection").
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit
from supercoil.contact.broadphase_blocks import (
    PREFILTER_SLACK,
    brute_prefilter,
    kdtree_prefilter,
    single_members,
    upper_pairs,
)

__all__ = ["candidate_pairs", "pair_separation", "polygon_segments", "verlet_displacement"]

METHODS = ("kdtree", "brute")

# Relative widening of the tests, see the module docstring.
_ROUNDING_SLACK = 1e-12
# Up to this many segments the exact tests run on every pair, without the blocks
# (:mod:`supercoil.contact.broadphase_blocks`, "Small rods").
_ALL_PAIRS_UP_TO = 128


def polygon_segments(
    points: np.ndarray, closed: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float | None]:
    """Segments between consecutive vertices of a polygon, with arc length by chord lengths.

    Parameters
    ----------
    points : (n, 3) vertices; for a closed polygon the first vertex is not repeated
        at the end (n ≥ 3), for an open one n ≥ 2.
    closed : whether the last vertex is joined to the first.

    Returns
    -------
    starts, ends : (k, 3) segment end points, ``k = n`` (closed) or ``n − 1`` (open);
    s_start, s_end : (k,) arc length at the segment ends, ``s_start[0] = 0``,
        ``s_end[i] = s_start[i] + |ends[i] − starts[i]|``;
    period : the total length for a closed polygon, else None.
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {points.shape}")
    minimum = 3 if closed else 2
    if points.shape[0] < minimum:
        kind = "closed" if closed else "open"
        raise ValueError(f"a {kind} polygon needs at least {minimum} points, got {points.shape[0]}")
    if not np.all(np.isfinite(points)):
        raise ValueError("points must be finite")
    starts = points if closed else points[:-1]
    ends = np.roll(points, -1, axis=0) if closed else points[1:]
    lengths = np.linalg.norm(ends - starts, axis=1)
    s_end = np.cumsum(lengths)
    s_start = s_end - lengths
    # s_start[i + 1] == s_end[i] exactly, so consecutive segments touch in arc length.
    s_start[1:] = s_end[:-1]
    s_start[0] = 0.0
    period = float(s_end[-1]) if closed else None
    return starts.copy(), ends.copy(), s_start, s_end, period


def pair_separation(
    first: np.ndarray,
    second: np.ndarray,
    s_start: np.ndarray,
    s_end: np.ndarray,
    period: float | None = None,
) -> np.ndarray:
    """Arc-length separation (m,) of the segment pairs ``(first[m], second[m])``.

    Open rod: ``max(0, s_start[j] − s_end[i], s_start[i] − s_end[j])``. Closed rod
    of length ``P = period``: ``max(0, min(δ − ℓ_i, P − δ − ℓ_j))`` with
    ``δ = (s_start[j] − s_start[i]) mod P`` and ``ℓ = s_end − s_start`` (the
    shorter gap around the loop). No validation: `candidate_pairs` validates.
    """
    if period is None:
        gap = np.maximum(s_start[second] - s_end[first], s_start[first] - s_end[second])
        return np.maximum(gap, 0.0, out=gap)
    lengths = s_end - s_start
    wrapped_start = np.mod(s_start, period)
    # np.mod on every pair would cost half of the whole broad phase; the
    # difference of two wrapped starts lies in (−P, P] and needs one shift at most.
    offset = wrapped_start[second] - wrapped_start[first]
    offset += np.where(offset < 0.0, period, 0.0)
    forward = offset - lengths[first]
    backward = np.subtract(period, offset, out=offset)
    backward -= lengths[second]
    separation = np.minimum(forward, backward, out=forward)
    return np.maximum(separation, 0.0, out=separation)


def candidate_pairs(
    starts: np.ndarray,
    ends: np.ndarray,
    s_start: np.ndarray,
    s_end: np.ndarray,
    cutoff: float,
    exclusion: float,
    period: float | None = None,
    method: str = "kdtree",
) -> np.ndarray:
    """All pairs (i, j), i < j, of segments that may be within ``cutoff`` and are not excluded.

    A pair is returned when its arc-length separation along the rod is
    ``≥ exclusion`` and the bounding test ``|m_i − m_j| ≤ cutoff + r_i + r_j``
    passes (``m`` = midpoint, ``r = |end − start| / 2``); both tests are widened
    by ``1e-12`` relative to the problem's scale (module docstring). The result
    is a superset of the pairs with segment–segment distance ``≤ cutoff`` and
    separation ``≥ exclusion``.

    Parameters
    ----------
    starts, ends : (k, 3) segment end points.
    s_start, s_end : (k,) arc-length positions of the segment ends along the rod,
        ``s_end ≥ s_start``. The separation of two segments is the arc length
        between their nearest points along the rod (0 if they share a point),
        measured around the loop (the shorter way) when ``period`` is given.
    cutoff : distance threshold, finite and ≥ 0.
    exclusion : arc-length neighbour exclusion, ≥ 0 (``inf`` excludes every pair).
    period : total length of a closed rod (> 0, at least every ``s_end − s_start``),
        or None for an open rod.
    method : ``"kdtree"`` (`scipy.spatial.cKDTree` on the midpoints, O(N log N))
        or ``"brute"`` (all pairs in bounded-memory blocks; the reference).

    Returns
    -------
    (m, 2) int64 array of pairs with ``i < j``, sorted lexicographically.
    """
    starts, ends, s_start, s_end = _validated(
        starts, ends, s_start, s_end, cutoff, exclusion, period, method
    )
    cutoff, exclusion = float(cutoff), float(exclusion)
    n_segments = starts.shape[0]
    if n_segments < 2 or exclusion == np.inf:
        return np.empty((0, 2), dtype=np.int64)

    midpoints = 0.5 * (starts + ends)
    half_chords = 0.5 * np.linalg.norm(ends - starts, axis=1)
    scale = max(float(np.max(np.abs(starts))), float(np.max(np.abs(ends))), cutoff)
    distance_slack = _ROUNDING_SLACK * scale
    if period is None:
        s_scale = max(float(np.max(np.abs(s_start))), float(np.max(np.abs(s_end))))
    else:
        s_scale = period
    separation_floor = exclusion - _ROUNDING_SLACK * s_scale

    arc_start = s_start if period is None else np.mod(s_start, period)
    arc_length = s_end - s_start
    arc_end = s_end if period is None else arc_start + arc_length
    if method == "kdtree" and n_segments <= _ALL_PAIRS_UP_TO:
        block_a, block_b = upper_pairs(n_segments)
        members = single_members(n_segments)
    elif method == "kdtree":
        block_a, block_b, members = kdtree_prefilter(
            midpoints,
            half_chords + distance_slack,
            arc_start,
            arc_end,
            cutoff,
            exclusion - PREFILTER_SLACK * s_scale,
        )
    else:
        block_a, block_b = brute_prefilter(midpoints, half_chords, cutoff + distance_slack)
        members = np.arange(n_segments, dtype=np.int64)[:, None]

    keys = np.empty(block_a.size * members.shape[1] ** 2, dtype=np.int64)
    x, y, z = (np.ascontiguousarray(midpoints[:, axis]) for axis in range(3))
    # writable arrays (a copy of a read-only one): one compiled specialisation
    count = _exact_tests(
        np.require(block_a, np.int64, "CW"),
        np.require(block_b, np.int64, "CW"),
        np.require(members, np.int64, "CW"),
        x,
        y,
        z,
        half_chords,
        arc_start,
        arc_end,
        arc_length,
        -1.0 if period is None else float(period),
        cutoff + distance_slack,
        separation_floor,
        keys,
    )
    # i < j < k, so i·k + j orders the pairs lexicographically.
    keys = np.sort(keys[:count])
    return np.column_stack([keys // n_segments, keys % n_segments])


@njit(error_model="numpy")
def _exact_tests(
    block_a,
    block_b,
    members,
    x,
    y,
    z,
    half_chords,
    arc_start,
    arc_end,
    arc_length,
    period,
    cutoff,
    separation_floor,
    keys,
):
    """Write ``i·k + j`` (i < j) of the pairs that pass both exact tests; return their count.

    The pairs tested are (members[A, u], members[B, v]) for every block pair (A, B)
    (u < v when A == B; padding −1 skipped). The separation is `pair_separation`'s
    formula (``period < 0``: open rod, ``arc_start``, ``arc_end`` = ``s_start``, ``s_end``;
    closed rod: ``arc_start`` wrapped into ``[0, P)``, ``arc_length = s_end − s_start``); the bounding test is ``|m_i − m_j|² ≤ (cutoff + r_i + r_j)²``. One
    compiled loop: the same tests as numpy expressions made about twenty passes
    over the pairs (measured 2.5× slower at N = 10000, see the module docstring).
    """
    n_segments = x.size
    width = members.shape[1]
    count = 0
    for pair in range(block_a.size):
        a = block_a[pair]
        b = block_b[pair]
        for u in range(width):
            i = members[a, u]
            if i < 0:
                continue
            for v in range(u + 1 if a == b else 0, width):
                j = members[b, v]
                if j < 0:
                    continue
                first, second = (i, j) if i < j else (j, i)
                if period < 0.0:
                    gap = max(
                        arc_start[second] - arc_end[first], arc_start[first] - arc_end[second]
                    )
                else:
                    offset = arc_start[second] - arc_start[first]
                    if offset < 0.0:
                        offset += period
                    gap = min(offset - arc_length[first], (period - offset) - arc_length[second])
                if max(gap, 0.0) < separation_floor:
                    continue
                dx = x[first] - x[second]
                dy = y[first] - y[second]
                dz = z[first] - z[second]
                bound = cutoff + half_chords[first] + half_chords[second]
                if dx * dx + dy * dy + dz * dz <= bound * bound:
                    keys[count] = first * n_segments + second
                    count += 1
    return count


def _validated(starts, ends, s_start, s_end, cutoff, exclusion, period, method):
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    starts = np.asarray(starts, dtype=float)
    ends = np.asarray(ends, dtype=float)
    if starts.ndim != 2 or starts.shape[1] != 3:
        raise ValueError(f"starts must have shape (k, 3), got {starts.shape}")
    if ends.shape != starts.shape:
        raise ValueError(f"ends must have the shape of starts {starts.shape}, got {ends.shape}")
    n_segments = starts.shape[0]
    s_start = np.asarray(s_start, dtype=float)
    s_end = np.asarray(s_end, dtype=float)
    for name, values in (("s_start", s_start), ("s_end", s_end)):
        if values.shape != (n_segments,):
            raise ValueError(f"{name} must have shape ({n_segments},), got {values.shape}")
    for name, values in (
        ("starts", starts),
        ("ends", ends),
        ("s_start", s_start),
        ("s_end", s_end),
    ):
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{name} must be finite")
    if np.any(s_end < s_start):
        raise ValueError("s_end must be >= s_start for every segment")
    if not _is_real(cutoff) or not np.isfinite(cutoff) or cutoff < 0:
        raise ValueError(f"cutoff must be a finite number >= 0, got {cutoff!r}")
    if not _is_real(exclusion) or np.isnan(exclusion) or exclusion < 0:
        raise ValueError(f"exclusion must be a number >= 0, got {exclusion!r}")
    if period is not None:
        if not _is_real(period) or not np.isfinite(period) or period <= 0:
            raise ValueError(f"period must be a finite number > 0 or None, got {period!r}")
        if n_segments and np.max(s_end - s_start) > period:
            raise ValueError("a segment is longer in arc length than the period")
    return starts, ends, s_start, s_end


def _is_real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


@njit()
def _displacement_kernel(x, x_ref):
    largest = 0.0
    moved2 = 0.0
    for i in range(x.shape[0]):
        d0 = x[i, 0] - x_ref[i, 0]
        d1 = x[i, 1] - x_ref[i, 1]
        d2 = x[i, 2] - x_ref[i, 2]
        dd = d0 * d0 + d1 * d1 + d2 * d2
        if not math.isnan(moved2) and (dd > moved2 or math.isnan(dd)):  # nan stays (np.max)
            moved2 = dd
        for c in range(3):
            a = abs(x[i, c])
            if not math.isnan(largest) and (a > largest or math.isnan(a)):
                largest = a
    return largest, math.sqrt(moved2)


def verlet_displacement(x: np.ndarray, x_ref: np.ndarray) -> tuple[float, float]:
    """``(max |x|, largest node displacement |x_k - x_ref_k|)`` of nodes ``(n, 3)`` (n >= 1),
    the values of ``np.max(np.abs(x))`` and ``sqrt(max(sum((x - x_ref)**2, axis=1)))``
    (nan if some coordinate is nan), in one compiled call: a Verlet list's test of
    whether it still holds (``ContactCurve._candidates``, some 3000 calls on the
    tweezers' contact branch, 12 us each as numpy reductions at N = 100)."""
    # writable arrays (a copy of a read-only one): one compiled specialisation
    return _displacement_kernel(np.require(x, np.float64, "CW"),
                                np.require(x_ref, np.float64, "CW"))
