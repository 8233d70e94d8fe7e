"""The ring diagram's branches with self-contact: their start, their runs, their pins.

A contact branch starts from the last point of a contact-free primary branch
that the contact terms do not reach yet
(:func:`~supercoil.problems.contact_events.contact_start`) and is
followed with self-contact in the direction that branch was going, within
``0 <= dLk <= max_excess_link`` (folds are passed, so a branch that turns is
followed back up or down). Steps are a fraction of ``D`` in the arclength
metric (the RMS node displacement, plus ``D`` times the change of ``dLk``: a
step of ``D/2`` changes ``dLk`` by at most 1/2), so that no strand can cross
another within a step; the corrector's steps are guarded by continuous
collision detection (``ContactProblem.step_bound``) as well.

Material sliding. Sliding the material along the centreline is an exact
symmetry of the continuous homogeneous ring, with or without contact, and is
removed from the unstable count (docs/model.md, "Stability"). A discrete
contact breaks it: a segment-segment contact force is normal to the two
segments, not to the tangents at their nodes, so it pushes the material along
the rod (with a force of order ``F h kappa (2 t - 1)``, ``t`` the contact's
position on its segment), a potential of period ``h`` that locks contacts to
the mesh. With the sliding free, the lowest eigenvalue of the constrained
Hessian on alpha after contact is negative (C/A = 2/3, L/D = 122, N = 100:
-0.003 just after the onset, -50 at ``dLk = 1.36``, M metric), and the
continuation cannot pass the onset, where the contact force, hence the sliding
stiffness, starts from zero. So contact branches are followed with the sliding
pinned (``ContinuationOptions.near_symmetry_gauge``, the default
``contact_gauge=True``; docs/continuation.md, "Closed rods: the sliding gauge
and the pins"): their states are equilibria of the discrete energy with the
material's position along the rod held, which is what the continuous rod's
symmetry allows. The force the pin holds is reported as ``sliding_residual``
(max ``|grad E + J^T mu|`` without the pin,
:func:`~supercoil.problems.ring_diagram.records.kkt_residual`). With the
pair sum on the polygon it does not clearly fall under mesh refinement once
the contact force is large; the default contact, the double integral on the
cubic spline (``contact_formulation="integral"``, docs/contact.md, "Contact
energy: pair sum or double integral"), keeps it below about 3e-3 on alpha up
to ``dLk`` 6 (N = 200), against up to 27 with the pair sum. On a state with a
two-fold axis that is a symmetry of the mesh (through a node or an edge
midpoint) the force vanishes: the sliding mode is odd under the axis and the
gradient even. The primary branches are switched off the circle with an axis
through node 0 (:func:`~supercoil.problems.ring_diagram.primary.on_mesh_direction`)
and followed with rigid pins that this axis maps onto themselves
(:func:`~supercoil.rod.closed.rigid_pins`), so they keep it to round-off and
their states are equilibria without the gauge (tests/test_ring_diagram.py);
states without such an axis (tertiary branches) still need it.

Rigid pins. The ring removes its rigid motions by fixing six DOFs
(``ClosedRodEnergy.fixed``, chosen on the circle). As alpha folds into a
plectoneme those pins lose their grip (``pin_quality``, the determinant of
their response to rotations against the best choice, fell to 0.1): the pinned
Hessian keeps a nearly null rotation whose eigenvalue the gauge's small force
pushes through zero, and the branch folded back and forth there (L/D = 122,
N = 200, from ``dLk`` 3.40). Contact branches therefore run in segments of
``CONTACT_SEGMENT_POINTS`` points (:mod:`supercoil.problems.segments`): the
pins are picked at the branch's start and re-picked at a segment boundary
where their quality fell below ``PIN_QUALITY``, and within a run a point where
their determinant fell below a quarter of its value at the run's start is
refused and the pins picked there (``segments.follow(grip=...)``: a fixed set
can pass through a shape where it removes no rotation); the pinned
coordinates keep their values there.
:attr:`~supercoil.problems.ring_diagram.RingDiagram.pins` records them
(:meth:`~supercoil.problems.ring_diagram.RingDiagram.pin_branch` sets them for
checking a point), a resumed branch replays them, and the ring's own pins are
restored afterwards.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Mapping

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions, continuation
from supercoil.continuation.resume import resume_branch
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.ring_branches import ring_records
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.records import contact_records
from supercoil.problems.segments import follow, grip_stop, set_pin

# Contact branches run in segments of this many points; between them the rigid pins are
# re-picked where their quality (ClosedRodEnergy.pin_quality) fell below PIN_QUALITY.
CONTACT_SEGMENT_POINTS = 40
PIN_QUALITY = 0.5

Pins = tuple[tuple[int, tuple[int, ...]], ...]


def contact_options(opts: DiagramOptions, diameter: float, direction: int
                    ) -> ContinuationOptions:
    """The continuation options of a contact branch going in ``direction`` (+1 / -1) from
    its start, tube ``diameter`` (a length)."""
    D = diameter
    return ContinuationOptions(
        initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
        max_step=opts.contact_max_step * D, max_points=opts.contact_max_points,
        parameter_bounds=(0.0, opts.max_excess_link), direction=direction,
        parameter_weight=D, tolerance=opts.contact_tolerance,
        near_symmetry_gauge=opts.contact_gauge, gauge=opts.gauge, regauge=True,
        rephase=opts.gauge == "integral", predictor=opts.contact_predictor,
        factor_refinement=True, event_tolerance=opts.contact_event_tolerance)


def contact_branch(cp: ContactProblem, free: Branch, k: int, options: ContinuationOptions,
                   name: str, stored: Mapping[str, tuple[Branch, bool]], on_point=None
                   ) -> tuple[Branch, Pins]:
    """The contact branch ``name`` from point ``k`` of ``free`` and its rigid pins: the
    stored one when complete (its pins replayed), else computed (an incomplete stored
    one continued) with its contact events classified."""
    old, complete = stored.get(name, (None, False))
    if complete:
        with pins_restored(cp):
            return old, tuple(replayed_pins(cp, old.states))
    branch, pins = _follow_contact(cp, free.states[k], float(free.parameter_values[k]), old,
                                   options, name, on_point)
    return classify_contact_events(branch, cp), pins


def sliding_note(contact: Branch, opts: DiagramOptions, name: str) -> str | None:
    """The note on the sliding force the gauge held along ``contact``, when it is above
    the corrector's own level."""
    sliding = contact.records.get("sliding_residual", np.zeros(0))
    # on a branch with a two-fold axis on the mesh the force vanishes by symmetry (module
    # doc, "Material sliding"): no note while it is at the corrector's own level (the
    # residual without the gauge measured 6e-9 to 1.5e-8 there, tolerance 1e-8)
    if not (len(contact) and opts.contact_gauge
            and np.max(sliding) > 10 * opts.contact_tolerance):
        return None
    return (f"{name}: the material sliding is held fixed (a gauge); the "
            f"sliding force it holds, max |KKT residual| without the gauge, is at "
            f"most {float(np.max(sliding)):.2e} (at dLk = "
            f"{float(contact.parameter_values[int(np.argmax(sliding))]):.4g}): "
            f"an artefact of the {opts.contact_curve} contact (see the docs of "
            "ring_diagram)")


