"""Benchmark: the tweezers' branches of long rods over a grid of lengths and forces.

For each ``L/D`` and ``lambda = L sqrt(F/A)`` (``F L^2/A = lambda^2``) at ``C/A``, the
branches from 0 turns through buckling, the first contact and the plectoneme's growth
up to ``--factor`` (default 1.5) times the straight rod's exact buckling turns, at
``N = n0`` and ``2 n0`` nodes (``n0 = ceil(L/D) + 2``, the smallest N whose segments are
no longer than D), or with ``--resolving`` at the DNA runs' default nodes
(:func:`supercoil.units.tweezers.default_nodes`: segments also short enough to resolve
the loop's core ``sqrt(A/F)``, at most
:func:`~supercoil.problems.tweezers.options.resolved_core` of it). One row per
run: the turns at which the hard-core ply would span the whole rod
(:mod:`supercoil.problems.ply`; a target beyond them lies past the plectoneme's growth),
whether the last branch reached the last turn, the turns reached, the points and
seconds per run, the unstable counts met on the plectoneme (contact) branch, the
verified bifurcations and the count changes located off the straight rod (with, in
brackets, those in the mesh's snake: label ``snake``,
:mod:`supercoil.problems.tweezers.coarse`), and the notes (why a run stopped).

The runs are long (minutes each at L/D = 500): run it niced in the background; each row
is appended to the table as soon as it is computed, so a partial run leaves the rows
that completed. While a run goes on, ``OUT.progress`` holds its last accepted point
(branch, points, turns, seconds), rewritten every ``--progress-every`` points, and
``OUT.progress.tsv`` gains a line with the same and the unstable count there (the path
of a snaking branch through the turns, run after run); on
SIGTERM or SIGINT the running row is appended as stopped, with what it had reached
(the turns each branch spanned) and the run ends.

Run: ``python benchmarks/bench_long_dna_grid.py [--ld 100,200,500] [--lambdas
10,20,40,80,150] [--twist-ratio 1.5] [--multiples 1,2 | --resolving] [--factor 1.5]
[--nodes N1,N2] [--max-points 4000] [--contact-curve spline]
[--contact-stiffness load] [--contact-stiffness-scale 1] [--progress-every 50]
[--keep DIR] [--out benchmarks/results/long_dna_grid.md]``. With ``--keep DIR`` each run
stores its points as they come in ``DIR/ld{L/D}_lambda{lambda}_ca{C/A}_n{N}/result.h5``
(the library's result file: ``supercoil.load`` reads it), and the same command run again
continues every stored run from its last point (the row then says so and counts only
this run's seconds), so that a row longer than one sitting is computed over several.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import time
from pathlib import Path

import numpy as np

import supercoil as sc
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ply import hard_core_ply
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.units.tweezers import default_nodes

HEADER = ("| L/D | lambda | F L^2/A | N | target turns | ply spans | reached | last turns | points | "
          "seconds | counts on the contact branch | bifurcations | count changes | notes |")


class Progress:
    """The running row's last accepted point, kept for a row written on a signal."""

    def __init__(self, path: Path | None, every: int) -> None:
        self.path, self.every = path, max(1, every)
        self.start = time.perf_counter()
        self.counts: dict[str, int] = {}
        self.spans: dict[str, tuple[float, float]] = {}  # the turns each branch spanned
        self.last = ("-", 0, float("nan"))
        self.continued = ""  # the note of a run continued from its stored points

    def __call__(self, branch) -> None:
        n = len(branch)
        turns = float(branch.parameter_values[-1])
        self.counts[branch.name] = n
        low, high = self.spans.get(branch.name, (turns, turns))
        self.spans[branch.name] = (min(low, turns), max(high, turns))
        self.last = (branch.name, n, turns)
        if self.path is not None and n % self.every == 0:
            seconds = time.perf_counter() - self.start
            self.path.write_text(f"{self.last[0]} {n} points, turns = {self.last[2]:.6g}, "
                                 f"{seconds:.0f} s\n")
            trail = self.path.with_name(self.path.name + ".tsv")
            new = not trail.exists()
            with trail.open("a") as f:
                if new:
                    f.write("branch\tpoints\tturns\tunstable\tseconds\n")
                f.write(f"{branch.name}\t{n}\t{turns:.6f}\t{int(branch.unstable_count[-1])}"
                        f"\t{seconds:.1f}\n")

    def stopped_row(self, head: str, signame: str) -> str:
        """The row of a run stopped by a signal: what it had reached, said as stopped."""
        name, n, turns = self.last
        points = "+".join(str(v) for v in self.counts.values()) or "0"
        spans = "; ".join(f"{b} {low:.4g} to {high:.4g}" for b, (low, high) in self.spans.items())
        where = (f"at {name} point {n}, turns = {turns:.6g}; the turns each branch spanned "
                 f"at its accepted points: {spans}" if self.counts else
                 "before its first new point")
        return (f"{head} no | {'-' if not self.counts else f'{turns:.4g}'} | {points} | "
                f"{time.perf_counter() - self.start:.0f} | - | - | - | "
                f"{self.continued + '; ' if self.continued else ''}stopped by {signame} "
                f"{where} |")


