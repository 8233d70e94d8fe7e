"""Quasi-static protocols of the tweezers experiment: what an experiment would see.

:func:`quasistatic_path` turns the end in small steps (``step`` turns), up
from ``start`` to ``stop`` and, for the ``up-down`` protocol, back down to
``start``, as a slow experiment does: at each step the energy (elastic +
dead load + barrier contact) is **minimised** from the previous state
(:func:`~supercoil.contact.solve.solve_contact`, Newton in minimisation mode
with continuous collision detection). When the state reached is not stable
(a saddle: the straight rod beyond its buckling, a loop beyond a fold) it is
perturbed along its most unstable mode (amplitude ``kick`` times L, made
smaller until the perturbed state is free of contact) and minimised again,
until a stable state is found: this is the state the rod snaps to.

A step whose state moved far from the previous one (some node by more than
``jump_distance`` L, default one tube diameter) is a **jump**: recorded as a
special point of kind ``jump`` on branch ``path`` with the turns, the
extension before and after and the unstable count of the state that was
left. The path's points carry the records of
:func:`~supercoil.problems.tweezers.tweezers_records` plus
``unstable_count``, ``zero_modes``, ``direction`` (+1 up, -1 down) and
``stable``.

The path complements the branches of :func:`tweezers_branches` (which hold
the unstable parts too): together they are seed 001's Figure 6 picture of
hysteresis, here with our end conditions (tangents along the force).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from supercoil.contact.problem import ContactOptions, ContactProblem
from supercoil.contact.solve import solve_contact
from supercoil.problems.tweezers import (
    TweezersOptions,
    clamped_problem,
    set_pin,
    tweezers_records,
)
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import analyse

PROTOCOLS = ("up", "up-down")


@dataclass(frozen=True)
class PathResult:
    """The experiment's path: per-step records, states, jumps; ``ok`` when every step solved."""

    points: tuple[dict, ...]
    states: np.ndarray  # (k, n_dofs)
    jumps: tuple[dict, ...]
    ok: bool
    message: str


def _minimise(problem, rod, q, contact: bool):
    set_pin(problem, rod, q)
    opts = NewtonOptions(mode="minimize", max_iterations=300, tolerance=1e-9)
    if contact:
        res = solve_contact(problem, q, opts)
        return res.q, res.multipliers, bool(res.converged and res.admissible), res.message
    res = newton(problem, q, opts)
    return res.q, res.multipliers, bool(res.converged), res.message


def quasistatic_path(options: TweezersOptions, protocol: str = "up-down", step: float = 0.02,
                     kick: float = 0.02, jump_distance: float | None = None,
                     max_kicks: int = 6) -> PathResult:
    """The quasi-static path of ``protocol`` (module doc); load control only."""
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol must be one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    if not options.load_control:
        raise ValueError("the quasi-static protocols need load control (a tension)")
    if not (math.isfinite(step) and step > 0):
        raise ValueError(f"step must be a positive number of turns, got {step!r}")
    start, stop = options.turns
    n_up = max(1, math.ceil((stop - start) / step))
    grid = list(np.linspace(start, stop, n_up + 1))
    directions = [1] * len(grid)
    if protocol == "up-down":
        grid += grid[-2::-1]
        directions += [-1] * (len(grid) - len(directions))
    rod, q = clamped_problem(options)
    D = options.diameter
    problem = ContactProblem(rod, ContactOptions(diameter=D)) if D is not None else rod
    contact = D is not None
    records = tweezers_records(problem, rod, contact,
                               None if not contact else problem)
    reach = D if D is not None else 0.02
    jump_distance = reach if jump_distance is None else jump_distance
    points, states, jumps = [], [], []
    ok, message = True, f"{len(grid)} steps"
    previous = None
    for k, (turns, direction) in enumerate(zip(grid, directions)):
        problem.turns = float(turns)
        rod.accept(q)
        q_new, mu, converged, why = _minimise(problem, rod, q, contact)
        report = analyse(problem, q_new, mu) if converged else None
        left = report.unstable_count if report is not None else -1
        kicks = 0
        while converged and report.unstable_count > 0 and kicks < max_kicks:
            mode = report.lowest_modes[0]
            mode = mode / max(np.max(np.abs(mode)), 1e-300)
            amplitude = kick
            trial = q_new + amplitude * mode
            while contact and problem.min_distance(trial) <= 1.05 * D and amplitude > 1e-6:
                amplitude *= 0.5
                trial = q_new + amplitude * mode
            rod.accept(trial)
            q_new, mu, converged, why = _minimise(problem, rod, trial, contact)
            report = analyse(problem, q_new, mu) if converged else None
            kicks += 1
        if not converged:
            ok, message = False, f"step {k} at {turns:.6g} turns did not converge: {why}"
            break
        rod.accept(q_new)
        rec = dict(records(q_new, mu, float(turns)))
        rec.update(unstable_count=int(report.unstable_count), zero_modes=int(report.zero_modes),
                   stable=bool(report.unstable_count == 0 and report.zero_modes == 0),
                   direction=int(direction), branch="path", index=len(points))
        moved = float(np.max(np.linalg.norm((q_new - q).reshape(-1, 3), axis=1)))
        if previous is not None and moved > jump_distance:
            jumps.append({"kind": "jump", "branch": "path", "index": len(points) - 1,
                          "turns": float(turns), "direction": int(direction),
                          "extension": previous["extension"],
                          "extension_after": rec["extension"],
                          "writhe": previous["writhe"], "writhe_after": rec["writhe"],
                          "torque": previous["torque"], "torque_after": rec["torque"],
                          "largest_node_move": moved, "count_left": int(left)})
        points.append(rec)
        states.append(q_new)
        previous = rec
        q = q_new
    return PathResult(tuple(points), np.array(states), tuple(jumps), ok, message)