@contextlib.contextmanager
def pins_restored(cp: ContactProblem):
    """Restore the ring's rigid pins (on the rod and its contact wrapper) on exit."""
    rod = cp.base
    saved = (rod.fixed, rod.gauge_dofs, cp.fixed)
    try:
        yield
    finally:
        rod.fixed, rod.gauge_dofs, cp.fixed = saved


def replayed_pins(cp: ContactProblem, states: np.ndarray
                  ) -> list[tuple[int, tuple[int, ...]]]:
    """The rigid pins of a contact branch computed by :func:`contact_branch` without
    interruption, from its states: picked at its first point, then re-picked at every
    run boundary (every ``CONTACT_SEGMENT_POINTS - 1`` points) where their quality had
    fallen below ``PIN_QUALITY``. Leaves ``cp`` pinned as at the last state."""
    rod = cp.base
    set_pin(cp, rod, states[0])
    pins = [(0, tuple(int(d) for d in rod.fixed))]
    for b in range(CONTACT_SEGMENT_POINTS - 1, len(states) - 1, CONTACT_SEGMENT_POINTS - 1):
        if rod.pin_quality(states[b]) < PIN_QUALITY:
            set_pin(cp, rod, states[b])
            pins.append((b, tuple(int(d) for d in rod.fixed)))
    return pins


def run_bounds(n_points: int) -> tuple[int, int]:
    """The first and last point indices of the run (of :func:`_follow_contact`'s runs of
    ``CONTACT_SEGMENT_POINTS``, each starting at the last point of the previous) that
    computed point ``n_points - 1`` of a contact branch (its start for the first point)."""
    step = CONTACT_SEGMENT_POINTS - 1
    j = max(n_points - 2, 0) // step
    return j * step, (j + 1) * step


def _follow_contact(cp: ContactProblem, q_start: np.ndarray, start: float, old: Branch | None,
                    options: ContinuationOptions, name: str, on_point=None
                    ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]]:
    """A contact branch from ``q_start`` at ``excess_link = start`` (or ``old``, an
    interrupted one, continued) in runs
    of ``CONTACT_SEGMENT_POINTS``, the rigid pins re-picked between runs (module doc,
    "Rigid pins"), and its pins (``RingDiagram.pins``); the ring's construction pins
    are restored afterwards."""
    rod = cp.base
    records = contact_records(cp, ring_records(cp.base), free=False)
    events = (contact_count_event(cp),)
    first_opts = dataclasses.replace(options, max_points=min(CONTACT_SEGMENT_POINTS,
                                                             options.max_points))
    with pins_restored(cp):
        if old is not None and len(old):
            # the pins the interrupted run had, and the rest of the run it was stopped
            # in: the runs' boundaries are the uninterrupted run's
            earlier = replayed_pins(cp, old.states)
            start, end = run_bounds(len(old))
            first = old if len(old) == end + 1 else resume_branch(
                cp, old, dataclasses.replace(options, max_points=min(end + 1,
                                                                     options.max_points)),
                on_point=on_point, records=records, events=events,
                stop=grip_stop(rod.pin_grip, old.states[start]))
        else:
            set_pin(cp, rod, q_start)
            earlier = [(0, tuple(int(d) for d in rod.fixed))]
            first = continuation(cp, q_start, parameter="excess_link", start=start,
                                 options=first_opts,
                                 name=name, records=records, events=events,
                                 on_point=on_point, stop=grip_stop(rod.pin_grip, q_start))
        branch, later = follow(cp, rod, first, options, name, records, events,
                               max_points=options.max_points,
                               segment_points=CONTACT_SEGMENT_POINTS, on_point=on_point,
                               quality=PIN_QUALITY, grip=rod.pin_grip)
    # follow reports the rod's gauge_dofs, which are all six pins for a ring
    return branch, tuple(earlier) + tuple((i, d) for i, d in later if i > 0)
