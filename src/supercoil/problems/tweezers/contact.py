"""The tweezers' branch with self-contact: the plectoneme's growth up to the last turn.

From the last point of the contact-free branch that the barrier does not
reach yet (:func:`~supercoil.problems.contact_events.contact_start`), the
branch is followed with self-contact (barrier treatment) in turns, in runs
between which the azimuth pin is picked again where needed
(:mod:`supercoil.problems.tweezers.pins`), its contact events classified
(:mod:`supercoil.problems.contact_events`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, continuation
from supercoil.continuation.carry import frames_at
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import (
    classify_contact_events,
    contact_count_event,
    contact_start,
)
from supercoil.problems.segments import either, follow, set_pin
from supercoil.problems.tweezers.buckled import (
    RunRecords,
    resume_stored,
    resumed_pins,
    stored_pins,
)
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.pins import PIN_QUALITY, SLIDING_HYSTERESIS
from supercoil.problems.tweezers.problem import tweezers_records
from supercoil.rod.mirror import mirror_asymmetry
from supercoil.rod.open import ClampedRodEnergy
from supercoil.rod.sliding import sliding_threshold

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
# eigenvalue is the contact's ripple, of either sign. Measured at L/D = 40, F L^2/A = 320
# (C/A = 1.5): the lowest eigenvalue is the sliding (overlap 0.8-0.9 with it) up to a tail
# ratio of 0.2, -1700 to -140 at N = 123 where N = 82's lowest is +340 (overlap 0.3);
# from 0.25 the lowest is another mode, the same at both meshes (248 and 257, 228 and
# 228): with 0.1 N = 123 counted one from 4.8 to 5.4 turns and N = 82 zero
SLIDING_TAIL_CONTACT = 0.25
# of D: the largest distance of a node from its mirror image (supercoil.rod.mirror) on a
# symmetric state: a contact branch held on its symmetry starts from one (the centred loop
# at its contact: 1e-10 to 4e-7 D at L/D = 200 and 500, lambda = 10 and 20; a loop slid
# off by round-off: a large part of its size). Its corrector projects every iterate onto
# the symmetric states (ClampedRodEnergy.held_part: 1e-17 D), and a run refuses a state
# beyond this, which only a failed projection (a straight rod, no axis) would leave
MIRROR_TOLERANCE = 1e-3


class ContactSliding:
    """The sliding's phase row on the contact branch's runs (``TweezersOptions.loop_sliding``).

    Where no contact acts yet (before the barrier reaches, or after a release) the
    structure's sliding is the free one of the contact-free branch, nearly null, and a
    run carries its phase row as that branch's do (integral, rephased at the step's
    midpoint, anchored towards the centred structure); where a contact acts it carries
    none (docs/continuation.md, "Long open rods"). :meth:`options` gives a run's options
    from its first state (the row beyond ``ENGAGE`` barrier layers of the contact),
    :meth:`stop` the ``stop`` that ends it where the state needs the other: a run with
    the row after its first point where the barrier acts (the next run starts there,
    the sliding stiffened by the contact), or before one whose tails stop being
    straight (by ``SLIDING_HYSTERESIS``); a run
    without it where the gap opened ``RELEASE`` layers beyond its start (and beyond the
    contact) while the tails are straight. Without the row the contact-free start of the contact
    branch crawled (L/D = 200, lambda = 40, N = 202: 42 points from a gap of 1.12 D to
    1.09 D in steps of 1e-8 D, the corrector moving along the sliding by the residual
    over its eigenvalue, then "the tangent turned" at the minimum step).

    ``hold``: the branch held on its half-turn symmetry
    (:mod:`supercoil.problems.tweezers.mirrored`, its states projected onto the
    symmetric ones): the row in contact too, while the sliding is left out of the count
    (tail ratio below ``SLIDING_TAIL_CONTACT``), a run with it refusing a state off the
    symmetry by more than ``MIRROR_TOLERANCE`` D."""

    ENGAGE = 2.0  # barrier layers (barrier_activation * D): start a run with the row beyond
    RELEASE = 3.0  # ... end a run without the row beyond this many, and as many past its start

    def __init__(self, rod: ClampedRodEnergy, cp: ContactProblem, base: ContinuationOptions,
                 enabled: bool, hold: bool = False):
        self.rod, self.cp, self.base, self.enabled = rod, cp, base, enabled
        self.hold = enabled and hold
        self.layer = (cp.options.barrier_activation if cp.treatment == "barrier" else 0.0)
        self.threshold = sliding_threshold(rod.rod.n_nodes)
        self.row = False

    def gap(self, q: np.ndarray) -> float:
        return self.cp.min_distance(q) / self.cp.diameter - 1.0

    def options(self, q: np.ndarray) -> ContinuationOptions:
        if self.hold:  # in contact too, while the sliding is left out of the count
            self.row = self.rod.sliding(q)[1] <= SLIDING_TAIL_CONTACT / SLIDING_HYSTERESIS
        else:
            self.row = (self.enabled and self.gap(q) > self.ENGAGE * self.layer
                        and self.rod.sliding(q)[1] <= self.threshold)
        return dataclasses.replace(self.base, near_symmetry_gauge=self.row, gauge="integral",
                                   rephase=self.row, midpoint_phase=self.row)

    def stop(self, q_start: np.ndarray) -> Callable[[np.ndarray], str | None] | None:
        if not self.enabled:
            return None
        if self.hold:
            return self._held_stop()
        if self.row:
            touched = []

            def refuse(q: np.ndarray) -> str | None:
                if touched:
                    return "the contact acts: the sliding's phase row is dropped"
                if self.gap(q) <= self.layer:
                    touched.append(True)  # kept: the next run starts in contact
                    return None
                if self.rod.sliding(q)[1] > self.threshold * SLIDING_HYSTERESIS:
                    return "the sliding of the structure stopped being an approximate symmetry"
                return None
            return refuse
        opened = max(self.gap(q_start), 0.0) + self.RELEASE * self.layer

        def refuse(q: np.ndarray) -> str | None:
            if (self.gap(q) > opened
                    and self.rod.sliding(q)[1] <= self.threshold / SLIDING_HYSTERESIS):
                return "no contact acts and the sliding is an approximate symmetry"
            return None
        return refuse

    def _held_stop(self) -> Callable[[np.ndarray], str | None]:
        tail = SLIDING_TAIL_CONTACT
        if self.row:
            def refuse(q: np.ndarray) -> str | None:
                if self.rod.sliding(q)[1] > tail:
                    return "the sliding of the structure stopped being left out of the count"
                asymmetry = mirror_asymmetry(q) / self.cp.diameter
                if asymmetry > MIRROR_TOLERANCE:
                    return (f"the state lost its half-turn symmetry (by {asymmetry:.3g} D): "
                            f"not on the symmetric branch")
                return None
            return refuse
        return lambda q: ("the sliding of the structure is left out of the count again"
                          if self.rod.sliding(q)[1] <= tail / SLIDING_HYSTERESIS**2 else None)


def contact_options(opts: TweezersOptions, direction: int = 1) -> ContinuationOptions:
    """The continuation options of a contact branch's runs (no phase row)."""
    D = opts.diameter
    return ContinuationOptions(
        initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
        max_step=opts.contact_max_step * D,
        max_points=min(opts.segment_points, opts.max_points),
        parameter_bounds=opts.turns, direction=direction,
        parameter_weight=D, tolerance=opts.contact_tolerance,
        event_tolerance=opts.contact_event_tolerance,
        predictor=opts.contact_predictor, max_corrector_distance=CONTACT_CORRECTOR_DISTANCE,
        chord_steps=True, near_symmetry_gauge=False)


