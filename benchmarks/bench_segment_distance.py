"""Benchmark: the narrow phase of bench_contact.py alone, optionally against another kernel.

Run from the repository root:

    python benchmarks/bench_segment_distance.py
    git show main:src/supercoil/contact/distance.py > /tmp/distance_main.py
    python benchmarks/bench_segment_distance.py --compare /tmp/distance_main.py

Times ``segment_distance`` on the candidate pairs that ``candidate_pairs`` returns
for the closed plectoneme of ``bench_contact.py`` (same cutoff and exclusion) at
N = 1000, 3000, 10000. With ``--compare FILE`` the ``segment_distance`` of that
file (a copy of ``supercoil/contact/distance.py`` from another version, loaded
as a module of its own) is timed too, alternated call by call with the
installed one (``A B B A …``), so that a load change on a shared machine hits
both alike. Prints medians, minima, the median of the per-round ratios, the
largest difference between the two distances and whether the same pairs are
within the contact threshold.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import time
from pathlib import Path

import numpy as np
from bench_contact import CONTACT_TOLERANCE, plectonemic_ring

from supercoil.contact.broadphase import candidate_pairs, polygon_segments
from supercoil.contact.distance import segment_distance


def load_kernel(path: Path):
    """``segment_distance`` of the module file ``path``."""
    spec = importlib.util.spec_from_file_location("compared_distance", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # numba's cache finds the module again by its name
    spec.loader.exec_module(module)
    return module.segment_distance


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=61, help="timed calls per kernel and N")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 3000, 10000])
    parser.add_argument("--compare", type=Path, help="another distance.py to time against")
    arguments = parser.parse_args()
    kernels = {"this": segment_distance}
    if arguments.compare is not None:
        kernels["compared"] = load_kernel(arguments.compare)
    print(f"load average {os.getloadavg()[0]:.1f}")
    print("| N | pairs | kernel | median (ms) | min (ms) | ns per pair (median) "
          "| median ratio to compared |")
    print("|---:|---:|---|---:|---:|---:|---:|")
    for n_nodes in arguments.sizes:
        points, diameter = plectonemic_ring(n_nodes, fine_points=max(40000, 40 * n_nodes))
        starts, ends, s_start, s_end, period = polygon_segments(points, True)
        threshold = diameter * (1 + CONTACT_TOLERANCE)
        pairs = candidate_pairs(starts, ends, s_start, s_end, threshold, np.pi * diameter / 2,
                                period)
        first, second = pairs[:, 0], pairs[:, 1]
        endpoints = (starts[first], ends[first], starts[second], ends[second])
        distances = {name: kernel(*endpoints)[0] for name, kernel in kernels.items()}  # warm
        seconds = {name: [] for name in kernels}
        names = list(kernels)
        for round_ in range(arguments.rounds):
            for name in names if round_ % 2 == 0 else names[::-1]:
                start = time.perf_counter()
                kernels[name](*endpoints)
                seconds[name].append(time.perf_counter() - start)
        for name in names:
            times = np.array(seconds[name])
            ratio = (f"{np.median(times / np.array(seconds['compared'])):.3f}"
                     if "compared" in kernels else "–")
            print(f"| {n_nodes} | {len(pairs)} | {name} | {np.median(times) * 1e3:.3f} "
                  f"| {times.min() * 1e3:.3f} | {np.median(times) / len(pairs) * 1e9:.1f} "
                  f"| {ratio} |")
        if "compared" in kernels:
            difference = np.abs(distances["this"] - distances["compared"]).max()
            same = np.array_equal(distances["this"] <= threshold,
                                  distances["compared"] <= threshold)
            print(f"|  |  | max difference {difference:.2e}, same contacts: "
                  f"{'yes' if same else 'NO'} |  |  |  |  |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
