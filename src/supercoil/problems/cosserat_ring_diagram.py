"""The Cosserat ring's diagram, :func:`cosserat_ring_diagram`: the circle, the primary
branches without and with contact, the secondary and tertiary branches; recorded point
by point and continued after an interruption.

The branches are those of :mod:`supercoil.problems.cosserat_ring` (the circle and the
primary branches to their first contact), :mod:`supercoil.problems.cosserat_ring_contact`
(on with self-contact) and :mod:`supercoil.problems.cosserat_ring_secondary` (switched
at the bifurcation points of the primary families, ``branch_depth`` 2 and 3). Every
accepted point is handed to ``on_point`` and every final branch to ``on_branch`` as
they are stored (:mod:`supercoil.problems.cosserat_stored`: centrelines, with each
point's sections' frames), and ``resume`` continues a stored run as the Kirchhoff
diagram does (:func:`~supercoil.problems.ring_diagram.ring_diagram`): complete primary
and contact branches are kept, incomplete ones continued from their last point; the
circle, and the secondary branches, are computed again.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions
from supercoil.continuation.resume import resume_branch
from supercoil.cosserat.centreline import StoredCentrelines
from supercoil.cosserat.ring import michell_excess_link
from supercoil.errors import InputError
from supercoil.problems.circle_switch import (
    SWITCH_AMPLITUDES,
    SWITCH_TRIAL_POINTS,
    leaves_circle,
    mode_points,
)
from supercoil.problems.contact_events import cut_at_onset, first_onset, stop_after_onset
from supercoil.problems.cosserat_ring import (
    FAST_ITERATIONS,
    PREDICTOR,
    TOLERANCE,
    cosserat_circle_branch,
    cosserat_ring_records,
    gap_curve,
    onset_event,
    switch_off_circle,
)
from supercoil.problems.cosserat_stored import centreline_branch, cosserat_stored
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.result import RingDiagram


def _stored_form(on_point):
    """``on_point`` of the branches in the Cosserat unknowns, handing the stored form on."""
    if on_point is None:
        return None
    return lambda branch: on_point(centreline_branch(branch))


def _free_branch(problem, circle, point, constants, options, name, curve, notes, stored,
                 on_point) -> tuple[Branch, bool]:
    """The primary branch ``name`` without contact and whether it is a stored complete one:
    kept; an incomplete stored one that has left the circle continued from its last
    point; else switched off the circle (a stored run that had not yet shown it left the
    circle is switched again: the switch is deterministic)."""
    old, complete = stored.get(name, (None, False))
    if complete:
        return old, True
    if old is not None and len(old) >= SWITCH_TRIAL_POINTS and leaves_circle(old):
        watched, at_onset = stop_after_onset(on_point)
        return resume_branch(problem, old, options, records=cosserat_ring_records(problem, curve),
                             events=(onset_event(curve),), on_point=watched,
                             stop=at_onset), False
    return switch_off_circle(problem, circle, point, constants, options, name, curve, notes,
                             on_point), False


def cosserat_ring_diagram(options: DiagramOptions, stretch_stiffness: float,
                          shear_stiffness: float,
                          progress: Callable[[str], None] | None = None,
                          contact: bool = False, *,
                          on_point: Callable[[Branch], None] | None = None,
                          on_branch: Callable[[Branch, bool], None] | None = None,
                          resume: Mapping[str, tuple[Branch, bool]] | None = None
                          ) -> RingDiagram:
    """The circle, its bifurcations of ``options.modes`` and the primary branches to their
    first self-contact at the tube diameter ``options.diameter``, for the Cosserat ring of
    ``stretch_stiffness`` EA L^2/A and ``shear_stiffness`` GA L^2/A, and with ``contact``
    on from there with self-contact (``options.contact``), then the branches switched
    at their bifurcation points up to ``options.branch_depth`` (with ``contact`` only).
    ``on_point``, ``on_branch`` and ``resume`` (branches in their stored form) as for
    :func:`~supercoil.problems.ring_diagram.ring_diagram` (module doc)."""
    from supercoil.problems.cosserat_ring_contact import (
        cosserat_contact_branch,
        cosserat_contact_problem,
    )
    from supercoil.problems.cosserat_ring_secondary import cosserat_secondary_branches

    opts = options
    if opts.branch_depth >= 2 and not contact:
        raise InputError("branch_depth: the Cosserat ring's secondary branches are "
                         "followed with self-contact; give a contact, or branch_depth 1",
                         name="branch_depth")
    stored = cosserat_stored(dict(resume or {}))
    final = on_branch or (lambda branch, is_contact: None)
    point_of = _stored_form(on_point)
    diameter = opts.diameter
    say = progress or (lambda message: None)
    notes: list[str] = [] if contact else [
        (f"the Cosserat model without contact: primary branches stop at their first "
         f"self-contact (D = {diameter:.4g} L)")]
    constants = (opts.twist_ratio, float(stretch_stiffness), float(shear_stiffness))
    # with contact the onset is measured on the contact's own curve (as the Kirchhoff
    # diagram's probe)
    curve = gap_curve(opts.n_nodes, diameter, dataclasses.replace(
        opts.contact_options(diameter), treatment="barrier") if contact else None)
    top = max(michell_excess_link(opts.twist_ratio, m) for m in opts.modes)
    circle_top = max(opts.max_excess_link, 1.1 * top)
    say(f"circle up to dLk = {circle_top:.4g} (Cosserat rod)")
    seconds: dict[str, float] = {}
    start = time.perf_counter()
    # d1 turned by the whole turns nearest the requested thresholds' mean
    link = int(np.rint(np.mean([michell_excess_link(opts.twist_ratio, m) for m in opts.modes])))
    circle, problem = cosserat_circle_branch(opts.twist_ratio, opts.n_nodes, circle_top,
                                             *constants[1:], curve, link)
    seconds["circle"] = time.perf_counter() - start
    final(centreline_branch(circle), False)
    branches = [circle]  # in the Cosserat unknowns
    contact_names: set[str] = set()
    cp = cosserat_contact_problem(problem, opts) if contact else None
    free_opts = ContinuationOptions(
        initial_step=SWITCH_AMPLITUDES[0], max_step=opts.free_max_step,
        max_points=opts.free_max_points, parameter_bounds=(0.0, circle_top),
        event_tolerance=opts.event_tolerance, tolerance=TOLERANCE, predictor=PREDICTOR,
        factor_refinement=True, chord_steps=True, fast_iterations=FAST_ITERATIONS)
    for name, point in mode_points(circle, opts.modes, notes, say):
        start = time.perf_counter()
        free, complete = _free_branch(problem, circle, point, constants, free_opts, name,
                                      curve, notes, stored, point_of)
        onset = first_onset(free)
        if onset is not None and not onset.located:
            before = free.parameter_values[onset.index]
            notes.append(f"{name}: the contact onset lies between dLk = {before:.6g} and "
                         f"{onset.parameter:.6g}, where its location failed (a trial "
                         "correction across the step did not converge); it is reported "
                         "at the step's end")
        if onset is not None and not complete:
            free = cut_at_onset(free, onset, f"dLk = {onset.parameter:.6g}")
        elif onset is None:
            notes.append(f"{name}: no contact found without contact ({free.message})")
        seconds[name] = time.perf_counter() - start
        final(centreline_branch(free), False)
        branches.append(free)
        if onset is None or not contact:
            continue
        contact_name = f"{name}_contact"
        say(f"{contact_name}: from dLk = {onset.parameter:.4g}, with self-contact "
            f"({opts.contact})")
        start = time.perf_counter()
        old, done = stored.get(contact_name, (None, False))
        if done:
            with_contact = old
        else:
            with_contact = cosserat_contact_branch(cp, free, onset, opts,
                                                   cosserat_ring_records(problem, curve),
                                                   contact_name, old, point_of)
        if with_contact is None:
            notes.append(f"{contact_name}: contact at dLk = {onset.parameter:.4g} is "
                         f"outside [0, {opts.max_excess_link:g}]: not computed")
            continue
        with_contact = dataclasses.replace(with_contact, parent=name, origin=onset)
        seconds[contact_name] = time.perf_counter() - start
        final(centreline_branch(with_contact), True)
        branches.append(with_contact)
        contact_names.add(contact_name)
    generations: dict[str, int] = {}
    if contact and opts.branch_depth >= 2:
        added, notes = cosserat_secondary_branches(
            cp, branches, opts, cosserat_ring_records(problem, curve), notes=notes, say=say,
            on_point=point_of,
            on_branch=lambda b: final(centreline_branch(b), True))
        for switched in added:
            branches.append(switched.branch)
            contact_names.add(switched.branch.name)
            generations[switched.branch.name] = switched.generation
            seconds[switched.branch.name] = switched.seconds
    # the contact of the stored centrelines, for the outputs' contact lists
    view = None if cp is None else ContactProblem(StoredCentrelines(problem.rod), cp.options)
    model = {"model": "cosserat", "stretch_stiffness": float(stretch_stiffness),
             "shear_stiffness": float(shear_stiffness)}
    return RingDiagram(opts, tuple(centreline_branch(b) for b in branches),
                       frozenset(contact_names), seconds, tuple(notes), view,
                       generations=generations, model=model)
