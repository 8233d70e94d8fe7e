"""Broad phase of self-contact (supercoil.contact.broadphase).

Oracles:

- the KD tree equals the brute-force reference (all pairs) on random curves of
  many kinds (random walks, points in a small ball, straight lines, coincident
  points, tightly wound helices; closed and open; exclusions from 0 to more
  than half the loop), and on fixed larger cases;
- the superset property against exact segment distances
  (`segment_distance`): every pair within the cutoff and not excluded is
  returned, including pairs exactly at the cutoff;
- the definition itself, evaluated pair by pair in plain Python with an
  independent arc-length separation (the smallest circular distance between
  the arcs' end points, 0 when the arcs overlap);
- exclusion semantics on hand-built cases with exact arc lengths (closed-loop
  wrap-around neighbours, pairs exactly at and just beyond the exclusion);
- invariances: relabelling the segments, shifting the arc-length origin of a
  closed rod;
- input validation.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from supercoil.contact.broadphase import candidate_pairs, pair_separation, polygon_segments
from supercoil.contact.distance import segment_distance

CURVE_KINDS = ("random_walk", "small_ball", "straight_line", "coincident_points", "tight_helix")


def make_curve(kind: str, n_points: int, seed: int) -> np.ndarray:
    """(n_points, 3) vertices of a test curve."""
    rng = np.random.default_rng(seed)
    if kind == "random_walk":
        return np.cumsum(rng.normal(size=(n_points, 3)), axis=0)
    if kind == "small_ball":  # everything within the cutoff of everything
        direction = rng.normal(size=(n_points, 3))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        return 0.05 * direction * rng.uniform(size=(n_points, 1)) ** (1 / 3)
    if kind == "straight_line":
        spacing = rng.uniform(0.1, 1.0, size=n_points)
        return np.outer(np.cumsum(spacing), rng.normal(size=3)) + rng.normal(size=3)
    if kind == "coincident_points":
        points = np.cumsum(rng.normal(size=(n_points, 3)), axis=0)
        repeated = rng.integers(0, n_points, size=n_points // 2)
        points[repeated] = points[rng.integers(0, n_points, size=repeated.size)]
        # and some zero-length segments
        doubled = rng.integers(1, n_points, size=n_points // 4)
        points[doubled] = points[doubled - 1]
        return points
    if kind == "tight_helix":  # pitch far below the radius: many close pairs
        turns = rng.uniform(2.0, 8.0)
        angle = np.linspace(0.0, 2 * np.pi * turns, n_points)
        pitch = rng.uniform(0.02, 0.2)
        return np.column_stack([np.cos(angle), np.sin(angle), pitch * angle / (2 * np.pi)])
    raise AssertionError(kind)


def separation_oracle(i, j, s_start, s_end, period):
    """Arc length between the nearest points of arcs i and j: 0 if they overlap, else the
    smallest (circular, if closed) distance between their end points."""
    a0, a1, b0, b1 = s_start[i], s_end[i], s_start[j], s_end[j]

    def distance(x, y):
        if period is None:
            return abs(x - y)
        d = math.fmod(abs(x - y), period)
        return min(d, period - d)

    def inside(x, start, end):  # x on the arc [start, end]
        if period is None:
            return start <= x <= end
        return math.fmod(x - start, period) % period <= end - start

    if inside(b0, a0, a1) or inside(a0, b0, b1):
        return 0.0
    return min(distance(x, y) for x in (a0, a1) for y in (b0, b1))


def definition_oracle(starts, ends, s_start, s_end, cutoff, exclusion, period, margin):
    """Pairs passing the bounding test and the exclusion by more than ``margin`` (sure),
    and pairs failing neither by more than ``margin`` (possible), pair by pair."""
    midpoints = 0.5 * (starts + ends)
    radii = 0.5 * np.linalg.norm(ends - starts, axis=1)
    sure, possible = set(), set()
    for i, j in itertools.combinations(range(len(starts)), 2):
        slack = cutoff + radii[i] + radii[j] - np.linalg.norm(midpoints[i] - midpoints[j])
        excess = separation_oracle(i, j, s_start, s_end, period) - exclusion
        if slack >= margin and excess >= margin:
            sure.add((i, j))
        if slack >= -margin and excess >= -margin:
            possible.add((i, j))
    return sure, possible


def assert_well_formed(pairs: np.ndarray, n_segments: int) -> None:
    assert pairs.dtype == np.int64 and pairs.ndim == 2 and pairs.shape[1] == 2
    assert np.all(pairs[:, 0] < pairs[:, 1])
    assert np.all((pairs >= 0) & (pairs < n_segments))
    keys = pairs[:, 0] * n_segments + pairs[:, 1]
    assert np.all(np.diff(keys) > 0)  # sorted lexicographically, no duplicates


@st.composite
def curves(draw):
    kind = draw(st.sampled_from(CURVE_KINDS))
    closed = draw(st.booleans())
    n_points = draw(st.integers(3 if closed else 2, 70))
    points = make_curve(kind, n_points, draw(st.integers(0, 2**32 - 1)))
    return kind, closed, points


@st.composite
def generic_segments(draw):
    """Unconnected segments with arbitrary (possibly overlapping) arcs, in random order."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n_segments = draw(st.integers(2, 60))
    starts = rng.normal(size=(n_segments, 3))
    ends = starts + rng.normal(scale=draw(st.sampled_from([0.0, 0.1, 1.0])), size=(n_segments, 3))
    period = draw(st.sampled_from([None, 5.0]))
    spread = draw(st.sampled_from([1.0, 10.0]))  # 1: most arcs overlap
    s_start = rng.uniform(-spread, spread, size=n_segments)
    s_end = s_start + rng.uniform(0.0, 2.0, size=n_segments)
    return "generic", starts, ends, s_start, s_end, period


