"""CPU time of the figures of ``supercoil tweezers`` (issue 5's command at N = 100), drawn
from a saved run, as its figure helper draws them.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_figures.py [--run DIR]
[--against SRC] [--repeat K] [--shared] [--keep DIR]``

Each measurement is a fresh interpreter doing what the figure helper
(:mod:`supercoil.plotting.painter`) does: the collector's thresholds raised, the
warm-up (:func:`~supercoil.plotting.painter._warm_up`), the objects frozen; then the
figure jobs of the run (:func:`~supercoil.plotting.tweezers.figure_jobs`) drawn one by
one in that process, each timed in process CPU time (``time.process_time``). Prints the
smallest and the median of each figure and of all of them.

* ``--run DIR``: the output folder of one run of the command (``branch.json``,
  ``result.h5``); without it the command is run once into a temporary folder.
* ``--against SRC``: alternates every run of this tree with one of the source tree
  ``SRC`` (a ``src`` folder, e.g. ``git archive <commit> src | tar -x -C /tmp/old``),
  the order swapped every round, and compares the PNGs of the two trees' last runs
  pixel by pixel (the fraction of pixels that differ and the largest difference of a
  channel, per figure); given twice or more, every tree in each round.
* ``--shared``: the jobs drawn as the helper draws them
  (:func:`~supercoil.plotting.painter.draw_shared`: the process and a fork of it, from
  one queue); the CPU time of both processes (the process's own and its waited-for
  fork's) and the wall time of the four.
* ``--instructions``: the figures counted in instructions instead of timed, by valgrind's
  callgrind (not disturbed by other jobs, unlike CPU time on a shared host): one
  interpreter per number k = 0, 1, ... of jobs drawn (``PYTHONHASHSEED=0``), each
  figure's count the difference of two consecutive totals; millions of instructions.
  About 50 s an interpreter, five a tree.
* ``--keep DIR``: the figures of each tree's last run are kept in ``DIR/this``,
  ``DIR/against``, ``DIR/against2``, ...

Bytecode is written first (``compileall``), as an installed package has it.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# issue 5's command, a source tree put on the path, its bytecode written
from bench_fixed_costs import COMMAND, _compile, _env

CHILD = r"""
import json, os, sys, time
from pathlib import Path
import numpy as np
from supercoil._gc import collect_less, freeze
from supercoil.plotting import painter
from supercoil.plotting.tweezers import figure_jobs, pick_configurations

run, out, shared = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3] == "shared"
payload = json.loads((run / "branch.json").read_text())
from supercoil import load
stored = load(run)
states = {b["name"]: np.asarray(stored.branches[b["name"]].states)
          for b in payload["branches"] if b["name"] in stored.branches}
jobs = figure_jobs(payload, pick_configurations(payload, states), out)
if len(sys.argv) > 4:
    jobs = jobs[:int(sys.argv[4])]  # --instructions: the first k jobs
collect_less()
painter._warm_up()
freeze()
times = {}
if shared:
    before, wall = os.times(), time.perf_counter()
    painter.draw_shared(jobs, fork=True)
    after = os.times()
    times["wall"] = time.perf_counter() - wall
    times["cpu, both processes"] = sum(
        getattr(after, k) - getattr(before, k)
        for k in ("user", "system", "children_user", "children_system"))
else:
    for job in jobs:
        start = time.process_time()
        painter._draw(job)
        times[Path(job[0]).name] = time.process_time() - start
    times["all"] = sum(times.values())
print(json.dumps(times))
"""


def _measure(source: str | None, run: Path, out: Path, shared: bool) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    done = subprocess.run([sys.executable, "-c", CHILD, str(run), str(out),
                           "shared" if shared else "one"], check=True, capture_output=True,
                          text=True, env=_env(source))
    return json.loads(done.stdout.strip().splitlines()[-1])


def _instructions(source: str | None, run: Path, out: Path) -> dict:
    """Millions of instructions of each figure (callgrind, see the module doc)."""
    names = list(_measure(source, run, out / "names", False))[:-1]
    totals = []
    for k in range(len(names) + 1):
        done = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                               sys.executable, "-c", CHILD, str(run), str(out / "names"), "one",
                               str(k)], check=True, capture_output=True, text=True,
                              env={**_env(source), "PYTHONHASHSEED": "0"})
        totals.append(int(re.search(r"Collected : (\d+)", done.stderr).group(1)))
    counts = {name: (totals[i + 1] - totals[i]) / 1e6 for i, name in enumerate(names)}
    counts["all"] = (totals[-1] - totals[0]) / 1e6
    return counts


def _report(name: str, rows: list[dict]) -> None:
    parts = []
    for key in rows[0]:
        values = sorted(r[key] for r in rows)
        parts.append(f"{key} {values[0]:.3f} / {values[len(values) // 2]:.3f}")
    print(f"{name} (min / median s): " + "; ".join(parts))


def compare_pngs(first: Path, second: Path) -> None:
    """Print, per PNG of ``first``, the fraction of pixels that differ from ``second``'s
    and the largest difference of a channel (0-255)."""
    import numpy as np
    from PIL import Image

    for path in sorted(first.glob("*.png")):
        a = np.asarray(Image.open(path)).astype(int)
        b = np.asarray(Image.open(second / path.name)).astype(int)
        if a.shape != b.shape:
            print(f"  {path.name}: sizes differ, {a.shape} against {b.shape}")
            continue
        differ = np.abs(a - b).max(axis=-1)
        print(f"  {path.name}: {np.count_nonzero(differ) / differ.size:.2e} of the pixels "
              f"differ, by at most {differ.max()}; files identical: "
              f"{path.read_bytes() == (second / path.name).read_bytes()}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--run", metavar="DIR", default=None)
    parser.add_argument("--against", metavar="SRC", action="append", default=[])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--shared", action="store_true")
    parser.add_argument("--instructions", action="store_true")
    parser.add_argument("--keep", metavar="DIR", default=None)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        run = Path(args.run) if args.run else folder / "run"
        if args.run is None:
            subprocess.run([sys.executable, "-m", "supercoil.cli.main", *COMMAND, "--out",
                            str(run)], check=True, capture_output=True, env=_env(None))
        trees = {"this": None}
        for k, source in enumerate(args.against):
            trees["against" + (str(k + 1) if k else "")] = source
        for source in trees.values():
            _compile(source)
        rows: dict = {name: [] for name in trees}
        names = list(trees)
        if args.instructions:
            for name in names:
                counts = _instructions(trees[name], run, folder / "instructions" / name)
                print(f"{trees[name] or 'this'} (millions of instructions): "
                      + "; ".join(f"{key} {value:.0f}" for key, value in counts.items()))
            return
        for k in range(args.repeat):
            for name in names if k % 2 == 0 else names[::-1]:
                rows[name].append(_measure(trees[name], run, folder / name, args.shared))
        for name in names:
            _report(name if trees[name] is None else trees[name], rows[name])
        for name in names[1:]:
            print(f"pixels of this tree's figures against {trees[name]}'s:")
            compare_pngs(folder / "this", folder / name)
        if args.keep:
            for name in names:
                shutil.copytree(folder / name, Path(args.keep) / name, dirs_exist_ok=True)


if __name__ == "__main__":
    main()
