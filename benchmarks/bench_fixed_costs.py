"""Fixed costs of ``supercoil tweezers`` (the tweezers benchmark's command at N = 100), each
part alone.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fixed_costs.py PART [--against SRC]
[--repeat K]`` with PART one of

* ``imports``: a fresh interpreter imports ``supercoil.cli.main`` and the modules the
  tweezers command imports before it computes; wall time of the imports.
* ``exit``: the whole command; time from its last output line ('wrote branch.json ...')
  to the end of its process (the interpreter's exit), and the whole wall time.

``--against SRC`` alternates every run with the source tree ``SRC`` (a ``src`` folder,
e.g. ``git archive <commit> src | tar -x -C /tmp/old``), for ``imports`` and ``exit``.
Prints the smallest and the median of each. Bytecode is written first (``compileall``),
as an installed package has it.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMMAND = ["tweezers", "--twist-ratio", str(4 / 3), "--length-over-diameter", "33",
           "--tension", "75", "--turns", "0:5", "--nodes", "100", "--quiet"]
IMPORTS = ("import time; t = time.perf_counter(); import supercoil.cli.main; "
           "import supercoil.problems.tweezers, supercoil.cli.diagram_output; "
           "print(time.perf_counter() - t)")


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


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("part", choices=("imports", "exit"))
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
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
