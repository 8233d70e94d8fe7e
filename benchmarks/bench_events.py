"""Benchmark: what locating special points costs (trial corrections, tangents, counts,
eigenproblems, user-event evaluations per located event) and which points are found.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_events.py tweezers [--nodes 100] [--json out.json]
    python benchmarks/bench_events.py ring [--nodes 200] [--json out.json]
    python benchmarks/bench_events.py compare old.json new.json

``tweezers`` is the tweezers' branch (C/A = 4/3, L/D = 33, F L^2/A = 75, 0 -> 5
turns; the library call of ``supercoil tweezers``); ``ring`` the diagram
``DiagramOptions(2/3, 122.0, n_nodes=N, modes=(2,), max_excess_link=6.0,
contact_max_points=400)``. The kernels the localisation calls (``correct``,
``tangent``, ``inertia``, ``eigenpairs``, ``user_values`` as seen from
:mod:`supercoil.continuation.events`) are wrapped by counters, attributed to the
``locate_*`` function running, and the time in ``Tracer._search_events`` is
measured. Point ``PYTHONPATH`` at another source tree (a ``git archive`` of an
older commit) to measure it; ``compare`` checks that two runs found the same
special points (kind, label, branch, counts, located) at parameters within their
tolerances and prints the evaluation counts side by side.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path


def instrumented(run) -> dict:
    from supercoil.continuation import events, special_points, tracer

    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    active = ["search"]
    spent = collections.Counter()

    def kernel(name):
        function = getattr(events, name)

        def wrapper(*args, **kwargs):
            start = time.perf_counter()
            result = function(*args, **kwargs)
            spent[f"{active[-1]}: {name}"] += time.perf_counter() - start
            counts[active[-1]][name] += 1
            if name == "correct":
                counts[active[-1]]["corrector iterations"] += result.iterations
            return result

        setattr(events, name, wrapper)

    for name in ("correct", "tangent", "inertia", "eigenpairs", "user_values"):
        kernel(name)

    def locator(name):
        function = getattr(special_points, name)

        def wrapper(*args, **kwargs):
            active.append(name)
            start = time.perf_counter()
            try:
                result = function(*args, **kwargs)
            finally:
                spent[name] += time.perf_counter() - start
                active.pop()
            counts[name]["calls"] += 1
            if result is not None:
                counts[name]["located"] += 1
            return result

        setattr(special_points, name, wrapper)

    for name in ("locate_fold", "locate_count_change", "locate_user_event"):
        locator(name)
    search = tracer.Tracer._search_events

    def timed_search(self):
        start = time.perf_counter()
        try:
            return search(self)
        finally:
            spent["_search_events"] += time.perf_counter() - start

    tracer.Tracer._search_events = timed_search
    start = time.perf_counter()
    result = run()
    total = time.perf_counter() - start
    specials = [{"branch": sp.branch, "kind": sp.kind, "label": sp.label, "index": sp.index,
                 "parameter": sp.parameter, "arclength": sp.arclength,
                 "tolerance": sp.tolerance, "located": bool(sp.located),
                 "count_before": sp.count_before, "count_after": sp.count_after}
                for b in result.branches for sp in b.special_points]
    return {"total": total, "spent": dict(spent),
            "counts": {k: dict(v) for k, v in counts.items()}, "specials": specials,
            "points": {b.name: len(b) for b in result.branches}}


def run_tweezers(n_nodes: int):
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    return lambda: tweezers_branches(TweezersOptions(
        n_nodes=n_nodes, max_points=3000, twist_ratio=1.3333, length_over_diameter=33,
        tension=75, turns=(0, 5)))


def run_ring(n_nodes: int):
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    return lambda: ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=n_nodes, modes=(2,),
                                               max_excess_link=6.0, contact_max_points=400))


def report(data: dict) -> None:
    print(f"total {data['total']:.2f} s; points {data['points']}")
    for name, seconds in sorted(data["spent"].items()):
        print(f"  {name}: {seconds:.3f} s")
    for name, counter in sorted(data["counts"].items()):
        print(f"  {name}: " + ", ".join(f"{k} {v}" for k, v in sorted(counter.items())))
    for sp in data["specials"]:
        print(f"  {sp['branch']:>24} {sp['kind']:>15} {sp['label']:>14} {sp['parameter']:.12g} "
              f"tol {sp['tolerance']:.1e} {sp['count_before']}->{sp['count_after']}"
              f"{'' if sp['located'] else ' NOT LOCATED'}")


def compare(old: dict, new: dict) -> int:
    """Same special points (kind, label, branch, counts, located) and parameters within
    the tolerances; evaluation counts side by side. Returns the number of mismatches."""
    bad = 0
    if len(old["specials"]) != len(new["specials"]):
        print(f"different numbers of special points: {len(old['specials'])} vs "
              f"{len(new['specials'])}")
        bad += 1
    worst = 0.0
    for a, b in zip(old["specials"], new["specials"]):
        keys = ("branch", "kind", "label", "count_before", "count_after", "located", "index")
        same = all(a[k] == b[k] for k in keys)
        # arclength difference against the sum of the two stated accuracies
        gap = abs(a["arclength"] - b["arclength"])
        allowed = a["tolerance"] + b["tolerance"]
        worst = max(worst, gap / allowed)
        if not same or gap > allowed:
            bad += 1
            print("MISMATCH", {k: (a[k], b[k]) for k in keys + ("parameter", "arclength")})
    print(f"{len(new['specials'])} special points; largest |s_old - s_new| / (tol_old + tol_new)"
          f" = {worst:.3g}; mismatches {bad}")
    print(f"points: old {old['points']}\n        new {new['points']}")
    for name in sorted(set(old["counts"]) | set(new["counts"])):
        o, n = old["counts"].get(name, {}), new["counts"].get(name, {})
        print(f"  {name}: " + ", ".join(f"{k} {o.get(k, 0)} -> {n.get(k, 0)}"
                                        for k in sorted(set(o) | set(n))))
    for name in sorted(set(old["spent"]) | set(new["spent"])):
        print(f"  {name}: {old['spent'].get(name, 0):.3f} -> {new['spent'].get(name, 0):.3f} s")
    return bad


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", choices=("tweezers", "ring", "compare"))
    parser.add_argument("files", nargs="*")
    parser.add_argument("--nodes", type=int, default=None)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    if args.case == "compare":
        old, new = (json.loads(Path(f).read_text()) for f in args.files)
        return 1 if compare(old, new) else 0
    run = (run_tweezers(args.nodes or 100) if args.case == "tweezers"
           else run_ring(args.nodes or 200))
    data = instrumented(run)
    report(data)
    if args.json:
        with open(args.json, "w") as out:
            json.dump(data, out, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
