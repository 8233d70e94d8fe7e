"""The tweezers' contact-free branch: its start, runs continued from a stored branch.

Under load control the buckled branch is switched from the straight rod's
first bifurcation along the critical mode (:func:`switch_off_straight`);
under displacement control the branch starts from the clamped planar Euler
buckle at the first number of turns (:func:`clamped_buckle_run`). Either is
followed without contact until the closest approach of non-neighbouring
points reaches ``D`` (a ``contact_onset``, :mod:`supercoil.problems.contact_events`;
the branch is cut just after it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import numpy as np

from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    SpecialPoint,
    continuation,
    switch_branch,
)
from supercoil.continuation.resume import resume_branch
from supercoil.problems.segments import either, set_pin
from supercoil.problems.tweezers.pins import (
    hold_azimuth,
    pin_node,
    rotated_mode,
    sliding_stop,
)
from supercoil.rod.open import ClampedRodEnergy
from supercoil.solvers.newton import NewtonOptions, newton

SWITCH_AMPLITUDE = 2e-2  # first point of the buckled branch from the bifurcation (arclength)
# tried in turn when the switch finds no point (the subcritical branch turns back sharply
# under a large tension: measured at F L^2/A = 900, N = 120, 2e-2 diverged)
SWITCH_AMPLITUDES = (SWITCH_AMPLITUDE, 5e-3, 1e-3)


def resume_stored(stored: Mapping[str, tuple[Branch, bool]], rod: ClampedRodEnergy,
                  problem, name: str, segment_opts: ContinuationOptions, records,
                  events, on_point=None, stop=None, sliding: bool = True) -> Branch | None:
    """The stored branch ``name`` continued for one segment, or None (none stored, or
    complete, or of fewer than two points); with the azimuth pin its points were
    computed with (the record ``azimuth_pin``), the same gauge. ``sliding``: the run
    also ends where the sliding's phase row must come or go
    (:func:`~supercoil.problems.tweezers.pins.sliding_stop`)."""
    old, complete = stored.get(name, (None, False))
    if old is None or complete or len(old) < 2:
        return None
    q = old.states[-1]
    problem.turns = float(old.parameter_values[-1])
    problem.accept(q)
    pin = int(old.records["azimuth_pin"][-1]) if "azimuth_pin" in old.records else -1
    if pin >= 0:  # the pin the stored points were computed with: the same gauge
        hold_azimuth(rod, (pin,), problem)
    else:
        set_pin(problem, rod, q)
    return resume_branch(problem, old, dataclasses.replace(
        segment_opts, max_points=len(old) + segment_opts.max_points - 1),
        records=records, events=events, on_point=on_point,
        stop=either(stop, sliding_stop(rod, q) if sliding else None))


def switch_off_straight(rod: ClampedRodEnergy, straight: Branch, point: SpecialPoint,
                        options: ContinuationOptions, name: str, records, events,
                        on_point=None, stop=None,
                        say: Callable[[str], None] = lambda message: None) -> Branch:
    """The first run of the buckled branch ``name``, switched from the straight rod's
    bifurcation ``point`` along its critical mode turned so that the pinned node moves
    along +x (:func:`~supercoil.problems.tweezers.pins.pin_node`); the amplitudes of
    ``SWITCH_AMPLITUDES`` tried in turn until one gives a point."""
    direction, node = rotated_mode(point.critical_modes[0])
    first = None
    for amplitude in SWITCH_AMPLITUDES:
        if amplitude == SWITCH_AMPLITUDES[0]:
            say(f"{name}: switched from the straight rod at {point.parameter:.6g} turns")
        rod.turns = point.parameter
        pin_node(rod, node)
        first = switch_branch(rod, straight, point,
                              dataclasses.replace(options, initial_step=amplitude),
                              direction=direction, amplitude=amplitude, name=name,
                              records=records, events=events, on_point=on_point, stop=stop)
        if len(first):
            break
    return first


def clamped_buckle_run(rod: ClampedRodEnergy, q0: np.ndarray, options: ContinuationOptions,
                       name: str, records, events, on_point=None, stop=None
                       ) -> tuple[Branch | None, str]:
    """The first run of the displacement-controlled branch ``name`` from the clamped
    buckle ``q0`` solved by Newton, and a message: ``(None, why)`` when Newton fails."""
    set_pin(rod, rod, q0)
    res = newton(rod, q0, NewtonOptions(mode="stationary"))
    if not res.converged:
        return None, res.message
    rod.accept(res.q)
    return continuation(rod, res.q, res.multipliers, parameter="turns", options=options,
                        name=name, records=records, events=events, on_point=on_point,
                        stop=stop), res.message


def onset_passed(run: Branch) -> bool:
    """The run has a located ``contact_onset`` with a point after it."""
    return any(p.kind == "contact_onset" and p.index + 1 < len(run) for p in run.special_points)
