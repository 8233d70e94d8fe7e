"""A Cosserat rod in magnetic tweezers: the straight rod in turns, its buckling, the
buckled branch; or, under displacement control, the clamped buckle in turns.

The rod is clamped at both ends on the axis
(:class:`~supercoil.cosserat.ClampedCosseratEnergy`). Under load control the turned
end slides along it under the dead load ``tension``: the straight rod, uniformly
twisted and stretched by ``tension / EA``, is followed in ``turns`` by the same
continuation as the Kirchhoff rod's; it buckles where a pair of eigenvalues crosses
zero (Greenhill's condition in the Kirchhoff limit), and the buckled branch is
switched off that point along a critical mode and followed to the end of the turns'
range. Under displacement control (``end_distance``, the end's height over L, the
stretch included) the branch ``clamped`` starts from the planar clamped buckle
(:func:`~supercoil.cosserat.clamped.planar_buckle`) solved by Newton at the first
turn, and is followed in turns the same way; ``tension`` is then the end's
reaction. At ``end_distance >= 1`` (the rod stretched: its tension ``EA (z/L - 1)``
exactly, twisted or not) the straight rod held there is followed in turns and the
buckled branch switched off its first bifurcation, as under load control. Without
self-contact the rod may pass through itself there (``closure_failed``); with it
(``options.length_over_diameter``) the buckled branch stops past its first contact
and goes on with self-contact to the plectoneme
(:mod:`supercoil.problems.cosserat_tweezers_contact`).

Per point the records are the Kirchhoff tweezers' (``turns``, ``extension``, ``torque``,
``twist``, ``writhe``, ``closure_error``, ``closure_failed``, ``energy``,
``load_potential``, ``tension``, the contact counts and ``min_gap_over_diameter``) plus
``max_stretch_strain`` and ``max_shear_strain``;
``extension`` is the end's height over L, stretch included; ``load_potential`` is
zero under displacement control. ``twist`` is that of
the ribbon of ``d1`` projected normal to the centreline, closed by the clamps'
frames along tails on the axis, so that ``twist + writhe = turns`` (Fuller's closure)
holds with shear too.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, continuation, switch_branch
from supercoil.continuation.resume import resume_branch
from supercoil.cosserat.centreline import StoredCentrelines
from supercoil.cosserat.clamped import ClampedCosseratEnergy, planar_buckle
from supercoil.cosserat.rod import CosseratRod
from supercoil.problems.contact_events import onset_event, stop_after_onset, truncate_after
from supercoil.problems.cosserat_stored import centreline_branch, cosserat_stored
from supercoil.problems.cosserat_tweezers_contact import (
    cosserat_contact_branch,
    with_contact_records,
)
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.result import TweezersResult
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.topology import twist_from_frames, writhe

TAIL_WRAP = 0.5  # |Tw + Wr - turns| above this: the closure failed
STRAIGHT_MAX_STEP = 0.25  # turns
SWITCH_AMPLITUDE = 2e-3


def clamped_cosserat_problem(options: TweezersOptions, stretch_stiffness: float,
                             shear_stiffness: float) -> ClampedCosseratEnergy:
    """The clamped Cosserat rod at ``turns = start``: under the options' tension at its
    straight state (``problem.straight_state()``), or with the end held at the options'
    end distance at the planar buckle (``problem.initial_state()``); at an end distance
    ``z/L >= 1`` at the straight rod stretched to it (its ``tension`` attribute
    ``EA (z/L - 1)``, the reaction, which the straight state uses)."""
    rod = CosseratRod(options.n_nodes - 1, twist_stiffness=options.twist_ratio,
                      shear_stiffness=shear_stiffness, stretch_stiffness=stretch_stiffness)
    if options.load_control:
        return ClampedCosseratEnergy(rod, options.turns[0], options.tension)
    if stretched(options):
        # the straight rod stretched to the end distance: its tension EA (z/L - 1) is
        # the end's reaction (the dead load is off under end-distance control)
        tension = stretch_stiffness * (options.end_distance - 1.0)
        return ClampedCosseratEnergy(rod, options.turns[0], tension,
                                     end_distance_control=True)
    x, R = planar_buckle(rod, options.end_distance, options.turns[0])
    return ClampedCosseratEnergy(rod, options.turns[0], end_distance_control=True,
                                 positions=x, rotations=R)


def stretched(options: TweezersOptions) -> bool:
    """Displacement control at ``z/L >= 1``: the straight rod, stretched, is the start."""
    return not options.load_control and options.end_distance >= 1.0


def axial_twist(problem: ClampedCosseratEnergy, q: np.ndarray) -> float:
    """Twist in turns of the ribbon ``d1`` (per element, the midpoint director projected
    normal to the chord) closed by tails on the axis framed by the clamps (module doc)."""
    x, R = problem.configuration(q)
    state = problem.rod.elements(x, R)
    t = state.chord / np.linalg.norm(state.chord, axis=1, keepdims=True)
    d1 = state.Rm[:, :, 0]
    d1 = d1 - np.sum(d1 * t, axis=1, keepdims=True) * t
    h = problem.rod.element_length
    points = np.vstack([x[:1] - [0.0, 0.0, h], x, x[-1:] + [0.0, 0.0, h]])
    frames = np.vstack([R[0][:, 0], d1, R[-1][:, 0]])
    return twist_from_frames(points, frames / np.linalg.norm(frames, axis=1, keepdims=True),
                             closed=False)


def end_torque(problem: ClampedCosseratEnergy, q: np.ndarray) -> float:
    """Axial moment ``M L / A`` carried by the last element, ``e_z . R_m C_K (K - K_0)``."""
    x, R = problem.configuration(q)
    state = problem.rod.elements(x, R)
    stress = problem.rod.bending_moduli * (state.curvature[-1]
                                           - [0.0, 0.0, problem.rod.intrinsic_twist])
    return float((state.Rm[-1] @ stress)[2] * problem.rod.length / problem.rod.bending_stiffness)


def azimuth_pinned_direction(problem: ClampedCosseratEnergy, modes: np.ndarray
                             ) -> np.ndarray | None:
    """Pin the rotation about the axis and return the buckling direction that respects it.

    Turning the centreline about the axis together with every section about its own
    ``d3`` (isotropy) leaves the clamps' frames and the energy unchanged: an exact
    symmetry of the clamped isotropic rod, the reason the straight rod's buckling
    eigenvalue is double. Off the straight rod it is a zero mode; it is removed by
    fixing the ``y`` of the node that the critical modes move most, and the switch
    goes along the combination of the two modes that keeps that ``y`` (None for a
    simple eigenvalue: nothing pinned)."""
    modes = np.asarray(modes, dtype=float)
    if modes.ndim != 2 or modes.shape[0] < 2:
        return None
    xy = modes[:2].reshape(2, -1, 6)[:, :, :2]
    node = int(np.argmax(np.linalg.norm(xy, axis=(0, 2))))
    a, b = xy[1, node, 1], -xy[0, node, 1]
    if np.hypot(a, b) == 0.0:
        a, b = 1.0, 0.0
    problem.hold_azimuth([6 * node + 1])
    return a * modes[0] + b * modes[1]


def cosserat_tweezers_records(rod: ClampedCosseratEnergy):
    """Per-point records (module doc) for ``continuation(records=)``."""

    def records(q, multipliers, turns, problem=None):
        # the rod at the point (the continuation's, with its chart), else this one there
        at = rod.at(turns=float(turns)) if problem is None else problem
        x, R = at.configuration(q)
        wr = writhe(x, closure="axis", self_crossing="nan")
        tw = axial_twist(at, q)
        error = abs(tw + wr - turns)
        return {"turns": float(turns), "extension": at.extension(q),
                "torque": end_torque(at, q), "twist": tw, "writhe": wr,
                "closure_error": error, "closure_failed": bool(not error <= TAIL_WRAP),
                "energy": at.rod.energy(x, R),
                "load_potential": (0.0 if at.end_distance_control
                                   else -at.tension * float(x[-1, 2])),
                "tension": at.end_force(q),
                "max_stretch_strain": at.max_stretch_strain(q),
                "max_shear_strain": at.max_shear_strain(q),
                "n_contact_points": 0, "n_contact_intervals": 0,
                "min_gap_over_diameter": math.inf}

    return records


def cosserat_tweezers(options: TweezersOptions, stretch_stiffness: float,
                      shear_stiffness: float,
                      progress: Callable[[str], None] | None = None, *,
                      on_point: Callable[[Branch], None] | None = None,
                      on_branch: Callable[[Branch, bool], None] | None = None,
                      resume: Mapping[str, tuple[Branch, bool]] | None = None
                      ) -> TweezersResult:
    """The straight Cosserat rod in turns, its buckling and the buckled branch, or the
    clamped buckle in turns under displacement control (module doc); numerical
    failures end up in statuses and notes.

    ``on_point`` sees every accepted point and ``on_branch(branch, contact)`` every
    final branch, in their stored form (:mod:`supercoil.problems.cosserat_stored`);
    ``resume`` maps branch names to ``(branch, complete)`` of an interrupted run with
    the same options (stored form): complete branches are kept, an incomplete buckled,
    clamped or contact branch is continued from its last point with the azimuth pin
    the run had (:func:`~supercoil.continuation.resume.resume_branch`); the straight
    rod is computed again."""
    opts = options
    say = progress or (lambda message: None)
    stored = cosserat_stored(dict(resume or {}))
    final = on_branch or (lambda branch, is_contact: None)
    point_of = None if on_point is None else (lambda b: on_point(centreline_branch(b)))
    notes: list[str] = []
    model = {"model": "cosserat", "stretch_stiffness": float(stretch_stiffness),
             "shear_stiffness": float(shear_stiffness)}
    problem = clamped_cosserat_problem(opts, stretch_stiffness, shear_stiffness)
    records = cosserat_tweezers_records(problem)
    cp = view = None
    if opts.diameter is not None:
        cp = ContactProblem(problem, opts.contact_options())
        # the contact of the stored centrelines, for the outputs' contact lists
        view = ContactProblem(StoredCentrelines(problem.rod), cp.options)
        records = with_contact_records(records, cp, False)
    free_opts = ContinuationOptions(initial_step=SWITCH_AMPLITUDE, max_step=opts.free_max_step,
                                    parameter_bounds=opts.turns, max_points=opts.max_points,
                                    event_tolerance=opts.event_tolerance)
    watched, at_onset = stop_after_onset(point_of) if cp is not None else (point_of, None)
    events = () if cp is None else (onset_event(cp),)
    seconds: dict[str, float] = {}
    branches: list = []

    def result(contact=frozenset(), cut=frozenset()):
        return TweezersResult(opts, tuple(centreline_branch(b) for b in branches), contact,
                              problem, view, seconds, tuple(notes), cut_at_contact=cut,
                              model=model)

    def continued(name: str, start):
        """The stored branch ``name`` when complete; continued when partial; else
        ``start()``. Returns ``(branch, complete)``."""
        old, complete = stored.get(name, (None, False))
        if complete:
            return old, True
        if old is not None and len(old) >= 2:
            return resume_branch(problem, old, free_opts, records=records, events=events,
                                 on_point=watched, stop=at_onset), False
        return start(), False

    start_time = time.perf_counter()
    if opts.load_control or stretched(opts):
        free_name = "buckled"
        free, complete = _buckled_off_straight(problem, opts, records, free_opts, events,
                                               watched, at_onset, branches, notes, seconds,
                                               say, continued, final)
        if free is None:
            return result()
    else:
        free_name = "clamped"
        say(f"clamped buckle at z/L = {opts.end_distance:g}, in turns")
        q0 = problem.initial_state()
        problem.repin(q0)

        def clamped():
            solved = newton(problem, q0, NewtonOptions(mode="stationary"))
            if not solved.converged:
                notes.append(f"failed: the clamped buckle at z/L = {opts.end_distance:g} "
                             f"did not converge ({solved.message})")
                return None
            problem.accept(solved.q)
            return continuation(problem, solved.q, parameter="turns",
                                options=free_opts, name=free_name, records=records,
                                events=events, on_point=watched, stop=at_onset)

        free, complete = continued(free_name, clamped)
        if free is None:
            return result()
    onsets = [p for p in free.points_of_kind("contact_onset") if p.index + 1 < len(free)]
    if onsets and complete:
        pass  # stored complete: cut after its onset already
    elif onsets:
        free = truncate_after(free, onsets[0], f"stopped at the first contact "
                              f"({onsets[0].parameter:.6g} turns); the contact-free run: "
                              f"{free.message}")
    elif not len(free):
        notes.append(f"failed: {free_name}: no point found from its start ({free.message})")
    elif not free.status.complete:
        notes.append(f"incomplete: {free_name} stopped at {free.parameter_values[-1]:.6g} "
                     f"turns: {free.message}")
    elif cp is not None:
        notes.append(f"{free_name}: no contact found ({free.message})")
    seconds[free_name] = time.perf_counter() - start_time
    final(centreline_branch(free), False)
    branches.append(free)
    if not onsets:
        return result()
    contact_name = f"{free_name}_contact"
    say(f"{contact_name}: from {onsets[0].parameter:.6g} turns, with self-contact (barrier)")
    start_time = time.perf_counter()
    old, complete = stored.get(contact_name, (None, False))
    contact = old if complete else cosserat_contact_branch(
        opts, cp, free, onsets[0], cosserat_tweezers_records(problem), contact_name,
        old=old, on_point=point_of)
    contact = dataclasses.replace(contact, parent=free_name, origin=onsets[0])
    if not contact.ok:
        notes.append(f"failed: {contact_name}: {contact.message}")
    elif contact.parameter_values[-1] < opts.turns[1] - 1e-9:
        notes.append(f"incomplete: {contact_name} ended at "
                     f"{contact.parameter_values[-1]:.6g} turns, before {opts.turns[1]:g}: "
                     f"{contact.message}")
    seconds[contact_name] = time.perf_counter() - start_time
    final(centreline_branch(contact), True)
    branches.append(contact)
    return result(frozenset({contact_name}), frozenset({free_name}))


def _buckled_off_straight(problem, opts, records, free_opts, events, watched, at_onset,
                          branches, notes, seconds, say, continued, final):
    """The straight rod in turns (appended to ``branches``) and the buckled branch
    switched off its first bifurcation (or its stored form, through ``continued``):
    ``(branch, complete)``, or ``(None, False)`` (no buckling: a note)."""
    if opts.load_control:
        say(f"straight Cosserat rod in turns at F L^2/A = {opts.tension:g}")
    else:
        say(f"straight Cosserat rod in turns held at z/L = {opts.end_distance:g}")
    cont = ContinuationOptions(initial_step=0.05, max_step=STRAIGHT_MAX_STEP,
                               parameter_bounds=opts.turns, max_points=opts.max_points,
                               event_tolerance=opts.event_tolerance)
    start_time = time.perf_counter()
    straight = continuation(problem, problem.straight_state(), parameter="turns",
                            options=cont, name="straight", records=records)
    seconds["straight"] = time.perf_counter() - start_time
    final(centreline_branch(straight), False)
    branches.append(straight)
    bifurcations = [p for p in straight.points_of_kind("bifurcation") if p.count_before == 0]
    if not bifurcations:
        if straight.status.complete:
            notes.append(f"the straight rod does not buckle below {opts.turns[1]:g} turns")
        else:
            notes.append(f"incomplete: straight stopped at {straight.parameter_values[-1]:.6g} "
                         f"turns ({straight.message})")
        return None, False
    point = bifurcations[0]
    say(f"buckled: switched from the straight rod at {point.parameter:.6g} turns")
    # the straight rod at the point, exactly, in the current chart (a stored state is
    # exact only in the chart it was accepted in: supercoil.cosserat.problem)
    at = problem.at(turns=point.parameter)
    start = dataclasses.replace(point, q=problem.state(*at.straight(at.rod, at.turns,
                                                                    at.tension)))
    problem.accept(start.q)
    start = dataclasses.replace(start, frames=problem.frames)  # the chart of its q
    direction = azimuth_pinned_direction(problem, point.critical_modes)
    return continued("buckled", lambda: switch_branch(
        problem, straight, start, free_opts, name="buckled", amplitude=SWITCH_AMPLITUDE,
        records=records, direction=direction, events=events, on_point=watched,
        stop=at_onset))
