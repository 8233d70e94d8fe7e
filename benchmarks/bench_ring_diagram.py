"""Benchmark: the ring's alpha branch from the circle through contact.

Run from the repository root:

    python benchmarks/bench_ring_diagram.py [--nodes 200] [--max-excess-link 6]
        [--contact-max-points 400] [--contact-formulation integral|pairs]
        [--contact-curve spline|polygon|quintic] [--gauge integral|node]
        [--predictor quadratic|tangent|secant] [--profile]
    python benchmarks/bench_ring_diagram.py --command [--repeat K [--against SRC]]

Times :func:`supercoil.problems.ring_diagram.ring_diagram` for C/A = 2/3,
L/D = 122 (Coleman & Swigon's DNA example), mode 2 only (the circle, alpha without
contact to its first contact, alpha with barrier contact up to
``--max-excess-link``; defaults: those of ``DiagramOptions``) after one warm-up
run at N = 48 (numba caches). It
prints the wall time per branch, the points, the excess link and writhe
reached, and the time per contact-branch point; with ``--profile`` the
top of a cProfile by cumulative time. Target: the whole alpha
branch to dLk = 6 at N = 200 in at most 10 s, for the whole command.

``--command`` times that command instead, ``supercoil diagram ring --twist-ratio
2/3 --length-over-diameter 122 --nodes N --modes 2 --max-excess-link X
--contact-max-points K --out DIR --quiet`` in a fresh process (imports, numba's
cache loads, figures and files included), and prints its wall time and the
branches' seconds from ``diagram.json``; ``--repeat K [--against SRC]`` runs it
K times, alternating with the source tree SRC (a ``src`` folder put on
``PYTHONPATH``), and prints the smallest and median times (``bench_tweezers``'s
``repeated``). ``--bytecode`` first writes the bytecode of the timed trees
(``bench_tweezers.compile_trees``): with ``PYTHONDONTWRITEBYTECODE`` set, as on the
development machine, every run would otherwise compile the edited modules again
(tens of ms), which an installed package never does.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200)
    parser.add_argument("--max-excess-link", type=float, default=6.0)
    parser.add_argument("--contact-max-points", type=int, default=400)
    parser.add_argument("--contact-formulation", default="integral",
                        choices=("integral", "pairs"))
    parser.add_argument("--contact-curve", default="spline",
                        choices=("spline", "polygon", "quintic"))
    parser.add_argument("--gauge", default="integral", choices=("integral", "node"))
    parser.add_argument("--predictor", default="quadratic",
                        choices=("quadratic", "tangent", "secant"))
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--command", action="store_true")
    parser.add_argument("--repeat", type=int, default=0)
    parser.add_argument("--against", metavar="SRC", default=None)
    parser.add_argument("--bytecode", action="store_true")
    args = parser.parse_args(argv)
    if args.command or args.repeat:
        return whole_command(args)

    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    ring_diagram(DiagramOptions(2 / 3, 122.0, n_nodes=48, modes=(2,), max_excess_link=2.0,
                                contact_max_points=5))
    options = DiagramOptions(2 / 3, 122.0, n_nodes=args.nodes, modes=(2,),
                             max_excess_link=args.max_excess_link,
                             contact_max_points=args.contact_max_points,
                             contact_formulation=args.contact_formulation,
                             contact_curve=args.contact_curve, gauge=args.gauge,
                             contact_predictor=args.predictor)
    profile = cProfile.Profile() if args.profile else None
    start = time.perf_counter()
    if profile:
        profile.enable()
    diagram = ring_diagram(options)
    if profile:
        profile.disable()
    total = time.perf_counter() - start
    print(f"C/A = 2/3, L/D = 122, N = {args.nodes}, mode 2, dLk <= {args.max_excess_link:g}, "
          f"{args.contact_formulation} contact on the {args.contact_curve}, {args.gauge} gauge, "
          f"{args.predictor} predictor")
    print("| branch | points | seconds | s/point | dLk range | max writhe | status |")
    print("|---|---|---|---|---|---|---|")
    for b in diagram.branches:
        sec = diagram.seconds.get(b.name, float("nan"))
        lam = b.parameter_values
        print(f"| {b.name} | {len(b)} | {sec:.2f} | {sec / max(len(b), 1):.3f} | "
              f"{lam.min():.3f} .. {lam.max():.3f} | {float(b.records['writhe'].max()):.3f} | "
              f"{b.status.name} |")
    kinds: dict[str, int] = {}
    for p in diagram.special_points():
        kinds[p.kind] = kinds.get(p.kind, 0) + 1
    print("special points:", ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))
    print(f"total {total:.2f} s")
    if profile:
        pstats.Stats(profile).sort_stats("cumulative").print_stats(30)
    return 0


def whole_command(args) -> int:
    """Time the ``diagram ring`` command (module doc, ``--command``)."""
    import json
    import sys
    import tempfile
    from pathlib import Path

    from bench_tweezers import compile_trees, repeated, timed_command

    if args.bytecode:
        compile_trees([None] + ([args.against] if args.against else []))

    def cmd_for(out: Path) -> list[str]:
        return [sys.executable, "-m", "supercoil.cli.main", "diagram", "ring", "--twist-ratio",
                "2/3", "--length-over-diameter", "122", "--nodes", str(args.nodes), "--modes",
                "2", "--max-excess-link", str(args.max_excess_link), "--contact-max-points",
                str(args.contact_max_points), "--out", str(out), "--quiet"]

    if args.repeat:
        repeated(cmd_for, args.repeat, args.against)
        return 0
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run"
        wall, cpu, proc = timed_command(cmd_for(out), None)
        if proc.returncode != 0:
            print(proc.stderr.strip()[-500:])
            return proc.returncode
        data = json.loads((out / "diagram.json").read_text())
    print(f"whole command: wall {wall:.2f} s, cpu {cpu:.2f} s; " + ", ".join(
        f"{b['name']} {b['n_points']} points {b['seconds']:.2f} s" for b in data["branches"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
