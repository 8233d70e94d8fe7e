"""A Cosserat rod in tweezers with self-contact: the buckled branch's contact, then the
plectoneme.

The same steps as the Kirchhoff rod's (:mod:`supercoil.problems.tweezers`): the
buckled branch watches the closest approach of non-neighbouring centreline points on
the contact's curve (``contact_onset``) and stops past it; from its last point that
the barrier does not reach yet the branch is followed with self-contact in turns
(``buckled_contact``), its contact events classified. The contact acts on the
Cosserat rod's centreline (:mod:`supercoil.cosserat.centreline`). The azimuth pin
picked at the buckling (:func:`~supercoil.problems.cosserat_tweezers.azimuth_pinned_direction`)
is kept along both branches.
"""

from __future__ import annotations

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import COUNT_KEYS, contact_summary
from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, continuation
from supercoil.continuation.carry import frames_at
from supercoil.continuation.resume import resume_branch
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import (
    classify_contact_events,
    contact_count_event,
    contact_start,
)
from supercoil.problems.ring_diagram.records import kkt_residual
from supercoil.problems.tweezers.contact import CONTACT_CORRECTOR_DISTANCE
from supercoil.problems.tweezers.options import TweezersOptions


def with_contact_records(records, cp: ContactProblem, contact: bool):
    """The Cosserat tweezers' records with the contact's: the counts and the closest
    approach (contact branch, with the force the continuation's phase row holds), or the
    closest approach alone (contact-free branch, no contact counted)."""

    def out(q: np.ndarray, multipliers: np.ndarray, turns: float, problem=None) -> dict:
        # the rod at the point, with its chart (the continuation's problem is the contact
        # problem on the contact branch)
        row = dict(records(q, multipliers, turns, problem=getattr(problem, "base", problem)))
        if contact:
            summary = contact_summary(cp, q, multipliers, COUNT_KEYS)
            gap = summary["min_gap_over_diameter"]
            row.update(n_contact_points=summary["n_contact_points"],
                       n_contact_intervals=summary["n_contact_intervals"],
                       min_gap_over_diameter=float("inf") if gap is None else gap,
                       sliding_residual=kkt_residual(cp, q, multipliers))
        else:
            row.update(min_gap_over_diameter=float(cp.min_distance(q) / cp.diameter))
        return row

    return out


def cosserat_contact_branch(options: TweezersOptions, cp: ContactProblem, free: Branch,
                            onset: SpecialPoint, records, name: str,
                            old: Branch | None = None, on_point=None) -> Branch:
    """The branch with self-contact from the contact-free ``free`` (states in the
    Cosserat unknowns) past its ``onset`` (module doc); ``old``: the same branch stored
    by an interrupted run (in the unknowns, with its frames), continued from its last
    point; ``on_point`` as for :func:`~supercoil.continuation.continuation`."""
    opts = options
    D = opts.diameter
    k = contact_start(free, onset, cp)
    q = free.states[k]
    contact_opts = ContinuationOptions(
        initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
        max_step=opts.contact_max_step * D, max_points=opts.max_points,
        parameter_bounds=opts.turns, direction=1 if free.tangents[k, -1] >= 0 else -1,
        parameter_weight=D, tolerance=opts.contact_tolerance,
        event_tolerance=opts.contact_event_tolerance, predictor=opts.contact_predictor,
        max_corrector_distance=CONTACT_CORRECTOR_DISTANCE, chord_steps=True)
    own = with_contact_records(records, cp, True)
    events = (contact_count_event(cp),)
    if old is not None and len(old):
        branch = resume_branch(cp, old, contact_opts, records=own, events=events,
                               on_point=on_point)
    else:
        # from the frames of the contact-free branch's point k (cp unchanged)
        branch = continuation(frames_at(cp, free, k), q, parameter="turns",
                              start=float(free.parameter_values[k]), options=contact_opts,
                              name=name, records=own, events=events, on_point=on_point)
    return classify_contact_events(branch, cp)

