"""Wall time of ``supercoil sweep`` on eight short tweezers branches, by number of workers.

The sweep: the hat curve of ``examples/sweep_hat_curves.toml`` (C/A = 4/3, L/D = 20,
N = 24, 0 -> 1.6 turns) at eight forces F L^2/A = 5, 10, ..., 40, each a task. For
each ``--workers K`` the whole command runs in a fresh process into a fresh folder
(cluster start, the workers' imports, the tasks, the dataset), ``--repeat`` times,
alternating the worker counts; prints the smallest and median wall time per count
and the speed-up over the first count. Checks that every run gives the same dataset.

    python benchmarks/bench_sweep.py --workers 1 2 --repeat 1
    python benchmarks/bench_sweep.py --workers 1 2 --repeat 2 --nodes 80 --stop 3
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "sweep_hat_curves.toml"
FORCES = [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0]


def study_text(nodes: int | None = None, stop: float | None = None) -> str:
    """The example's study at the eight forces; ``nodes``, ``stop`` (turns) replace the
    example's N = 24 and 1.6 turns for longer branches."""
    text = EXAMPLE.read_text(encoding="utf-8")
    head, _ = text.split("\n[sweep]\n")
    if nodes is not None:
        head = head.replace("nodes = 24", f"nodes = {nodes}")
    if stop is not None:
        head = head.replace("turns = [0.0, 1.6]", f"turns = [0.0, {stop}]")
    return head + f"\n[sweep]\n\"problem.tension\" = {FORCES}\n"


def run(study: Path, out: Path, workers: int) -> float:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "supercoil.cli.main", "sweep", str(study),
                           "--out", str(out), "--workers", str(workers), "-q"],
                          capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"supercoil sweep failed ({done.returncode}): {done.stderr}")
    return seconds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--nodes", type=int, default=None,
                        help="nodes of each branch (default: the example's 24)")
    parser.add_argument("--stop", type=float, default=None,
                        help="last turn of each branch (default: the example's 1.6)")
    args = parser.parse_args()
    from supercoil.sweeps import load_sweep

    times: dict[int, list[float]] = {k: [] for k in args.workers}
    reference = None
    with tempfile.TemporaryDirectory() as folder:
        study = Path(folder) / "sweep8.toml"
        study.write_text(study_text(args.nodes, args.stop), encoding="utf-8")
        # a first run loads (or compiles) the numba cache, untimed
        run(study, Path(folder) / "warm", 1)
        for r in range(args.repeat):
            for k in args.workers:
                out = Path(folder) / f"run{r}_{k}"
                times[k].append(run(study, out, k))
                dataset = load_sweep(out)
                if reference is None:
                    reference = dataset
                elif not dataset.equals(reference):
                    raise SystemExit(f"{k} workers gave another dataset")
    base = min(times[args.workers[0]])
    print("| workers | smallest (s) | median (s) | speed-up (smallest) |")
    print("|---|---|---|---|")
    for k in args.workers:
        best = min(times[k])
        print(f"| {k} | {best:.1f} | {statistics.median(times[k]):.1f} | {base / best:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
