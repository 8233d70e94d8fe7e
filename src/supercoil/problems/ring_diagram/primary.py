"""The ring diagram's primary branches without contact, switched off the circle.

For each requested mode ``m`` the primary branch is switched from the
circle's bifurcation of mode ``m`` (``alpha``, ``beta``, ...) and followed
**without contact**. A :class:`~supercoil.continuation.UserEvent` watches the
closest approach of non-neighbouring centreline points, ``d_min / D - 1``
(``ContactProblem.min_distance``: segments closer than the neighbour exclusion
``pi D / 2`` along the rod are not compared); its sign change is located by
Brent's method and is the special point ``contact_onset`` (label
``min_gap``). The run stops at the first point beyond the onset
(:func:`~supercoil.problems.contact_events.stop_after_onset`), and the branch is
cut there (that last point penetrates; it is kept so that the onset lies
between two points of the branch).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, switch_branch
from supercoil.continuation.resume import resume_branch
from supercoil.geometry.symmetry import axis_invariant_combination
from supercoil.problems.circle_switch import (
    SWITCH_AMPLITUDE,
    SWITCH_TRIAL_POINTS,
    leaves_circle,
    switch_attempts,
    switch_notes,
)
from supercoil.problems.contact_events import onset_event, stop_after_onset
from supercoil.problems.ring_branches import ring_records
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.records import contact_records


def contact_free_branch(problem, circle: Branch, point: SpecialPoint, name: str,
                        opts: DiagramOptions, circle_top: float, probe: ContactProblem,
                        stored: Mapping[str, tuple[Branch, bool]], notes: list[str],
                        on_point=None) -> tuple[Branch, bool]:
    """The primary branch ``name`` from the circle's bifurcation ``point`` without contact,
    and whether it is a stored complete one (taken as it is); an incomplete stored one
    is continued from its last point, else the branch is switched off the circle
    (:func:`switch_off_circle`). ``probe`` measures the closest approach."""
    free_opts = ContinuationOptions(
        initial_step=SWITCH_AMPLITUDE, max_step=opts.free_max_step,
        max_points=opts.free_max_points, parameter_bounds=(0.0, circle_top),
        event_tolerance=opts.event_tolerance, gauge=opts.gauge,
        rephase=opts.gauge == "integral", factor_refinement=True)
    old, complete = stored.get(name, (None, False))
    if complete:
        return old, True
    if old is not None and len(old):
        watched, stop = stop_after_onset(on_point)
        return resume_branch(problem, old, free_opts, on_point=watched,
                             records=contact_records(probe, ring_records(problem), True),
                             events=(onset_event(probe),), stop=stop,
                             admissible=probe.admissible_over), False
    return switch_off_circle(problem, circle, point, free_opts, name, probe, notes,
                             on_point), False


def switch_off_circle(problem, circle: Branch, point: SpecialPoint,
                      options: ContinuationOptions, name: str, probe: ContactProblem,
                      notes: list[str], on_point=None) -> Branch:
    """The primary branch from ``point``, checked to leave the circle.

    Measured: the switch can fall back onto the circle (writhe ~1e-6 and the
    circle's count along the "new" branch; C/A = 0.6667, N = 40). A short
    trial run (``SWITCH_TRIAL_POINTS`` points) must show the writhe growing
    away from zero; otherwise the other side of the critical mode and larger
    amplitudes are tried, in that order. The last attempt is returned anyway.

    The run refuses a state past a strand passage (``probe.admissible``: the
    double-sum writhe off the carried one by 2) and retries the step shorter:
    the onset event measures an unsigned distance, positive on both sides of
    a step that carries the rod through itself (measured: alpha at N = 200
    with steps of 0.2 L ran to dLk = 0 without an onset, and at 0.1 L the
    demo's N = 132 kept a point with Tw + Wr off dLk by 2 after the onset).
    The run stops (``STOPPED``) at the first point past the located onset: the
    branch is cut there anyway
    (:func:`~supercoil.problems.contact_events.truncate_after`), and beyond it
    alpha creeps towards its figure-eight in ever shorter steps (measured: 30
    points at N = 200, every longer step refused as a strand passage).
    """
    records = contact_records(probe, ring_records(problem), free=True)
    direction = on_mesh_direction(problem, point)
    attempts = switch_attempts()
    for number, (amplitude, side) in enumerate(attempts):
        trial_opts = dataclasses.replace(options, max_points=SWITCH_TRIAL_POINTS,
                                         initial_step=amplitude)
        trial = switch_branch(problem, circle, point, trial_opts, side=side,
                              amplitude=amplitude, name=name, records=records,
                              direction=direction)
        leaves = leaves_circle(trial)
        if leaves or number == len(attempts) - 1:
            switch_notes(notes, name, number, amplitude, side, leaves)
            opts = dataclasses.replace(options, initial_step=amplitude)
            watched, stop = stop_after_onset(on_point)
            return switch_branch(problem, circle, point, opts, side=side, amplitude=amplitude,
                                 name=name, records=records, events=(onset_event(probe),),
                                 on_point=watched, direction=direction, stop=stop,
                                 admissible=probe.admissible_over)
    raise AssertionError("unreachable")


def on_mesh_direction(problem, point: SpecialPoint) -> np.ndarray | None:
    """The combination of a circle bifurcation's two critical modes (``cos m theta``,
    ``sin m theta``: the circle's O(2) makes the eigenvalue double) whose two-fold axis
    passes through node 0 (``c = 0`` of :func:`~supercoil.geometry.symmetry.reversal_axes`),
    a full DOF vector; None for a simple eigenvalue.

    On the discrete ring the map ``x_i -> R x_{c - i}`` is an exact symmetry only for
    an integer ``c`` (an axis through a node or an edge midpoint); the switch picks
    the axis, and the continuation (equivariant, the integral phase row included)
    keeps it: measured at L/D 122, N = 132, beta with the axis at ``c = 0`` kept it to
    1e-11 D up to dLk 6, where the modes' own combination put it at ``c = 22.03``
    (``22 + 0.03``) and the axes drifted to ``0.11`` off the mesh. An axis off the
    mesh is a symmetry of no discrete problem: the secondary branches' C_2 was then
    approximate, and their symmetry-breaking bifurcations (S of Coleman & Swigon 2002)
    unfolded into smooth turns from C_2 to C_1. With ``m`` dividing ``N`` all ``m``
    axes of a D_m branch are on the mesh.
    """
    modes = np.asarray(point.critical_modes, dtype=float)
    if modes.ndim != 2 or modes.shape[0] < 2:
        return None
    x = np.asarray(point.q, dtype=float).reshape(-1, 3)
    fields = modes.reshape(modes.shape[0], -1, 3)
    mass = np.asarray(problem.mass, dtype=float).reshape(-1, 3)[:, 0]
    direction = axis_invariant_combination(x, 0.0, fields, mass) @ modes
    # node 0 moves outward: for even m it then sits at a lobe's tip, far from node n/2
    # (the axis's other point), and the rigid pins on that axis keep their grip (with
    # node 0 at alpha's crossing, nodes 0 and n/2 came within 1.7 D)
    if direction.reshape(-1, 3)[0] @ (x[0] - x.mean(axis=0)) < 0:
        direction = -direction
    return direction
