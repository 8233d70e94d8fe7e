"""Work of the tweezers' contact branch in counts: continuation points, corrections, Newton
iterations and bordered factorisations (they do not depend on the machine's load, unlike
times on a shared host), for the tweezers' problem (C/A = 4/3, N = 100, 0 -> 5 turns, F L^2/A
= 75, L/D = 33) and neighbours of it.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_tweezers_steps.py [--problems 75,33
60,33 ...] [--set JSON] [--against JSON]``. ``--problems``: ``tension,L/D`` pairs (default
five: 75,33 60,33 90,33 75,28 75,40). ``--set``: fields of the contact branch's
:class:`~supercoil.continuation.ContinuationOptions` to override (JSON, e.g.
``'{"max_corrector_distance": null}'``); ``--against``: a second set of overrides, run
after the first on each problem, with a line saying whether the two give the same branches
bit for bit (states of every branch and the special points' parameters). Counted on the
contact branch: the corrections of its continuation steps (the starting correction
included; failed and refused ones too), their Newton iterations, and every bordered
factorisation from its start on (corrections, tangents, event localisation). The CPU time
of the whole computation is printed too, for orientation only.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from supercoil.continuation import bordered, step
from supercoil.problems import tweezers
from supercoil.problems.tweezers import contact as contact_module

PROBLEMS = ("75,33", "60,33", "90,33", "75,28", "75,40")


class Counter:
    """Counts corrections and factorisations once the contact branch's options are made."""

    def __init__(self):
        self.contact = False
        self.factors = self.factors_at_start = 0
        self.corrections: list[tuple[bool, int]] = []


def run(problem: str, overrides: dict) -> tuple[dict, list[np.ndarray], np.ndarray]:
    """Counts, the states of each branch and the special points' parameters of one run."""
    tension, length_over_diameter = (float(v) for v in problem.split(","))
    counter = Counter()
    factor_init, correct, options = (bordered.BorderedFactor.__init__,
                                     step.correct, contact_module.ContinuationOptions)

    def counted_factor(self, *args, **kwargs):
        counter.factors += 1
        return factor_init(self, *args, **kwargs)

    def counted_correct(*args, **kwargs):
        result = correct(*args, **kwargs)
        if counter.contact:
            counter.corrections.append((result.ok, result.iterations))
        return result

    def contact_options(**kwargs):
        # only the contact branch weighs the parameter (by D)
        if "parameter_weight" in kwargs:
            counter.contact = True
            counter.factors_at_start = counter.factors
            kwargs.update(overrides)
        return options(**kwargs)

    bordered.BorderedFactor.__init__ = counted_factor
    step.correct = counted_correct
    contact_module.ContinuationOptions = contact_options
    try:
        start = time.process_time()
        result = tweezers.tweezers_branches(tweezers.TweezersOptions(
            4 / 3, length_over_diameter, tension=tension, turns=(0.0, 5.0), n_nodes=100))
        cpu = time.process_time() - start
    finally:
        bordered.BorderedFactor.__init__ = factor_init
        step.correct = correct
        contact_module.ContinuationOptions = options
    contact = [b for b in result.branches if b.name in result.contact_branches]
    counts = {
        "points": sum(len(b) for b in contact),
        "corrections": len(counter.corrections),
        "failed": sum(not ok for ok, _ in counter.corrections),
        "iterations": sum(it for _, it in counter.corrections),
        "factorisations": counter.factors - counter.factors_at_start,
        "cpu_s": round(cpu, 2),
    }
    specials = np.array([p.parameter for b in result.branches for p in b.special_points])
    return counts, [b.states for b in result.branches], specials


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problems", nargs="+", default=list(PROBLEMS))
    parser.add_argument("--set", default="{}", help="contact ContinuationOptions overrides")
    parser.add_argument("--against", default=None, help="second overrides, compared")
    args = parser.parse_args()
    sets = [json.loads(args.set)] + ([json.loads(args.against)] if args.against else [])
    totals = [dict.fromkeys(("points", "corrections", "failed", "iterations",
                             "factorisations", "cpu_s"), 0) for _ in sets]
    for problem in args.problems:
        outcomes = []
        for overrides, total in zip(sets, totals):
            counts, states, specials = run(problem, overrides)
            outcomes.append((states, specials))
            for key, value in counts.items():
                total[key] += value
            print(f"F, L/D = {problem} {json.dumps(overrides)}: {counts}", flush=True)
        if len(outcomes) == 2:
            (a, sa), (b, sb) = outcomes
            same = (len(a) == len(b) and all(x.shape == y.shape and np.array_equal(x, y)
                                             for x, y in zip(a, b))
                    and sa.shape == sb.shape and np.array_equal(sa, sb))
            print(f"F, L/D = {problem}: the same branches bit for bit: {same}", flush=True)
    for overrides, total in zip(sets, totals):
        total["cpu_s"] = round(total["cpu_s"], 2)
        print(f"total {json.dumps(overrides)}: {total}")


if __name__ == "__main__":
    main()