def contact_branch(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
                   free: Branch, onset: SpecialPoint, name: str,
                   stored: Mapping[str, tuple[Branch, bool]], on_point=None, pinned=None,
                   say: Callable[[str], None] = lambda message: None, hold: bool = False
                   ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]]:
    """The contact branch ``name`` from the contact-free branch ``free`` past its
    ``onset`` and its azimuth pins: the stored one when complete, else computed (an
    incomplete stored one continued) with its contact events classified. ``pinned``:
    the runs' ``stop`` on the pin's quality (:func:`~supercoil.problems.tweezers.pins.pin_stop`).
    ``hold`` (where ``loop_sliding`` applies, ``loop_slides``): the states are held on the
    half-turn symmetry (``ClampedRodEnergy.mirror_hold``) and the sliding's phase row is
    carried in contact too, anchored at the state's symmetric part
    (:mod:`supercoil.problems.tweezers.mirrored`)."""
    # in contact the discrete contact makes the sliding of the plectoneme stiff, of
    # either sign: no phase row, but out of the count while the tails are straight
    # (docs/continuation.md, "Long open rods: the sliding of a localised structure"),
    # with or without loop_sliding (which decides the contact-free runs' phase rows)
    rod.sliding_tail = SLIDING_TAIL_CONTACT
    k = contact_start(free, onset, cp)
    q = free.states[k]
    set_pin(cp, rod, q)
    contact_opts = contact_options(opts, 1 if free.tangents[k, -1] >= 0 else -1)
    sliding = ContactSliding(rod, cp, contact_opts, opts.loop_slides_in_contact, hold)
    records = RunRecords(tweezers_records(cp, rod, True))
    events = (contact_count_event(cp),)
    old, complete = stored.get(name, (None, False))
    if complete:
        return old, stored_pins(old)
    rod.mirror_hold = sliding.hold
    try:
        contact, pins = _computed(opts, rod, cp, free, k, name, stored, on_point, pinned, say,
                                  contact_opts, sliding, records, events)
    finally:
        rod.mirror_hold = False
    return contact, pins


def _computed(opts, rod, cp, free, k, name, stored, on_point, pinned, say, contact_opts,
              sliding, records, events):
    """:func:`contact_branch`'s computation from the contact-free branch's point ``k``
    (or an incomplete stored branch continued), with the runs' phase rows of ``sliding``."""
    q = free.states[k]
    old = stored.get(name, (None, False))[0]
    first = resume_stored(stored, rod, cp, name, contact_opts, records, events, on_point,
                          pinned, sliding=False, max_points=opts.max_points)
    if first is not None:
        say(f"{name}: continued from point {len(old) - 1}")
    else:
        # from the frames of the contact-free branch's point k (cp unchanged)
        first = continuation(frames_at(cp, free, k), q, parameter="turns",
                             start=float(free.parameter_values[k]),
                             options=sliding.options(q), name=name,
                             records=records, events=events, on_point=on_point,
                             stop=either(pinned, sliding.stop(q)))
    contact, pins = follow(cp, rod, first, contact_opts, name, records, events,
                           max_points=opts.max_points, segment_points=opts.segment_points,
                           on_point=on_point, quality=PIN_QUALITY, refuse=pinned,
                           on_run=records.begin, run_options=sliding.options,
                           restart=sliding.stop)
    if old is not None and len(old) >= 2:  # resumed: the pins of the stored points
        pins = resumed_pins(old, pins)
    return classify_contact_events(contact, cp), pins
