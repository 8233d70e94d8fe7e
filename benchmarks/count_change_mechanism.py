"""Diagnosis: what changed the unstable count at each located count event of a stored
tweezers branch.

For every ``bifurcation`` (and, with ``--kinds``, ``count_change``) of a branch of a
stored tweezers result, recomputes at the two points around it the two tests that the
localisation applies (docs/continuation.md, "A count change that no eigenvalue makes
is no bifurcation"):

* the count's pencil: the factor's inertia on the complement of the approximate
  symmetries, before the count leaves the stiff sliding's eigenvalue out
  (``continuation.stability.stiff_sliding``). The same at both points: no eigenvalue of
  it crossed zero, and the event is a ``count_change`` labelled ``sliding``;
* the continued system's branch point: ``(-1)^n_K sign(t_lambda)`` (``n_K`` the
  negative eigenvalues of the continued system's Hessian on the constraints' kernel,
  ``t_lambda`` the stored tangent's parameter component). The same at both points: the
  extended Jacobian's determinant kept its sign, no branch point lies between, and the
  event is a ``count_change`` labelled ``determinant``.

Also printed: the stored eigenvalue nearest zero at both points and the critical
eigenvalue at the located point.

The problem is rebuilt from the result's settings (a run stored by ``supercoil.tweezers``
with ``out=`` or by ``supercoil tweezers --out``); each point is evaluated with the
frames and the azimuth pin it was computed with, as the branch-consistency check does,
and a stored count that the recomputation does not reproduce is counted.

Run: ``python benchmarks/count_change_mechanism.py RESULT.h5 [--branch buckled_contact]
[--kinds bifurcation,count_change] [--first 0] [--limit 0]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import supercoil as sc
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation.carry import branch_frames
from supercoil.continuation.special_points import continued_parity
from supercoil.continuation.stability import inertia_with_factor
from supercoil.continuation.system import ExtendedSystem
from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers.buckled import stored_pins
from supercoil.problems.tweezers.problem import clamped_problem
from supercoil.problems.tweezers.result import TweezersResult
from supercoil.solvers.carried import with_frames


def rebuilt(settings: dict, branch) -> TweezersResult:
    """The stored run's problems around ``branch`` (a contact branch), its pins set."""
    if "options" in settings:  # stored by supercoil.tweezers
        stored = dict(settings["options"])
        stored["turns"] = tuple(stored["turns"])
        options = TweezersOptions(**stored)
    else:  # stored by the command line
        options = TweezersOptions(
            twist_ratio=settings["twist_ratio"],
            length_over_diameter=settings["length_over_diameter"],
            tension=settings["tension"], turns=tuple(settings["turns"]),
            n_nodes=settings["nodes"], loop_sliding=settings.get("loop_sliding", False),
            contact_curve=settings.get("contact_curve", "spline"),
            contact_formulation=settings.get("contact_formulation", "integral"))
    rod, _q0 = clamped_problem(options)
    cp = ContactProblem(rod, ContactOptions(diameter=options.diameter,
                                            curve=options.contact_curve,
                                            formulation=options.contact_formulation))
    return TweezersResult(options=options, branches=(branch,),
                          contact_branches=frozenset([branch.name]), rod_problem=rod,
                          contact_problem=cp, pins={branch.name: stored_pins(branch)})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result")
    parser.add_argument("--branch", default="buckled_contact")
    parser.add_argument("--kinds", default="bifurcation")
    parser.add_argument("--first", type=int, default=0, help="the first point index looked at")
    parser.add_argument("--limit", type=int, default=0, help="at most this many events (0: all)")
    args = parser.parse_args()
    result = sc.load(args.result)
    branch = result.branches[args.branch]
    run = rebuilt(result.settings, branch)
    frames = branch_frames(run.contact_problem, branch)
    phase = branch.phase_modes if branch.phase_modes.size else None
    kinds = set(args.kinds.split(","))
    events = [p for p in branch.special_points if p.kind in kinds and p.index >= args.first]
    if args.limit:
        events = events[:args.limit]
    start = time.perf_counter()
    tally = {"sliding": 0, "determinant": 0, "bifurcation": 0}
    mismatched = 0
    for p in events:
        factor, left, continued = [], [], []
        for i in (p.index, p.index + 1):
            problem = run.pin_branch(branch.name, i)
            system = ExtendedSystem(problem, branch.parameter, branch.states[i], phase,
                                    branch.phase_state if phase is not None else None)
            system.problem = with_frames(problem, frames[i])
            x = system.pack(branch.states[i], branch.multipliers[i],
                            branch.parameter_values[i])
            hessian = system.hessian(x)
            count, _sign, _f, _dofs, left_out = inertia_with_factor(system, x, 1e-6, hessian)
            factor.append(count + left_out)
            left.append(left_out)
            continued.append(continued_parity(system, x, branch.tangents[i], hessian))
            if count != branch.unstable_count[i]:
                mismatched += 1
        if factor[0] == factor[1]:
            verdict = "sliding"
        elif continued[0] == continued[1] and (p.count_after - p.count_before) % 2:
            verdict = "determinant"
        else:
            verdict = "bifurcation"
        tally[verdict] += 1
        critical = p.critical_eigenvalues
        nearest = branch.nearest_eigenvalue
        print(f"{p.kind}/{p.label} between points {p.index} and {p.index + 1} "
              f"(turns {p.parameter:.5f}): count {p.count_before} -> {p.count_after}; "
              f"factor {factor[0]} -> {factor[1]}, left out {left[0]} -> {left[1]}; "
              f"parity of n_K + [t_lambda < 0] {continued[0]} -> {continued[1]}: {verdict}; "
              f"nearest eigenvalue {nearest[p.index]:.3g}, {nearest[p.index + 1]:.3g}; critical "
              f"{np.array2string(critical, precision=3)}", flush=True)
    print(f"{len(events)} events ({args.kinds}) on {branch.name}: "
          + ", ".join(f"{v} {k}" for k, v in tally.items())
          + f"; {mismatched} recomputed counts differ from the stored ones; "
          f"{time.perf_counter() - start:.0f} s")

if __name__ == "__main__":
    main()
