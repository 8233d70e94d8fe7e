"""Robustness and cost of the four contact treatments on a set of ring problems.

Run from the repository root:

    python benchmarks/bench_contact_treatments.py [--nodes 100]

Each case is solved with each treatment by ``solve_supercoiled_ring`` (from
the perturbed circle, or from a trefoil for the knotted case); the table
reports whether the solve converged to an admissible state, its unstable
count, writhe, elastic energy, closest approach over D, Newton iterations and
wall time. The default treatment is chosen from this table (docs/contact.md).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

CASES = [
    # name, C/A, excess link, L/D, initial curve
    ("ring C/A=1 dLk=2 L/D=100", 1.0, 2.0, 100.0, None),
    ("ring C/A=1 dLk=3 L/D=100", 1.0, 3.0, 100.0, None),
    ("ring C/A=1 dLk=5 L/D=100", 1.0, 5.0, 100.0, None),
    ("ring C/A=2/3 dLk=4 L/D=122", 2.0 / 3.0, 4.0, 122.0, None),
    ("trefoil C/A=1 dLk=0 L/D=40", 1.0, 0.0, 40.0, "trefoil"),
]


def trefoil(n: int = 300) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t),
                     -np.sin(3 * t)], axis=1)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--treatments", default="exact,augmented,barrier,penalty")
    args = parser.parse_args(argv)
    from supercoil.problems.ring_contact import solve_supercoiled_ring

    solve_supercoiled_ring(1.0, 3.0, 100.0, n_nodes=40, treatment="exact")  # warm-up
    print("| case | treatment | ok | unstable | writhe | energy | d_min/D | Newton its | time (s) |")
    print("|---|---|:---:|---:|---:|---:|---:|---:|---:|")
    for name, ca, dlk, lod, initial in CASES:
        for treatment in args.treatments.split(","):
            start = time.perf_counter()
            try:
                r = solve_supercoiled_ring(ca, dlk, lod, n_nodes=args.nodes, treatment=treatment,
                                           initial_points=trefoil() if initial else None)
            except (ValueError, RuntimeError, ArithmeticError) as exc:  # report, go on
                print(f"| {name} | {treatment} | error | | | | | | {exc} |")
                continue
            elapsed = time.perf_counter() - start
            s = r.summary()
            ok = "yes" if r.converged else "no"
            print(f"| {name} | {treatment} | {ok} | {r.unstable_count} | {r.writhe:.5f} | "
                  f"{r.energy:.4f} | {s['min_gap_over_diameter']:.6f} | {r.iterations} | "
                  f"{elapsed:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