@st.composite
def broad_phase_inputs(draw):
    if draw(st.integers(0, 5)) == 0:
        kind, starts, ends, s_start, s_end, period = draw(generic_segments())
        points = np.concatenate([starts, ends])
        length = period or float(np.ptp(np.concatenate([s_start, s_end])))
    else:
        kind, closed, points = draw(curves())
        starts, ends, s_start, s_end, period = polygon_segments(points, closed)
        length = float(s_end[-1])
        # a closed polygon of coincident vertices has no length: candidate_pairs refuses
        # its period 0 (test_a_closed_polygon_of_no_length_is_refused)
        assume(period is None or period > 0)
    extent = float(np.ptp(points, axis=0).max()) or 1.0
    cutoff = draw(st.sampled_from([0.0, 0.01, 0.1, 0.3, 1.0, 3.0])) * extent
    exclusion_fraction = draw(
        st.one_of(st.sampled_from([0.0, 0.5, 0.51, 1.0]), st.floats(0.0, 1.0))
    )
    exclusion = exclusion_fraction * length  # 0.51 and more: beyond half the loop
    return kind, starts, ends, s_start, s_end, cutoff, exclusion, period


@settings(max_examples=300, deadline=None)
@given(broad_phase_inputs())
def test_kdtree_equals_brute_force(case):
    _, starts, ends, s_start, s_end, cutoff, exclusion, period = case
    tree = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
    brute = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period, "brute")
    assert_well_formed(tree, starts.shape[0])
    np.testing.assert_array_equal(tree, brute)


@settings(max_examples=150, deadline=None)
@given(broad_phase_inputs())
def test_all_pairs_path_equals_the_blocks(case):
    """Up to ``_ALL_PAIRS_UP_TO`` segments the exact tests run on every pair; the blocks'
    prefilter (forced by a threshold below every size) gives the same array."""
    from supercoil.contact import broadphase

    _, starts, ends, s_start, s_end, cutoff, exclusion, period = case
    assert starts.shape[0] <= broadphase._ALL_PAIRS_UP_TO  # the strategy's sizes
    every_pair = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
    saved = broadphase._ALL_PAIRS_UP_TO
    try:
        broadphase._ALL_PAIRS_UP_TO = -1
        blocks = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
    finally:
        broadphase._ALL_PAIRS_UP_TO = saved
    np.testing.assert_array_equal(every_pair, blocks)


@settings(max_examples=150, deadline=None)
@given(broad_phase_inputs())
def test_output_is_the_definition(case):
    _, starts, ends, s_start, s_end, cutoff, exclusion, period = case
    pairs = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
    scale = max(1.0, float(np.abs(starts).max()), float(np.abs(s_end).max()))
    sure, possible = definition_oracle(
        starts, ends, s_start, s_end, cutoff, exclusion, period, 1e-9 * scale
    )
    found = set(map(tuple, pairs.tolist()))
    assert sure <= found <= possible


