"""Benchmark: polygon against B-spline contact on the ring's alpha contact branch.

Run from the repository root:

    python benchmarks/bench_spline_contact.py --curve polygon|spline [--nodes 128]
        [--max-excess-link 3.5] [--contact-max-points 150]

Computes :func:`supercoil.problems.ring_diagram.ring_diagram` for C/A = 2/3,
L/D = 122, mode 2 only, with ``DiagramOptions.contact_curve`` as given, and
prints the alpha contact branch: points, dLk reached, status, wall time, and
``sliding_residual`` (the force the sliding gauge holds, max |KKT residual|
without the gauge) per point and its median and maximum.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curve", default="polygon")
    parser.add_argument("--nodes", type=int, default=128)
    parser.add_argument("--max-excess-link", type=float, default=3.5)
    parser.add_argument("--contact-max-points", type=int, default=150)
    args = parser.parse_args(argv)

    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    # the pair sum with the node gauge and the tangent predictor: only the curve varies
    options = DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(2,),
                             max_excess_link=args.max_excess_link,
                             contact_max_points=args.contact_max_points,
                             contact_curve=args.curve, contact_formulation="pairs",
                             gauge="node", contact_predictor="tangent")
    start = time.perf_counter()
    diagram = ring_diagram(options, progress=lambda m: print(m, flush=True))
    total = time.perf_counter() - start
    print(f"curve {args.curve}, C/A = 2/3, L/D = 122, N = {args.nodes}, mode 2, "
          f"dLk <= {args.max_excess_link:g}, total {total:.1f} s")
    for b in diagram.branches:
        print(f"branch {b.name}: {len(b)} points, {diagram.seconds.get(b.name, float('nan')):.1f} s,"
              f" dLk {b.parameter_values.min():.4f} .. {b.parameter_values.max():.4f}, "
              f"last dLk {b.parameter_values[-1]:.4f}, {b.status.name}: {b.message}")
    contact = diagram.branch("alpha_contact")
    res = np.asarray(contact.records["sliding_residual"])
    lam = contact.parameter_values
    npts = contact.records["n_contact_points"]
    nint = contact.records["n_contact_intervals"]
    print("index dLk writhe sliding_residual points intervals unstable")
    for i in range(len(contact)):
        print(f"{i} {lam[i]:.5f} {contact.records['writhe'][i]:.5f} {res[i]:.3e} "
              f"{int(npts[i])} {int(nint[i])} {int(contact.unstable_count[i])}")
    folds = len(contact.points_of_kind("fold"))
    print(f"alpha_contact: {len(contact)} points, folds {folds}, max dLk {lam.max():.4f}, "
          f"final dLk {lam[-1]:.4f}, sliding_residual median {np.median(res):.3e} "
          f"max {res.max():.3e}")
    for p in contact.special_points:
        print(f"  special {p.kind} dLk={p.parameter:.5f} {p.label}")
    for n in diagram.notes:
        print("note:", n)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
