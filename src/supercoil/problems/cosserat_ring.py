"""The Cosserat ring's diagram: the circle, its Michell bifurcations and the primary branches.

The same continuation as the Kirchhoff ring's (:mod:`supercoil.problems.ring_branches`)
on the closed Cosserat rod at fixed excess link
(:class:`~supercoil.cosserat.ClosedCosseratEnergy`): the circle is followed in ``dLk``
from 0, its bifurcations located where the unstable count rises by two, and for each
requested mode the primary branch is switched off it along the critical mode and
followed without contact. A phantom ring that passes through itself changes its
linking number, which the Cosserat ring refuses (:class:`~supercoil.cosserat.LinkingError`),
so each primary branch watches the closest approach of non-neighbouring centreline
points against the tube diameter ``D`` (the event ``contact_onset``, as on the
Kirchhoff diagram) and stops at the first point past it. With ``contact`` the branch
goes on from there with self-contact (``alpha_contact``, parent ``alpha``,
:mod:`supercoil.problems.cosserat_ring_contact`), and the onset is measured on the
contact's own curve; without it ``D`` is the section's, ``L / slenderness``, and the
diagram ends at the first contacts.

Per point the records are the Kirchhoff ring's (``excess_link``, ``writhe``, ``twist``,
``energy``, ``link_error``, ``min_gap_over_diameter``, contact counts) plus
``max_stretch_strain`` and ``max_shear_strain``. The diagram
(:mod:`supercoil.problems.cosserat_ring_diagram`) returns and stores its branches with
the centrelines as states (``(k, 3 N)``), so the outputs and viewer take them as they
take the Kirchhoff ring's, and each point's frames beside them
(:mod:`supercoil.problems.cosserat_stored`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.contact.curve import ContactCurve
from supercoil.contact.options import ContactOptions
from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    SpecialPoint,
    UserEvent,
    continuation,
    switch_branch,
)
from supercoil.cosserat.circle import circle_state
from supercoil.cosserat.closed import ClosedCosseratEnergy
from supercoil.cosserat.ring import relax_circle, ring_problem
from supercoil.cosserat.rod import DOFS_PER_NODE
from supercoil.problems.circle_switch import (
    SWITCH_TRIAL_POINTS,
    leaves_circle,
    switch_attempts,
    switch_notes,
)
from supercoil.problems.contact_events import stop_after_onset

CIRCLE_MAX_STEP = 0.4  # largest step along the circle (dLk)
# corrector tolerance: the ring's residual stagnates near 1.5e-10 in the trial
# corrections that locate the circle's bifurcation (C/A = 0.8, N = 24, EA = GA = 1e3),
# above the continuation's default 1e-10
TOLERANCE = 1e-9
# Predictor of the primary branches. The shear and stretch strains are of second order
# in the rotation increments (a section turned by w ds moves its d3 by w ds and by
# |w ds|^2 / 2 along itself), so a straight step in (positions, rotation coordinates)
# leaves the nearly unshearable, inextensible states by a strain ~ |w ds|^2 / 2, a force
# ~ GA |w ds|^2 / 2: measured at N = 32, EA = GA = 1e5 A/L^2 on alpha, a residual of 0.65
# at ds = 1e-3 and 65 at ds = 1e-2 along the tangent. Newton's quadratic region shrinks
# as the soft modes' eigenvalue over GA, so the corrector took 4 to 10 iterations at
# ds = 2e-3 and the step control, which grows the step after at most 3, kept it there
# (80 points from dLk 2.62 to 2.32). The quadratic predictor carries that second-order
# term (the tangent's change between points): the same branch reached its contact at
# dLk 1.08 in 43 points at steps up to 0.08.
PREDICTOR = "quadratic"
# The corrector's first iteration takes out the predictor's remaining stiff residual
# (GA |w ds|^3), a step the Kirchhoff ring's constraints do not need: the step grows
# after at most one iteration more than the continuation's default (alpha at N = 200:
# 32 points instead of 44 to its contact, the same contact dLk to 1e-8).
FAST_ITERATIONS = 4


def positions_of(q: np.ndarray) -> np.ndarray:
    """The centreline ``(n, 3)`` of a Cosserat state ``q`` (positions are chart-free)."""
    return np.asarray(q, dtype=float).reshape(-1, DOFS_PER_NODE)[:, :3]


def gap_curve(n_nodes: int, diameter: float, options: ContactOptions | None = None
              ) -> ContactCurve:
    """The closed polygon's self-distance for a tube of ``diameter`` (units of L), or the
    self-distance of the contact curve of ``options`` (its diameter)."""
    a = np.arange(n_nodes)
    segments = np.stack([a, (a + 1) % n_nodes], axis=1)
    if options is None:
        options = ContactOptions(diameter=diameter, curve="polygon", formulation="pairs")
    return ContactCurve(segments, True, 1.0 / n_nodes, 1.0, options)


def cosserat_ring_records(ring: ClosedCosseratEnergy, curve: ContactCurve):
    """Per-point records of a Cosserat ring branch (module doc)."""

    def records(q, multipliers, excess_link, problem=None):
        # the ring at the point (the continuation's, with its chart), else this one there
        at = ring.at(excess_link=float(excess_link)) if problem is None else problem
        tw, wr = at.twist(q), at.writhe(q)
        x, R = at.configuration(q)
        d_min = curve.min_distance(x.ravel())
        return {"excess_link": float(excess_link), "writhe": wr, "twist": tw,
                "energy": at.rod.energy(x, R), "link_error": abs(tw + wr - excess_link),
                "max_stretch_strain": at.max_stretch_strain(q),
                "max_shear_strain": at.max_shear_strain(q),
                "n_contact_points": 0, "n_contact_intervals": 0,
                "min_gap_over_diameter": float(d_min / curve.diameter)}

    return records


def onset_event(curve: ContactCurve) -> UserEvent:
    """``d_min / D - 1`` of the centreline: the ``contact_onset`` event."""

    def gap(q, multipliers, excess_link):
        d_min = curve.min_distance(positions_of(q).ravel())
        return {"min_gap": float(min(d_min / curve.diameter - 1.0, 1e3))}

    return UserEvent("contact_onset", gap)


def relaxed_circle_state(problem: ClosedCosseratEnergy, excess_link: float,
                         constants: tuple[float, float, float]
                         ) -> tuple[ClosedCosseratEnergy, np.ndarray]:
    """``(problem with its chart re-based there, q)``: the discrete twisted circle at
    ``excess_link``; ``problem`` is unchanged."""
    ratio, stretch, shear = constants
    exact = circle_state(ratio, excess_link, stretch, shear)
    rod = problem.at(excess_link=float(excess_link)).rod  # its intrinsic twist at dLk
    x, R, _ = relax_circle(rod, problem.link, exact.tilt, exact.stretch)
    problem = problem.with_frames(problem.frames)  # a copy, whose chart state() re-bases
    q = problem.state(x, R)
    return problem.carried_to(q), q


def cosserat_circle_branch(twist_ratio: float, n_nodes: int, max_excess_link: float,
                           stretch_stiffness: float, shear_stiffness: float,
                           curve: ContactCurve, link: int = 0
                           ) -> tuple[Branch, ClosedCosseratEnergy]:
    """The circle from ``dLk = 0`` to ``max_excess_link`` (name ``circle``), its sections'
    ``d1`` turned ``link`` times (the rest of the excess link is carried by the intrinsic
    twist, :mod:`supercoil.cosserat.closed`).

    The discrete circle's thresholds depend on that split at O(h^2): measured at C/A = 0.8,
    EA = GA = 1e6 A/L^2, mode 2 (Michell 2.16506), link 0 gave 2.2157 (N = 24) and
    2.1774 (N = 48), link 2 gave 2.1796 and 2.1686: the error constant is least with
    ``link`` near the threshold's ``dLk``."""
    problem = ring_problem(twist_ratio, 0.0, n_nodes, stretch_stiffness, shear_stiffness,
                           link=int(link))
    problem, q = relaxed_circle_state(problem, 0.0,
                                      (twist_ratio, stretch_stiffness, shear_stiffness))
    # steps of 0.78 in dLk failed to locate the bifurcations (C/A = 0.8, N = 40, trial
    # corrections along the chord diverged); 0.4 located them to 1e-10
    step = min(CIRCLE_MAX_STEP, 0.1 * max_excess_link)
    opts = ContinuationOptions(initial_step=step / 2, max_step=step, tolerance=TOLERANCE,
                               parameter_bounds=(0.0, max_excess_link))
    branch = continuation(problem, q, parameter="excess_link", options=opts, name="circle",
                          records=cosserat_ring_records(problem, curve))
    return branch, problem