@settings(max_examples=150, deadline=None)
@given(broad_phase_inputs())
def test_superset_of_pairs_within_the_cutoff(case):
    _, starts, ends, s_start, s_end, cutoff, exclusion, period = case
    pairs = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
    found = set(map(tuple, pairs.tolist()))
    first, second = np.triu_indices(starts.shape[0], 1)
    distance, _, _ = segment_distance(starts[first], ends[first], starts[second], ends[second])
    separation = np.array(
        [separation_oracle(i, j, s_start, s_end, period) for i, j in zip(first, second)]
    )
    # the exclusion boundary itself is decided up to rounding (definition test above)
    s_tolerance = 1e-9 * float(np.abs(s_end).max())
    needed = (distance <= cutoff) & (separation >= exclusion + s_tolerance)
    assert set(zip(first[needed].tolist(), second[needed].tolist())) <= found


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("seed", range(4))
def test_pairs_exactly_at_the_cutoff_are_found(closed, seed):
    """cutoff = the exact distance of some pairs: rounding must not lose them."""
    points = make_curve("random_walk", 40, seed) * 1e3 + 5e3  # far from the origin
    starts, ends, s_start, s_end, period = polygon_segments(points, closed)
    first, second = np.triu_indices(starts.shape[0], 1)
    distance, _, _ = segment_distance(starts[first], ends[first], starts[second], ends[second])
    for cutoff in np.quantile(distance, [0.0, 0.01, 0.1, 0.5]):
        needed = distance <= cutoff
        for method in ("kdtree", "brute"):
            pairs = candidate_pairs(starts, ends, s_start, s_end, cutoff, 0.0, period, method)
            found = set(map(tuple, pairs.tolist()))
            assert set(zip(first[needed].tolist(), second[needed].tolist())) <= found


def test_crossing_segments_with_zero_cutoff():
    """Two segments far apart along the rod that cross in space are found with cutoff 0."""
    starts = np.array([[-1.0, 0.0, 0.0], [5.0, 5.0, 5.0], [0.0, -1.0, 0.0]])
    ends = np.array([[1.0, 0.0, 0.0], [6.0, 5.0, 5.0], [0.0, 1.0, 0.0]])
    s_start, s_end = np.array([0.0, 2.0, 4.0]), np.array([2.0, 3.0, 6.0])
    for method in ("kdtree", "brute"):
        pairs = candidate_pairs(starts, ends, s_start, s_end, 0.0, 1.0, method=method)
        np.testing.assert_array_equal(pairs, [[0, 2]])


# --------------------------------------------------------------------------
# exclusion semantics with exact arc lengths
# --------------------------------------------------------------------------


def unit_arcs(n_segments: int):
    """Segments [i, i + 1] in arc length, all within any cutoff of each other."""
    rng = np.random.default_rng(n_segments)
    starts = rng.normal(scale=1e-3, size=(n_segments, 3))
    ends = rng.normal(scale=1e-3, size=(n_segments, 3))
    s_start = np.arange(n_segments, dtype=float)
    return starts, ends, s_start, s_start + 1.0


def gap_pairs(n_segments: int, closed: bool, minimum_gap: float) -> list[tuple[int, int]]:
    """Pairs of unit arcs whose separation (number of arcs between them) is >= minimum_gap."""
    kept = []
    for i, j in itertools.combinations(range(n_segments), 2):
        gap = j - i - 1
        if closed:
            gap = min(gap, n_segments - (j - i) - 1)
        if gap >= minimum_gap:
            kept.append((i, j))
    return kept


@pytest.mark.parametrize("method", ["kdtree", "brute"])
@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("exclusion", [0.0, 0.5, 1.0, 2.0, 4.5, 5.0, 5.5, 11.0, 12.0, np.inf])
def test_exclusion_on_unit_arcs(method, closed, exclusion):
    n_segments = 12
    starts, ends, s_start, s_end = unit_arcs(n_segments)
    period = float(n_segments) if closed else None
    pairs = candidate_pairs(starts, ends, s_start, s_end, 1.0, exclusion, period, method)
    # exclusion 0 keeps neighbours (gap 0); a gap equal to the exclusion is kept
    expected = gap_pairs(n_segments, closed, exclusion)
    assert list(map(tuple, pairs.tolist())) == expected


