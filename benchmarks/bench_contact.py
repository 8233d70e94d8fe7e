"""Benchmark: contact detection on a supercoiled ring, broad phase + narrow phase against all pairs.

Run from the repository root:

    python benchmarks/bench_contact.py

The curve is a closed plectoneme: two interwound strands of a superhelix of
radius ``R = D/2`` (so the strands touch: tube diameter ``D``), closed by an end
loop at each end, with total length 1 and ``L/D ≈ 105``. It is resampled at N
nodes of equal arc-length spacing for N = 100, 300, 1000, 3000, 10000. The
neighbour exclusion is ``πD/2`` and a pair of segments is in contact when its
exact distance is ``d ≤ D (1 + 1e-3)``.

Two ways to find the contact pairs are timed (median of ``--repeat`` warm runs):

(a) ``candidate_pairs`` (KD tree, cutoff ``D (1 + 1e-3)``, exclusion ``πD/2``)
    then the exact narrow phase ``segment_distance`` on the candidates;
(b) all pairs (what PyElastica does): ``segment_distance`` of every pair of
    segments i < j, in chunks of about 2**20 pairs, then the exclusion and the
    distance threshold. Run at the next N only while one run is predicted (from
    the last measured one, as N²) to take at most ``--all-pairs-budget``
    seconds; only measured times are printed.

With ``--fixed-resolution`` the plectoneme grows with N instead (9 turns per
1000 nodes: D/h fixed, the number of contacts proportional to N): the
series that shows how the cost grows with the size of the problem rather
than with the refinement of one shape.

At every N where both run, the two sets of contact pairs must be equal (exit
status 1 otherwise). Prints a markdown table, the ratios and the exponents p of
``time ~ N^p`` fitted by least squares on log-log axes.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Callable

import numpy as np
import scipy

from supercoil.contact.broadphase import candidate_pairs, pair_separation, polygon_segments
from supercoil.contact.distance import segment_distance

SIZES = (100, 300, 1000, 3000, 10000)
CONTACT_TOLERANCE = 1e-3  # contact: d <= D (1 + CONTACT_TOLERANCE)
ALL_PAIRS_CHUNK = 1 << 20


def plectonemic_ring(n_nodes: int, fine_points: int = 40000,
                     turns: float = 9.0) -> tuple[np.ndarray, float]:
    """(n_nodes, 3) nodes of a closed plectoneme of length 1, equally spaced in arc length, and D.

    Built in a frame that turns about the z axis: two straight strands at x = ±R
    (R = D/2) for 0 ≤ z ≤ H, joined at the top by a bulb-shaped end loop (an arc
    of radius 1.5 D bending outwards by 0.6 rad, an arc turning back over the top,
    the mirror image of the first arc) and at the bottom by the image of the top
    half under (x, z) → (−x, H − z). Each point is then rotated about the z axis
    by z / p with p = 1.2 R, so the strands are interwound helices of radius R in
    phase opposition; their distance is ≥ 2R = D, with equality at equal
    heights, because p ≥ R. ``turns`` turns of the superhelix (nine by
    default), C¹ (piecewise circular and straight in the turning frame).
    """
    diameter = 0.01
    radius = diameter / 2
    rise = 1.2 * radius  # axial rise per radian of superhelical turn
    height = turns * 2 * np.pi * rise
    bulge_radius, bulge_angle = 1.5 * diameter, 0.6
    bulge_x = radius + bulge_radius * (1 - np.cos(bulge_angle))
    bulge_z = height + bulge_radius * np.sin(bulge_angle)
    top_radius = bulge_x / np.cos(bulge_angle)
    top_centre_z = bulge_z + bulge_x * np.tan(bulge_angle)

    def arc(centre_x, centre_z, arc_radius, angle_from, angle_to, count):
        angle = np.linspace(angle_from, angle_to, count, endpoint=False)
        return np.column_stack(
            [centre_x + arc_radius * np.cos(angle), centre_z + arc_radius * np.sin(angle)]
        )

    lengths = np.array([height, bulge_radius * bulge_angle, top_radius * (np.pi + 2 * bulge_angle)])
    counts = np.maximum((fine_points * lengths / (2 * lengths.sum())).astype(int), 16)
    half = np.vstack(
        [
            np.column_stack(
                [np.full(counts[0], radius), np.linspace(0, height, counts[0], endpoint=False)]
            ),
            arc(radius + bulge_radius, height, bulge_radius, np.pi, np.pi - bulge_angle, counts[1]),
            arc(0.0, top_centre_z, top_radius, -bulge_angle, np.pi + bulge_angle, counts[2]),
            arc(-radius - bulge_radius, height, bulge_radius, bulge_angle, 0.0, counts[1]),
        ]
    )
    planar = np.vstack([half, np.column_stack([-half[:, 0], height - half[:, 1]])])
    turn = planar[:, 1] / rise
    curve = np.column_stack(
        [planar[:, 0] * np.cos(turn), planar[:, 0] * np.sin(turn), planar[:, 1]]
    )
    loop = np.vstack([curve, curve[:1]])
    arc_length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(loop, axis=0), axis=1))])
    target = arc_length[-1] * np.arange(n_nodes) / n_nodes
    nodes = np.column_stack([np.interp(target, arc_length, loop[:, k]) for k in range(3)])
    return nodes / arc_length[-1], diameter / arc_length[-1]


def contacts_by_broad_phase(segments, diameter: float) -> tuple[np.ndarray, int, float, float]:
    """(a): (contact pairs (m, 2), number of candidates, seconds in the broad phase, min d)."""
    starts, ends, s_start, s_end, period = segments
    threshold = diameter * (1 + CONTACT_TOLERANCE)
    start = time.perf_counter()
    pairs = candidate_pairs(starts, ends, s_start, s_end, threshold, np.pi * diameter / 2, period)
    broad = time.perf_counter() - start
    first, second = pairs[:, 0], pairs[:, 1]
    distance, _, _ = segment_distance(starts[first], ends[first], starts[second], ends[second])
    closest = float(distance.min()) if distance.size else float("inf")
    return pairs[distance <= threshold], len(pairs), broad, closest


def contacts_by_all_pairs(segments, diameter: float) -> np.ndarray:
    """(b): distances of all pairs i < j in chunks, then exclusion and threshold; (m, 2)."""
    starts, ends, s_start, s_end, period = segments
    threshold = diameter * (1 + CONTACT_TOLERANCE)
    n_segments = starts.shape[0]
    rows_per_chunk = max(1, ALL_PAIRS_CHUNK // n_segments)
    found = []
    for row_start in range(0, n_segments - 1, rows_per_chunk):
        rows = np.arange(row_start, min(row_start + rows_per_chunk, n_segments - 1))
        first, second = np.nonzero(np.arange(n_segments)[None, :] > rows[:, None])
        first = rows[first]
        distance, _, _ = segment_distance(starts[first], ends[first], starts[second], ends[second])
        separation = pair_separation(first, second, s_start, s_end, period)
        keep = (distance <= threshold) & (separation >= np.pi * diameter / 2)
        found.append(np.column_stack([first[keep], second[keep]]))
    return np.concatenate(found)


def median_time(function: Callable[[], object], repeat: int) -> tuple[float, object]:
    """(median wall time in seconds, last value) over ``repeat`` calls."""
    times, value = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), value


def exponent(sizes, seconds) -> float:
    """Least-squares slope of log(seconds) against log(N)."""
    return float(np.polyfit(np.log(sizes), np.log(seconds), 1)[0])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=9, help="runs of (a) per size")
    parser.add_argument("--all-pairs-repeat", type=int, default=3, help="runs of (b) per size")
    parser.add_argument(
        "--all-pairs-budget", type=float, default=20.0, help="seconds allowed for one run of (b)"
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument(
        "--fixed-resolution",
        action="store_true",
        help="scale the plectoneme with N (9 superhelical turns per 1000 nodes), so that D/h "
        "stays fixed and the number of contacts grows like N",
    )
    arguments = parser.parse_args()

    # compile (or load the numba cache) outside the timings
    warm = polygon_segments(plectonemic_ring(50)[0], True)
    contacts_by_broad_phase(warm, 0.1)
    contacts_by_all_pairs(warm, 0.1)

    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.1f}; numpy {np.__version__}, scipy {scipy.__version__}"
    )
    print()
    print(
        "| N | D/h | min d/D | candidates | contact pairs | (a) broad (s) | (a) broad+narrow (s) "
        "| (b) all pairs (s) | (b)/(a) | same pairs |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|")
    measured_a, measured_broad, measured_b, counted = [], [], [], []
    last_all_pairs = None  # (N, seconds of one run)
    all_agree = True
    for n_nodes in arguments.sizes:
        turns = 9.0 * n_nodes / 1000 if arguments.fixed_resolution else 9.0
        fine = max(40000, 40 * n_nodes)
        points, diameter = plectonemic_ring(n_nodes, fine_points=fine, turns=turns)
        segments = polygon_segments(points, True)
        spacing = float(np.mean(segments[3] - segments[2]))
        totals, broads = [], []
        for _ in range(arguments.repeat):
            start = time.perf_counter()
            contacts_a, n_candidates, broad, closest = contacts_by_broad_phase(segments, diameter)
            totals.append(time.perf_counter() - start)
            broads.append(broad)
        seconds_a, broad = float(np.median(totals)), float(np.median(broads))
        measured_a.append((n_nodes, seconds_a))
        measured_broad.append((n_nodes, broad))
        counted.append((n_nodes, n_candidates))
        row = (
            f"| {n_nodes} | {diameter / spacing:.1f} | {closest / diameter:.4f} | {n_candidates} "
            f"| {len(contacts_a)} "
            f"| {broad:.5f} | {seconds_a:.5f} "
        )
        predicted = (
            0.0
            if last_all_pairs is None
            else last_all_pairs[1] * (n_nodes / last_all_pairs[0]) ** 2
        )
        if predicted <= arguments.all_pairs_budget:
            seconds_b, contacts_b = median_time(
                lambda s=segments, d=diameter: contacts_by_all_pairs(s, d),
                arguments.all_pairs_repeat,
            )
            last_all_pairs = (n_nodes, seconds_b)
            measured_b.append((n_nodes, seconds_b))
            same = np.array_equal(contacts_a, contacts_b)
            all_agree &= same
            row += f"| {seconds_b:.4f} | {seconds_b / seconds_a:.0f} | {'yes' if same else 'NO'} |"
        else:
            row += "| – | – | – |"
        print(row, flush=True)

    print()
    print("Exponent p of time (or count) ~ N^p (least squares on log-log axes):")
    for label, measured in (
        ("(a) broad phase", measured_broad),
        ("(a) broad+narrow", measured_a),
        ("(b) all pairs", measured_b),
        ("number of candidates", counted),
    ):
        sizes, seconds = (np.array(column) for column in zip(*measured))
        line = f"- {label}: N = {sizes[0]} … {sizes[-1]}: {exponent(sizes, seconds):.2f}"
        large = sizes >= 1000
        if large.sum() >= 2 and not large.all():
            line += f"; N = 1000 … {sizes[-1]}: {exponent(sizes[large], seconds[large]):.2f}"
        print(line)
    if not all_agree:
        print("ERROR: (a) and (b) found different contact pairs")
    return 0 if all_agree else 1


if __name__ == "__main__":
    raise SystemExit(main())
