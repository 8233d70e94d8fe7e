"""Benchmark: the whole tweezers branch 0 -> 5 turns, N = 100, L/D = 33, C/A = 4/3,
F L^2/A = 75 (the problem also run with PyElastica), timed for the whole command.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_tweezers.py [--nodes N] [--stop T]
[--repeat K [--against SRC [--against-seconds S]]] [--bytecode] [--pyelastica PYTHON [--pyelastica-steps K] [--repeat K]]``.
Prints wall time, points per branch, folds, the last state's extension and writhe and the
closest approach. ``--repeat K`` runs the command K times and prints the smallest and
the median wall and CPU time (user + system of the command's process); with
``--against SRC`` each run alternates with one of the source tree ``SRC`` (its
``src`` folder, put on ``PYTHONPATH``; e.g. a ``git archive`` of an older commit) and
the ratio of the smallest times is printed: on a shared machine the smallest of
alternated runs is the least disturbed comparison. ``--against-seconds S`` (with
``--against``): ``SRC``'s smallest wall time measured on a reference host; the host's
slowdown against it (``SRC``'s smallest time now over ``S``) and this tree's time scaled
to the reference host are printed too, a ruler for a host whose speed varies
(e.g. ``git archive 1a51be0 src``: 2.81 s on a quiet host of this machine). Each round is preceded by a
pure-Python probe (``probe``, printed), the host's speed at that moment. ``--bytecode`` first compiles the
timed source trees' modules (``python -m compileall``), as an installed package has them:
where the environment sets ``PYTHONDONTWRITEBYTECODE=1`` (this machine's), every run
otherwise compiles supercoil's 850 kB of source again (about 0.5 s of the command,
measured: the command's imports 1.06-1.10 s without, 0.58-0.59 s with). With ``--pyelastica PYTHON`` (an interpreter with PyElastica installed,
``pip install pyelastica`` or ``pip install -e ".[pyelastica]"``) the same problem is run
by :mod:`bench_tweezers_pyelastica` (explicit dynamics to rest, 1.1 million steps at N = 100;
``--pyelastica-steps`` runs only that many and extrapolates the time) and the wall-time
ratio and the agreement of extension and writhe are printed. With ``--repeat K`` too, the
command runs K times before PyElastica and K times after it, in one sitting, and the ratio
of PyElastica's time to the command's smallest (and median) is printed: the
target, 2 s where PyElastica needs about 400 s, is a ratio of at least 200, a figure that
does not depend on the host's speed of the hour as an absolute time does.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def timed_command(cmd: list[str], source: str | None) -> tuple[float, float, subprocess.CompletedProcess]:
    """``(wall s, CPU s of the process, completed process)`` of one run of ``cmd``
    (``source``: a ``src`` folder put first on ``PYTHONPATH``)."""
    env = dict(os.environ)
    if source is not None:
        env["PYTHONPATH"] = os.pathsep.join([source, env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, check=False, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc


def compile_trees(sources: list[str | None]) -> None:
    """Write the bytecode of the supercoil package of each source tree (None: the one this
    interpreter imports) with ``python -m compileall``, as pip does on installation."""
    for source in sources:
        env = dict(os.environ)
        if source is not None:
            env["PYTHONPATH"] = os.pathsep.join([source, env.get("PYTHONPATH", "")]).rstrip(
                os.pathsep)
        code = "import os, supercoil; print(os.path.dirname(supercoil.__file__))"
        where = subprocess.run([sys.executable, "-c", code], check=True,
                               capture_output=True, text=True, env=env)
        folder = where.stdout.strip()
        subprocess.run([sys.executable, "-m", "compileall", "-q", folder], check=True,
                       capture_output=True, env=env)
        print(f"compiled {folder}")


PROBE = compile("s = 0\nfor i in range(3_000_000):\n    s += i\n", "<probe>", "exec")


def probe() -> float:
    """Process time of a fixed pure-Python loop, run at module level (globals, as the
    ``python -c`` probe runs it: in a function's locals it runs about twice as fast):
    the host's speed, 0.15 s on a quiet host of this machine, 0.26-0.29 s on a busy
    one."""
    start = time.process_time()
    exec(PROBE, {})  # noqa: S102 (a constant loop)
    return time.process_time() - start


def repeated(cmd_for, repeat: int, against: str | None,
             against_seconds: float | None = None) -> None:
    """Run the command ``repeat`` times (alternating with ``against``); print min/median,
    and the host's speed (:func:`probe`) before each round. ``against_seconds``: the
    smallest wall time of ``against`` measured on a reference host (a quiet hour); this
    tree's smallest time is then also printed scaled to that host's speed: this tree's
    minimum times ``against_seconds`` over ``against``'s minimum now."""
    trees = [None] + ([against] if against else [])
    times: dict[str | None, list[tuple[float, float]]] = {t: [] for t in trees}
    probes = []
    for _ in range(repeat):
        probes.append(probe())
        print(f"probe {probes[-1]:.3f} s", flush=True)
        for tree in trees:
            with tempfile.TemporaryDirectory() as folder:
                wall, cpu, proc = timed_command(cmd_for(Path(folder) / "run"), tree)
            if proc.returncode != 0:
                print(f"exit {proc.returncode}: {proc.stderr.strip()[-300:]}")
            label = tree or "this tree"
            print(f"{label}: wall {wall:.2f} s, cpu {cpu:.2f} s", flush=True)
            times[tree].append((wall, cpu))
    best = {}
    for tree, rows in times.items():
        walls, cpus = sorted(r[0] for r in rows), sorted(r[1] for r in rows)
        best[tree] = (walls[0], cpus[0])
        print(f"{tree or 'this tree'}: wall min {walls[0]:.2f} median {walls[len(walls) // 2]:.2f}"
              f" s; cpu min {cpus[0]:.2f} median {cpus[len(cpus) // 2]:.2f} s")
    probes.sort()
    print(f"probe min {probes[0]:.3f} median {probes[len(probes) // 2]:.3f} s")
    if against:
        print(f"ratio this / against (smallest): wall {best[None][0] / best[against][0]:.2f}, "
              f"cpu {best[None][1] / best[against][1]:.2f}")
        if against_seconds is not None:
            slower = best[against][0] / against_seconds
            print(f"host {slower:.2f} times slower than the reference ({against} took "
                  f"{against_seconds:.2f} s there): this tree there about "
                  f"{best[None][0] / slower:.2f} s (scaled, not measured)")


def run_peer(args) -> dict | None:
    """Run :mod:`bench_tweezers_pyelastica` with ``args.pyelastica``; its JSON result (with
    ``wall``, the wall time of the whole subprocess), or None after printing its error."""
    import json

    peer = Path(__file__).with_name("bench_tweezers_pyelastica.py")
    cmd = [args.pyelastica, str(peer), "--elements", str(args.nodes), "--turns",
           str(args.stop), "--steps", str(args.pyelastica_steps)]
    start = time.perf_counter()
    run = subprocess.run(cmd, check=False, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if run.returncode != 0:
        print("PyElastica run failed:", run.stderr.strip().splitlines()[-1:])
        return None
    result = json.loads(run.stdout.strip().splitlines()[-1])
    result["wall"] = wall
    return result


def print_agreement(peer: dict, last: dict) -> None:
    """PyElastica's end state (a full run's result) against supercoil's last point."""
    print(f"  extension {peer['extension']:.4f} (supercoil {last['extension']:.4f}), "
          f"writhe {peer['writhe']:.4f} (supercoil {last['writhe']:.4f}), "
          f"overlap {100 * peer['overlap_over_diameter']:.2f} % of D, "
          f"largest speed {peer['largest_speed']:.2e}")


def peer_against_repeats(cmd_for, args) -> None:
    """``--repeat K --pyelastica PYTHON``: the command K times, PyElastica once, the
    command K times again, all in one sitting, so that the wall-time ratio (PyElastica's
    time over the command's smallest, and over its median) is measured on one host at one
    speed. The target (the whole command in at most 2 s where PyElastica needs about
    400 s) is a ratio of at least 200; a full PyElastica run took 446 s on this machine
    (ratio 223 for 2 s). Prints the agreement of the
    extension and writhe at the last turn too (full PyElastica runs only)."""
    import json

    def rounds(count: int, walls: list[float], last: list[dict]) -> None:
        for _ in range(count):
            print(f"probe {probe():.3f} s", flush=True)
            with tempfile.TemporaryDirectory() as folder:
                out = Path(folder) / "run"
                wall, cpu, proc = timed_command(cmd_for(out), None)
                if proc.returncode != 0:
                    print(f"exit {proc.returncode}: {proc.stderr.strip()[-300:]}")
                    continue
                last[:] = [json.loads((out / "branch.json").read_text())["points"][-1]]
            print(f"supercoil: wall {wall:.2f} s, cpu {cpu:.2f} s", flush=True)
            walls.append(wall)

    walls: list[float] = []
    last: list[dict] = []
    rounds(args.repeat, walls, last)
    print("PyElastica running ...", flush=True)
    peer = run_peer(args)
    if peer is None:  # no ratio to measure: the second rounds would be wasted
        return
    rounds(args.repeat, walls, last)
    if not walls:
        return
    walls.sort()
    smallest, median = walls[0], walls[len(walls) // 2]
    full = peer["seconds_per_step"] * peer["total_steps"]
    measured = peer["steps"] == peer["total_steps"]
    how = f"measured, {peer['wall']:.0f} s with start-up" if measured else \
        f"extrapolated from {peer['steps']} steps"
    print(f"supercoil: wall min {smallest:.2f} median {median:.2f} s over {len(walls)} runs")
    print(f"PyElastica: {full:.0f} s ({how}) for {peer['total_steps']} steps")
    print(f"ratio PyElastica / supercoil: {full / smallest:.0f} (smallest), "
          f"{full / median:.0f} (median); the target is a ratio of at least 200 "
          f"(2 s against about 400 s)")
    print(f"supercoil's smallest time on a host where PyElastica takes 400 s: "
          f"{400 * smallest / full:.2f} s (median {400 * median / full:.2f} s)")
    if measured and last:
        print_agreement(peer, last[0])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--stop", type=float, default=5.0)
    parser.add_argument("--max-points", type=int, default=3000)
    parser.add_argument("--pyelastica", metavar="PYTHON", default=None)
    parser.add_argument("--pyelastica-steps", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=0)
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--against-seconds", type=float, default=None, metavar="S")
    parser.add_argument("--bytecode", action="store_true")
    args = parser.parse_args()
    if args.against_seconds is not None:
        if not (args.against and args.repeat):
            parser.error("--against-seconds needs --against SRC and --repeat K")
        if not (math.isfinite(args.against_seconds) and args.against_seconds > 0):
            parser.error(f"--against-seconds {args.against_seconds:g}: give SRC's smallest "
                         "wall time on the reference host, a positive number of seconds")
    if args.pyelastica and args.repeat and args.against:
        parser.error("--pyelastica with --repeat times this tree against PyElastica; "
                     "drop --against (or --repeat)")
    if args.bytecode:
        compile_trees([None] + ([args.against] if args.against else []))
    import json

    def cmd_for(out: Path) -> list[str]:
        return [sys.executable, "-m", "supercoil.cli.main", "tweezers", "--twist-ratio",
                str(4 / 3), "--length-over-diameter", "33", "--tension", "75", "--turns",
                f"0:{args.stop}", "--nodes", str(args.nodes), "--max-points",
                str(args.max_points), "--out", str(out)]

    if args.repeat and args.pyelastica:
        peer_against_repeats(cmd_for, args)
        return
    if args.repeat:
        repeated(cmd_for, args.repeat, args.against, args.against_seconds)
        return
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run"
        wall, _cpu, proc = timed_command(cmd_for(out), None)
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
    if args.pyelastica:
        peer_result = run_peer(args)
        if peer_result is None:
            return
        full = peer_result["seconds_per_step"] * peer_result["total_steps"]
        measured = "measured" if peer_result["steps"] == peer_result["total_steps"] else \
            f"extrapolated from {peer_result['steps']} steps"
        print(f"PyElastica: {full:.0f} s ({measured}) for {peer_result['total_steps']} steps; "
              f"ratio {full / wall:.1f}")
        if peer_result["steps"] == peer_result["total_steps"]:
            print_agreement(peer_result, last)


if __name__ == "__main__":
    main()
