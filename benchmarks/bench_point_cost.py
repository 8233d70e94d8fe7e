"""Benchmark: what one continuation point costs, against one factorisation of its matrix.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_point_cost.py [tweezers] [ring] [--quick] [--json FILE]
    python benchmarks/bench_point_cost.py --per-call 100 200 400

The first form computes, in one warm process, the branches of

* ``tweezers``: the tweezers hat curve (C/A = 4/3, L/D = 33, F L^2/A = 75,
  0 -> 5 turns, N = 100; the library call of ``supercoil tweezers`` without
  saving or figures);
* ``ring``: the ring's alpha branch (C/A = 2/3, L/D = 122, N = 200, mode 2, to
  dLk = 6, at most 400 contact points; the library call of ``supercoil diagram
  ring --twist-ratio 2/3 --length-over-diameter 122 --nodes 200 --modes 2
  --max-excess-link 6 --contact-max-points 400`` without saving or figures);

each once as a warm-up (numba's kernels loaded), then once timed. It prints the
CPU time (``time.process_time``: a loaded host disturbs it less than the wall
time) per accepted point, the CPU time of one band LU (LAPACK's ``dgbtrf``, the
factorisation of :class:`~supercoil.continuation.bordered.BorderedFactor`) of the
branch's own bordered KKT matrix (captured during the run: the band shape met
most often), their ratio, the bordered factorisations per point, and a profile
by phase: predictor (and the rest of the step), corrector, tangent, step bound
(continuous collision detection), stability (inertia count and eigenpairs of
the accepted points), events (the user events' values at the points, the search
and localisation of special points, with their trial corrections and
counts), records, contact detection (broad and narrow phase, wherever it is
called) and what is left. A phase's time is exclusive: a call of another phase
inside it (contact detection inside the corrector, records at a special point)
counts there. ``--quick`` runs the same branches at a CI size (N = 60 to 3
turns, N = 100 to dLk = 3) in seconds; ``--nodes N`` sets N (how the ratio scales).
``--json FILE`` writes the figures.

The second form times single calls at a contact state of the tweezers problem
for each N: a residual and a Hessian at a new state, one corrector iteration
(residual, Hessian, bordered factorisation and solve), and the stability of a
point (inertia count and eigenpairs).

Point it at another source tree with ``PYTHONPATH`` to compare versions;
alternate the two trees and read the ratios, not the absolute times.
"""

from __future__ import annotations

import argparse
import collections
import json
import statistics
import time

import numpy as np

PROBLEM = {"twist_ratio": 1.3333, "length_over_diameter": 33, "tension": 75, "turns": (0, 5)}

PHASES = ("predictor and step", "corrector", "tangent", "step bound", "stability", "events", "records",
          "contact detection", "other")


def tweezers(quick: bool, n_nodes: int | None = None):
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    options = dict(PROBLEM, n_nodes=60, turns=(0, 3)) if quick else dict(PROBLEM, n_nodes=100)
    if n_nodes:
        options["n_nodes"] = n_nodes
    return tweezers_branches(TweezersOptions(**options))


def ring(quick: bool, n_nodes: int | None = None):
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    if quick:
        return ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=n_nodes or 100, modes=(2,),
                                           max_excess_link=3.0, contact_max_points=100))
    return ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=n_nodes or 200, modes=(2,),
                                       max_excess_link=6.0, contact_max_points=400))


WORKLOADS = {"tweezers": tweezers, "ring": ring}


