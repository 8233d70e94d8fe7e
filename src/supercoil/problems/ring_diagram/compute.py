"""The ring diagram's driver, :func:`ring_diagram`: the circle, then per mode the primary
branch without and with contact, then the secondary and tertiary branches."""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch
from supercoil.continuation.carry import frames_at
from supercoil.problems.branch_options import coarse_mesh_note
from supercoil.problems.circle_switch import mode_points
from supercoil.problems.contact_events import contact_start, cut_at_onset, first_onset
from supercoil.problems.ring import michell_excess_link
from supercoil.problems.ring_branches import circle_branch, ring_records
from supercoil.problems.ring_diagram.contact_branches import (
    Pins,
    contact_branch,
    contact_options,
    sliding_note,
)
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.primary import contact_free_branch
from supercoil.problems.ring_diagram.records import contact_records, with_records
from supercoil.problems.ring_diagram.result import RingDiagram
from supercoil.problems.ring_diagram.secondary import secondary_branches


def ring_diagram(options: DiagramOptions,
                 progress: Callable[[str], None] | None = None, *,
                 on_point: Callable[[Branch], None] | None = None,
                 on_branch: Callable[[Branch, bool], None] | None = None,
                 resume: Mapping[str, tuple[Branch, bool]] | None = None) -> RingDiagram:
    """Compute the diagram (:mod:`supercoil.problems.ring_diagram`); numerical failures end
    up in branch statuses.

    ``on_point(partial_branch)`` is called after each accepted point of the
    primary and contact branches (not of the switch's short trial runs), and
    ``on_branch(branch, contact)`` once per branch when it is final (the
    circle with its records, a primary branch cut after its contact onset, a
    contact branch with its events classified): e.g. to save them as they
    come (``supercoil run``). ``resume`` maps branch names to ``(branch,
    complete)`` of an interrupted run with the same options: complete primary
    and contact branches are taken as they are, incomplete ones continued
    from their last point (:func:`~supercoil.continuation.resume.resume_branch`);
    the circle is computed again (its problem is needed; about a second).
    """
    opts = options
    stored = dict(resume or {})
    final = on_branch or (lambda branch, contact: None)
    say = progress or (lambda message: None)
    seconds: dict[str, float] = {}
    notes: list[str] = []
    top = max(michell_excess_link(opts.twist_ratio, m) for m in opts.modes)
    circle_top = max(opts.max_excess_link, 1.1 * top)
    say(f"circle up to dLk = {circle_top:.4g}")
    start = time.perf_counter()
    circle, problem = circle_branch(opts.twist_ratio, opts.n_nodes, circle_top)
    seconds["circle"] = time.perf_counter() - start
    D = opts.diameter * problem.rod.length
    contact_opts = opts.contact_options(D)
    # the onset is measured on the contact's own curve (and samples, for the integral)
    probe = ContactProblem(problem, dataclasses.replace(contact_opts, treatment="barrier"))
    cp = ContactProblem(problem, contact_opts)
    for guarded in (probe, cp):  # every branch keeps the circle's knot type, the unknot
        guarded.keep_knot_type(circle.states[0])
    notes += _mesh_notes(opts, problem.rod, D)
    circle = with_records(circle, problem, contact_records(probe, ring_records(problem),
                                                           free=True))
    final(circle, False)
    branches: list[Branch] = [circle]
    contact_names: set[str] = set()
    pins: dict[str, Pins] = {}
    for name, point in mode_points(circle, opts.modes, notes, say):
        start = time.perf_counter()
        free, complete = contact_free_branch(problem, circle, point, name, opts, circle_top,
                                             probe, stored, notes, on_point)
        onset = first_onset(free)
        seconds[name] = time.perf_counter() - start
        if onset is None:
            notes.append(f"{name}: no contact found without contact ({free.message})")
            final(free, False)
            branches.append(free)
            continue
        if not complete:
            free = cut_at_onset(free, onset, f"dLk = {onset.parameter:.6g}")
        final(free, False)
        branches.append(free)
        contact_name = f"{name}_contact"
        say(f"{contact_name}: from dLk = {onset.parameter:.4g}, with self-contact "
            f"({opts.contact})")
        start = time.perf_counter()
        k = contact_start(free, onset, cp)
        direction = 1 if free.tangents[k, -1] >= 0 else -1
        at = float(free.parameter_values[k])
        carrying = frames_at(cp, free, k)  # the frames of the free branch's point k
        if not 0.0 <= at <= opts.max_excess_link:
            notes.append(f"{contact_name}: contact at dLk = {at:.4g} is outside "
                         f"[0, {opts.max_excess_link:g}]: not computed")
            continue
        contact, pins[contact_name] = contact_branch(
            carrying, free, k, contact_options(opts, D, direction), contact_name, stored, on_point)
        note = sliding_note(contact, opts, contact_name)
        if note is not None:
            notes.append(note)
        contact = dataclasses.replace(contact, parent=name, origin=onset)
        final(contact, True)
        seconds[contact_name] = time.perf_counter() - start
        branches.append(contact)
        contact_names.add(contact_name)
    diagram = RingDiagram(opts, tuple(branches), frozenset(contact_names), seconds,
                          tuple(notes), cp, pins=pins)
    if opts.branch_depth >= 2:
        diagram = secondary_branches(diagram, opts.branch_depth,
                                     max_points=opts.secondary_max_points,
                                     max_branches=opts.secondary_max_branches, progress=say,
                                     on_point=on_point, on_branch=final)
    return diagram


def _mesh_notes(opts: DiagramOptions, rod, D: float) -> list[str]:
    """Notes on a mesh too coarse for the tube, or without the primary branches' D_m."""
    note = coarse_mesh_note(rod, D)
    notes = [] if note is None else [note]
    asymmetric = [m for m in opts.modes if opts.n_nodes % m]
    if asymmetric:
        notes.append(f"N = {opts.n_nodes} is not a multiple of "
                     f"{', '.join(map(str, asymmetric))}: the mesh lacks the D_m symmetry of "
                     f"those primary branches, so their symmetry-breaking bifurcations "
                     f"(Coleman & Swigon's P on beta) unfold into folds; use --nodes a "
                     f"multiple of {math.lcm(*opts.modes)}")
    return notes
