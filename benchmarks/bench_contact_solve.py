"""Benchmark: one equilibrium solve of a ring with self-contact from a nearby state.

Run from the repository root:

    python benchmarks/bench_contact_solve.py [--nodes 200] [--treatment barrier]

Set-up (untimed): the twisted ring C/A = 1, L/D = 100, excess link 3.0 is
relaxed from its perturbed circle to a stable supercoiled equilibrium with
contact (``solve_supercoiled_ring``'s path). Timed: the excess link is
raised by ``--step`` (0.02 turns by default) and the equilibrium is solved
again from the previous one with :func:`supercoil.contact.solve.solve_contact`
(Newton with the collision guard), as a continuation step would; the best and
the median of ``--repeat`` such steps are reported (each from the same
starting state), warm. Target: at most 0.1 s at N = 200.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200)
    parser.add_argument("--treatment", default="barrier", help="contact treatment (default: the library default)")
    parser.add_argument("--step", type=float, default=0.02)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)

    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.contact.solve import solve_contact
    from supercoil.problems.ring_contact import solve_supercoiled_ring
    from supercoil.rod.closed import ClosedRodEnergy
    from supercoil.rod.model import Rod
    from supercoil.solvers.newton import NewtonOptions

    excess_link, lod = 3.0, 100.0
    t0 = time.perf_counter()
    ring = solve_supercoiled_ring(1.0, excess_link, lod, args.nodes,
                                  treatment=args.treatment)
    setup = time.perf_counter() - t0
    if not ring.converged:
        print(f"set-up relaxation failed: {ring.message}")
        return 1
    print(f"set-up: relaxed from the circle, writhe {ring.writhe:.4f}, {setup:.1f} s "
          "(includes compilation)")
    rod = Rod(n_nodes=args.nodes, twist_stiffness=1.0)
    options = NewtonOptions(tolerance=1e-9, max_iterations=1000)
    problem = ContactProblem(ClosedRodEnergy(rod, ring.points, excess_link),
                             ContactOptions(diameter=1.0 / lod, treatment=args.treatment))
    relaxed = solve_contact(problem, ring.points.ravel(), options)  # the treatment's state
    if not relaxed.converged:
        print(f"set-up solve failed: {relaxed.message}")
        return 1
    q0 = relaxed.q
    times, iterations = [], []
    for k in range(args.repeat + 1):
        # the problem at the raised excess link, from the relaxed state and the
        # treatment's state there (multipliers, active set), as a continuation step
        trial = problem.at(excess_link=excess_link + args.step)
        t = time.perf_counter()
        res = solve_contact(trial, q0, options)
        elapsed = time.perf_counter() - t
        if not res.converged:
            print(f"nearby solve failed: {res.message}")
            return 1
        if k:  # the first run is the warm-up
            times.append(elapsed)
            iterations.append(res.newton_iterations)
    print("| N | treatment | dLk step | Newton iterations | best (s) | median (s) |")
    print("|---:|---|---:|---:|---:|---:|")
    print(f"| {args.nodes} | {args.treatment} | {args.step} | {iterations[0]} | "
          f"{min(times):.3f} | {statistics.median(times):.3f} |")
    target = 0.1
    verdict = "meets" if statistics.median(times) <= target else "misses"
    print(f"median {verdict} the {target} s target (at N = 200)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