def run(ld: float, lam: float, twist_ratio: float, nodes: int, factor: float,
        max_points: int, contact_curve: str = "spline", progress: Progress | None = None,
        keep: Path | None = None, stiffness_scale: float = 1.0,
        stiffness: str = "load") -> str:
    """One table row (module doc); ``contact_curve``: ``TweezersOptions.contact_curve``;
    ``progress`` is called with every accepted point; ``keep``: the folder whose
    ``result.h5`` stores the run point by point, continued if it holds one;
    ``stiffness`` and ``stiffness_scale``: ``TweezersOptions.contact_stiffness`` and
    ``contact_stiffness_scale``."""
    tension = lam**2
    target = factor * critical_turns(twist_ratio, tension)
    settings = {"loop_sliding": True, "max_points": max_points, "contact_curve": contact_curve,
                "contact_stiffness": stiffness, "contact_stiffness_scale": stiffness_scale}
    start = time.perf_counter()
    continued = ""
    if keep is None:
        options = TweezersOptions(twist_ratio=twist_ratio, length_over_diameter=ld,
                                  tension=tension, n_nodes=nodes, turns=(0.0, target), **settings)
        result = tweezers_branches(options, on_point=progress)
    else:
        resume = (keep / "result.h5").is_file()
        if resume:
            stored = sc.load(keep / "result.h5")
            continued = ("continued from the points stored in " + keep.name + " ("
                         + "+".join(str(len(b)) for b in stored.branches.values()) + ")")
            if progress is not None:
                progress.continued = continued
        problem = sc.Tweezers(sc.Rod(twist_ratio=twist_ratio, nodes=nodes), tension=tension,
                              contact=sc.Barrier(length_over_diameter=ld))
        result = sc.tweezers(problem, (0.0, target), on_point=progress, out=keep,
                             resume=resume, **settings).computed
    seconds = time.perf_counter() - start
    last = [b for b in result.branches if len(b)][-1]
    reached = float(last.parameter_values[-1])
    points = "+".join(str(len(b)) for b in result.branches)
    contact = [b for b in result.branches if b.name in result.contact_branches]
    counts = "-"
    if contact:
        values, times = np.unique(contact[0].unstable_count, return_counts=True)
        counts = ", ".join(f"{v}: {t}" for v, t in zip(values, times, strict=True))
    off_straight = [p for b in result.branches if b.name != "straight"
                    for p in b.special_points]
    bifurcations = sum(p.kind == "bifurcation" for p in off_straight)
    changes = sum(p.kind == "count_change" for p in off_straight)
    snake = sum(p.kind == "count_change" and p.label == "snake" for p in off_straight)
    changes = f"{changes} ({snake} snake)" if snake else f"{changes}"
    ok = result.ok and reached >= target - 1e-9
    notes = "; ".join(([continued] if continued else []) + list(result.notes))
    notes = notes.replace("|", "/") or "-"
    return (f"{row_head(ld, lam, twist_ratio, nodes, factor)} {'yes' if ok else 'no'} | "
            f"{reached:.4g} | {points} | {seconds:.0f} | {counts} | "
            f"{bifurcations} | {changes} | {notes} |")


