"""Benchmark: what one continuation point costs, against one factorisation of its matrix.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_point_cost.py [tweezers] [ring] [--quick] [--nodes N] [--json FILE]
                                          [--contact-tolerance TOL] [--without-point-eigenpairs]
                                          [--newton]
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
of special points; their localisation, with its trial corrections and counts,
by kind: user events, folds, count changes; and the special points' own
stability), records, contact detection (broad and narrow phase, wherever it is
called) and what is left. A phase's time is exclusive: a call of another phase
inside it (contact detection inside the corrector, records at a special point)
counts there. ``--quick`` runs the same branches at a CI size (N = 60 to 3
turns, N = 100 to dLk = 3) in seconds; ``--nodes N`` sets N (how the ratio scales).
``--json FILE`` writes the figures. It also prints the CPU time spent in
LAPACK's band kernels (``dgbtrf``, ``dgbtrs``: every band factorisation and
solve of the run, the bordered and the KKT ones), in band LUs per point: the
factorisation work a point cannot avoid, against all the rest.

Two switches measure levers: ``--contact-tolerance TOL`` sets the contact
branches' corrector tolerance (the commands' is 1e-8);
``--without-point-eigenpairs`` replaces the accepted points' stability by the
inertia count alone (``nearest_eigenvalue`` NaN, ``zero_modes`` 0: not a valid
result), an upper bound of what computing eigenpairs only where the count
changes would save. Alternate runs with and without, and read the ratios.
``--newton`` also prints the continuation steps' Newton iterations (accepted
and failed steps), the predictor's residual, the contraction ``e_(k+1) / e_k^2``
of their residuals ``e_k = max |F|``, and the hits and misses of the bordered
factors' pattern memo (its wrappers cost time: read the ratios without it).

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

PHASES = ("predictor and step", "corrector", "tangent", "step bound", "stability",
          "stability: the stiff sliding's check", "events",
          "events: user events", "events: folds", "events: count changes",
          "events: special points", "records", "contact detection", "other")


def tweezers(quick: bool, n_nodes: int | None = None, **extra):
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    options = dict(PROBLEM, n_nodes=60, turns=(0, 3)) if quick else dict(PROBLEM, n_nodes=100)
    if n_nodes:
        options["n_nodes"] = n_nodes
    return tweezers_branches(TweezersOptions(**options, **extra))


def ring(quick: bool, n_nodes: int | None = None, **extra):
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    if quick:
        return ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=n_nodes or 100, modes=(2,),
                                           max_excess_link=3.0, contact_max_points=100,
                                           **extra))
    return ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=n_nodes or 200, modes=(2,),
                                       max_excess_link=6.0, contact_max_points=400, **extra))


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
        self.lapack = collections.Counter()  # CPU seconds in LAPACK's band kernels
        self.lapack_calls = collections.Counter()

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

    def time_lapack(self, names=("dgbtrf", "dgbtrs")) -> None:
        """CPU time and calls of LAPACK's band kernels (looked up on ``scipy.linalg.lapack``
        at each call by the modules that use them), whatever the phase."""
        from scipy.linalg import lapack

        for name in names:
            function = getattr(lapack, name)

            def wrapper(*args, _function=function, _name=name, **kwargs):
                start = time.process_time()
                try:
                    return _function(*args, **kwargs)
                finally:
                    self.lapack[_name] += time.process_time() - start
                    self.lapack_calls[_name] += 1

            setattr(lapack, name, wrapper)

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
    clock.wrap(stability, "stiff_sliding", "stability: the stiff sliding's check")
    clock.wrap(tracer, "user_values", "events")
    clock.wrap(tracer.Tracer, "_search_events", "events")
    clock.wrap(special_points, "locate_events", "events")
    clock.wrap(special_points, "locate_user_event", "events: user events")
    clock.wrap(special_points, "locate_fold", "events: folds")
    clock.wrap(special_points, "locate_count_change", "events: count changes")
    clock.wrap(tracer, "special_point", "events: special points")
    clock.wrap(tracer.Tracer, "_records", "records")
    clock.wrap(curve.ContactCurve, "pair_state", "contact detection")
    clock.wrap(contact.ContactProblem, "min_distance", "contact detection")
    clock.capture_band(band_bordered)
    clock.time_lapack()
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


def without_point_eigenpairs() -> None:
    """The accepted points' stability without their eigenpairs: the inertia count only
    (``nearest_eigenvalue`` NaN, ``zero_modes`` 0; special points keep theirs). Not a
    valid result: what the eigenpairs of every point cost, as an upper bound of what
    computing them only where the count changes would save."""
    import numpy as np

    from supercoil.continuation import stability, tracer

    def count_only(system, x, zero_tolerance, n_modes, full=None):
        full = system.full_hessian(x) if full is None else full
        negative, sign = stability.inertia(system, x, zero_tolerance, full.restrict(system.free))
        return stability.PointStability(negative, 0, negative, sign, np.zeros(0),
                                        np.zeros((0, system.problem.n_dofs)))

    tracer.point_stability = count_only


class NewtonLog:
    """The continuation steps' corrections (``--newton``): for each, whether it converged,
    its iterations and the residuals ``max |F|`` of its iterates (the last trial of each
    damped step); and the bordered factors' pattern memo: hits, misses, and factors
    outside it (a dense phase row's pins)."""

    def __init__(self):
        from supercoil.continuation import bordered, corrector, step, system

        self.corrections: list[tuple[bool, int, list[float]]] = []
        self.memo = collections.Counter()
        residuals: list | None = None
        log = self

        residual = system.ExtendedSystem.residual
        factor = corrector.bordered_factor
        correct = step.correct
        pattern = bordered.BorderedFactor._pattern

        def logged_residual(self_, x):
            F = residual(self_, x)
            if residuals is not None:
                residuals.append(float(np.max(np.abs(F))) if F.size else 0.0)
            return F

        def logged_factor(*args, **kwargs):
            if residuals is not None:
                residuals.append(None)  # a Newton step: the residual before it is an iterate's
            return factor(*args, **kwargs)

        def logged_correct(*args, **kwargs):
            nonlocal residuals
            residuals = []
            try:
                result = correct(*args, **kwargs)
            finally:
                trace, residuals = residuals, None
            iterates = [trace[i - 1] for i, r in enumerate(trace) if r is None and i]
            log.corrections.append((result.ok, result.iterations, iterates + trace[-1:]))
            return result

        def logged_pattern(*args):
            known = {id(entry[0]) for entry in bordered._PATTERNS.values()}
            found = pattern(*args)
            remembered = found[0].words is not None
            self.memo["hit" if id(found[0]) in known else
                      "miss" if remembered else "outside the memo"] += 1
            return found

        system.ExtendedSystem.residual = logged_residual
        corrector.bordered_factor = logged_factor
        step.correct = logged_correct
        bordered.BorderedFactor._pattern = staticmethod(logged_pattern)

    def summary(self) -> dict:
        accepted = [c for c in self.corrections if c[0]]
        first = [c[2][0] for c in accepted if len(c[2]) >= 3]
        contraction = [b / a**2 for c in accepted if len(c[2]) >= 3
                       for a, b in zip(c[2], c[2][1:]) if a > 1e-6]
        quantiles = (lambda v: [float(q) for q in np.quantile(v, [0.1, 0.5, 0.9])]
                     if v else [])
        return {"accepted": len(accepted),
                "accepted_iterations": sum(c[1] for c in accepted),
                "failed": len(self.corrections) - len(accepted),
                "failed_iterations": sum(c[1] for c in self.corrections if not c[0]),
                "predictor_residual": quantiles(first),
                "contraction": quantiles(contraction), "memo": dict(self.memo)}


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


def measure(workload: str, quick: bool, n_nodes: int | None = None, newton: bool = False,
            **extra) -> dict:
    run = WORKLOADS[workload]
    run(True, **extra)  # warm-up at the small size: kernels compiled or loaded, modules imported
    clock = instrument()
    newton_log = NewtonLog() if newton else None
    start = time.process_time()
    result = run(quick, n_nodes, **extra)
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
            "lapack": dict(clock.lapack), "lapack_calls": dict(clock.lapack_calls),
            "special_points": special_summary(result),
            "newton": None if newton_log is None else newton_log.summary()}


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
    in_lapack = sum(m["lapack"].values())
    print("in LAPACK's band kernels: " + ", ".join(
        f"{name} {m['lapack_calls'][name] / m['points']:.1f} calls"
        for name in sorted(m["lapack"])) + f" a point, {1e3 * in_lapack / m['points']:.2f} ms a "
        f"point ({in_lapack / m['points'] / m['band_lu']:.1f} band LUs, "
        f"{100 * in_lapack / m['cpu_seconds']:.0f} % of the run)")
    if m.get("newton"):
        n = m["newton"]
        print(f"continuation steps: {n['accepted']} accepted, {n['accepted_iterations']} "
              f"Newton iterations ({n['accepted_iterations'] / max(n['accepted'], 1):.1f} a "
              f"step); {n['failed']} failed, {n['failed_iterations']} iterations")
        print("accepted steps of 3 or more iterations, 10th / 50th / 90th percentiles: "
              "predictor's residual " + " / ".join(f"{v:.2g}" for v in n["predictor_residual"])
              + "; e_(k+1) / e_k^2 " + " / ".join(f"{v:.2g}" for v in n["contraction"]))
        print("bordered factors' pattern memo: " + ", ".join(
            f"{k} {v}" for k, v in sorted(n["memo"].items())))
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
    parser.add_argument("--contact-tolerance", type=float, metavar="TOL",
                        help="the contact branches' corrector tolerance (default the "
                             "commands', 1e-8)")
    parser.add_argument("--newton", action="store_true",
                        help="also the continuation steps' Newton iterations, contraction "
                             "and the bordered factors' pattern memo")
    parser.add_argument("--without-point-eigenpairs", action="store_true",
                        help="the accepted points' inertia count without their eigenpairs "
                             "(not a valid result: what the eigenpairs cost)")
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
    extra = {} if args.contact_tolerance is None else {"contact_tolerance": args.contact_tolerance}
    if args.without_point_eigenpairs:
        without_point_eigenpairs()
    measured = []
    for workload in args.workloads or list(WORKLOADS):
        measured.append(measure(workload, args.quick, args.nodes, args.newton, **extra))
        report(measured[-1])
    if args.json:
        with open(args.json, "w") as f:
            json.dump(measured, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
