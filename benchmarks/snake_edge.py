"""Benchmark: where does the mesh's snake end as the nodes grow?

Runs one (L/D, lambda, C/A) of the long-rod grid (``bench_long_dna_grid.py``) at several
node counts and reports, for the contact branch that reaches the furthest turns, its
folds, its changes of the unstable count and the snakes among them
(:func:`supercoil.problems.tweezers.coarse.snakes_on`: pairs of events a steady period
apart, the extension falling by two segments per period: a node of each strand entering
the plectoneme's ply). Oracle: the period of a snake is ``2 h / |dz/dn|`` with the
hard-core ply's slope (Neukirch & van der Heijden 2002), printed beside it; the edge of
the snake in ``h sqrt(F/A)`` is compared with the rule that sets the DNA runs' default
nodes (:func:`supercoil.problems.tweezers.options.resolved_core`).

Run: ``python benchmarks/snake_edge.py --ld 200 --lam 100 --nodes 252,302,352,402,452
[--twist-ratio 1.5] [--factor 1.5] [--max-points 20000]``; one markdown row per N.
"""

from __future__ import annotations

import argparse

from grid_counts_refinement import contact_branch

from supercoil.problems.ply import hard_core_ply
from supercoil.problems.tweezers.coarse import snakes_on
from supercoil.problems.tweezers.options import core_segments, resolved_core, segment_length

HEADER = ("| N | h sqrt(F/A) | rule | s | branch | points | last turn | folds | count changes "
          "| of them snake | snakes: kind, pairs, turns, period, width, segments |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")


def row(ld: float, lam: float, twist_ratio: float, nodes: int, factor: float,
        max_points: int) -> str:
    """The markdown row of one run (module doc)."""
    branch, seconds = contact_branch(ld, lam, twist_ratio, nodes, factor, max_points)
    changes = [p for p in branch.special_points
               if p.kind in ("bifurcation", "count_change") and p.label != "sliding"]
    snakes = snakes_on(branch, segment_length(nodes))
    described = "; ".join(
        f"{s.kind}, {s.pairs}, {s.turns[0]:.4g}-{s.turns[1]:.4g}, {s.period:.3g}, "
        f"{s.width:.1e}, {s.segments:.3f}" for s in snakes) or "none"
    return (f"| {nodes} | {core_segments(lam**2, nodes):.3f} | {resolved_core(lam**2):.3f} "
            f"| {seconds:.0f} | {branch.name} | {len(branch)} "
            f"| {float(branch.parameter_values[-1]):.4g} "
            f"| {len(branch.points_of_kind('fold'))} | {len(changes)} "
            f"| {sum(p.label == 'snake' for p in changes)} | {described} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ld", type=float, required=True, help="L/D")
    parser.add_argument("--lam", type=float, required=True, help="lambda = L sqrt(F/A)")
    parser.add_argument("--nodes", required=True, help="comma-separated node counts")
    parser.add_argument("--twist-ratio", type=float, default=1.5, help="C/A")
    parser.add_argument("--factor", type=float, default=1.5,
                        help="the last turn over Greenhill's clamped condition")
    parser.add_argument("--max-points", type=int, default=20000)
    args = parser.parse_args()
    ply = hard_core_ply(1 / args.ld, args.lam**2, args.twist_ratio)
    print(f"L/D = {args.ld:g}, lambda = {args.lam:g}, C/A = {args.twist_ratio:g}; the "
          f"hard-core ply spans the rod at {ply.spanning_turns:.4g} turns, its period "
          f"2 h / |dz/dn| = {2 / abs(ply.extension_per_turn):.4g} h turns")
    print(HEADER, flush=True)
    for nodes in (int(n) for n in args.nodes.split(",")):
        print(row(args.ld, args.lam, args.twist_ratio, nodes, args.factor, args.max_points),
              flush=True)


if __name__ == "__main__":
    main()
