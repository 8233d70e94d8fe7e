"""Benchmark: what one continuation point costs, by phase, and how the kernels grow with N.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_point_cost.py [--nodes 100] [--max-points 2000]
    python benchmarks/bench_point_cost.py --per-call 100 200 400

The first form runs the tweezers branches (C/A = 4/3, L/D = 33,
F L^2/A = 75, 0 -> 5 turns; the library call of ``supercoil tweezers``
without saving and figures) and prints a markdown table of wall time per
phase of the continuation (corrector steps, tangents, stability, event search
and localisation, records; nested calls counted once, in the outermost phase)
and per kernel (inertia count, eigenpairs, bordered factorisation, Hessian
assembly, residual, ...; these overlap the phases), measured by wrapping the
functions with timers (no profiler: cProfile inflated the many small calls
several times). The second form times single calls at a contact state of the
same problem for each N: a residual and a Hessian at a new state, one
corrector iteration (residual, Hessian, bordered factorisation and solve),
and the stability of a point (inertia count and eigenpairs). Point it at
another source tree with ``PYTHONPATH`` to compare versions.
"""

from __future__ import annotations

import argparse
import collections
import time

import numpy as np

PROBLEM = {"twist_ratio": 1.3333, "length_over_diameter": 33, "tension": 75, "turns": (0, 5)}


def breakdown(n_nodes: int, max_points: int) -> None:
    import supercoil.contact.problem as contact
    from supercoil.continuation import bordered, events, phase, stability, step, system, tracer
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    spent = collections.defaultdict(float)
    calls = collections.Counter()
    depth = [0]

    def timed(owner, name, label, phase=False):
        function = getattr(owner, name, None)
        if function is None:
            return

        def wrapper(*args, **kwargs):
            if phase and depth[0]:
                return function(*args, **kwargs)
            depth[0] += phase
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                spent[label] += time.perf_counter() - start
                calls[label] += 1
                depth[0] -= phase

        setattr(owner, name, wrapper)

    timed(step, "correct", "P corrector (the steps)", True)
    timed(step, "tangent", "P tangents", True)
    timed(phase, "tangent", "P tangents", True)
    timed(tracer, "point_stability", "P stability (inertia + eigenpairs)", True)
    timed(tracer.Tracer, "_records", "P records", True)
    timed(tracer.Tracer, "_search_events", "P event search and localisation", True)
    timed(tracer, "user_values", "P user events", True)
    for module in (stability, events):
        timed(module, "inertia", "K inertia count (KKT LU + block inertia)")
        timed(module, "eigenpairs", "K eigenpairs (shift-invert Lanczos)")
    timed(bordered.BorderedFactor, "__init__", "K bordered factorisation")
    timed(system.ExtendedSystem, "hessian", "K Hessian assembly")
    timed(system.ExtendedSystem, "residual", "K residual")
    timed(system.ExtendedSystem, "parameter_derivative", "K parameter derivative (FD)")
    timed(contact.ContactProblem, "step_bound", "K collision step bound (CCD)")
    timed(contact, "candidate_pairs", "K broad phase")
    start = time.perf_counter()
    result = tweezers_branches(TweezersOptions(n_nodes=n_nodes, max_points=max_points,
                                               **PROBLEM))
    total = time.perf_counter() - start
    points = sum(len(b) for b in result.branches)
    print(f"N = {n_nodes}: {points} points ("
          + ", ".join(f"{b.name} {len(b)}" for b in result.branches)
          + f"), {total:.2f} s, {1e3 * total / points:.1f} ms per point")
    print("| phase or kernel | s | share | calls | ms per call |")
    print("|---|---:|---:|---:|---:|")
    in_phases = 0.0
    for label, seconds in sorted(spent.items(), key=lambda t: (t[0][0] != "P", -t[1])):
        in_phases += seconds if label[0] == "P" else 0.0
        kind = "phase" if label[0] == "P" else "kernel"
        print(f"| {kind}: {label[2:]} | {seconds:.2f} | {100 * seconds / total:.0f} % | "
              f"{calls[label]} | {1e3 * seconds / max(calls[label], 1):.3f} |")
    print(f"| outside the phases | {total - in_phases:.2f} | "
          f"{100 * (total - in_phases) / total:.0f} % | | |")


def per_call(n_nodes: int) -> None:
    from supercoil.continuation.corrector import bordered_factor
    from supercoil.continuation.stability import eigenpairs, inertia, point_stability
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    result = tweezers_branches(TweezersOptions(n_nodes=n_nodes, max_points=40, **PROBLEM))
    branch, problem = result.branches[-1], result.contact_problem
    q, mu, turns = branch.states[-1], branch.multipliers[-1], branch.parameter_values[-1]
    problem.turns = turns
    problem.accept(q)
    extended = ExtendedSystem(problem, "turns", q)
    x0 = extended.pack(q, mu, turns)
    rng = np.random.default_rng(0)
    moved = np.arange(x0.size) < extended.n

    def per(label, function, repeats=100):
        states = [x0 + 1e-9 * rng.standard_normal(x0.size) * moved for _ in range(repeats)]
        function(states[0])
        start = time.perf_counter()
        for x in states:
            function(x)
        print(f"| {n_nodes} | {label} | {1e3 * (time.perf_counter() - start) / repeats:.2f} |")

    def iteration(x):
        F = extended.residual(x)
        H = extended.hessian(x)
        factor = bordered_factor(extended, x, extended.weights * x0, H)
        factor.solve(np.concatenate([F, [0.0]]))

    per("residual, new state", extended.residual)
    per("Hessian, new state", extended.hessian)
    per("one corrector iteration", iteration)
    per("stability of a point", lambda x: point_stability(extended, x, 1e-6, 6), 20)
    per("  inertia count", lambda x: inertia(extended, x, 1e-6), 20)
    per("  eigenpairs", lambda x: eigenpairs(extended, x, 8), 20)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--max-points", type=int, default=2000)
    parser.add_argument("--per-call", type=int, nargs="*", metavar="N")
    args = parser.parse_args(argv)
    if args.per_call:
        print("| N | call | ms |")
        print("|---:|---|---:|")
        for n_nodes in args.per_call:
            per_call(n_nodes)
    else:
        breakdown(args.nodes, args.max_points)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
