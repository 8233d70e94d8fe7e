"""Coleman & Swigon's β family at their DNA parameters: P, the secondary branch β_II
and its S.

Run from the repository root:

    python benchmarks/bench_beta_secondary.py [--nodes 132] [--max-points 90]

Computes the ring's mode-3 diagram (C/A = 2/3, L/D = 122, dLk <= 6: the circle,
beta, beta with contact), then switches at beta's last bifurcation point (P) onto
both halves of the secondary branch β_II and follows each with self-contact
(:func:`supercoil.problems.ring_diagram.secondary.follow_bifurcating_branch`). Prints
beta's bifurcation points, and for each half its folds and bifurcations (with the
two-fold axis under which a pitchfork's critical mode is odd, as
:func:`~supercoil.problems.ring_diagram.secondary.mirror_axis` finds it: Coleman &
Swigon's S),
the stretch where its unstable count is 0 and condition E there, and the wall
time. Use a multiple of 6 for ``--nodes`` (beta's three axes on the mesh).
``benchmarks/results/beta_stability.md`` records N = 132 and 204.
"""

from __future__ import annotations

import argparse
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=132)
    parser.add_argument("--max-points", type=int, default=90)
    args = parser.parse_args()

    from supercoil.problems.ring_diagram import (
        DiagramOptions,
        link_writhe_slope_sign,
        ring_diagram,
    )
    from supercoil.problems.ring_diagram.secondary import follow_bifurcating_branch, mirror_axis

    options = DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(3,),
                             max_excess_link=6.0, contact_max_points=200)
    start = time.perf_counter()
    diagram = ring_diagram(options)
    print(f"N = {args.nodes}: circle, beta, beta_contact in {time.perf_counter() - start:.1f} s")
    beta = diagram.branch("beta_contact")
    points = beta.points_of_kind("bifurcation")
    print("beta_contact bifurcations (dLk, count before -> after): " + ", ".join(
        f"{p.parameter:.4f} ({p.count_before} -> {p.count_after})" for p in points))
    if not points:
        raise SystemExit("no bifurcation point on beta_contact")
    p = points[-1]
    for side in (1, -1):
        start = time.perf_counter()
        half = follow_bifurcating_branch(diagram, beta, p, side, max_points=args.max_points,
                                         name=f"beta_II{'+' if side > 0 else '-'}")
        if half is None:
            print(f"side {side:+d}: no first point")
            continue
        print(f"{half.name}: {len(half)} points, {time.perf_counter() - start:.1f} s, "
              f"{half.status.name}")
        for q in half.special_points:
            if q.kind == "fold":
                print(f"   fold {q.parameter:.4f} ({q.count_before} -> {q.count_after})")
            elif q.kind == "bifurcation":
                axis = mirror_axis(q)
                kind = (f"pitchfork, mode odd under the axis c = {axis}" if axis is not None
                        else "critical mode not odd under a mesh axis")
                print(f"   bifurcation {q.parameter:.4f} ({q.count_before} -> "
                      f"{q.count_after}): {kind}")
        stable = half.unstable_count == 0
        if stable.any():
            condition_e = link_writhe_slope_sign(half)[stable]
            lam = half.parameter_values[stable]
            print(f"   unstable count 0 at {int(stable.sum())} points, dLk {lam.min():.4f} .. "
                  f"{lam.max():.4f}; condition E there: {sorted(set(condition_e.tolist()))}")


if __name__ == "__main__":
    main()
