"""Contact events along a branch of a rod with self-contact (ring diagram, tweezers).

A contact-free branch watches the closest approach of non-neighbouring
centreline points, ``d_min / D - 1`` (:func:`onset_event`): its sign change,
located by Brent's method, is the special point ``contact_onset`` (label
``min_gap``); the branch is then cut after the first point beyond it
(:func:`truncate_after`), the run stopped there (:func:`stop_after_onset`), and
the branch goes on with self-contact from its last point that the contact
terms do not reach yet (:func:`contact_start`).

Contact events along a contact branch: the number of contact points and of
contact intervals (:func:`supercoil.contact.report.contact_summary`) are
integers, so a change between two branch points is a jump of the indicators
``n - k + 1/2`` (``k = 1 .. MAX_LEVEL``), one named scalar of a single
:class:`UserEvent` each; the jump is bracketed by Brent's method (bisection
safeguarded) on the branch between the two points, re-corrected at every
trial, to ``contact_event_tolerance`` in arclength. The kind is then read
from the counts at the two neighbouring points (both indicators of one
transition, e.g. a point opening into an interval, land on the same state
and are merged into one special point):

* the number of intervals rises: ``contact_interval_onset``;
* otherwise the number of contacts (points + intervals) rises: a
  ``contact_split`` when every contact after it lies within
  ``SPLIT_DISTANCE`` (in s/L, on both strands) of a contact before it (a
  point that became two nearby points), else a ``contact_onset``;
* otherwise (a count falls): ``contact_release``.

With the barrier treatment a contact carries a force once its gap is below
``barrier_activation * D`` (1 % of D), so the ``contact_onset`` of a contact
branch sits where the gap reaches that value, a little before the geometric
onset of the contact-free branch (``d_min = D``). The grouping into points
and intervals is done on the discrete rod (``contact_summary``): a contact
that slides along a segment can make a count flicker at coarse resolution.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import COUNT_KEYS, PLACE_KEYS, contact_summary
from supercoil.continuation import Branch, ContinuationStatus, SpecialPoint, UserEvent

MAX_LEVEL = 8  # contact-count indicators n - k + 1/2 for k = 1 .. MAX_LEVEL
SPLIT_DISTANCE = 0.1  # s/L, see the module docstring
CONTACT_KINDS = ("contact_onset", "contact_release", "contact_split", "contact_interval_onset")


def onset_event(problem: ContactProblem) -> UserEvent:
    """``d_min / D - 1`` (closest approach of non-neighbouring points): contact onset."""

    def gap(q, multipliers, excess_link):
        d_min = problem.min_distance(q)
        return {"min_gap": float(min(d_min / problem.diameter - 1.0, 1e3))}

    return UserEvent("contact_onset", gap)


def contact_count_event(problem: ContactProblem) -> UserEvent:
    """Indicators ``n - k + 1/2`` of the contact point and interval counts (module doc)."""

    def levels(q, multipliers, excess_link):
        summary = contact_summary(problem, q, multipliers, COUNT_KEYS)
        out = {}
        for k in range(1, MAX_LEVEL + 1):
            out[f"points>={k}"] = summary["n_contact_points"] - k + 0.5
            out[f"intervals>={k}"] = summary["n_contact_intervals"] - k + 0.5
        return out

    return UserEvent("contact_change", levels)


def _positions(problem: ContactProblem, q, multipliers) -> np.ndarray:
    """(k, 2) positions (s1, s2) of the contacts (interval midpoints) at a state."""
    summary = contact_summary(problem, q, multipliers, PLACE_KEYS)
    rows = [(p["s1"], p["s2"]) for p in summary["contact_points"]]
    for iv in summary["contact_intervals"]:
        rows.append((_mid(iv["s1_start"], iv["s1_end"]), _mid(iv["s2_start"], iv["s2_end"])))
    return np.array(rows, dtype=float).reshape(-1, 2)


def _mid(a: float, b: float) -> float:
    return (0.5 * (a + b + (1.0 if b < a else 0.0))) % 1.0


def _near(after: np.ndarray, before: np.ndarray, distance: float) -> bool:
    if len(before) == 0 or len(after) == 0:
        return False
    for a in after:
        d = np.abs(before - a)
        d = np.minimum(d, 1.0 - d)  # periodic in s/L
        d_swapped = np.abs(before[:, ::-1] - a)
        d_swapped = np.minimum(d_swapped, 1.0 - d_swapped)
        if min(np.max(d, axis=1).min(), np.max(d_swapped, axis=1).min()) > distance:
            return False
    return True


def classify_contact_events(branch: Branch, problem: ContactProblem) -> Branch:
    """The branch with its ``contact_change`` points given their kinds (module doc), merged."""
    out: list[SpecialPoint] = []
    if "n_contact_points" not in branch.records:  # no point computed (a failed start)
        return branch
    n_points = branch.records["n_contact_points"]
    n_intervals = branch.records["n_contact_intervals"]
    for p in branch.special_points:
        if p.kind != "contact_change":
            out.append(p)
            continue
        i = p.index
        previous = out[-1] if out else None
        if (previous is not None and previous.kind in CONTACT_KINDS and previous.index == i
                and abs(previous.arclength - p.arclength) <= 4 * p.tolerance + 1e-12):
            continue  # the other indicator of the same transition
        dp = int(n_points[i + 1] - n_points[i])
        di = int(n_intervals[i + 1] - n_intervals[i])
        total_before = int(n_points[i] + n_intervals[i])
        if di > 0:
            kind = "contact_interval_onset"
        elif dp + di > 0:
            before = _positions(problem, branch.states[i], branch.multipliers[i])
            after = _positions(problem, branch.states[i + 1], branch.multipliers[i + 1])
            split = total_before >= 1 and _near(after, before, SPLIT_DISTANCE)
            kind = "contact_split" if split else "contact_onset"
        else:
            kind = "contact_release"
        label = (f"{p.label}: points {int(n_points[i])}->{int(n_points[i + 1])}, intervals "
                 f"{int(n_intervals[i])}->{int(n_intervals[i + 1])}")
        out.append(dataclasses.replace(p, kind=kind, label=label))
    return dataclasses.replace(branch, special_points=tuple(_mark_contact_bifurcations(
        out, problem)))


def _mark_contact_bifurcations(points: list[SpecialPoint], problem: ContactProblem | None
                               ) -> list[SpecialPoint]:
    """Label bifurcation points that lie within the barrier's reach of a contact event.

    A change of the unstable count at a contact event is not, by itself, a
    bifurcation of the rod with hard contact. The barrier smooths the event over
    a layer of about ``barrier_activation * D``, where a count change is a
    bifurcation of the smoothed problem (a simple eigenvalue crossing zero
    without a fold always is), and it can be one of the rod too (B_1 of Coleman &
    Swigon 2002: beta's three contact points appear and the C_2 branches start).
    So the kind stays ``bifurcation`` and the label says ``at <contact event>``,
    for the reader to weigh; distance measured in arclength.
    """
    if problem is None or problem.treatment != "barrier":
        return points
    reach = problem.options.barrier_activation * problem.diameter
    contact = [p for p in points if p.kind in CONTACT_KINDS]
    out = []
    for p in points:
        near = [c for c in contact if abs(c.arclength - p.arclength) <= reach]
        if p.kind == "bifurcation" and near:
            nearest = min(near, key=lambda c: abs(c.arclength - p.arclength))
            p = dataclasses.replace(p, label=f"bifurcation at {nearest.kind} (within the "
                                    f"barrier's reach)")
        out.append(p)
    return out


def truncate_after(branch: Branch, point: SpecialPoint, message: str) -> Branch:
    """The branch up to ``point`` (a located contact onset): its points before it, then the
    located point itself as the last one, so that no state beyond the first contact (where
    the contact-free rod passes through itself) is kept; later special points dropped.
    Status ``STOPPED`` and ``message``: how the run went on past it (a failure there, e.g.
    Newton diverging where the rod passes through itself, does not make the branch
    incomplete; the message says it). The located point's stability counts other than
    its unstable count (zero modes, determinant sign, the eigenvalue nearest zero) are
    those of the point before it: an onset is not a change of the count."""
    k = point.index + 1
    keep = tuple(p for p in branch.special_points
                 if p.index < point.index or (p.index == point.index
                                              and p.arclength <= point.arclength))
    last = {"parameter_values": point.parameter, "states": point.q,
            "multipliers": point.multipliers, "tangents": point.tangent,
            "arclength": point.arclength,
            "unstable_count": (point.unstable_count if point.unstable_count >= 0
                               else branch.unstable_count[k - 1])}
    arrays = {}
    for name in ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                 "determinant_sign", "nearest_eigenvalue", "tangents", "arclength"):
        values = getattr(branch, name)
        arrays[name] = np.concatenate([values[:k], [last.get(name, values[k - 1])]])
    records = {}
    for name, values in branch.records.items():
        value = point.records.get(name, values[k - 1])
        records[name] = np.concatenate([values[:k], [np.asarray(value, values.dtype)]])
    return dataclasses.replace(branch, special_points=keep, records=records,
                               status=ContinuationStatus.STOPPED, message=message, **arrays)


def first_onset(branch: Branch) -> SpecialPoint | None:
    """The first ``contact_onset`` of a contact-free ``branch`` with a point computed
    beyond it (where the branch is cut and the contact branch starts), or None."""
    onsets = [p for p in branch.points_of_kind("contact_onset") if p.index + 1 < len(branch)]
    return onsets[0] if onsets else None


def cut_at_onset(branch: Branch, onset: SpecialPoint, where: str) -> Branch:
    """:func:`truncate_after` the first contact ``onset``, ``where`` (e.g. ``"dLk = 1.2"``)
    in the message beside how the contact-free run went on."""
    return truncate_after(branch, onset, f"stopped at the first contact ({where}); the "
                          f"contact-free run: {branch.message}")


def contact_start(free: Branch, onset: SpecialPoint, cp: ContactProblem) -> int:
    """The index of the point of the contact-free branch ``free`` a contact branch starts
    from: the last one up to ``onset`` that the contact terms do not yet act on.

    Its closest approach is above the treatment's reach (e.g. the barrier's 1 % of D),
    so it is an equilibrium of the contact problem too and the continuation's start
    correction has nothing to do. Points inside the reach are off that problem's
    equilibria (the branch turns sharply there) and the start correction diverged
    from them."""
    reach = 1.0 + (cp.options.barrier_activation if cp.treatment == "barrier" else 0.0)
    gaps = free.records["min_gap_over_diameter"]
    k = onset.index
    while k > 0 and gaps[k] <= reach:
        k -= 1
    return k


def stop_after_onset(on_point: Callable[[Branch], None] | None = None
                     ) -> tuple[Callable[[Branch], None], Callable[[np.ndarray], str | None]]:
    """``(on_point, stop)`` for a contact-free run: the first passes each partial branch
    on to ``on_point`` and notes a located ``contact_onset``; from then on the second
    refuses the next state (the run ends ``STOPPED`` at the point past the onset)."""
    located = []

    def watched(branch: Branch) -> None:
        if branch.points_of_kind("contact_onset"):
            located.append(True)
        if on_point is not None:
            on_point(branch)

    return watched, lambda q: "the contact onset is located" if located else None