def row_head(ld: float, lam: float, twist_ratio: float, nodes: int, factor: float) -> str:
    """The row's first six cells, known before the run."""
    tension = lam**2
    target = factor * critical_turns(twist_ratio, tension)
    spans = hard_core_ply(1.0 / ld, tension, twist_ratio).spanning_turns
    return f"| {ld:g} | {lam:g} | {tension:g} | {nodes} | {target:.4g} | {spans:.4g} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ld", default="100,200,500")
    parser.add_argument("--lambdas", default="10,20,40,80,150")
    parser.add_argument("--twist-ratio", type=float, default=1.5)
    parser.add_argument("--multiples", default="1,2", help="N as multiples of n0")
    parser.add_argument("--resolving", action="store_true", help="N = the DNA runs' default "
                        "nodes instead of the multiples: segments no longer than D and at "
                        "most min(1/3, 1.25/ln(lambda/0.54)) of the loop's core sqrt(A/F)")
    parser.add_argument("--factor", type=float, default=1.5)
    parser.add_argument("--max-points", type=int, default=4000)
    parser.add_argument("--contact-curve", default="spline", help="spline (the cubic "
                        "B-spline) or quintic")
    parser.add_argument("--contact-stiffness", default="load", help="the rule of the "
                        "barrier's stiffness: load, max(A/h^3, F/(pi g_hat)), or bending, "
                        "A/h^3 (TweezersOptions.contact_stiffness)")
    parser.add_argument("--contact-stiffness-scale", type=float, default=1.0,
                        help="a factor on the rule's stiffness "
                        "(TweezersOptions.contact_stiffness_scale)")
    parser.add_argument("--out", default="benchmarks/results/long_dna_grid.md")
    parser.add_argument("--nodes", default=None, help="comma-separated N, instead of "
                        "--multiples and --resolving")
    parser.add_argument("--keep", default=None, help="folder in which each run stores its "
                        "points as it goes (KEEP/ld200_lambda150_ca1.5_n202/result.h5); "
                        "the same command again continues a run stopped there")
    parser.add_argument("--progress-every", type=int, default=50, help="rewrite "
                        "OUT.progress every this many accepted points")
    args = parser.parse_args()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w") as f:
        f.write(f"# Long rods in the tweezers: C/A = {args.twist_ratio:g}, up to "
                f"{args.factor:g} x the buckling turns\n\n"
                f"`python benchmarks/bench_long_dna_grid.py --ld {args.ld} --lambdas "
                f"{args.lambdas} --twist-ratio {args.twist_ratio:g} "
                + (f"--nodes {args.nodes}" if args.nodes else
                   f"--multiples {args.multiples}{' --resolving' if args.resolving else ''}")
                + f" --factor "
                f"{args.factor:g} --max-points "
                f"{args.max_points}"
                + ("" if args.contact_curve == "spline"
                   else f" --contact-curve {args.contact_curve}")
                + ("" if args.contact_stiffness == "load"
                   else f" --contact-stiffness {args.contact_stiffness}")
                + ("" if args.contact_stiffness_scale == 1.0
                   else f" --contact-stiffness-scale {args.contact_stiffness_scale:g}")
                + f"`\n\n{HEADER}\n|{'---|' * HEADER.count(' | ')}---|\n")
    for ld in (float(v) for v in args.ld.split(",")):
        n0 = math.ceil(ld) + 2
        for lam in (float(v) for v in args.lambdas.split(",")):
            meshes = ([int(v) for v in args.nodes.split(",")] if args.nodes else
                      [default_nodes(ld, lam**2)] if args.resolving else
                      [int(v) * n0 for v in args.multiples.split(",")])
            for nodes in meshes:
                progress = Progress(out.with_name(out.name + ".progress"), args.progress_every)
                head = row_head(ld, lam, args.twist_ratio, nodes, args.factor)

                def stop(signum, frame, progress=progress, head=head):
                    row = progress.stopped_row(head, signal.Signals(signum).name)
                    print(row, flush=True)
                    with out.open("a") as f:
                        f.write(row + "\n")
                    # not sys.exit: a signal that arrives inside a callback whose
                    # exceptions Python ignores (a weakref's) would let the run go on
                    os._exit(1)

                signal.signal(signal.SIGTERM, stop)
                signal.signal(signal.SIGINT, stop)
                keep = None if args.keep is None else Path(args.keep) / (
                    f"ld{ld:g}_lambda{lam:g}_ca{args.twist_ratio:g}_n{nodes}")
                row = run(ld, lam, args.twist_ratio, nodes, args.factor,
                          args.max_points, args.contact_curve, progress, keep,
                          args.contact_stiffness_scale, args.contact_stiffness)
                print(row, flush=True)
                with out.open("a") as f:
                    f.write(row + "\n")


if __name__ == "__main__":
    main()
