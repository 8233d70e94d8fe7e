"""Benchmark: the ring's alpha branch from the circle through contact (issue 4's target).

Run from the repository root:

    python benchmarks/bench_ring_diagram.py [--nodes 200] [--max-excess-link 6]
        [--contact-max-points 400] [--contact-formulation integral|pairs]
        [--contact-curve spline|polygon|quintic] [--gauge integral|node]
        [--predictor quadratic|tangent|secant] [--profile]

Times :func:`supercoil.problems.ring_diagram.ring_diagram` for C/A = 2/3,
L/D = 122 (seed 001's DNA example), mode 2 only (the circle, alpha without
contact to its first contact, alpha with barrier contact up to
``--max-excess-link``; defaults: those of ``DiagramOptions``) after one warm-up
run at N = 48 (numba caches). It
prints the wall time per branch, the points, the excess link and writhe
reached, and the time per contact-branch point; with ``--profile`` the
top of a cProfile by cumulative time. Target (issue 4): the whole alpha
branch to dLk = 6 at N = 200 in at most 10 s.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200)
    parser.add_argument("--max-excess-link", type=float, default=6.0)
    parser.add_argument("--contact-max-points", type=int, default=400)
    parser.add_argument("--contact-formulation", default="integral",
                        choices=("integral", "pairs"))
    parser.add_argument("--contact-curve", default="spline",
                        choices=("spline", "polygon", "quintic"))
    parser.add_argument("--gauge", default="integral", choices=("integral", "node"))
    parser.add_argument("--predictor", default="quadratic",
                        choices=("quadratic", "tangent", "secant"))
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args(argv)

    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=48, modes=(2,), max_excess_link=2.0,
                                contact_max_points=5))
    options = DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(2,),
                             max_excess_link=args.max_excess_link,
                             contact_max_points=args.contact_max_points,
                             contact_formulation=args.contact_formulation,
                             contact_curve=args.contact_curve, gauge=args.gauge,
                             contact_predictor=args.predictor)
    profile = cProfile.Profile() if args.profile else None
    start = time.perf_counter()
    if profile:
        profile.enable()
    diagram = ring_diagram(options)
    if profile:
        profile.disable()
    total = time.perf_counter() - start
    print(f"C/A = 2/3, L/D = 122, N = {args.nodes}, mode 2, dLk <= {args.max_excess_link:g}, "
          f"{args.contact_formulation} contact on the {args.contact_curve}, {args.gauge} gauge, "
          f"{args.predictor} predictor")
    print("| branch | points | seconds | s/point | dLk range | max writhe | status |")
    print("|---|---|---|---|---|---|---|")
    for b in diagram.branches:
        sec = diagram.seconds.get(b.name, float("nan"))
        lam = b.parameter_values
        print(f"| {b.name} | {len(b)} | {sec:.2f} | {sec / max(len(b), 1):.3f} | "
              f"{lam.min():.3f} .. {lam.max():.3f} | {float(b.records['writhe'].max()):.3f} | "
              f"{b.status.name} |")
    kinds: dict[str, int] = {}
    for p in diagram.special_points():
        kinds[p.kind] = kinds.get(p.kind, 0) + 1
    print("special points:", ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))
    print(f"total {total:.2f} s")
    if profile:
        pstats.Stats(profile).sort_stats("cumulative").print_stats(30)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
