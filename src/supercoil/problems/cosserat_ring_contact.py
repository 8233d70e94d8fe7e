"""The Cosserat ring's primary branches continued with self-contact.

From the last point of a contact-free primary branch that the contact terms do not
reach yet (:func:`~supercoil.problems.contact_events.contact_start`) the branch is
followed with self-contact in the direction it was going, as the Kirchhoff ring's
(:mod:`supercoil.problems.ring_diagram.contact_branches`): the same continuation
options (steps a fraction of ``D``, the material sliding held by the integral phase
condition, continuous collision detection on every corrector step), the same
contact events and records. The contact acts on the Cosserat rod's centreline
(:mod:`supercoil.cosserat.centreline`), so the equilibria balance the rod's
internal forces and moments, with shear and extension, against normal contact
forces on the centreline.

The rigid pins need no re-picking here: the Cosserat ring fixes node 0's position
and rotation, which holds every rigid rotation whatever the shape (a rigid rotation
turns node 0's frame), and one coordinate of a far node against the last exact
symmetry, the turn about node 0's tangent less the sections' isotropy
(:func:`~supercoil.cosserat.closed.ring_pins`).
"""

from __future__ import annotations

import dataclasses

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, SpecialPoint, continuation
from supercoil.continuation.carry import frames_at
from supercoil.continuation.resume import resume_branch
from supercoil.cosserat.closed import ClosedCosseratEnergy
from supercoil.problems.contact_events import (
    classify_contact_events,
    contact_count_event,
    contact_start,
)
from supercoil.problems.ring_diagram.contact_branches import contact_options
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.records import contact_records


def cosserat_contact_problem(problem: ClosedCosseratEnergy, options: DiagramOptions,
                             treatment: str | None = None) -> ContactProblem:
    """The ring ``problem`` with the diagram's self-contact (``treatment``: another one
    than the options', e.g. the barrier that measures the onset); the knot type kept is
    the unknot of the circle."""
    contact = options.contact_options(options.diameter * problem.rod.length)
    if treatment is not None:
        contact = dataclasses.replace(contact, treatment=treatment)
    cp = ContactProblem(problem, contact)
    cp.keep_knot_type(problem.configuration(problem.initial_state())[0])
    return cp


def cosserat_contact_branch(cp: ContactProblem, free: Branch, onset: SpecialPoint,
                            options: DiagramOptions, records, name: str,
                            old: Branch | None = None, on_point=None) -> Branch | None:
    """The contact branch ``name`` from the contact-free branch ``free`` (states in the
    Cosserat unknowns) at its ``onset``, its contact events classified; None when its
    start lies outside ``[0, max_excess_link]``. ``records``: the ring's own per-point
    records, to which the contact counts and the sliding force are added. ``old``: the
    same branch stored by an interrupted run (in the Cosserat unknowns, with its
    frames), continued from its last point
    (:func:`~supercoil.continuation.resume.resume_branch`); ``on_point`` as for
    :func:`~supercoil.continuation.continuation`."""
    k = contact_start(free, onset, cp)
    direction = 1 if free.tangents[k, -1] >= 0 else -1
    start = float(free.parameter_values[k])
    if not 0.0 <= start <= options.max_excess_link:
        return None
    opts = contact_options(options, cp.diameter, direction)
    own = contact_records(cp, records, free=False)
    events = (contact_count_event(cp),)
    if old is not None and len(old):
        branch = resume_branch(cp, old, opts, records=own, events=events, on_point=on_point)
    else:
        # from the frames of the contact-free branch's point k (cp unchanged)
        branch = continuation(frames_at(cp, free, k), free.states[k],
                              parameter="excess_link", start=start, options=opts, name=name,
                              records=own, events=events, on_point=on_point)
    return classify_contact_events(branch, cp)
