"""Benchmark: a long branch saved point by point, as ``supercoil tweezers`` saves it.

Every accepted point is handed to ``on_point`` as the branch so far, and the result
file appends it (``supercoil.tweezers(..., out=folder)``). The cost of that hand-over
must not grow with the branch's length, or a run of k points costs O(k^2).

The run: a long rod in the tweezers whose plectoneme branch snakes between many folds
(L/D = 100, lambda = 150, C/A = 1.5, N = 102: the mesh pins the loop's core), from 0
turns, ``--points`` points in all (default 3000). Each run is a fresh process (the
tree's ``src`` first on ``PYTHONPATH``; this tree when ``SRC`` is not given) that
prints the CPU time (``time.process_time``) of the whole run and of the hand-over
(``Tracer.publish``: the partial branch and the file's append), and the hand-over's
CPU time a point over the first and the last tenth of the points. ``--against SRC``
alternates the runs with the tree ``SRC`` (``--repeat K`` times each) and prints
their ratios, and whether the two trees' branches are equal point for point.

Run from the repository root:

    python benchmarks/bench_long_branch_saving.py [--points 3000] [--repeat K]
        [--against SRC]
"""

from __future__ import annotations

import argparse

from trees import alternated, print_ratios, run_json

RUN = r'''
import json, sys, tempfile, time
import numpy as np
import supercoil as sc
from supercoil.continuation import tracer
from supercoil.problems.greenhill import critical_turns
points = int(sys.argv[1])
marks = []
original = tracer.Tracer.publish
def publish(self):
    start = time.process_time()
    try:
        return original(self)
    finally:
        marks.append(time.process_time() - start)
tracer.Tracer.publish = publish
problem = sc.Tweezers(sc.Rod(1.5, nodes=102), tension=150.0**2,
                      contact=sc.Barrier(length_over_diameter=100.0))
target = 1.5 * critical_turns(1.5, 150.0**2)
start = time.process_time()
with tempfile.TemporaryDirectory() as folder:
    diagram = sc.tweezers(problem, (0.0, target), out=folder + "/run", max_points=points,
                          loop_sliding=True)
total = time.process_time() - start
tenth = max(len(marks) // 10, 1)
print(json.dumps({
    "total": total, "publish": sum(marks), "calls": len(marks),
    "first": sum(marks[:tenth]) / tenth, "last": sum(marks[-tenth:]) / tenth,
    "branches": {name: [b.parameter_values.tolist(), b.unstable_count.tolist()]
                 for name, b in diagram.branches.items()}}))
'''


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=3000)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--against", metavar="SRC", default=None)
    args = parser.parse_args()
    trees = [None] + ([args.against] if args.against else [])

    def report(tree, r):
        print(f"{tree or 'this tree'}: {r['calls']} points, total {r['total']:.1f} s CPU, "
              f"hand-over {r['publish']:.1f} s ({1e3 * r['first']:.2f} ms a point over "
              f"the first tenth, {1e3 * r['last']:.2f} ms over the last)", flush=True)

    # BLAS threads as the user has them: with one thread (OPENBLAS_NUM_THREADS=1) the
    # buckled branch of this coarse mesh stops near a bifurcation at 37.97 turns
    results = alternated(trees, args.repeat,
                         lambda tree: run_json(RUN, [args.points], tree), report)
    if args.against:
        print_ratios(results, args.against, ("total", "publish"), " s")
        same = results[None][-1]["branches"] == results[args.against][-1]["branches"]
        print("branches equal point for point (parameters, unstable counts):", same)


if __name__ == "__main__":
    main()
