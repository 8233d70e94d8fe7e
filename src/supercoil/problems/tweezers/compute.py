"""The tweezers' driver, :func:`tweezers_branches`: the straight rod (load control), the
contact-free branch, then the branch with self-contact."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, ContinuationStatus
from supercoil.problems.branch_options import coarse_mesh_note
from supercoil.problems.contact_events import (
    cut_at_onset,
    first_onset,
    onset_event,
    stop_after_onset,
)
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ply import spanning_note
from supercoil.problems.segments import either, follow
from supercoil.problems.tweezers.buckled import (
    SWITCH_AMPLITUDE,
    RunRecords,
    clamped_buckle_run,
    onset_passed,
    resume_stored,
    resumed_pins,
    stored_pins,
    switch_off_straight,
)
from supercoil.problems.tweezers.coarse import (
    pinned_loop_note,
    snake_note,
    unresolved_loop_note,
)
from supercoil.problems.tweezers.contact import contact_branch
from supercoil.problems.tweezers.mirrored import closed_before, held_contact
from supercoil.problems.tweezers.options import TweezersOptions, check_inextensible
from supercoil.problems.tweezers.pins import PIN_QUALITY, pin_stop, sliding_stop
from supercoil.problems.tweezers.plectoneme import switch_to_plectoneme, tries_note
from supercoil.problems.tweezers.problem import clamped_problem, tweezers_records
from supercoil.problems.tweezers.rejoin import REJOINS, rejoined
from supercoil.problems.tweezers.result import TweezersResult, options_ply
from supercoil.problems.tweezers.returned import close_on_return, returned_onto
from supercoil.problems.tweezers.straight import (
    resolution_note,
    straight_branch,
    unreached_note,
)
from supercoil.problems.tweezers.verify import verify_bifurcations

# a note when the sliding's phase row holds a force above this (a hundred times the
# residuals' round-off floor on the contact-free branches, 1e-8 at F L^2/A = 1200)
SLIDING_NOTE = 1e-6


def tweezers_branches(options: TweezersOptions,
                      progress: Callable[[str], None] | None = None, *,
                      on_point: Callable[[Branch], None] | None = None,
                      on_branch: Callable[[Branch, bool], None] | None = None,
                      resume: Mapping[str, tuple[Branch, bool]] | None = None,
                      ) -> TweezersResult:
    """Compute the branches (:mod:`supercoil.problems.tweezers`); numerical failures end
    up in statuses.

    ``on_point(branch_so_far)`` is called after every accepted point (of the
    runs that make a branch, merged), ``on_branch(branch, contact)`` once per
    branch when it is final (the contact-free branch cut after its contact
    onset): e.g. to save them as they come (``supercoil run``). ``resume`` maps
    branch names to ``(branch, complete)`` of an interrupted run with the same
    options: complete branches are taken as they are, an incomplete one with at
    least two points is continued from its last point with the azimuth pin its
    points were computed with (the record ``azimuth_pin``) by
    :func:`~supercoil.continuation.resume.resume_branch`, then in segments as usual.
    """
    opts = options
    check_inextensible(opts.end_distance)
    final = on_branch or (lambda branch, contact: None)
    stored = dict(resume or {})
    say = progress or (lambda message: None)
    seconds: dict[str, float] = {}
    notes: list[str] = []
    rod, q0 = clamped_problem(opts)
    D = opts.diameter
    contact_options = opts.contact_options() if D is not None else None
    probe = ContactProblem(rod, contact_options) if D is not None else None
    cp = ContactProblem(rod, contact_options) if D is not None else None
    note = coarse_mesh_note(rod.rod, D, extra_nodes=2) if D is not None else None
    if note is not None:
        notes.append(note)
    straight_records = tweezers_records(rod, rod, False, probe)
    free_records = RunRecords(straight_records)
    events = (onset_event(probe),) if probe is not None else ()
    free_opts = ContinuationOptions(initial_step=SWITCH_AMPLITUDE, max_step=opts.free_max_step,
                                    parameter_bounds=opts.turns,
                                    max_points=min(opts.segment_points, opts.max_points),
                                    event_tolerance=opts.event_tolerance, chord_steps=True,
                                    gauge="integral", rephase=True, midpoint_phase=True)
    # The contact-free runs end at the first point past a located contact onset (the
    # branch is cut there anyway): the switch's run computed 27 points, 12 beyond the
    # 15 kept (N = 100, L/D = 33, F L^2/A = 75, 0-5 turns).
    free_point, past_onset = (stop_after_onset(on_point) if probe is not None
                              else (on_point, None))
    pinned = pin_stop(rod)
    free_stop = either(past_onset, pinned)
    if opts.loop_sliding is True and not opts.loop_slides_in_contact:
        notes.append(f"loop_sliding is applied on the contact-free branches only: the "
                     f"segments ({rod.rod.edge_length:.3g} L) are longer than half the "
                     f"loop's core sqrt(A/F) ({1 / np.sqrt(opts.tension):.3g} L), which "
                     f"the mesh pins in contact")
    branches: list[Branch] = []
    start = time.perf_counter()
    if opts.load_control:
        say(f"straight rod in turns at F L^2/A = {opts.tension:g}")
        old, complete = stored.get("straight", (None, False))
        straight = (old if complete else
                    straight_branch(opts, rod, q0, straight_records, on_point=on_point))
        seconds["straight"] = time.perf_counter() - start
        final(straight, False)
        branches.append(straight)
        bifurcations = straight.points_of_kind("bifurcation")
        if not bifurcations:
            exact = critical_turns(opts.twist_ratio, opts.tension)
            if straight.status.complete:
                notes.append(f"the straight rod does not buckle below {opts.turns[1]:g} turns "
                             f"(exact threshold {exact:.6g})")
                unreached = unreached_note(opts)
                if unreached is not None:
                    notes.append(unreached)
            else:  # no conclusion beyond the last point computed
                notes.append(f"incomplete: straight stopped at "
                             f"{straight.parameter_values[-1]:.6g} turns ({straight.message}), "
                             f"before {opts.turns[1]:g}; no buckling found up to there (exact "
                             f"threshold {exact:.6g})")
            return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                                  tuple(notes))
        point = bifurcations[0]
        coarse = resolution_note(opts, point.parameter)
        if coarse is not None:
            notes.append(coarse)
        spanning = spanning_note(options_ply(opts), opts.turns[1])
        if spanning is not None:
            notes.append(spanning)
        free_name = "buckled"
        start = time.perf_counter()
        free_complete = stored.get(free_name, (None, False))[1]
        first = resume_stored(stored, rod, rod, free_name, free_opts, free_records, events,
                              free_point, free_stop, max_points=opts.max_points, first=q0)
        if first is not None:
            say(f"{free_name}: continued from point {len(stored[free_name][0]) - 1}")
        if first is None and not free_complete:
            first = switch_off_straight(rod, straight, point, free_opts, free_name,
                                        free_records, events, free_point,
                                        either(free_stop, sliding_stop(rod, q0)), say)
        if not free_complete and not len(first):
            notes.append(f"failed: {free_name}: no point found off the straight rod at "
                         f"{point.parameter:.6g} turns ({first.message})")
            branches.append(first)
            return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                                  tuple(notes), {"straight": ((0, ()),)})
    else:
        free_name = "clamped"
        say(f"clamped buckle at z/L = {opts.end_distance:g}, in turns")
        free_complete = stored.get(free_name, (None, False))[1]
        first = resume_stored(stored, rod, rod, free_name, free_opts, free_records, events,
                              free_point, free_stop, max_points=opts.max_points, first=q0)
    if not opts.load_control and first is None and not free_complete:
        first, why = clamped_buckle_run(rod, q0, free_opts, free_name, free_records, events,
                                        free_point, either(free_stop, sliding_stop(rod, q0)))
        if first is None:
            notes.append(f"failed: the clamped buckle at z/L = {opts.end_distance:g} did not "
                         f"converge ({why})")
            return TweezersResult(opts, (), frozenset(), rod, cp, seconds, tuple(notes))
    old, free_complete = stored.get(free_name, (None, False))
    if free_complete:
        free, free_pins = old, stored_pins(old)
    else:
        free, free_pins = follow(rod, rod, first, free_opts, free_name, free_records, events,
                                 stop=onset_passed if probe is not None else None,
                                 max_points=opts.max_points,
                                 segment_points=opts.segment_points, on_point=free_point,
                                 quality=PIN_QUALITY, refuse=free_stop,
                                 restart=lambda q: sliding_stop(rod, q),
                                 on_run=free_records.begin)
        if old is not None and len(old) >= 2:  # resumed: the pins of the stored points
            free_pins = resumed_pins(old, free_pins)
    free = verify_bifurcations(free)
    held = ("the sliding of the localised loop is held by a phase row (docs/continuation.md); "
            "the force it holds")
    onset = first_onset(free)
    seconds[free_name] = time.perf_counter() - start
    pins = {"straight": ((0, ()),), free_name: free_pins}
    if probe is None or onset is None:
        if not free.status.complete:
            notes.append(f"incomplete: {free_name} stopped at "
                         f"{free.parameter_values[-1]:.6g} turns: {free.message}")
        elif probe is not None and free.parameter_values[-1] < opts.turns[1] - 1e-9:
            # back at the first turn (the subcritical branch folded back to it) without
            # contact: the plectoneme was not reached
            notes.append(f"incomplete: {free_name} ended at {free.parameter_values[-1]:.6g} "
                         f"turns without contact, before {opts.turns[1]:g} ({free.message})")
        elif probe is not None:
            notes.append(f"{free_name}: no contact found ({free.message})")
        held_force_note(free, held, notes)
        final(free, False)
        branches.append(free)
        return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                              tuple(notes), pins)
    if not free_complete:
        free = cut_at_onset(free, onset, f"{onset.parameter:.6g} turns")
    held_force_note(free, held, notes)  # on the points kept, the located onset's too
    final(free, False)
    branches.append(free)
    contact_name = f"{free_name}_contact"
    say(f"{contact_name}: from {onset.parameter:.6g} turns, with self-contact (barrier)")
    start = time.perf_counter()
    contact, contact_pins = contact_branch(opts, rod, cp, free, onset, contact_name, stored,
                                           on_point, pinned, say)
    # released every contact and back on the contact-free branch: closed (returned.py)
    reach = 1.0 + (cp.options.barrier_activation if cp.treatment == "barrier" else 0.0)
    contact = close_on_return(contact, free, D, reach)
    contact = verify_bifurcations(dataclasses.replace(contact, parent=free_name, origin=onset),
                                  opts.segment)
    seconds[contact_name] = time.perf_counter() - start
    final(contact, True)
    branches.append(contact)
    pins[contact_name] = contact_pins
    names = {contact_name}
    last, handed = contact, frozenset()
    closed = closed_before(contact, opts.turns[1])
    if closed or (contact.parameter_values[-1] < opts.turns[1] - 1e-9
                  and contact.status is not ContinuationStatus.MAX_POINTS):
        # closed, or stopped before the last turn (not by the points it was given): the
        # same branch held on its half-turn symmetry (mirrored.py), which a freely
        # followed one leaves at a pitchfork of the contact's ripple, or loses along the
        # sliding that the turns drive
        start = time.perf_counter()
        held = held_contact(opts, rod, cp, free, onset, contact_name, stored, on_point,
                            pinned, say, reach)
        if held is not None:
            last, pins[held[0].name] = held
            seconds[last.name] = time.perf_counter() - start
            final(last, True)
            branches.append(last)
            names.add(last.name)
            handed = frozenset() if closed else frozenset({contact_name})
            why = ("closed" if closed else
                   f"stopped at {contact.parameter_values[-1]:.6g} turns")
            notes.append(f"{contact_name}: {why} ({contact.message}); followed again held "
                         f"on its half-turn symmetry: {last.name}")
            held_force_note(last, "the force its phase row holds", notes)
    guards: tuple = ()
    for _ in range(REJOINS if last is contact else 0):
        # closed on a curve it entered: followed again from before it, every curve met
        # refused (rejoin.py), and taken on where it reaches further
        if not closed_before(last, opts.turns[1]) \
                or returned_onto(last, free, D, reach) is not None:
            break
        start = time.perf_counter()
        again = rejoined(opts, rod, cp, last, stored, on_point, pinned, say, guards)
        if again is None:
            break
        branch = verify_bifurcations(close_on_return(again.branch, free, D, reach), opts.segment)
        seconds[branch.name] = time.perf_counter() - start
        final(branch, True)
        branches.append(branch)
        names.add(branch.name)
        pins[branch.name] = again.pins
        notes.append(f"{last.name}: closed ({last.message}); followed again from its point "
                     f"{again.start}, before the closed curve it entered at its point "
                     f"{again.entry} ({last.parameter_values[again.entry]:.6g} turns), the "
                     f"curves met refused: {branch.name}"
                     + ("" if not len(branch) else
                        f" ({branch.status.name.lower()} at {branch.parameter_values[-1]:.6g} "
                        f"turns, {branch.parameter_values.max():.6g} at most)"))
        guards = again.guards
        if not len(branch) or branch.parameter_values.max() <= last.parameter_values.max():
            break
        last = branch
    tried: list[Branch] = []  # the switches' tries, as they ended
    closed_contact = last
    if closed_before(last, opts.turns[1]):
        # the contact branch of a centred loop comes back onto itself or onto the
        # contact-free branch: the plectoneme branches off it at a bifurcation
        # (supercoil.problems.tweezers.plectoneme)
        start = time.perf_counter()
        switched = switch_to_plectoneme(opts, rod, cp, last, on_point, pinned, say,
                                        free=free, reach=reach, stored=stored,
                                        on_branch=final, tried=tried)
        if switched is None:
            why = ("no switch at its bifurcations gave a branch"
                   if last.points_of_kind("bifurcation") else
                   "it has no bifurcation to switch at (its count changes are count_change)")
            notes.append(f"incomplete: {last.name} closed before {opts.turns[1]:g} turns "
                         f"({last.message}) and {why}")
        else:
            closed_branch = last
            for via, via_pins in switched.via:  # closed switched branches, switched again
                final(via, True)  # verified before they were switched again
                branches.append(via)
                names.add(via.name)
                pins[via.name] = via_pins
                seconds[via.name] = switched.seconds.get(via.name, 0.0)
                notes.append(f"{closed_branch.name}: closed ({closed_branch.message}); "
                             f"switched at its bifurcation at {via.origin.parameter:.6g} "
                             f"turns: {via.name}")
                closed_branch = via
            last, switched_pins = switched.branch, switched.pins
            last = verify_bifurcations(last, opts.segment)
            seconds[last.name] = (time.perf_counter() - start
                                  - sum(seconds[b.name] for b, _ in switched.via))
            final(last, True)
            branches.append(last)
            names.add(last.name)
            pins[last.name] = switched_pins
            notes.append(f"{closed_branch.name}: closed ({closed_branch.message}); switched "
                         f"at its bifurcation at {last.origin.parameter:.6g} turns: "
                         f"{last.name}")
    if not last.ok:
        notes.append(f"failed: {last.name}: {last.message}")
    elif last.parameter_values[-1] < opts.turns[1] - 1e-9 and not any(
            n.startswith(f"incomplete: {last.name} closed") for n in notes):
        notes.append(f"incomplete: {last.name} ended at {last.parameter_values[-1]:.6g} "
                     f"turns, before {opts.turns[1]:g}: {last.message}")
    if tried and (len(last) == 0 or last.parameter_values[-1] < opts.turns[1] - 1e-9):
        notes.append(tries_note(closed_contact, tried))
    mesh_note = (pinned_loop_note(opts, last) or snake_note(opts, last)
                 or unresolved_loop_note(opts, last))
    if mesh_note is not None:
        notes.append(mesh_note)
    return TweezersResult(opts, tuple(branches), frozenset(names), rod, cp, seconds,
                          tuple(notes), pins, frozenset({free_name}), held_instead=handed)


def held_force_note(branch, what: str, notes: list[str]) -> None:
    """Append to ``notes`` where the force a phase row holds along ``branch`` (its record
    ``sliding_residual``, the KKT residual without the row) exceeds ``SLIDING_NOTE``:
    ``what``, its largest value and the turns there."""
    force = branch.records.get("sliding_residual", np.zeros(0))
    if len(branch) and np.max(force) > SLIDING_NOTE:
        k = int(np.argmax(force))
        notes.append(f"{branch.name}: {what}, max |KKT residual| without it, is at most "
                     f"{float(force[k]):.2e} (at {float(branch.parameter_values[k]):.4g} "
                     f"turns)")
