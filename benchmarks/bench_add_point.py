"""Benchmark: the cost of an accepted continuation point beyond the corrector
(``Tracer.add_point``: stability, records, event search, the partial branch for
``on_point`` and its saves), alternated between two source trees, with the results
compared.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_add_point.py [--problem tweezers|ring] [--repeat K]
        [--against SRC]

``tweezers``: the library call of ``supercoil tweezers`` (C/A = 4/3,
L/D = 33, F L^2/A = 75, 0 -> 5 turns, N = 100), without saving or figures. ``ring``: the ring diagram of
``bench_ring_diagram.py`` (C/A = 2/3, L/D = 122, N = 200, mode 2, dLk to 6) after a
warm-up at N = 48. Each run is a fresh process (the tree's ``src`` first on
``PYTHONPATH``; this tree when ``SRC`` is not given) that computes once to warm the
caches, then once timed: it prints the CPU time (``time.process_time``: less
disturbed by other jobs on a shared machine than the wall time) of the whole
computation and of ``Tracer.add_point``. ``--against SRC`` alternates the runs with
the tree ``SRC`` and prints the smallest and median times of each tree, their ratios,
and the comparison of the last runs' results: per branch the unstable counts, zero
modes and determinant signs (equal or not), the largest difference of the nearest
eigenvalues (relative to the largest), of the accepted points' parameters, and of the
special points' parameters (kinds and counts before / after equal or not).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

RUN = r'''
import json, sys, time
import numpy as np
from supercoil.continuation import tracer
spent = [0.0]
original = tracer.Tracer.add_point
def add_point(*args, **kwargs):
    start = time.process_time()
    try:
        return original(*args, **kwargs)
    finally:
        spent[0] += time.process_time() - start
tracer.Tracer.add_point = add_point
if sys.argv[1] == "tweezers":
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
    options = TweezersOptions(4 / 3, 33.0, tension=75.0, turns=(0, 5), n_nodes=100)
    def compute():
        return tweezers_branches(options).branches
else:
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
    ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=48, modes=(2,), max_excess_link=2.0))
    def compute():
        return ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=200, modes=(2,))).branches
compute()
spent[0] = 0.0
start = time.process_time()
branches = compute()
total = time.process_time() - start
out = {"total": total, "add_point": spent[0], "branches": {b.name: {
    "unstable": b.unstable_count.tolist(), "zero": b.zero_modes.tolist(),
    "det": b.determinant_sign.tolist(), "nearest": b.nearest_eigenvalue.tolist(),
    "parameter": b.parameter_values.tolist(),
    "special": [[p.kind, p.count_before, p.count_after, p.parameter]
                for p in b.special_points]} for b in branches}}
print(json.dumps(out))
'''


def run(problem: str, source: str | None) -> dict:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as an installed package: bytecode kept
    if source is not None:
        env["PYTHONPATH"] = os.pathsep.join([source, env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep)
    with tempfile.TemporaryDirectory() as folder:
        proc = subprocess.run([sys.executable, "-c", RUN, problem], env=env, cwd=folder,
                              capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def compare(new: dict, old: dict) -> None:
    for name, b in new["branches"].items():
        a = old["branches"].get(name)
        if a is None or len(a["parameter"]) != len(b["parameter"]):
            print(f"  {name}: points {len(b['parameter'])} here, "
                  f"{None if a is None else len(a['parameter'])} there")
            continue
        same = {k: a[k] == b[k] for k in ("unstable", "zero", "det")}
        scale = max(max(map(abs, a["nearest"]), default=0.0), 1e-300)
        d_eig = max((abs(x - y) for x, y in zip(a["nearest"], b["nearest"])), default=0.0)
        d_par = max((abs(x - y) for x, y in zip(a["parameter"], b["parameter"])), default=0.0)
        kinds = [s[:3] for s in a["special"]] == [s[:3] for s in b["special"]]
        d_special = max((abs(x[3] - y[3]) for x, y in zip(a["special"], b["special"])),
                        default=0.0)
        print(f"  {name}: {len(b['parameter'])} points; counts/zero modes/det signs equal "
              f"{same['unstable']}/{same['zero']}/{same['det']}; nearest eigenvalue "
              f"{d_eig / scale:.1e} of the largest; parameters {d_par:.1e}; "
              f"{len(b['special'])} special points, kinds and counts equal {kinds}, "
              f"parameters within {d_special:.1e}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--problem", choices=("tweezers", "ring"), default="tweezers")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--against", metavar="SRC", default=None)
    args = parser.parse_args()
    trees = [None] + ([args.against] if args.against else [])
    times: dict = {tree: [] for tree in trees}
    last: dict = {}
    for _ in range(args.repeat):
        for tree in trees:
            result = run(args.problem, tree)
            last[tree] = result
            times[tree].append((result["total"], result["add_point"]))
            print(f"{tree or 'this tree'}: computation {result['total']:.3f} s CPU, "
                  f"add_point {result['add_point']:.3f} s", flush=True)
    for tree, rows in times.items():
        totals, points = [r[0] for r in rows], [r[1] for r in rows]
        print(f"{tree or 'this tree'}: computation min {min(totals):.3f} median "
              f"{statistics.median(totals):.3f}; add_point min {min(points):.3f} median "
              f"{statistics.median(points):.3f} (s CPU)")
    if args.against:
        here, there = times[None], times[args.against]
        for i, label in enumerate(("computation", "add_point")):
            print(f"ratio this / against, {label}: min "
                  f"{min(r[i] for r in here) / min(r[i] for r in there):.3f}, median "
                  f"{statistics.median(r[i] for r in here) / statistics.median(r[i] for r in there):.3f}")
        print("results, this tree against the other:")
        compare(last[None], last[args.against])


if __name__ == "__main__":
    main()
