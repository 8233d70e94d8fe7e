"""Fixed costs of ``supercoil tweezers`` (issue 5's command at N = 100), each part alone.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fixed_costs.py PART [--against SRC]
[--repeat K]`` with PART one of

* ``imports``: a fresh interpreter imports ``supercoil.cli.main`` and the modules the
  tweezers command imports before it computes; wall time of the imports.
* ``exit``: the whole command; time from its last output line ('wrote branch.json ...')
  to the end of its process (the interpreter's exit, the figure helper's end), and the
  whole wall time.
* ``figures``: the four figures of one run of the command, drawn after a warm-up
  (matplotlib imported, a small figure drawn, as the figure helper does) in one
  process, then shared with a fork (:func:`supercoil.plotting.painter.draw_shared`);
  this tree only.
* ``fallback``: the same four figures drawn by a fresh interpreter that imported the
  tweezers modules but not matplotlib (the command's own process when its helper
  was not ready): one by one, or by ``draw_shared`` (the first, then a fork);
  this tree only, the two alternated.

``--against SRC`` alternates every run with the source tree ``SRC`` (a ``src`` folder,
e.g. ``git archive <commit> src | tar -x -C /tmp/old``), for ``imports`` and ``exit``.
Prints the smallest and the median of each. Bytecode is written first (``compileall``),
as an installed package has it.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMMAND = ["tweezers", "--twist-ratio", str(4 / 3), "--length-over-diameter", "33",
           "--tension", "75", "--turns", "0:5", "--nodes", "100", "--quiet"]
IMPORTS = ("import time; t = time.perf_counter(); import supercoil.cli.main; "
           "import supercoil.problems.tweezers, supercoil.cli.diagram_output, "
           "supercoil.plotting.painter; print(time.perf_counter() - t)")


def _env(source: str | None) -> dict:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if source is not None:
        env["PYTHONPATH"] = os.pathsep.join([source, env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep)
    return env


def _compile(source: str | None) -> None:
    code = "import os, supercoil; print(os.path.dirname(supercoil.__file__))"
    folder = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                            text=True, env=_env(source)).stdout.strip()
    subprocess.run([sys.executable, "-m", "compileall", "-q", folder], check=True,
                   capture_output=True, env=_env(source))


def _imports(source: str | None) -> tuple[float, ...]:
    out = subprocess.run([sys.executable, "-c", IMPORTS], check=True, capture_output=True,
                         text=True, env=_env(source)).stdout
    return (float(out.strip().splitlines()[-1]),)


def _exit(source: str | None) -> tuple[float, ...]:
    with tempfile.TemporaryDirectory() as folder:
        cmd = [sys.executable, "-m", "supercoil.cli.main", *COMMAND, "--out",
               str(Path(folder) / "run")]
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                text=True, env=_env(source))
        last = None
        for line in proc.stdout:
            if line.startswith("wrote branch.json"):
                last = time.perf_counter()
        proc.wait()
        end = time.perf_counter()
    if last is None:
        raise RuntimeError(f"the command ended with status {proc.returncode} before its "
                           "last line")
    return end - last, end - start


def _report(name: str, rows: list[tuple[float, ...]], labels: tuple[str, ...]) -> None:
    parts = []
    for k, label in enumerate(labels):
        values = sorted(r[k] for r in rows)
        parts.append(f"{label} min {values[0]:.3f} median {values[len(values) // 2]:.3f} s")
    print(f"{name}: " + "; ".join(parts))


FALLBACK = """
import pickle, sys, time
import supercoil.problems.tweezers  # a process of the command's size
from supercoil.plotting import painter
jobs = pickle.loads(open(sys.argv[1], "rb").read())
start = time.perf_counter()
if sys.argv[2] == "shared":
    painter.draw_shared(jobs)
else:
    for job in jobs:
        painter._draw(job)
print(time.perf_counter() - start)
"""


def _jobs(folder: str) -> list:
    """The figure jobs of one run of the command (this tree), drawing into ``folder``."""
    import numpy as np

    from supercoil.plotting.tweezers import figure_jobs, pick_configurations

    run = Path(folder) / "run"
    subprocess.run([sys.executable, "-m", "supercoil.cli.main", *COMMAND, "--out",
                    str(run)], check=True, capture_output=True, env=_env(None))
    payload = json.loads((run / "branch.json").read_text())
    from supercoil import load

    stored = load(run)
    states = {b["name"]: np.asarray(stored.branch(b["name"]).states)
              for b in payload["branches"]}
    return figure_jobs(payload, pick_configurations(payload, states), folder)


def _fallback(repeat: int) -> None:
    import pickle

    rows: dict = {"one by one": [], "shared": []}
    with tempfile.TemporaryDirectory() as folder:
        jobs_file = Path(folder) / "jobs.pkl"
        jobs_file.write_bytes(pickle.dumps(_jobs(folder)))
        for _ in range(repeat):
            for mode, values in rows.items():
                out = subprocess.run([sys.executable, "-c", FALLBACK, str(jobs_file), mode],
                                     check=True, capture_output=True, text=True,
                                     env=_env(None)).stdout
                values.append((float(out.strip().splitlines()[-1]),))
    for mode, values in rows.items():
        _report(mode, values, ("figures",))


def _figures(repeat: int) -> None:
    from supercoil.plotting.painter import _warm_up, draw_shared

    with tempfile.TemporaryDirectory() as folder:
        jobs = _jobs(folder)
        _warm_up()
        rows = {False: [], True: []}
        for _ in range(repeat):
            for fork in (False, True):
                start = time.perf_counter()
                draw_shared(jobs, fork=fork)
                rows[fork].append((time.perf_counter() - start,))
    _report("one process", rows[False], ("figures",))
    _report("with a fork", rows[True], ("figures",))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("part", choices=("imports", "exit", "figures", "fallback"))
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    if args.part in ("figures", "fallback"):
        (_figures if args.part == "figures" else _fallback)(args.repeat)
        return
    trees = [None] + ([args.against] if args.against else [])
    for tree in trees:
        _compile(tree)
    measure, labels = ((_imports, ("imports",)) if args.part == "imports"
                       else (_exit, ("exit after the last line", "wall")))
    rows: dict = {tree: [] for tree in trees}
    for _ in range(args.repeat):
        for tree in trees:
            rows[tree].append(measure(tree))
    for tree in trees:
        _report(tree or "this tree", rows[tree], labels)


if __name__ == "__main__":
    main()
