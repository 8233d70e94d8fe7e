"""Benchmark: the DNA preset's hat curves, 3 kbp from sigma 0 to 0.06, over force and salt.

Each force and salt runs ``supercoil --log DIR/fF_sS.log tweezers --dna --bp 3000
--force-pN F --salt-mM S --sigma 0:0.06 --out DIR/fF_sS`` as its own process (so the
seconds include the start-up, with the compiled kernels cached) and appends one row to
the table: the nodes (the default), the exit status, the wall seconds, the branch that
reaches the last sigma and its points, the folds located on the contact branches, the
bifurcations and count changes there (of which in the mesh's snake, label ``snake``:
:mod:`supercoil.problems.tweezers.coarse`), and the extension (nm) and torque (pN nm) at the last point of that branch, read back from
the run's ``branch.json``.

Run: ``python benchmarks/bench_dna_preset.py [--forces 0.25,0.5,1,2,4]
[--salts 10,25,50,150,200] [--bp 3000] [--sigma 0:0.06] [--dir DIR] [--out FILE]
[-- extra options of supercoil tweezers]``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

HEADER = ("| F (pN) | salt (mM) | N | exit | seconds | branch that reaches the last sigma | "
          "its points | folds on the contact branches | bifurcations, count changes (snake) | "
          "extension (nm) | torque (pN nm) |")


def row(force: str, salt: str, folder: Path, status: int, seconds: float) -> str:
    """The table row of one run (module doc), from its ``branch.json``."""
    head = f"| {force} | {salt} |"
    path = folder / "branch.json"
    if not path.is_file():
        return f"{head} - | {status} | {seconds:.0f} | - | - | - | - | - | - |"
    data = json.loads(path.read_text())
    last_turns = data["turns_range"][1]
    points = data["points"]
    reaching = [b for b in data["branches"]
                if any(p["branch"] == b["name"] and abs(p["turns"] - last_turns) < 1e-9
                       for p in points)]
    contact = {b["name"] for b in data["branches"] if b["contact"]}
    on_contact = [p for p in data["special_points"] if p["branch"] in contact]
    folds = sum(p["kind"] == "fold" for p in on_contact)
    changes = (f"{sum(p['kind'] == 'bifurcation' for p in on_contact)}, "
               f"{sum(p['kind'] == 'count_change' for p in on_contact)} "
               f"({sum(p['label'] == 'snake' for p in on_contact)})") if contact else "-"
    if not reaching:
        return (f"{head} {data['n_nodes']} | {status} | {seconds:.0f} | none | - | "
                f"{folds if contact else '-'} | {changes} | - | - |")
    branch = reaching[-1]
    last = [p for p in points if p["branch"] == branch["name"]][-1]
    return (f"{head} {data['n_nodes']} | {status} | {seconds:.0f} | `{branch['name']}` | "
            f"{branch['n_points']} | {folds if contact else '-'} | {changes} | "
            f"{last['extension_nm']:.1f} | {last['torque_pN_nm']:.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--forces", default="0.25,0.5,1,2,4")
    parser.add_argument("--salts", default="10,25,50,150,200")
    parser.add_argument("--bp", default="3000")
    parser.add_argument("--sigma", default="0:0.06")
    parser.add_argument("--dir", default="dna_preset", help="folder of the runs' folders")
    parser.add_argument("--out", default="dna_preset.md")
    parser.add_argument("extra", nargs="*", help="more options of supercoil tweezers "
                        "(after --)")
    args = parser.parse_args()
    folder, out = Path(args.dir), Path(args.out)
    folder.mkdir(parents=True, exist_ok=True)
    with out.open("w") as f:
        f.write(f"`python benchmarks/bench_dna_preset.py --forces {args.forces} --salts "
                f"{args.salts} --bp {args.bp} --sigma {args.sigma}"
                + (f" -- {' '.join(args.extra)}" if args.extra else "")
                + f"`\n\n{HEADER}\n|{'---|' * HEADER.count(' | ')}---|\n")
    for force in args.forces.split(","):
        for salt in args.salts.split(","):
            run = folder / f"f{force}_s{salt}"
            command = [sys.executable, "-m", "supercoil", "--log", str(run) + ".log",
                       "tweezers", "--dna", "--bp", args.bp, "--force-pN", force,
                       "--salt-mM", salt, "--sigma", args.sigma, "--out", str(run),
                       "--quiet", *args.extra]
            start = time.perf_counter()
            status = subprocess.run(command, check=False, stdout=subprocess.DEVNULL).returncode
            line = row(force, salt, run, status, time.perf_counter() - start)
            print(line, flush=True)
            with out.open("a") as f:
                f.write(line + "\n")


if __name__ == "__main__":
    main()
