"""A knotted ring followed in its excess link with self-contact.

A knotted ring has no trivial branch: :func:`knotted_branch` relaxes the knot
(:func:`~supercoil.problems.knot_ring.knot_start`, then
:func:`~supercoil.problems.ring_contact.solve_supercoiled_ring`) at the first
excess link and follows that equilibrium in ``dLk`` by pseudo-arclength
continuation with self-contact, as the ring diagram's contact branches are
followed (:mod:`supercoil.problems.ring_diagram.contact_branches`: the
material sliding pinned, the rigid pins re-picked between runs, steps a
fraction of D). Every corrected state is vetted by
:meth:`~supercoil.contact.problem.ContactProblem.admissible` (linking number,
knot type, and a radius of curvature of at least D/2) and a step that would
break one is refused and retried shorter. Per point the records add ``knot_determinant`` and
``knot_alexander_degree`` (of the state's own knot type, computed anew: they
stay the start's exactly when the guard did its work) to the ring's
(``excess_link``, ``writhe`` from the double sum, ``twist`` from the material
frames, ``link_error``, ``energy``) and the contact counts, and ``run_start``
(the first point of the run that computed the point, for resuming it).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationOptions
from supercoil.continuation.resume import resume_branch
from supercoil.continuation.singular_start import start_branch
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.knot_ring import knot_start, parse_knot
from supercoil.problems.ring_branches import ring_records
from supercoil.problems.ring_contact import solve_supercoiled_ring
from supercoil.problems.ring_diagram.records import contact_records
from supercoil.problems.segments import RunRecords, follow, grip_stop, replay_pins, set_pin
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.topology.knots import identify

SEGMENT_POINTS = 40  # points per run, the rigid pins re-picked between runs
MAX_STEP = 0.5  # of D, in the arclength metric (see contact_branches)


@dataclasses.dataclass(frozen=True)
class KnottedBranch:
    """The branch (``Branch``), the knot it keeps (a ``KnotType``), and its problem."""

    branch: Branch
    knot: object
    problem: ContactProblem
    start_message: str


def _knot_records(base_records):
    def records(q, multipliers, excess_link, problem=None):
        out = dict(base_records(q, multipliers, excess_link, problem=problem))
        knot = identify(np.asarray(q, float).reshape(-1, 3))
        out.update(knot_determinant=knot.determinant,
                   knot_alexander_degree=len(knot.alexander) - 1)
        return out
    return records


def knotted_branch(knot, twist_ratio: float, length_over_diameter: float,
                   excess_link: tuple[float, float], n_nodes: int = 100,
                   max_points: int = 100, tolerance: float = 1e-8) -> KnottedBranch:
    """The knotted ring's branch from ``excess_link[0]`` towards ``excess_link[1]``
    (module doc)."""
    start, stop = (float(v) for v in excess_link)
    cp, q0, reference, message = relaxed_knot(knot, twist_ratio, length_over_diameter,
                                              start, n_nodes, tolerance)
    branch = follow_knot(cp, q0, start, stop, max_points, tolerance, "knot")
    return KnottedBranch(branch, reference, cp, message)


def relaxed_knot(knot, twist_ratio: float, length_over_diameter: float, excess_link: float,
                 n_nodes: int, tolerance: float = 1e-8):
    """``(problem, q, knot type, message)``: the knot relaxed with self-contact (barrier)
    at ``excess_link``, and the contact problem that keeps its knot type."""
    parse_knot(knot)
    points, _note = knot_start(knot, n_nodes, length_over_diameter, twist_ratio)
    relaxed = solve_supercoiled_ring(twist_ratio, excess_link, length_over_diameter, n_nodes,
                                     treatment="barrier", tolerance=tolerance,
                                     initial_points=points)
    rod = Rod(n_nodes=n_nodes, twist_stiffness=twist_ratio)
    base = ClosedRodEnergy(rod, relaxed.points, excess_link)
    D = rod.length / length_over_diameter
    cp = ContactProblem(base, ContactOptions(diameter=D, treatment="barrier"))
    cp.curvature_limit = 0.5 * D  # a radius of curvature of at least D/2 at every step
    # the relaxation guards the built knot's invariants, so its name carries over
    reference = cp.keep_knot_type(relaxed.points, known=identify(points))
    q0 = relaxed.points.ravel()
    cp.accept(q0)
    return cp, q0, reference, relaxed.message


def follow_knot(cp: ContactProblem, q0: np.ndarray, start: float, stop: float,
                max_points: int, tolerance: float = 1e-8, name: str = "knot",
                on_point=None, old: Branch | None = None, first=None,
                bounds: tuple[float, float] | None = None,
                notes: list | None = None,
                singular_bounds: tuple[float, float] | None = None) -> Branch | None:
    """The branch of ``cp`` (a knotted ring's contact problem) from its equilibrium ``q0``
    at ``dLk = start`` towards ``stop``, in runs with the rigid pins re-picked (module
    doc); its contact events classified. ``on_point(branch)`` after every point.

    ``old``: the same branch stored partially by an interrupted run (its records with
    ``run_start``): continued from its last point with the pins and the run the
    interrupted computation had there, so that it ends as the uninterrupted run does.

    ``first(options, records, events, on_point, stop)``: the first run, instead of the
    continuation from ``q0`` (a switch from the bifurcation point ``q0``, whose pins the
    first run has); None from it (no point found) is returned as None. ``bounds``: the
    ``dLk`` range of the branch (default from ``start`` to ``stop``).

    A start at a singular point (a fold or a bifurcation point of the branch, where the
    plain start fails) is made off it along its critical mode
    (:func:`~supercoil.continuation.singular_start.start_branch`: at a fold on the side
    of its critical mode given by the sign of ``stop - start``, within
    ``singular_bounds``, default ``bounds``), and ``notes`` (a list) gets a note saying
    so."""
    base = cp.base
    D = cp.diameter
    cp.accept(q0)
    options = ContinuationOptions(
        initial_step=0.05 * D, min_step=CONTACT_MIN_STEP, max_step=MAX_STEP * D,
        max_points=max_points,
        parameter_bounds=bounds or (min(start, stop), max(start, stop)),
        direction=1 if stop >= start else -1, parameter_weight=D, tolerance=tolerance,
        near_symmetry_gauge=True, regauge=True, factor_refinement=True)
    records = RunRecords(_knot_records(contact_records(cp, ring_records(base), free=False)))
    events = (contact_count_event(cp),)
    low, high = options.parameter_bounds
    if old is not None and len(old) and "run_start" in old.records:
        lam = np.asarray(old.parameter_values, float)
        if singular_bounds is not None and np.any((lam < low) | (lam > high)):
            # a branch started off a singular point, within singular_bounds
            options = dataclasses.replace(options, parameter_bounds=singular_bounds)
        run = replay_pins(cp, base, old, q0, SEGMENT_POINTS, max_points)
        records.begin(run)
        first = resume_branch(
            cp, old, dataclasses.replace(options, max_points=min(run + SEGMENT_POINTS,
                                                                 max_points)),
            records=records, events=events, on_point=on_point,
            stop=grip_stop(base.pin_grip, q0 if run == 0 else old.states[run]))
    else:
        set_pin(cp, base, q0)
        run_options = dataclasses.replace(options, max_points=min(SEGMENT_POINTS, max_points))
        if first is None:
            first, note = start_branch(cp, q0, parameter="excess_link", start=start,
                                       options=run_options, name=name, records=records,
                                       events=events, on_point=on_point,
                                       stop=grip_stop(base.pin_grip, q0),
                                       bounds=singular_bounds)
            if note is not None:
                if notes is not None:
                    notes.append(f"{name}: {note}")
                if singular_bounds is not None:
                    options = dataclasses.replace(options, parameter_bounds=singular_bounds)
        else:
            first = first(run_options, records, events, on_point,
                          grip_stop(base.pin_grip, q0))
            if first is None:
                return None
    branch, _pins = follow(cp, base, first, options, name, records, events,
                           max_points=max_points, segment_points=SEGMENT_POINTS,
                           grip=base.pin_grip, on_point=on_point, on_run=records.begin)
    return classify_contact_events(branch, cp)
