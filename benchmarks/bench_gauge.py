"""Benchmark: the cost per point of the integral gauge against the node gauge.

Run from the repository root:

    python benchmarks/bench_gauge.py [--nodes 200] [--contact-max-points 60]

Computes the ring's mode-2 diagram of :mod:`benchmarks.bench_ring_diagram`
(C/A = 2/3, L/D = 122, dLk <= 6; the circle, alpha, alpha with contact) three
times in one process, after a short warm-up of both gauges at the same N: with ``gauge="node"``, with
``gauge="integral"`` (its dense phase row pinned and carried as extra borders,
:mod:`supercoil.continuation.bordered`), and with ``gauge="integral"`` and the
row left in the sparse matrix (``pinned_rows.DENSE_ROW_MIN_ENTRIES`` raised: the path
before pinning, band too wide, SuperLU). Prints per branch the points, the
seconds per point, and the mean time of one bordered factorisation
(``corrector.bordered_factor``) and of one inertia count
(``stability.inertia``). The gauges follow slightly different branches (the
node pin breaks symmetries, the contact branches fold differently), so the
per-call columns are the like-for-like comparison.
"""

from __future__ import annotations

import argparse
import time
from collections import defaultdict


def _timed(module, name, totals):
    original = getattr(module, name)

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            totals[name][0] += time.perf_counter() - start
            totals[name][1] += 1

    setattr(module, name, wrapper)
    return original


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200)
    parser.add_argument("--max-excess-link", type=float, default=6.0)
    parser.add_argument("--contact-max-points", type=int, default=60)
    args = parser.parse_args(argv)

    from supercoil.continuation import corrector, events, stability
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
    from supercoil.solvers import pinned_rows

    for gauge in ("node", "integral"):  # numba caches and pattern memos, at this N
        ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(2,),
                                    max_excess_link=2.0, free_max_points=4,
                                    contact_max_points=2, gauge=gauge,
                                    contact_formulation="pairs", contact_curve="polygon",
                                    contact_predictor="tangent"))
    runs = (("node", "node", None), ("integral", "integral, pinned", None),
            ("integral", "integral, dense row", 10**9))
    print(f"C/A = 2/3, L/D = 122, N = {args.nodes}, mode 2, dLk <= {args.max_excess_link:g}, "
          f"contact branch <= {args.contact_max_points} points")
    rows, per_call = [], []
    limit = pinned_rows.DENSE_ROW_MIN_ENTRIES
    for gauge, label, min_entries in runs:
        if min_entries is not None:
            pinned_rows.DENSE_ROW_MIN_ENTRIES = min_entries
        options = DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(2,),
                                 max_excess_link=args.max_excess_link,
                                 contact_max_points=args.contact_max_points, gauge=gauge,
                                 # the contact of the recorded measurement
                                 contact_formulation="pairs", contact_curve="polygon",
                                 contact_predictor="tangent")
        totals = defaultdict(lambda: [0.0, 0])
        saved = [(corrector, "bordered_factor", _timed(corrector, "bordered_factor", totals))]
        inertia = _timed(stability, "inertia", totals)
        saved += [(stability, "inertia", inertia), (events, "inertia", events.inertia)]
        events.inertia = stability.inertia
        try:
            diagram = ring_diagram(options)
        finally:
            for module, name, original in saved:
                setattr(module, name, original)
            if limit is not None:
                pinned_rows.DENSE_ROW_MIN_ENTRIES = limit
        factor_ms = 1e3 * totals["bordered_factor"][0] / max(totals["bordered_factor"][1], 1)
        inertia_ms = 1e3 * totals["inertia"][0] / max(totals["inertia"][1], 1)
        per_call.append(f"| {label} | {factor_ms:.2f} ({totals['bordered_factor'][1]}) | "
                        f"{inertia_ms:.2f} ({totals['inertia'][1]}) |")
        for b in diagram.branches:
            sec = diagram.seconds.get(b.name, float("nan"))
            lam = b.parameter_values
            rows.append(f"| {label} | {b.name} | {len(b)} | {sec:.2f} | "
                        f"{sec / max(len(b), 1):.3f} | {lam.min():.3f} .. {lam.max():.3f} | "
                        f"{b.status.name} |")
    print("| gauge | branch | points | seconds | s/point | dLk range | status |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print()
    print("| gauge | bordered factor, ms (calls) | inertia, ms (calls) |")
    print("|---|---|---|")
    print("\n".join(per_call))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
