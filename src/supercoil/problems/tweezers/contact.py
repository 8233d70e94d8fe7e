"""The tweezers' branch with self-contact: the plectoneme's growth up to the last turn.

From the last point of the contact-free branch that the barrier does not
reach yet (:func:`~supercoil.problems.contact_events.contact_start`), the
branch is followed with self-contact (barrier treatment) in turns, in runs
between which the azimuth pin is picked again where needed
(:mod:`supercoil.problems.tweezers.pins`), its contact events classified
(:mod:`supercoil.problems.contact_events`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, continuation
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import (
    classify_contact_events,
    contact_count_event,
    contact_start,
)
from supercoil.problems.segments import follow, set_pin
from supercoil.problems.tweezers.buckled import (
    RunRecords,
    resume_stored,
    resumed_pins,
    stored_pins,
)
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.pins import PIN_QUALITY
from supercoil.problems.tweezers.problem import tweezers_records
from supercoil.rod.open import ClampedRodEnergy

# The contact branch's corrector trust region, in steps (ContinuationOptions.
# max_corrector_distance): where the branch turns back at the contact onset (80 degrees
# within 3e-5 of arclength at N = 100, L/D = 33, F L^2/A = 75) steps that cross the
# corner converged 2-5 steps away from the predictor in 5-9 Newton iterations, then were
# refused by the turn test; stopped at the first iterate beyond one step, the same points
# came with 461 corrector iterations instead of 501 (benchmarks/bench_tweezers_steps.py
# --problems 75,33, then with --set '{"max_corrector_distance": null}').
CONTACT_CORRECTOR_DISTANCE = 1.0
# the tail ratio (ClampedRodEnergy.sliding) below which the sliding of the plectoneme is
# left out of the count on the contact branch: the continuum's symmetry, whose discrete
# eigenvalue is the contact's ripple, of either sign
SLIDING_TAIL_CONTACT = 0.1


def contact_branch(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
                   free: Branch, onset: SpecialPoint, name: str,
                   stored: Mapping[str, tuple[Branch, bool]], on_point=None, pinned=None,
                   say: Callable[[str], None] = lambda message: None
                   ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]]:
    """The contact branch ``name`` from the contact-free branch ``free`` past its
    ``onset`` and its azimuth pins: the stored one when complete, else computed (an
    incomplete stored one continued) with its contact events classified. ``pinned``:
    the runs' ``stop`` on the pin's quality (:func:`~supercoil.problems.tweezers.pins.pin_stop`)."""
    D = opts.diameter
    # in contact the discrete contact makes the sliding of the plectoneme stiff, of
    # either sign: no phase row, but out of the count while the tails are straight
    # (docs/continuation.md, "Long open rods: the sliding of a localised structure")
    if opts.loop_slides:
        rod.sliding_tail = SLIDING_TAIL_CONTACT
    k = contact_start(free, onset, cp)
    q = free.states[k]
    cp.turns = float(free.parameter_values[k])
    cp.accept(q)
    set_pin(cp, rod, q)
    contact_opts = ContinuationOptions(
        initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
        max_step=opts.contact_max_step * D,
        max_points=min(opts.segment_points, opts.max_points),
        parameter_bounds=opts.turns, direction=1 if free.tangents[k, -1] >= 0 else -1,
        parameter_weight=D, tolerance=opts.contact_tolerance,
        event_tolerance=opts.contact_event_tolerance,
        predictor=opts.contact_predictor, max_corrector_distance=CONTACT_CORRECTOR_DISTANCE,
        chord_steps=True, near_symmetry_gauge=False)
    records = RunRecords(tweezers_records(cp, rod, True))
    events = (contact_count_event(cp),)
    old, complete = stored.get(name, (None, False))
    if complete:
        return old, stored_pins(old)
    first = resume_stored(stored, rod, cp, name, contact_opts, records, events, on_point,
                          pinned, sliding=False, max_points=opts.max_points)
    if first is not None:
        say(f"{name}: continued from point {len(old) - 1}")
    else:
        first = continuation(cp, q, parameter="turns", options=contact_opts, name=name,
                             records=records, events=events, on_point=on_point,
                             stop=pinned)
    contact, pins = follow(cp, rod, first, contact_opts, name, records, events,
                           max_points=opts.max_points, segment_points=opts.segment_points,
                           on_point=on_point, quality=PIN_QUALITY, refuse=pinned,
                           on_run=records.begin)
    if old is not None and len(old) >= 2:  # resumed: the pins of the stored points
        pins = resumed_pins(old, pins)
    return classify_contact_events(contact, cp), pins