class PhaseClock:
    """Exclusive CPU time per phase: a wrapped function's time, less that of the wrapped
    calls inside it, goes to its phase; calls of a phase inside the same phase count once."""

    def __init__(self):
        self.spent = collections.defaultdict(float)
        self.calls = collections.Counter()
        self.stack: list[list] = []  # [phase, start, time of wrapped calls inside]
        self.bands = collections.Counter()  # (size, kl, ku) of every band LU
        self.storage: dict[tuple, np.ndarray] = {}  # one band storage per shape
        self.counts = collections.Counter()  # calls of the counted kernels

    def wrap(self, owner, name: str, phase: str) -> None:
        function = getattr(owner, name)
        clock = self

        def wrapper(*args, **kwargs):
            if clock.stack and clock.stack[-1][0] == phase:
                return function(*args, **kwargs)
            frame = [phase, time.process_time(), 0.0]
            clock.stack.append(frame)
            try:
                return function(*args, **kwargs)
            finally:
                elapsed = time.process_time() - frame[1]
                clock.stack.pop()
                clock.spent[phase] += elapsed - frame[2]
                clock.calls[phase] += 1
                if clock.stack:
                    clock.stack[-1][2] += elapsed

        setattr(owner, name, wrapper)

    def count(self, owner, name: str, label: str) -> None:
        """Count the calls of ``owner.name`` under ``label`` (no clock)."""
        function = getattr(owner, name)
        counts = self.counts

        def wrapper(*args, **kwargs):
            counts[label] += 1
            return function(*args, **kwargs)

        setattr(owner, name, wrapper)

    def capture_band(self, module) -> None:
        """Count the band LUs of ``module.factor_band_storage`` and keep one storage per
        shape (copied outside the phases' clocks)."""
        function = module.factor_band_storage
        clock = self

        def wrapper(layout, flat):
            key = (layout.size, layout.kl, layout.ku)
            clock.bands[key] += 1
            if key not in clock.storage:
                start = time.process_time()
                clock.storage[key] = (layout, flat.copy())
                if clock.stack:  # not the run's cost
                    clock.stack[-1][1] += time.process_time() - start
            return function(layout, flat)

        module.factor_band_storage = wrapper


def instrument() -> PhaseClock:
    import supercoil.contact.problem as contact
    from supercoil.contact import curve
    from supercoil.continuation import (
        band_bordered,
        special_points,
        stability,
        step,
        system,
        tracer,
    )
    from supercoil.solvers import band, kkt

    clock = PhaseClock()
    clock.wrap(tracer, "take_step", "predictor and step")
    clock.wrap(step, "correct", "corrector")
    clock.wrap(step, "tangent", "tangent")
    clock.wrap(contact.ContactProblem, "step_bound", "step bound")
    clock.wrap(tracer, "point_stability", "stability")
    clock.wrap(tracer, "user_values", "events")
    clock.wrap(tracer.Tracer, "_search_events", "events")
    clock.wrap(special_points, "locate_events", "events")
    clock.wrap(tracer.Tracer, "_records", "records")
    clock.wrap(curve.ContactCurve, "pair_state", "contact detection")
    clock.wrap(contact.ContactProblem, "min_distance", "contact detection")
    clock.capture_band(band_bordered)
    # what a point needs, counted: the KKT band LUs of the inertia count and of the
    # eigenproblem's shift-invert (solvers.band's own), the exact inertia counts, the
    # eigenproblems, the Hessian assemblies and the residuals
    clock.count(band, "factor_band_storage", "KKT band LUs (count, shift-invert)")
    clock.count(kkt, "symmetric_inertia", "inertia counts (block elimination)")
    clock.count(stability, "lowest_pairs", "eigenproblems (shift-invert Lanczos)")
    clock.count(system.ExtendedSystem, "full_hessian", "Hessian assemblies")
    clock.count(system.ExtendedSystem, "hessian", "Hessian assemblies")
    clock.count(system.ExtendedSystem, "residual", "residuals")
    return clock


def band_lu_seconds(layout, flat: np.ndarray, repeat: int = 200) -> float:
    """Median CPU seconds of one ``dgbtrf`` of the captured storage (a fresh copy each)."""
    from scipy.linalg import lapack

    kl, ku, size = layout.kl, layout.ku, layout.size
    rows = 2 * kl + ku + 1
    copies = [np.asfortranarray(flat[:rows * size].reshape((rows, size), order="F"))
              for _ in range(repeat)]
    times = []
    for ab in copies:
        start = time.process_time()
        lapack.dgbtrf(ab, kl, ku, overwrite_ab=1)
        times.append(time.process_time() - start)
    # process_time's resolution: the median of single calls, and the mean of all
    return min(statistics.median(times), sum(times) / len(times))


