"""Benchmark: factorisations of the count's matrix a point, on a tweezers branch.

Every accepted point's stability counts the negative eigenvalues of its constrained
Hessian from a sparse factorisation (``stability.inertia_with_factor``), and the check
of a count change without a fold factorises the same matrix at the step's end
(``Tracer._count_jumped``). This counts those factorisations (``KKTFactor`` made in
``supercoil.continuation.stability``) and the run's CPU time (``time.process_time``).

The run: the tweezers' branches from 0 turns to 1.5 times the buckling turns at L/D =
200, lambda = L sqrt(F/A) = 40, C/A = 1.5, N = 202 (``--ld``, ``--lam``, ``--nodes``,
``--twist-ratio`` choose another; ``--max-points``, default 4000, the points a
branch may take). Each run is a fresh process with
``OPENBLAS_NUM_THREADS=1`` (the tree's ``src`` first on ``PYTHONPATH``; this tree when
``SRC`` is not given). ``--against SRC`` alternates the runs with the tree ``SRC``
(``--repeat K`` times each), prints the medians' ratios and whether the two trees'
branches are equal bit for bit (every per-point array).

Run from the repository root:

    python benchmarks/bench_count_factorisations.py [--repeat K] [--against SRC]
        [--ld 200] [--lam 40] [--nodes 202] [--twist-ratio 1.5] [--max-points 4000]
"""

from __future__ import annotations

import argparse

from trees import alternated, print_ratios, run_json

RUN = r'''
import hashlib, importlib, json, sys, time
import supercoil as sc
from supercoil.continuation.branch import POINT_ARRAYS
from supercoil.problems.greenhill import critical_turns
stability = importlib.import_module("supercoil.continuation.stability")
ld, lam, nodes, ratio = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
most = int(sys.argv[5])
made = [0]
class Counted(stability.KKTFactor):
    def __init__(self, *args, **kwargs):
        made[0] += 1
        super().__init__(*args, **kwargs)
stability.KKTFactor = Counted
problem = sc.Tweezers(sc.Rod(ratio, nodes=nodes), tension=lam**2,
                      contact=sc.Barrier(length_over_diameter=ld))
start = time.process_time()
diagram = sc.tweezers(problem, (0.0, 1.5 * critical_turns(ratio, lam**2)), max_points=most,
                      loop_sliding=True)
total = time.process_time() - start
digest = hashlib.sha256()
for name, branch in diagram.branches.items():
    digest.update(name.encode())
    for array in POINT_ARRAYS:
        digest.update(getattr(branch, array).tobytes())
    digest.update(repr([(p.kind, p.index, p.parameter) for p in branch.special_points]).encode())
print(json.dumps({"total": total, "factorisations": made[0],
                  "points": sum(len(b) for b in diagram.branches.values()),
                  "digest": digest.hexdigest()}))
'''


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--ld", type=float, default=200.0)
    parser.add_argument("--lam", type=float, default=40.0)
    parser.add_argument("--nodes", type=int, default=202)
    parser.add_argument("--twist-ratio", type=float, default=1.5)
    parser.add_argument("--max-points", type=int, default=4000)
    args = parser.parse_args()
    trees = [None] + ([args.against] if args.against else [])
    row = (args.ld, args.lam, args.nodes, args.twist_ratio, args.max_points)

    def report(tree, r):
        print(f"{tree or 'this tree'}: {r['points']} points, {r['total']:.1f} s CPU, "
              f"{r['factorisations']} factorisations of the count "
              f"({r['factorisations'] / r['points']:.2f} a point)", flush=True)

    results = alternated(trees, args.repeat,
                         lambda tree: run_json(RUN, row, tree, {"OPENBLAS_NUM_THREADS": "1"}),
                         report)
    if args.against:
        print_ratios(results, args.against, ("total", "factorisations"))
        same = results[None][-1]["digest"] == results[args.against][-1]["digest"]
        print("branches equal bit for bit (every per-point array, special points):", same)


if __name__ == "__main__":
    main()
