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
:func:`~supercoil.problems.tweezers.problem.tweezers_records` (those of
:func:`~supercoil.problems.cosserat_tweezers.cosserat_tweezers_records` for the
Cosserat rod, whose states are its positions and rotation coordinates) plus
``unstable_count``, ``zero_modes``, ``direction`` (+1 up, -1 down) and
``stable``.

The path complements the branches of
:func:`~supercoil.problems.tweezers.tweezers_branches` (which hold the
unstable parts too): together they are the picture of hysteresis of Coleman &
Swigon 2002, Figure 6, here with our end conditions (tangents along the force).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from supercoil import checks
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import solve_contact
from supercoil.problems.segments import set_pin
from supercoil.problems.tweezers import TweezersOptions, clamped_problem, tweezers_records
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import analyse

PROTOCOLS = ("up", "up-down", "force-ramp")
SUBSTEPS = (1, 2, 4, 8)  # sub-steps tried when the minimisation at a new load fails


@dataclass(frozen=True)
class PathResult:
    """The experiment's path: per-step records, states, jumps; ``ok`` when every step solved."""

    points: tuple[dict, ...]
    states: np.ndarray  # (k, 3 n_nodes): the centrelines
    jumps: tuple[dict, ...]
    ok: bool
    message: str

    def __repr__(self) -> str:
        return (f"PathResult({'ok' if self.ok else 'stopped'}: {len(self.points)} steps, "
                f"{len(self.jumps)} jumps; {self.message})")


def _minimise(problem, rod, q, contact: bool):
    set_pin(problem, rod, q)
    opts = NewtonOptions(mode="minimize", max_iterations=300, tolerance=1e-9)
    if contact:
        res = solve_contact(problem, q, opts)
        return res.q, res.multipliers, bool(res.converged and res.admissible), res.message
    res = newton(problem, q, opts)
    return res.q, res.multipliers, bool(res.converged), res.message


def _schedule(options: TweezersOptions, protocol: str, step: float,
              force_range: tuple[float, float] | None, force_step: float | None):
    """``[(turns, tension, direction, ramp)]`` of the protocol (module doc)."""
    start, stop = options.turns
    n_up = max(1, math.ceil((stop - start) / step))
    grid = list(np.linspace(start, stop, n_up + 1))
    tension = float(options.tension)
    out = [(t, tension, 1, "turns") for t in grid]
    if protocol == "up-down":
        out += [(t, tension, -1, "turns") for t in grid[-2::-1]]
    elif protocol == "force-ramp":
        low, high = force_range
        df = force_step if force_step is not None else max(high - low, 1e-12) / 50
        legs = ((tension, low, -1), (low, high, 1), (high, tension, -1))
        for a, b, _ in legs:
            if a == b:
                continue
            count = max(1, math.ceil(abs(b - a) / df))
            out += [(stop, float(f), 1 if b > a else -1, "tension")
                    for f in np.linspace(a, b, count + 1)[1:]]
    return out


def check_path(options: TweezersOptions, protocol: str, step: float,
               force_range: tuple[float, float] | None = None,
               force_step: float | None = None) -> None:
    """Raise :class:`~supercoil.errors.InputError` unless the protocol's inputs are valid:
    a known protocol under load control, positive finite steps, a force range
    ``0 <= low < high <= 1e6`` and at most :data:`~supercoil.checks.MAX_POINTS` steps in
    all (each step is a minimisation: a path of more would not end in any useful time)."""
    checks.choice("protocol", protocol, PROTOCOLS)
    if not options.load_control:
        raise checks.refuse("protocol", f"{protocol!r} needs load control (a tension), not "
                            "an end distance")
    start, stop = options.turns
    step = checks.number("step", step, 0.0, stop - start, low_open=True,
                         meaning="turns per quasi-static step")
    count = math.ceil((stop - start) / step) * (2 if protocol == "up-down" else 1)
    if protocol == "force-ramp":
        if force_range is None or len(force_range) != 2:
            raise checks.refuse("force_range", f"must be (low, high) forces, got "
                                f"{force_range!r}")
        low = checks.number("force_range", force_range[0], 0.0, checks.MAX_MAGNITUDE)
        high = checks.number("force_range", force_range[1], 0.0, checks.MAX_MAGNITUDE)
        if not low < high:
            raise checks.refuse("force_range", f"must be (low, high) with 0 <= low < high, "
                                f"got {force_range!r}")
        tension = float(options.tension)
        df = (checks.number("force_step", force_step, 0.0, high - low, low_open=True)
              if force_step is not None else (high - low) / 50)
        count += sum(math.ceil(abs(b - a) / df)
                     for a, b in ((tension, low), (low, high), (high, tension)))
    if count > checks.MAX_POINTS:
        what = "step" if protocol != "force-ramp" or force_step is None else "force_step"
        raise checks.refuse(what, f"gives {count} quasi-static steps; at most "
                            f"{checks.MAX_POINTS} are valid: give a larger {what}")


