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
from supercoil.problems.segments import RunRecords, either, set_pin
from supercoil.problems.tweezers.pins import (
    hold_azimuth,
    pin_node,
    rotated_mode,
    sliding_stop,
)
from supercoil.rod.open import ClampedRodEnergy
from supercoil.solvers.newton import NewtonOptions, newton

SWITCH_AMPLITUDE = 2e-2  # largest first step of the buckled branch (arclength)
# The first point's distance from the bifurcation, as the largest angle (radians) by
# which it turns an edge of the rod: tried in turn until one gives a point (see
# switch_amplitudes)
SWITCH_ANGLES = (0.2, 0.05, 0.01)


def stored_pins(branch: Branch) -> tuple[tuple[int, tuple[int, ...]], ...]:
    """The azimuth pins of a stored branch as :func:`~supercoil.problems.segments.follow`
    reports them, ``(first point index, pinned DOFs)`` per change, from its record
    ``azimuth_pin``: a pin first recorded at point ``i`` was picked at point ``i - 1``,
    where its run started (a pin picked again unchanged is not seen)."""
    pin = branch.records["azimuth_pin"]

    def dofs(i):
        return (int(pin[i]),) if pin[i] >= 0 else ()

    return ((0, dofs(0)),) + tuple((i - 1, dofs(i)) for i in range(1, len(pin))
                                   if pin[i] != pin[i - 1])


def resumed_pins(old: Branch, later: tuple[tuple[int, tuple[int, ...]], ...]
                 ) -> tuple[tuple[int, tuple[int, ...]], ...]:
    """The pins of a branch continued from the stored ``old``: those of its stored
    points (:func:`stored_pins`), then those ``follow`` picked after them (``later``,
    whose first entry is the pin the stored points ended with)."""
    return stored_pins(old) + tuple(p for p in later if p[0] >= len(old) - 1 and p[0] > 0)


def resume_stored(stored: Mapping[str, tuple[Branch, bool]], rod: ClampedRodEnergy,
                  problem, name: str, segment_opts: ContinuationOptions,
                  records: RunRecords, events, on_point=None, stop=None,
                  sliding: bool = True, max_points: int | None = None,
                  first: np.ndarray | None = None, resumed: bool = True) -> Branch | None:
    """The stored branch ``name`` continued to the end of the run it was stopped in, or
    None (none stored, or complete, or of fewer than two points).

    The run is the one the record ``run_start`` names (a branch stored without it: a
    run from its last point), continued as the uninterrupted run went on: up to its
    ``segment_opts.max_points`` points (``max_points`` bounds the whole branch), with
    the azimuth pin its points were computed with (the record ``azimuth_pin``, the same
    gauge), its phase rows (those stored with the branch), and ``stop``. ``sliding``:
    the run also ends where the sliding's phase row must come or go relative to the
    run's first state (:func:`~supercoil.problems.tweezers.pins.sliding_stop`), or
    relative to ``first`` for the branch's first run (the state its stop was made from).
    ``records.start`` is left at the run's start. ``resumed``: as
    :func:`~supercoil.continuation.resume.resume_branch` has it."""
    old, complete = stored.get(name, (None, False))
    if old is None or complete or len(old) < 2:
        return None
    q = old.states[-1]
    start = (int(old.records["run_start"][-1]) if "run_start" in old.records
             else len(old) - 1)
    total = segment_opts.max_points if max_points is None else max_points
    end = min(start + segment_opts.max_points, total)
    pin = int(old.records["azimuth_pin"][-1]) if "azimuth_pin" in old.records else -1
    if pin >= 0:  # the pin the stored points were computed with: the same gauge
        hold_azimuth(rod, (pin,), problem)
    else:
        set_pin(problem, rod, q)
    records.begin(start)
    since = first if start == 0 and first is not None else old.states[start]
    return resume_branch(problem, old, dataclasses.replace(segment_opts, max_points=end),
                         records=records, events=events, on_point=on_point,
                         stop=either(stop, sliding_stop(rod, since) if sliding else None),
                         resumed=resumed)


def switch_off_straight(rod: ClampedRodEnergy, straight: Branch, point: SpecialPoint,
                        options: ContinuationOptions, name: str, records, events,
                        on_point=None, stop=None,
                        say: Callable[[str], None] = lambda message: None) -> Branch:
    """The first run of the buckled branch ``name``, switched from the straight rod's
    bifurcation ``point`` along its critical mode turned so that the pinned node moves
    along +x (:func:`~supercoil.problems.tweezers.pins.pin_node`); the amplitudes of
    :func:`switch_amplitudes` tried in turn until one gives a point."""
    direction, node = rotated_mode(point.critical_modes[0])
    first = None
    amplitudes = switch_amplitudes(rod, direction)
    for amplitude in amplitudes:
        if amplitude == amplitudes[0]:
            say(f"{name}: switched from the straight rod at {point.parameter:.6g} turns")
        pin_node(rod, node)
        first = switch_branch(rod, straight, point,
                              dataclasses.replace(options, initial_step=amplitude),
                              direction=direction, amplitude=amplitude, name=name,
                              records=records, events=events, on_point=on_point, stop=stop)
        if len(first):
            break
    return first


def switch_amplitudes(rod: ClampedRodEnergy, mode: np.ndarray) -> tuple[float, ...]:
    """The first point's distances from the bifurcation along ``mode`` (arclength metric)
    to try in turn: those at which the mode turns the rod's most bent edge by the angles
    ``SWITCH_ANGLES``, at most ``SWITCH_AMPLITUDE``.

    The critical mode of a long rod under tension is a helix of wavenumber close to
    ``sqrt(F/A)`` under a slow envelope (Greenhill's clamped condition,
    :mod:`supercoil.problems.greenhill`): its largest slope per unit amplitude grows
    like ``L sqrt(F/A)`` (measured: 12 at ``lambda = 10``, 54 at 40, 98 at 80, 190-205 at
    150, in the arclength metric), so a fixed amplitude is a small deflection at small
    ``lambda`` and several radians at large ones. The branch is subcritical, its turns
    falling like the square of the amplitude, and the straight rod's next bifurcations
    (the envelope's next modes) lie close above (0.02-0.08 turns at ``lambda = 150``):
    at ``lambda = 150`` the corrector diverged from amplitudes turning the rod by 0.1-3
    radians and converged from 0.05 radians (N = 102 to 404)."""
    x = np.asarray(mode, dtype=float).reshape(-1, 3)
    slope = float(np.max(np.linalg.norm(np.diff(x, axis=0), axis=1))) / rod.rod.edge_length
    norm = float(np.sqrt(np.sum(np.asarray(rod.mass, dtype=float) * np.ravel(mode) ** 2)))
    per_angle = norm / slope if slope > 0 else SWITCH_AMPLITUDE
    return tuple(min(SWITCH_AMPLITUDE, angle * per_angle) for angle in SWITCH_ANGLES)


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
