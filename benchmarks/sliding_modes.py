"""Diagnosis: the sliding of a plectoneme along a stored tweezers contact branch.

For chosen points of a contact branch of a stored ``supercoil tweezers`` result (load
control, barrier on the integral formulation), prints the turns, the extension, the
unstable count, where the structure lies (the first and last node whose sliding
generator ``g_i = (x_{i+1} - x_{i-1}) / 2 - h e_z`` exceeds 5 % of its largest, the
tail ratio of ``ClampedRodEnergy.sliding``), and the constrained Hessian's eigenvalues
nearest zero with the sliding kept in (not projected out as the count does), each with
its overlap ``|<M v, g>|`` with the unit generator: an eigenvalue whose overlap is near
1 is the structure's sliding along the rod, which the continuum leaves free and the
discrete contact's ripple makes stiff, of either sign (docs/continuation.md, "Long open
rods: the sliding of a localised structure").

The problem is rebuilt from the result's settings, and the rod's reference frames are
carried along the stored states of the contact-free branch up to the contact branch's
first point, then along the contact branch, as the run carried them; the KKT residual
printed per point checks that the rebuilt problem is the one the states solve.

Run: ``python benchmarks/sliding_modes.py RESULT [--branch buckled_contact] [--points
300,380,433] [--modes 5]``; e.g. on ``supercoil tweezers --dna --bp 3000 --force-pN 1
--salt-mM 150 --sigma 0:0.06 --contact-curve spline --out hat3k``.
"""

from __future__ import annotations

import argparse

import numpy as np

import supercoil as sc
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation.system import problem_at
from supercoil.problems.ring_diagram.records import kkt_residual
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.problem import clamped_problem
from supercoil.solvers.carried import carried
from supercoil.stability.analysis import eigen_system
from supercoil.stability.eigen import lowest_pairs


def contact_problem(settings: dict) -> ContactProblem:
    """The contact problem of a stored tweezers run, at its first turn."""
    options = TweezersOptions(twist_ratio=settings["twist_ratio"],
                              length_over_diameter=settings["length_over_diameter"],
                              tension=settings["tension"], turns=tuple(settings["turns"]),
                              n_nodes=settings["nodes"])
    rod, _q0 = clamped_problem(options)
    return ContactProblem(rod, ContactOptions(
        diameter=options.diameter, curve=settings.get("contact_curve", "spline"),
        formulation=settings.get("contact_formulation", "integral")))


def structure(rod, q: np.ndarray) -> tuple[int, int, float, float]:
    """``(first node, last node, tail ratio, centre)`` of the structure at ``q``."""
    g, tail = rod.sliding(q)
    size = np.linalg.norm(g.reshape(-1, 3), axis=1)
    big = np.flatnonzero(size > 0.05 * size.max())
    weight = size**2
    s = (np.arange(size.size) - 0.5) * rod.rod.edge_length
    return int(big.min()), int(big.max()), tail, float(weight @ s / weight.sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result")
    parser.add_argument("--branch", default="buckled_contact")
    parser.add_argument("--points", default="", help="comma-separated point indices "
                        "(default: every 20th)")
    parser.add_argument("--modes", type=int, default=5)
    args = parser.parse_args()
    result = sc.load(args.result)
    branch = result.branches[args.branch]
    free = result.branches[branch.parent or "buckled"]
    wanted = ([int(v) for v in args.points.split(",")] if args.points
              else list(range(0, len(branch), 20)))
    problem = contact_problem(result.settings)
    start = int(np.argmin(np.linalg.norm(free.states - branch.states[0], axis=1)))
    for q in free.states[:start + 1]:
        problem = carried(problem, q)
    for i, q in enumerate(branch.states[:max(wanted) + 1]):
        problem = carried(problem, q)
        if i not in wanted:
            continue
        at = problem_at(problem, turns=float(branch.parameter_values[i]))
        rod = at.base
        rod.sliding_tail = None  # the sliding kept in the eigenproblem
        first, last, tail, centre = structure(rod, q)
        dofs, H, J, mass, sym = eigen_system(at, q, branch.multipliers[i])
        values, vectors = lowest_pairs(H, J, mass, n_wanted=args.modes, n=dofs.size,
                                       m=J.shape[0], symmetry=sym, force_sparse=True)
        g = rod.axial_free(rod.sliding(q)[0])[dofs]
        g = g / np.sqrt(g @ (mass * g))
        overlaps = [abs(v @ (mass * g)) / np.sqrt(v @ (mass * v)) for v in vectors.T]
        modes = " ".join(f"{v:.4g}({o:.2f})" for v, o in zip(values, overlaps, strict=True))
        print(f"{i} turns={branch.parameter_values[i]:.6f} "
              f"extension={branch.records['extension'][i]:.6f} "
              f"count={branch.unstable_count[i]} nodes={first}-{last} tail={tail:.2g} "
              f"centre={centre:.5f} residual={kkt_residual(at, q, branch.multipliers[i]):.1e} "
              f"eigenvalues(overlap with g): {modes}")


if __name__ == "__main__":
    main()