def _clamped_rod(options: TweezersOptions, contact: ContactProblem | None,
                 cosserat: tuple[float, float] | None):
    """``(rod problem, first state, records)`` of the straight rod at the first turn: the
    Kirchhoff rod's, or with ``cosserat = (EA L^2/A, GA L^2/A)`` the Cosserat rod's;
    ``contact``: the contact's options, None without."""
    if cosserat is None:
        rod, q = clamped_problem(options)
        problem = rod if contact is None else ContactProblem(rod, contact)
        return rod, problem, q, tweezers_records(problem, rod, contact is not None,
                                                 None if contact is None else problem)
    from supercoil.problems.cosserat_tweezers import (
        clamped_cosserat_problem,
        cosserat_tweezers_records,
        with_contact_records,
    )

    rod = clamped_cosserat_problem(options, *cosserat)
    q = rod.straight_state()
    records = cosserat_tweezers_records(rod)
    if contact is None:
        return rod, rod, q, records
    problem = ContactProblem(rod, contact)
    return rod, problem, q, with_contact_records(records, problem, True)


def quasistatic_path(options: TweezersOptions, protocol: str = "up-down", step: float = 0.02,
                     kick: float = 0.02, jump_distance: float | None = None,
                     max_kicks: int = 6, force_range: tuple[float, float] | None = None,
                     force_step: float | None = None,
                     cosserat: tuple[float, float] | None = None) -> PathResult:
    """The quasi-static path of ``protocol`` (module doc); load control only.

    ``up``: turns from start to stop; ``up-down``: and back; ``force-ramp``: up to
    ``stop`` turns at the options' tension, then, at ``stop`` turns, the tension
    ramped down to ``force_range[0]``, up to ``force_range[1]`` and back to the
    options' tension in steps of ``force_step`` (default 1/50 of the range).
    Each point has ``ramp`` (``turns`` or ``tension``) and ``direction`` (+1 the
    ramped parameter increases, -1 it decreases). ``cosserat``: ``(EA L^2/A, GA L^2/A)``
    of a Cosserat rod to compute with instead of the Kirchhoff rod.
    """
    check_path(options, protocol, step, force_range, force_step)
    schedule = _schedule(options, protocol, step, force_range, force_step)
    D = options.diameter
    contact = D is not None
    rod, problem, q, records = _clamped_rod(
        options, options.contact_options() if contact else None,
        cosserat)
    points_of = getattr(rod, "centreline", np.asarray)  # the positions among the unknowns
    reach = D if D is not None else 0.02
    jump_distance = reach if jump_distance is None else jump_distance
    points, states, jumps = [], [], []
    ok, message = True, f"{len(schedule)} steps"
    previous = None
    last = (float(schedule[0][0]), float(schedule[0][1]))
    for k, (turns, tension, direction, ramp) in enumerate(schedule):
        # minimise at the new load; when Newton fails, approach it in 2, 4, 8 sub-steps
        for pieces in SUBSTEPS:
            q_new, converged = q, True
            for j in range(1, pieces + 1):
                # each sub-step's problem at its load, carrying on what the last one
                # holds (frames, pins, contact state)
                problem = problem.at(turns=last[0] + (turns - last[0]) * j / pieces,
                                     tension=last[1] + (tension - last[1]) * j / pieces)
                rod = problem.base if contact else problem
                rod.accept(q_new)
                q_new, mu, converged, why = _minimise(problem, rod, q_new, contact)
                if not converged:
                    break
            if converged:
                break
        last = (float(turns), float(tension))
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
            ok, message = False, (f"step {k} at {turns:.6g} turns, F L^2/A = {tension:.6g} did "
                                  f"not converge: {why}")
            break
        rod.accept(q_new)
        rec = dict(records(q_new, mu, float(turns), problem=problem))  # at this load
        rec.update(unstable_count=int(report.unstable_count), zero_modes=int(report.zero_modes),
                   stable=bool(report.unstable_count == 0 and report.zero_modes == 0),
                   direction=int(direction), ramp=ramp, branch="path", index=len(points))
        moved = float(np.max(np.linalg.norm((points_of(q_new) - points_of(q)).reshape(-1, 3),
                                            axis=1)))
        if previous is not None and moved > jump_distance:
            jumps.append({"kind": "jump", "branch": "path", "index": len(points) - 1,
                          "turns": float(turns), "tension": float(tension), "ramp": ramp,
                          "direction": int(direction),
                          "extension": previous["extension"],
                          "extension_after": rec["extension"],
                          "writhe": previous["writhe"], "writhe_after": rec["writhe"],
                          "torque": previous["torque"], "torque_after": rec["torque"],
                          "largest_node_move": moved, "count_left": int(left)})
        points.append(rec)
        states.append(points_of(q_new))
        previous = rec
        q = q_new
    return PathResult(tuple(points), np.array(states), tuple(jumps), ok, message)
