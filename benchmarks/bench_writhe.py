"""Benchmark: fast (numba, parallel) writhe against the numpy reference.

Run from the repository root:

    python benchmarks/bench_writhe.py

Times ``supercoil.topology.writhe`` (warm: compiled and cached first, best of
``--repeat`` runs) on closed polygons with N = 1000, 2000, 5000, 10000 vertices,
and ``writhe_reference`` (plain vectorized numpy, best of ``--reference-repeat``
runs) for N = 1000, 2000, 5000. Prints a markdown table, whether N = 5000
meets the 0.25 s target, and the N = 5000 time on a single thread. The curve is a (3, 7) torus knot with a small random
perturbation (seeded), so every pair of edges is generic.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Callable

import numba
import numpy as np

from supercoil.topology import writhe, writhe_reference

FAST_SIZES = (1000, 2000, 5000, 10000)
REFERENCE_SIZES = (1000, 2000, 5000)
TARGET_SIZE, TARGET_SECONDS = 5000, 0.25


def closed_curve(n_vertices: int, seed: int = 0) -> np.ndarray:
    """(n_vertices, 3) perturbed (3, 7) torus knot."""
    phi = 2.0 * np.pi * np.arange(n_vertices) / n_vertices
    rho = 2.0 + 0.7 * np.cos(7.0 * phi)
    curve = np.column_stack([rho * np.cos(3.0 * phi), rho * np.sin(3.0 * phi), np.sin(7.0 * phi)])
    noise = np.random.default_rng(seed).normal(scale=0.1 / n_vertices, size=curve.shape)
    return curve + noise


def best_time(function: Callable[[], float], repeat: int) -> tuple[float, float]:
    """(best wall time in seconds, value) over ``repeat`` calls."""
    best, value = float("inf"), float("nan")
    for _ in range(repeat):
        start = time.perf_counter()
        value = function()
        best = min(best, time.perf_counter() - start)
    return best, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="runs of the fast path per size")
    parser.add_argument("--reference-repeat", type=int, default=2, help="runs of the reference")
    arguments = parser.parse_args()

    writhe(closed_curve(100))  # compile (or load the numba cache) outside the timings

    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"numba {numba.__version__} with {numba.get_num_threads()} threads "
        f"({numba.threading_layer()} layer), numpy {np.__version__}"
    )
    print()
    print("| N | fast (s) | numpy (s) | ratio | |Wr_fast − Wr_numpy| |")
    print("|---:|---:|---:|---:|---:|")
    fast_at_target = float("nan")
    for n in FAST_SIZES:
        points = closed_curve(n)
        fast, fast_value = best_time(lambda p=points: writhe(p), arguments.repeat)
        if n == TARGET_SIZE:
            fast_at_target = fast
        if n in REFERENCE_SIZES:
            slow, slow_value = best_time(
                lambda p=points: writhe_reference(p), arguments.reference_repeat
            )
            row = f"| {n} | {fast:.4f} | {slow:.3f} | {slow / fast:.0f} | {abs(fast_value - slow_value):.1e} |"
        else:
            row = f"| {n} | {fast:.4f} | – | – | – |"
        print(row)
    print()
    verdict = "meets" if fast_at_target <= TARGET_SECONDS else "MISSES"
    print(
        f"N = {TARGET_SIZE}: {fast_at_target:.4f} s (best of {arguments.repeat}, warm) "
        f"{verdict} the target of {TARGET_SECONDS} s"
    )
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    points = closed_curve(TARGET_SIZE)
    single, _ = best_time(lambda: writhe(points), arguments.repeat)
    numba.set_num_threads(threads)
    print(f"N = {TARGET_SIZE} on one thread: {single:.4f} s")


if __name__ == "__main__":
    main()
