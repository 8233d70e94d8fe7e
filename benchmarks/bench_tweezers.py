"""Benchmark of issue 5: the whole tweezers branch 0 -> 5 turns, N = 100, L/D = 33, C/A = 4/3,
F L^2/A = 75 (the problem the issue quotes for PyElastica), timed for the whole command.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_tweezers.py [--nodes N] [--stop T]``.
Prints wall time, points per branch, folds, the last state's extension and writhe, and the
largest KKT residual and overlap. PyElastica is not run (not implemented; see docs).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--stop", type=float, default=5.0)
    parser.add_argument("--max-points", type=int, default=3000)
    args = parser.parse_args()
    import json

    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run"
        cmd = [sys.executable, "-m", "supercoil.cli.main", "tweezers", "--twist-ratio",
               str(4 / 3), "--length-over-diameter", "33", "--tension", "75", "--turns",
               f"0:{args.stop}", "--nodes", str(args.nodes), "--max-points",
               str(args.max_points), "--out", str(out)]
        start = time.perf_counter()
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True)
        wall = time.perf_counter() - start
        print(proc.stdout, proc.stderr)
        data = json.loads((out / "branch.json").read_text())
    last = data["points"][-1]
    folds = sum(s["kind"] == "fold" for s in data["special_points"])
    gaps = [p["min_gap_over_diameter"] for p in data["points"]
            if p["branch"].endswith("_contact")]
    print(f"wall time {wall:.1f} s (exit {proc.returncode}); points "
          + ", ".join(f"{b['name']} {b['n_points']} ({b['seconds']:.1f} s)"
                      for b in data["branches"]))
    print(f"last state: turns {last['turns']:.4f}, extension {last['extension']:.4f}, "
          f"writhe {last['writhe']:.4f}, unstable_count {last['unstable_count']}; "
          f"{folds} folds; min gap/D on contact branch {min(gaps) if gaps else float('nan'):.4f}")


if __name__ == "__main__":
    main()
