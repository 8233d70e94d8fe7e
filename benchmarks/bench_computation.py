"""The computation of the tweezers branch and of the ring diagram, in one warm process.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_computation.py WORKLOAD [--repeat K]
[--against SRC]`` with WORKLOAD one of

* ``tweezers``: :func:`supercoil.problems.tweezers.tweezers_branches` with the options of
  ``supercoil tweezers --twist-ratio 1.3333 --length-over-diameter 33 --tension 75
  --turns 0:5 --nodes 100``;
* ``ring``: :func:`supercoil.problems.ring_diagram.ring_diagram` with the options of
  ``supercoil demo`` (C/A = 2/3, L/D = 122, N = 132, modes 2 and 3, dLk <= 3, at most
  300 points per contact branch, the double-integral contact on the cubic B-spline).

The workload runs once as a warm-up (numba's kernels loaded or compiled, every module
imported), then ``K`` times in the same process; the smallest and the median wall time
and CPU time (``time.process_time``: all threads of the process, less disturbed than
the wall time by other jobs on a shared machine) of those runs are printed, with a
fingerprint of the result (points per branch, the last parameter value of each) to
check that two trees compute the same branches.

``--against SRC`` alternates the measurement with the source tree ``SRC`` (a ``src``
folder): each round runs a fresh process for each tree, the warm-up and ``K`` runs in
it; the rounds' times are pooled per tree. Without it the workload runs in this
process, on the ``supercoil`` that ``PYTHONPATH`` gives.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time


def tweezers() -> object:
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    options = TweezersOptions(twist_ratio=1.3333, length_over_diameter=33.0, tension=75.0,
                              turns=(0.0, 5.0), n_nodes=100)
    return tweezers_branches(options)


def ring() -> object:
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    options = DiagramOptions(2.0 / 3.0, 122.0, n_nodes=132, modes=(2, 3), max_excess_link=3.0,
                             contact_max_points=300, contact_formulation="integral",
                             contact_curve="spline")
    return ring_diagram(options)


WORKLOADS = {"tweezers": tweezers, "ring": ring}


def fingerprint(result) -> list:
    """Points and last parameter value of every branch."""
    return [[b.name, len(b), round(float(b.parameter_values[-1]), 6) if len(b) else None]
            for b in result.branches]


def measure(workload: str, repeat: int) -> dict:
    """Warm-up, then ``repeat`` timed runs in this process."""
    run = WORKLOADS[workload]
    start = time.perf_counter()
    result = run()
    warm_up = time.perf_counter() - start
    times, cpu = [], []
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        result = run()
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return {"warm_up": warm_up, "times": times, "cpu": cpu, "fingerprint": fingerprint(result)}


def _in_process(source: str, workload: str, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=source)
    out = subprocess.run([sys.executable, __file__, workload, "--repeat", str(repeat),
                          "--json"], check=True, capture_output=True, text=True,
                         env=env).stdout
    return json.loads(out.strip().splitlines()[-1])


def _summary(label: str, times: list[float], cpu: list[float]) -> str:
    return (f"{label}: wall min {min(times):.2f} s, median {statistics.median(times):.2f} s; "
            f"CPU min {min(cpu):.2f} s, median {statistics.median(cpu):.2f} s "
            f"({len(times)} runs)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("workload", choices=sorted(WORKLOADS))
    parser.add_argument("--repeat", type=int, default=3, metavar="K")
    parser.add_argument("--rounds", type=int, default=2,
                        help="with --against: processes per tree, alternated")
    parser.add_argument("--against", metavar="SRC")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.json:
        print(json.dumps(measure(args.workload, args.repeat)))
        return
    if args.against is None:
        import supercoil

        data = measure(args.workload, args.repeat)
        print(f"{args.workload} ({os.path.dirname(supercoil.__file__)}): "
              f"warm-up {data['warm_up']:.2f} s")
        print(_summary(args.workload, data["times"], data["cpu"]))
        print("fingerprint:", json.dumps(data["fingerprint"]))
        return
    here = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")
    trees = {"this tree": here, "against": os.path.abspath(args.against)}
    pooled: dict[str, list[float]] = {name: [] for name in trees}
    pooled_cpu: dict[str, list[float]] = {name: [] for name in trees}
    prints = {}
    for index in range(args.rounds):
        for name, source in (trees.items() if index % 2 == 0 else reversed(trees.items())):
            data = _in_process(source, args.workload, args.repeat)
            pooled[name] += data["times"]
            pooled_cpu[name] += data["cpu"]
            prints[name] = data["fingerprint"]
            print(f"round {index + 1}, {name}: wall "
                  + ", ".join(f"{t:.2f}" for t in data["times"]) + "; CPU "
                  + ", ".join(f"{t:.2f}" for t in data["cpu"]), flush=True)
    for name, source in trees.items():
        print(_summary(f"{name} ({source})", pooled[name], pooled_cpu[name]))
    same = prints["this tree"] == prints["against"]
    print("same branches" if same else "different branches: "
          + json.dumps(prints))


if __name__ == "__main__":
    main()
