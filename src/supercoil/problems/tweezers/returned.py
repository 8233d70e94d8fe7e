"""A contact branch that comes back onto the contact-free branch it started from.

From a centred localised loop the contact branch can release all its contacts and
follow the contact-free family back towards the straight rod (where the azimuth pin
can no longer be picked, and the run stops). With the contact-free branch it makes a closed curve of
equilibria, but the tracer's test (:mod:`supercoil.continuation.closure`) does not see
it, since the points it comes back to belong to another branch.
:func:`close_on_return` ends such a branch where it has come back, reported as closed
(``ContinuationStatus.CLOSED_LOOP``), so that the plectoneme is sought by a switch at
one of its bifurcations (:mod:`supercoil.problems.tweezers.plectoneme`).

Come back means: a contact acted at an earlier point, none acts at this one (its closest
approach beyond the contact's reach), and its state lies within ``RETURN_TOLERANCE`` D
(the largest distance of a node) of the contact-free branch at the same turns, read on
a chord of that branch whose end points bracket the turns (linear in turns), after
the rotation about the axis that brings it closest (an exact symmetry: the azimuth
pins of the two branches differ). Such a point is an equilibrium of the contact-free
rod (no contact term acts on it), and near the contact-free branch at the same turns
it lies on that branch. The tolerance is above the chord's interpolation error and
below the distance of another equilibrium at the same turns: measured at L/D = 100,
lambda = 40, N = 102, a point of the contact-free branch read on the chord across its
two neighbours lies within 0.036 D of it (median 0.0015 D; the chord to the next point
halves the distance, so errs about four times less), and the contact branch's points
with no contact point (5.09 to 5.11 turns, a loop elsewhere, within the barrier's
reach) lie 11 D away.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation import Branch, ContinuationStatus
from supercoil.continuation.resume import head

RETURN_TOLERANCE = 0.1  # of D: the largest node distance to the other branch at the same turns


def axis_distance(q: np.ndarray, p: np.ndarray) -> float:
    """The largest node distance between the centrelines ``q`` and ``p`` (flat, x y z per
    node) after ``q`` is turned about the z axis to the angle that minimises the sum of
    the squared distances."""
    a = np.asarray(q, dtype=float).reshape(-1, 3)
    b = np.asarray(p, dtype=float).reshape(-1, 3)
    angle = np.arctan2(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]),
                       np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]))
    c, s = np.cos(angle), np.sin(angle)
    turned = np.column_stack([c * a[:, 0] - s * a[:, 1], s * a[:, 0] + c * a[:, 1], a[:, 2]])
    return float(np.max(np.linalg.norm(turned - b, axis=1)))


def distance_at_turns(q: np.ndarray, turns: float, other: Branch) -> float:
    """The smallest :func:`axis_distance` from ``q`` to the states of ``other`` read at
    ``turns`` on its chords whose end points bracket them (linear in turns); inf when
    none does."""
    t = np.asarray(other.parameter_values, dtype=float)
    best = float("inf")
    for i in np.flatnonzero((np.minimum(t[:-1], t[1:]) <= turns)
                            & (turns <= np.maximum(t[:-1], t[1:]))):
        span = t[i + 1] - t[i]
        u = 0.0 if span == 0.0 else (turns - t[i]) / span
        p = other.states[i] + u * (other.states[i + 1] - other.states[i])
        best = min(best, axis_distance(q, p))
    return best


def returned_onto(branch: Branch, other: Branch, diameter: float, reach: float = 1.0,
                  tolerance: float = RETURN_TOLERANCE) -> int | None:
    """The first point of the contact branch ``branch`` that has come back onto the
    contact-free branch ``other`` (module doc), or None. ``reach``: the closest approach,
    in D, below which a contact acts (1 plus the barrier's layer)."""
    contacts = np.asarray(branch.records["n_contact_points"])
    gaps = np.asarray(branch.records["min_gap_over_diameter"], dtype=float)
    touched = False
    for j in range(len(branch)):
        if contacts[j] > 0 or gaps[j] <= reach:
            touched = touched or contacts[j] > 0
            continue
        if touched and distance_at_turns(branch.states[j], float(branch.parameter_values[j]),
                                         other) <= tolerance * diameter:
            return j
    return None


def close_on_return(branch: Branch, other: Branch, diameter: float, reach: float = 1.0
                    ) -> Branch:
    """``branch`` up to the point where it came back onto ``other`` (:func:`returned_onto`),
    status ``CLOSED_LOOP``; ``branch`` itself when it did not."""
    j = returned_onto(branch, other, diameter, reach)
    if j is None:
        return branch
    turns = float(branch.parameter_values[j])
    message = (f"the branch closed on the contact-free branch {other.name}: after "
               f"{len(branch)} points, its point {j} (turns = {turns:.6g}) has released "
               f"every contact and lies within {RETURN_TOLERANCE:g} D of {other.name} at "
               f"the same turns (it went on: {branch.message})")
    return dataclasses.replace(head(branch, j + 1), status=ContinuationStatus.CLOSED_LOOP,
                               message=message)