@pytest.mark.parametrize("method", ["kdtree", "brute"])
@pytest.mark.parametrize("period", [None, 3.0])
def test_overlapping_arcs_are_not_excluded(method, period):
    """Arcs that overlap have separation 0: kept with exclusion 0, dropped with any more."""
    rng = np.random.default_rng(1)
    starts = rng.normal(scale=0.1, size=(40, 3))
    ends = rng.normal(scale=0.1, size=(40, 3))
    s_start = np.linspace(0.0, 0.9, 40)
    s_end = s_start + 1.0
    pairs = candidate_pairs(starts, ends, s_start, s_end, 10.0, 0.0, period, method)
    assert len(pairs) == 40 * 39 // 2
    assert len(candidate_pairs(starts, ends, s_start, s_end, 10.0, 1e-6, period, method)) == 0


@pytest.mark.parametrize("method", ["kdtree", "brute"])
def test_closed_loop_wrap_around(method):
    n_segments = 12
    starts, ends, s_start, s_end = unit_arcs(n_segments)
    found = set(
        map(tuple, candidate_pairs(starts, ends, s_start, s_end, 1.0, 1.0, 12.0, method).tolist())
    )
    assert (0, 11) not in found  # last and first segment share a point
    assert {(0, 10), (1, 11), (0, 2)} <= found  # one segment in between, either way
    found = set(
        map(tuple, candidate_pairs(starts, ends, s_start, s_end, 1.0, 2.0, 12.0, method).tolist())
    )
    assert {(0, 10), (1, 11), (0, 2), (0, 11)}.isdisjoint(found)
    assert {(0, 9), (2, 11), (0, 3)} <= found
    # the open rod has no wrap-around: first and last are 10 arcs apart
    found = set(
        map(tuple, candidate_pairs(starts, ends, s_start, s_end, 1.0, 10.0, None, method).tolist())
    )
    assert found == {(0, 11)}


@pytest.mark.parametrize("method", ["kdtree", "brute"])
@pytest.mark.parametrize("closed", [True, False])
def test_pairs_just_beyond_the_exclusion_are_kept(method, closed):
    """Arc lengths with rounding (h = 0.1): segments i and i + 3 are exactly 2h apart."""
    n_points = 30
    angle = 2 * np.pi * np.arange(n_points) / n_points
    radius = 0.1 / (2 * np.sin(np.pi / n_points))  # chords of length 0.1
    points = radius * np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n_points)])
    starts, ends, s_start, s_end, period = polygon_segments(points, closed)
    pairs = candidate_pairs(starts, ends, s_start, s_end, 10.0, 0.2, period, method)
    found = set(map(tuple, pairs.tolist()))
    n_segments = starts.shape[0]
    assert {(i, i + 3) for i in range(n_segments - 3)} <= found
    assert not any(j - i < 3 for i, j in found)
    if closed:
        assert (0, n_segments - 3) in found and (0, n_segments - 2) not in found
    # a hair more and they go
    pairs = candidate_pairs(starts, ends, s_start, s_end, 10.0, 0.2 + 1e-6, period, method)
    assert not any(j - i == 3 for i, j in pairs.tolist())


@pytest.mark.parametrize("method", ["kdtree", "brute"])
def test_half_edge_end_segments(method):
    """Open rod whose first and last segments are half edges (arc lengths given directly)."""
    edges = np.array([0.5, 1.0, 1.0, 1.0, 0.5])
    s_end = np.cumsum(edges)
    s_start = s_end - edges
    points = np.column_stack([np.concatenate([[0.0], s_end]), np.zeros(6), np.zeros(6)])
    starts, ends = points[:-1], points[1:]
    pairs = candidate_pairs(starts, ends, s_start, s_end, 10.0, 1.0, None, method)
    # separations: (0,2) 1.0, (0,3) 2.0, (0,4) 3.0, (1,3) 1.0, (1,4) 2.0, (2,4) 1.0
    assert pairs.tolist() == [[0, 2], [0, 3], [0, 4], [1, 3], [1, 4], [2, 4]]
    pairs = candidate_pairs(starts, ends, s_start, s_end, 10.0, 1.5, None, method)
    assert pairs.tolist() == [[0, 3], [0, 4], [1, 4]]


