"""Benchmarks that run one script in fresh processes with two source trees, alternated.

``run_json(script, args, src, env)`` runs ``python -c script *args`` in a temporary
folder with the tree's ``src`` first on ``PYTHONPATH`` (this tree's install when
``src`` is None) and returns the JSON object its last line prints.
``alternated(trees, repeat, run, report)`` calls ``run(tree)`` for each tree in turn,
``repeat`` times, so that the host's load falls on both alike, and returns the results
per tree; ``print_ratios`` prints the medians of some keys and their ratios.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence


def run_json(script: str, args: Sequence[str], src: str | None,
             env: dict[str, str] | None = None) -> dict:
    environment = dict(os.environ, **(env or {}))
    if src:
        environment["PYTHONPATH"] = (os.path.abspath(src) + os.pathsep
                                     + environment.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory() as cwd:
        out = subprocess.run([sys.executable, "-c", script, *map(str, args)],
                             env=environment, cwd=cwd, capture_output=True, text=True,
                             check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def alternated(trees: Sequence[str | None], repeat: int, run: Callable[[str | None], dict],
               report: Callable[[str | None, dict], None]) -> dict:
    results: dict = {tree: [] for tree in trees}
    for _ in range(repeat):
        for tree in trees:
            result = run(tree)
            results[tree].append(result)
            report(tree, result)
    return results


def print_ratios(results: dict, against: str, keys: Sequence[str], unit: str = "") -> None:
    for key in keys:
        here = statistics.median(r[key] for r in results[None])
        there = statistics.median(r[key] for r in results[against])
        print(f"median {key}: this tree {here:.1f}{unit}, against {there:.1f}{unit}, "
              f"ratio {here / there:.3f}")
