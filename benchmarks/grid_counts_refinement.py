"""Benchmark: do the unstable counts of a long rod's contact branch survive refinement?

Runs one (L/D, lambda, C/A) of the long-rod grid (``bench_long_dna_grid.py``) at two
node counts and compares the unstable counts of their contact (plectoneme) branches
state by state, not as tallies: the tallies differ whenever one mesh spends more points
on a stretch (a localised loop that slides between folds, say) without any count
differing.

Oracle: the continuum's count is a property of the state, constant between the events
that change it. Each point of the finer branch is matched with the coarser branch's
point nearest in the mesh-independent observables (turns, writhe); the counts of the two
must agree, except near a count event, where the matched states may lie on the two
sheets of one fold. Every disagreement is listed with its distance in turns to the
nearest count change of either branch (0 when one lies between the point's turns and its
match's), so none is hidden by the ``--window``.

Each mesh's snakes (:func:`supercoil.problems.tweezers.coarse.snakes_on`: the plectoneme
growing a node of each strand at a time across pairs of events) and the turns at which
the hard-core ply would span the rod are printed beside, and ``--save PREFIX`` keeps each
contact branch's turns, writhe, extension, torque, counts and nearest eigenvalues in
``PREFIX_N.npz`` to be looked at again.

Run: ``python benchmarks/grid_counts_refinement.py --ld 200 --lam 40 --nodes 202,404
[--twist-ratio 1.5] [--factor 1.5] [--max-points 4000] [--window 0.1] [--save PREFIX]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ply import hard_core_ply
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.problems.tweezers.coarse import snakes_on
from supercoil.problems.tweezers.options import segment_length


def contact_branch(ld: float, lam: float, twist_ratio: float, nodes: int, factor: float,
                   max_points: int):
    """The contact branch of the grid's run at ``nodes`` that reaches the furthest turns
    (the branch held on its half-turn symmetry where the free one closed), and the run's
    seconds."""
    tension = lam**2
    options = TweezersOptions(twist_ratio=twist_ratio, length_over_diameter=ld,
                              tension=tension, n_nodes=nodes,
                              turns=(0.0, factor * critical_turns(twist_ratio, tension)),
                              max_points=max_points)
    start = time.perf_counter()
    result = tweezers_branches(options)
    seconds = time.perf_counter() - start
    contact = [b for b in result.branches if b.name in result.contact_branches]
    return max(contact, key=lambda b: float(np.max(b.parameter_values))), seconds


def count_changes(branch) -> np.ndarray:
    """The turns midway between consecutive points whose counts differ."""
    c = np.asarray(branch.unstable_count)
    t = np.asarray(branch.parameter_values)
    k = np.flatnonzero(np.diff(c) != 0)
    return 0.5 * (t[k] + t[k + 1])


def compare(coarse, fine, window: float) -> dict:
    """Match every point of ``fine`` with ``coarse``'s nearest in (turns, writhe)."""
    fc = np.c_[coarse.parameter_values, coarse.records["writhe"]]
    ff = np.c_[fine.parameter_values, fine.records["writhe"]]
    cc = np.asarray(coarse.unstable_count)
    cf = np.asarray(fine.unstable_count)
    events = np.concatenate([count_changes(coarse), count_changes(fine)])
    gap, match = cKDTree(fc).query(ff)
    # distance in turns from the turns spanned by a point and its match to the nearest
    # count change (0 when one lies between them)
    low = np.minimum(ff[:, 0], fc[match, 0])[:, None]
    high = np.maximum(ff[:, 0], fc[match, 0])[:, None]
    near = (np.min(np.maximum(np.maximum(low - events, events - high), 0.0), axis=1)
            if events.size else np.full(len(ff), np.inf))
    differ = cf != cc[match]
    rows = [(int(i), float(ff[i, 0]), int(cf[i]), int(match[i]), int(cc[match[i]]),
             float(near[i])) for i in np.flatnonzero(differ)]
    return {"points": len(ff), "agree": int(np.sum(~differ)),
            "differ_near_event": int(np.sum(differ & (near <= window))),
            "differ_elsewhere": int(np.sum(differ & (near > window))),
            "largest_match_gap": float(gap.max()), "disagreements": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ld", type=float, required=True)
    parser.add_argument("--lam", type=float, required=True)
    parser.add_argument("--nodes", required=True, help="two node counts, coarse,fine")
    parser.add_argument("--twist-ratio", type=float, default=1.5)
    parser.add_argument("--factor", type=float, default=1.5)
    parser.add_argument("--max-points", type=int, default=4000)
    parser.add_argument("--save", default=None, help="keep each contact branch's arrays "
                        "in PREFIX_N.npz")
    parser.add_argument("--window", type=float, default=0.1,
                        help="turns from a count change within which a disagreement is "
                             "put down to the event")
    args = parser.parse_args()
    n_coarse, n_fine = (int(n) for n in args.nodes.split(","))
    coarse, s_coarse = contact_branch(args.ld, args.lam, args.twist_ratio, n_coarse,
                                      args.factor, args.max_points)
    fine, s_fine = contact_branch(args.ld, args.lam, args.twist_ratio, n_fine,
                                  args.factor, args.max_points)
    out = compare(coarse, fine, args.window)
    print(f"L/D {args.ld:g}, lambda {args.lam:g}, C/A {args.twist_ratio:g}: "
          f"N = {n_coarse} ({len(coarse)} contact points, {s_coarse:.0f} s) against "
          f"N = {n_fine} ({len(fine)}, {s_fine:.0f} s)")
    ply = hard_core_ply(1 / args.ld, args.lam**2, args.twist_ratio)
    print(f"  the hard-core ply spans the rod at {ply.spanning_turns:.4g} turns")
    for name, branch in ((n_coarse, coarse), (n_fine, fine)):
        values, times = np.unique(branch.unstable_count, return_counts=True)
        tally = ", ".join(f"{v}: {t}" for v, t in zip(values, times, strict=True))
        print(f"  N = {name}: tally {tally}; count changes at turns "
              f"{np.round(count_changes(branch), 4).tolist()}")
        kinds = {}
        for p in branch.special_points:
            if p.kind in ("bifurcation", "count_change"):
                key = f"{p.kind} ({p.label})"
                kinds[key] = kinds.get(key, 0) + 1
        print(f"    located: {kinds}")
        for snake in snakes_on(branch, segment_length(name)):
            print(f"    snake: {snake}")
        if args.save:
            np.savez(f"{args.save}_{name}.npz", turns=branch.parameter_values,
                     writhe=branch.records["writhe"], extension=branch.records["extension"],
                     torque=branch.records["torque"], counts=branch.unstable_count,
                     nearest=branch.nearest_eigenvalue)
    print(f"  state by state: {out['agree']} of {out['points']} agree; "
          f"{out['differ_near_event']} differ within {args.window:g} turns of a count "
          f"change, {out['differ_elsewhere']} elsewhere; largest (turns, writhe) gap to "
          f"the match {out['largest_match_gap']:.3g}")
    for i, t, c, j, cj, d in out["disagreements"]:
        print(f"    fine point {i} at {t:.4f} turns counts {c}, its match {j} at "
              f"{coarse.parameter_values[j]:.4f} counts {cj}; {d:.3g} turns from a count "
              f"change")


if __name__ == "__main__":
    main()