def test_pair_separation_matches_the_oracle():
    rng = np.random.default_rng(7)
    for period in (None, 10.0):
        lengths = rng.uniform(0.0, 3.0, size=50)
        s_start = rng.uniform(-20.0, 20.0, size=50)
        s_end = s_start + lengths
        first, second = np.triu_indices(50, 1)
        expected = [separation_oracle(i, j, s_start, s_end, period) for i, j in zip(first, second)]
        np.testing.assert_allclose(
            pair_separation(first, second, s_start, s_end, period), expected, atol=1e-12
        )


# --------------------------------------------------------------------------
# invariances and larger cases
# --------------------------------------------------------------------------


@pytest.mark.parametrize("closed", [True, False])
def test_relabelling_the_segments(closed):
    points = make_curve("tight_helix", 400, 3)
    starts, ends, s_start, s_end, period = polygon_segments(points, closed)
    reference = candidate_pairs(starts, ends, s_start, s_end, 0.15, 0.5, period)
    assert len(reference) > 1000
    order = np.random.default_rng(0).permutation(starts.shape[0])
    shuffled = candidate_pairs(
        starts[order], ends[order], s_start[order], s_end[order], 0.15, 0.5, period
    )
    relabelled = np.sort(order[shuffled], axis=1)
    assert set(map(tuple, relabelled.tolist())) == set(map(tuple, reference.tolist()))


def test_a_closed_polygon_of_no_length_is_refused():
    """Found by hypothesis: three coincident vertices, closed, make the period 0."""
    starts, ends, s_start, s_end, period = polygon_segments(np.ones((3, 3)), True)
    assert period == 0.0
    with pytest.raises(ValueError, match="period must be a finite number > 0"):
        candidate_pairs(starts, ends, s_start, s_end, 0.1, 0.0, period)


def test_arc_length_origin_of_a_closed_rod():
    points = make_curve("tight_helix", 300, 5)
    starts, ends, s_start, s_end, period = polygon_segments(points, True)
    reference = candidate_pairs(starts, ends, s_start, s_end, 0.2, 0.7, period)
    for shift in (3.3 * period, -0.37 * period, 1e3):
        shifted = candidate_pairs(starts, ends, s_start + shift, s_end + shift, 0.2, 0.7, period)
        np.testing.assert_array_equal(shifted, reference)


def test_two_rods_in_one_call():
    """A gap in arc length and space (two open rods) between blocks of the tree."""
    first_rod = make_curve("tight_helix", 501, 1)
    second_rod = make_curve("random_walk", 300, 2) * 0.02 + np.array([1e3, 0.0, 0.0])
    segments = [polygon_segments(points, False) for points in (first_rod, second_rod)]
    starts = np.concatenate([segments[0][0], segments[1][0]])
    ends = np.concatenate([segments[0][1], segments[1][1]])
    offset = segments[0][3][-1] + 100.0
    s_start = np.concatenate([segments[0][2], segments[1][2] + offset])
    s_end = np.concatenate([segments[0][3], segments[1][3] + offset])
    tree = candidate_pairs(starts, ends, s_start, s_end, 0.2, 0.5)
    brute = candidate_pairs(starts, ends, s_start, s_end, 0.2, 0.5, method="brute")
    assert len(tree) > 1000
    np.testing.assert_array_equal(tree, brute)


@pytest.mark.parametrize("kind", CURVE_KINDS)
def test_kdtree_equals_brute_force_at_larger_sizes(kind):
    points = make_curve(kind, 3000, 11)
    starts, ends, s_start, s_end, period = polygon_segments(points, True)
    length = s_end[-1]
    extent = float(np.ptp(points, axis=0).max())
    for cutoff, exclusion in ((0.02 * extent, 0.01 * length), (0.005 * extent, 0.0)):
        tree = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period)
        brute = candidate_pairs(starts, ends, s_start, s_end, cutoff, exclusion, period, "brute")
        np.testing.assert_array_equal(tree, brute)


def test_polygon_segments():
    points = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    starts, ends, s_start, s_end, period = polygon_segments(points, True)
    np.testing.assert_array_equal(starts, points)
    np.testing.assert_array_equal(ends, points[[1, 2, 0]])
    np.testing.assert_allclose(s_start, [0.0, 3.0, 7.0])
    np.testing.assert_allclose(s_end, [3.0, 7.0, 12.0])
    assert period == 12.0
    starts, ends, s_start, s_end, period = polygon_segments(points, False)
    np.testing.assert_array_equal(starts, points[:2])
    np.testing.assert_array_equal(ends, points[1:])
    np.testing.assert_allclose(s_end, [3.0, 7.0])
    assert period is None