def _switch_attempt(problem: ClosedCosseratEnergy, circle: Branch, start: SpecialPoint,
                    options: ContinuationOptions, side_amplitude: tuple[int, float], name: str,
                    records, curve: ContactCurve, judge: bool, on_point=None) -> Branch:
    """One switching run to the first contact; with ``judge``, stopped at its
    :data:`SWITCH_TRIAL_POINTS`-th point unless it leaves the circle there."""
    side, amplitude = side_amplitude
    fell_back = []
    watched, at_onset = stop_after_onset(on_point)

    def on_point(branch: Branch) -> None:
        if judge and len(branch) == SWITCH_TRIAL_POINTS and not leaves_circle(branch):
            fell_back.append(True)
        watched(branch)

    def stop(q: np.ndarray) -> str | None:
        return "fell back onto the circle" if fell_back else at_onset(q)

    return switch_branch(problem, circle, start, options, side=side, amplitude=amplitude,
                         name=name, records=records, events=(onset_event(curve),),
                         on_point=on_point, stop=stop)


def switch_off_circle(problem: ClosedCosseratEnergy, circle: Branch, point: SpecialPoint,
                      constants, options: ContinuationOptions, name: str,
                      curve: ContactCurve, notes: list[str], on_point=None) -> Branch:
    """The primary branch from the circle's bifurcation ``point``, checked to leave the
    circle (its first :data:`SWITCH_TRIAL_POINTS` points must show the writhe growing;
    a run that does not is stopped there and the other side and larger amplitudes are
    tried). The point's state is re-based on the exact discrete circle at its ``dLk``
    first: a state stored along the circle describes it exactly only in the chart it
    was accepted in (:mod:`supercoil.cosserat.problem`). ``on_point`` sees every
    accepted point of the attempts (a later attempt's points replace an earlier one's)."""
    records = cosserat_ring_records(problem, curve)
    attempts = switch_attempts()
    for number, (amplitude, side) in enumerate(attempts):
        last = number == len(attempts) - 1
        based, q = relaxed_circle_state(problem, point.parameter, constants)
        start = dataclasses.replace(point, q=q, frames=based.frames)
        opts = dataclasses.replace(options, initial_step=amplitude)
        branch = _switch_attempt(problem, circle, start, opts, (side, amplitude), name,
                                 records, curve, judge=not last, on_point=on_point)
        leaves = leaves_circle(branch)
        if leaves or last:
            switch_notes(notes, name, number, amplitude, side, leaves)
            return branch
    raise AssertionError("unreachable")