def special_summary(result) -> list:
    return [[p.kind, p.branch, round(float(p.parameter), 5), int(p.count_before),
             int(p.count_after)] for p in result.special_points()]


def measure(workload: str, quick: bool, n_nodes: int | None = None) -> dict:
    run = WORKLOADS[workload]
    run(True)  # warm-up at the small size: kernels compiled or loaded, modules imported
    clock = instrument()
    start = time.process_time()
    result = run(quick, n_nodes)
    total = time.process_time() - start
    points = sum(len(b) for b in result.branches)
    key = clock.bands.most_common(1)[0][0]
    lu = band_lu_seconds(*clock.storage[key])
    in_phases = sum(clock.spent.values())
    spent = {phase: clock.spent.get(phase, 0.0) for phase in PHASES[:-1]}
    spent["other"] = total - in_phases
    return {"workload": workload, "quick": quick, "nodes": n_nodes, "points": points,
            "branches": {b.name: len(b) for b in result.branches},
            "cpu_seconds": total, "per_point": total / points, "band_lu": lu,
            "band": {"size": key[0], "kl": key[1], "ku": key[2]},
            "factorisations": sum(clock.bands.values()), "ratio": total / points / lu,
            "phases": spent, "phase_calls": dict(clock.calls), "counts": dict(clock.counts),
            "special_points": special_summary(result)}


def report(m: dict) -> None:
    size = m["band"]
    nodes = f", N = {m['nodes']}" if m["nodes"] else ""
    print(f"\n{m['workload']}{' (quick)' if m['quick'] else ''}{nodes}: {m['points']} points ("
          + ", ".join(f"{k} {v}" for k, v in m["branches"].items())
          + f"), {m['cpu_seconds']:.2f} s CPU")
    print(f"| per point | one band LU (n = {size['size']}, kl = {size['kl']}, ku = {size['ku']}) "
          "| ratio | band LUs per point |")
    print("|---:|---:|---:|---:|")
    print(f"| {1e3 * m['per_point']:.1f} ms | {1e3 * m['band_lu']:.3f} ms | {m['ratio']:.0f} | "
          f"{m['factorisations'] / m['points']:.1f} |")
    print("| phase | s | share | ms per point | in band LUs |")
    print("|---|---:|---:|---:|---:|")
    for phase in PHASES:
        seconds = m["phases"][phase]
        print(f"| {phase} | {seconds:.2f} | {100 * seconds / m['cpu_seconds']:.0f} % | "
              f"{1e3 * seconds / m['points']:.1f} | "
              f"{seconds / m['points'] / m['band_lu']:.0f} |")
    print("per point: " + ", ".join(f"{label} {count / m['points']:.1f}"
                                    for label, count in m["counts"].items()))
    kinds = collections.Counter(p[0] for p in m["special_points"])
    print("special points: " + ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))


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
        start = time.process_time()
        for x in states:
            function(x)
        print(f"| {n_nodes} | {label} | {1e3 * (time.process_time() - start) / repeats:.2f} |")

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
    parser.add_argument("workloads", nargs="*", default=[],
                        help="tweezers, ring (default: both)")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument("--nodes", type=int, metavar="N",
                        help="N for the branches (default 100 for the tweezers, 200 for the ring)")
    parser.add_argument("--per-call", type=int, nargs="*", metavar="N")
    args = parser.parse_args(argv)
    if args.per_call:
        print("| N | call | ms |")
        print("|---:|---|---:|")
        for n_nodes in args.per_call:
            per_call(n_nodes)
        return 0
    unknown = set(args.workloads) - set(WORKLOADS)
    if unknown:
        parser.error(f"unknown workload {sorted(unknown)}: valid are {list(WORKLOADS)}")
    measured = []
    for workload in args.workloads or list(WORKLOADS):
        measured.append(measure(workload, args.quick, args.nodes))
        report(measured[-1])
    if args.json:
        with open(args.json, "w") as f:
            json.dump(measured, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