def test_fewer_than_two_segments_give_no_pairs():
    starts, ends, s_start, s_end, _ = polygon_segments(np.zeros((2, 3)), False)
    pairs = candidate_pairs(starts, ends, s_start, s_end, 1.0, 0.0)
    assert pairs.shape == (0, 2) and pairs.dtype == np.int64
    empty = np.empty((0, 3))
    pairs = candidate_pairs(empty, empty, np.empty(0), np.empty(0), 1.0, 0.0, method="brute")
    assert pairs.shape == (0, 2)


# --------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------


def valid_arguments():
    starts, ends, s_start, s_end, period = polygon_segments(make_curve("random_walk", 6, 0), True)
    return {
        "starts": starts,
        "ends": ends,
        "s_start": s_start,
        "s_end": s_end,
        "cutoff": 0.5,
        "exclusion": 1.0,
        "period": period,
    }


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"starts": np.zeros((6, 2))}, "starts must have shape"),
        ({"starts": np.zeros(6)}, "starts must have shape"),
        ({"ends": np.zeros((5, 3))}, "ends must have the shape"),
        ({"s_start": np.zeros(5)}, "s_start must have shape"),
        ({"s_end": np.zeros((6, 1))}, "s_end must have shape"),
        ({"starts": np.full((6, 3), np.nan)}, "starts must be finite"),
        ({"ends": np.full((6, 3), np.inf)}, "ends must be finite"),
        ({"s_start": np.full(6, np.nan)}, "s_start must be finite"),
        ({"s_end": np.full(6, -1.0)}, "s_end must be >= s_start"),
        ({"cutoff": -0.1}, "cutoff must be"),
        ({"cutoff": np.inf}, "cutoff must be"),
        ({"cutoff": np.nan}, "cutoff must be"),
        ({"cutoff": "1"}, "cutoff must be"),
        ({"exclusion": -1.0}, "exclusion must be"),
        ({"exclusion": np.nan}, "exclusion must be"),
        ({"period": 0.0}, "period must be"),
        ({"period": np.inf}, "period must be"),
        ({"period": 1e-3}, "longer in arc length than the period"),
        ({"method": "cells"}, "method must be one of"),
    ],
)
def test_invalid_input(changes, message):
    arguments = valid_arguments() | changes
    with pytest.raises(ValueError, match=message):
        candidate_pairs(**arguments)


@pytest.mark.parametrize(
    ("points", "closed", "message"),
    [
        (np.zeros((4, 2)), True, "shape"),
        (np.zeros((2, 3)), True, "at least 3 points"),
        (np.zeros((1, 3)), False, "at least 2 points"),
        (np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]), False, "finite"),
    ],
)
def test_invalid_polygon(points, closed, message):
    with pytest.raises(ValueError, match=message):
        polygon_segments(points, closed)


@pytest.mark.parametrize("count", [0, 1, 2, 13, 32, 33, 200])
def test_block_pairs_tested_at_once_equal_the_tree(count, monkeypatch):
    """Oracle: ``cKDTree.query_pairs``. Small block sets are paired in numpy (every pair
    tested), larger ones by the tree; both give the same pairs on either side of the
    threshold, also for centres exactly ``reach`` apart on a lattice."""
    from scipy.spatial import cKDTree

    from supercoil.contact import broadphase_blocks

    rng = np.random.default_rng(count)
    walk = np.cumsum(rng.normal(size=(count, 3)) * 0.01, axis=0)
    lattice = np.stack(np.meshgrid(*[np.arange(4) * 0.25] * 3), axis=-1).reshape(-1, 3)[:count]
    for centres, reach in ((walk, 0.03), (lattice, 0.25)):
        expected = {tuple(map(int, p)) for p in cKDTree(centres).query_pairs(reach)} \
            if count else set()
        for threshold in (0, 10**6):  # the tree always, numpy always
            monkeypatch.setattr(broadphase_blocks, "_TREE_ABOVE_BLOCKS", threshold)
            a, b = broadphase_blocks._close_block_pairs(centres, reach)
            assert np.all(a < b)
            assert set(zip(a.tolist(), b.tolist(), strict=True)) == expected
