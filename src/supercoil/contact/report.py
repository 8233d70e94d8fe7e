"""Contact output of a state: touching pairs, contact points and contact intervals.

Conventions (docs/model.md, "Contacts in the output"): arc-length
positions are fractions of L, forces are F·L²/A. ``contacts`` lists every
touching segment pair as ``{s1, s2, force}`` with ``s1 < s2``; pairs whose
closest points coincide (both segments of a joint touching at the same node)
are merged and their forces added.

A force below ``-force_tolerance * max(1, largest |force|)`` (only the exact
treatment's multipliers can pull) is counted in ``negative_contact_forces``
and kept in the lists.

Grouping into points and intervals uses the contacts that carry at least
``GROUPING_FLOOR`` (1 %) of the largest contact force: a barrier (or penalty)
pair at the edge of its activation carries a vanishing force and would
otherwise bridge separate contacts, so that the grouping would depend on the
treatment. Two such contacts are linked when they lie within 1.5 segment
lengths of each other on both strands (they touch along neighbouring
segments). A contact is an unordered pair of positions, so each is linked in
both orientations (across the seam s = 0 of a closed rod the order of its two
positions flips); chains are the connected groups, read in one orientation.
A chain that extends over more than two segment lengths on either strand is a
contact interval (a line contact, the "contact line" of Coleman & Swigon 2002):
``{s1_start, s1_end, s2_start, s2_end, force_per_length}`` (strand 1 is the
one that starts first; on a closed rod an interval across the seam has
``start > end``) with the force per length =
total force / (extent + one segment length), the length the chain's contacts
stand for. Any other chain is an isolated contact point ``{s1, s2, force}`` at
the force-weighted mean position with the total force (a point contact is
spread over one or two segment pairs by the discretisation). This is the data
of Figure 4 of Coleman & Swigon 2002.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from supercoil.contact.problem import ContactProblem

# Keys of a summary for callers that need only the counts and the closest approach
# (per-point records, contact-count events), or the contact places (figures, payload)
COUNT_KEYS = ("n_contact_points", "n_contact_intervals", "min_gap_over_diameter")
PLACE_KEYS = ("contact_points", "contact_intervals")
GROUPING_FLOOR = 1e-2  # of the largest contact force, see the module docstring
# summaries remembered per problem (contact_summary): a continuation point asks for its
# summary in its records and in its contact-count event, and a ring diagram's payload
# once more after the run; a few kilobytes each
SUMMARY_MEMO = 512
# Up to this many points the close pairs of the grouping are found by testing every
# pair (numpy), beyond by a KD tree (see close_pairs)
TREE_ABOVE_POINTS = 128


def _components(points: np.ndarray, reach: float, periodic: bool) -> np.ndarray:
    """Connected components (labels) of points within ``reach`` (max norm)."""
    n = len(points)
    parent = np.arange(n)

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j in close_pairs(points, reach, periodic):
        ri, rj = root(i), root(j)
        if ri != rj:
            parent[ri] = rj
    return np.array([root(i) for i in range(n)])


def close_pairs(points: np.ndarray, reach: float, periodic: bool) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, ``i < j``, of ``points`` (n, 2) within ``reach`` in the max norm;
    ``periodic``: coordinates modulo 1 (the distance the shorter way round).

    Up to ``TREE_ABOVE_POINTS`` points every pair is tested (numpy), beyond a
    `scipy.spatial.cKDTree` is asked (``query_pairs`` with ``p = inf`` and
    ``boxsize = 1``): the same pairs. A continuation point on a contact branch has a
    few tens of contacts (twice as many points), and ``scipy.spatial`` is imported
    only when needed.
    """
    n = len(points)
    wrapped = np.mod(points, 1.0) if periodic else np.asarray(points, dtype=float)
    if n > TREE_ABOVE_POINTS:
        from scipy.spatial import cKDTree  # here: only large contact sets need it

        tree = cKDTree(wrapped, boxsize=1.0 if periodic else None)
        return [(int(i), int(j)) for i, j in tree.query_pairs(reach, p=np.inf)]
    close = np.ones((n, n), dtype=bool)
    for axis in range(wrapped.shape[1]):
        gap = np.abs(wrapped[:, axis, None] - wrapped[None, :, axis])
        if periodic:
            gap = np.minimum(gap, 1.0 - gap)
        close &= gap <= reach
    i, j = np.nonzero(np.triu(close, 1))
    return list(zip(i.tolist(), j.tolist(), strict=True))


def _unwrap(values: np.ndarray) -> np.ndarray:
    """Arc-length fractions of one chain made contiguous across the seam at s = 0 = 1."""
    order = np.sort(values)
    gaps = np.diff(np.concatenate([order, [order[0] + 1.0]]))
    cut = order[(int(np.argmax(gaps)) + 1) % len(order)]  # start after the largest gap
    return np.where(values < cut, values + 1.0, values)


def group_contacts(s1: np.ndarray, s2: np.ndarray, force: np.ndarray, spacing: float,
                   closed: bool) -> tuple[list[dict], list[dict]]:
    """``(contact_points, contact_intervals)`` of contacts at ``(s1, s2)`` (fractions of L).

    ``spacing`` is the segment length over L; see the module docstring.
    """
    s1, s2, force = (np.asarray(v, dtype=float) for v in (s1, s2, force))
    n = len(force)
    if n == 0:
        return [], []
    # node k is contact k read as (s1, s2); node n + k the same contact read as (s2, s1)
    nodes = np.concatenate([np.stack([s1, s2], 1), np.stack([s2, s1], 1)])
    label = _components(nodes, 1.5 * spacing, closed)
    groups: dict[tuple[int, int], list[tuple[int, bool]]] = {}
    for k in range(n):
        a, b = label[k], label[n + k]
        key = (min(a, b), max(a, b))
        groups.setdefault(key, []).append((k, a != key[0]))  # read in the key's orientation
    points, intervals = [], []
    for members in sorted(groups.values(), key=lambda m: min(s1[k] for k, _ in m)):
        idx = np.array([k for k, _ in members])
        flip = np.array([f for _, f in members])
        a = np.where(flip, s2[idx], s1[idx])
        b = np.where(flip, s1[idx], s2[idx])
        f = force[idx]
        if closed:
            a, b = _unwrap(a), _unwrap(b)
        extent = max(float(np.ptp(a)), float(np.ptp(b)))
        wrap = (lambda v: float(v % 1.0)) if closed else float
        if extent > 2 * spacing:
            first, second = (wrap(a.min()), wrap(a.max())), (wrap(b.min()), wrap(b.max()))
            if first[0] > second[0]:  # the strand that starts first is strand 1
                first, second = second, first
            intervals.append({
                "s1_start": first[0], "s1_end": first[1],
                "s2_start": second[0], "s2_end": second[1],
                "force_per_length": float(f.sum() / (extent + spacing)),
            })
        else:
            w = f / f.sum() if f.sum() > 0 else np.full(len(f), 1.0 / len(f))
            p1, p2 = wrap(w @ a), wrap(w @ b)
            points.append({"s1": min(p1, p2), "s2": max(p1, p2), "force": float(f.sum())})
    return points, intervals


def contact_summary(problem: ContactProblem, q: np.ndarray,
                    multipliers: np.ndarray | None = None,
                    keys: Sequence[str] | None = None) -> dict:
    """The contact keys (docs/model.md, "Contacts in the output") for the state ``q``;
    with ``keys``, only those (a caller after the counts need not copy the list of
    every touching pair, ``contacts``: hundreds of entries on an interval contact).

    For the barrier and penalty treatments the summary is a function of ``q``,
    ``multipliers`` and the problem's stiffness, diameter and exclusion alone; it is
    remembered for the last ``SUMMARY_MEMO`` arguments (a copy is returned).
    """
    if problem.treatment not in ("barrier", "penalty"):
        found = computed_contact_summary(problem, q, multipliers)
        return found if keys is None else {k: found[k] for k in keys}
    key = (np.ascontiguousarray(q, dtype=np.float64).tobytes(),
           None if multipliers is None else
           np.ascontiguousarray(multipliers, dtype=np.float64).tobytes(),
           problem.treatment, float(problem.stiffness), float(problem.diameter),
           float(problem.curve.exclusion))
    memo = problem.summary_memo
    found = memo.get(key)
    if found is None:
        found = computed_contact_summary(problem, q, multipliers)
        if len(memo) >= SUMMARY_MEMO:
            del memo[next(iter(memo))]
        memo[key] = found
    return _copied(found, found.keys() if keys is None else keys)


def _copied(summary: dict, keys) -> dict:
    """A copy of ``keys`` of a summary that shares nothing mutable with it: its values are
    numbers, None, or lists of flat dicts of numbers (as :func:`copy.deepcopy`, at a
    tenth of the cost: deepcopy was half of a contact point's records at N = 200)."""
    return {k: [dict(entry) for entry in summary[k]] if isinstance(summary[k], list)
            else summary[k] for k in keys}


def computed_contact_summary(problem: ContactProblem, q: np.ndarray,
                             multipliers: np.ndarray | None) -> dict:
    """The contact summary at ``(q, multipliers)`` computed afresh (what
    :func:`contact_summary` remembers)."""
    rod = problem.base.rod
    force_scale = rod.length**2 / rod.bending_stiffness
    st, force = problem.pair_forces(q, multipliers)
    s1 = problem.arclength(st.pairs[:, 0], st.s) if len(st.pairs) else np.zeros(0)
    s2 = problem.arclength(st.pairs[:, 1], st.t) if len(st.pairs) else np.zeros(0)
    lo, hi = np.minimum(s1, s2), np.maximum(s1, s2)
    merged: dict[tuple[float, float], float] = {}
    for a, b, f in zip(lo, hi, force * force_scale):
        key = (round(float(a), 12), round(float(b), 12))
        merged[key] = merged.get(key, 0.0) + float(f)
    contacts = [{"s1": a, "s2": b, "force": f} for (a, b), f in sorted(merged.items())]
    forces = np.array([c["force"] for c in contacts])
    largest = float(np.max(np.abs(forces))) if forces.size else 0.0
    # Contact forces push apart (Coleman & Swigon 2002, eq. 10): a pulling one (possible
    # only for the exact treatment's multipliers) is not an admissible
    # equilibrium and is flagged, never dropped.
    negative = int(np.sum(forces < -problem.options.force_tolerance * max(1.0, largest)))
    strong = forces >= GROUPING_FLOOR * largest if forces.size else np.zeros(0, dtype=bool)
    points, intervals = group_contacts(
        np.array([c["s1"] for c in contacts])[strong] if contacts else np.zeros(0),
        np.array([c["s2"] for c in contacts])[strong] if contacts else np.zeros(0),
        forces[strong] if forces.size else np.zeros(0),
        problem.edge_length / rod.length, problem.closed)
    d_min = problem.min_distance(q)
    return {
        "negative_contact_forces": negative,
        "contacts": contacts,
        "contact_points": points,
        "contact_intervals": intervals,
        "n_contact_points": len(points),
        "n_contact_intervals": len(intervals),
        # closest approach of non-neighbour centreline points in diameters
        # (1 = touching, below 1 = penetrating; None when no pair is within reach)
        "min_gap_over_diameter": float(d_min / problem.diameter) if np.isfinite(d_min) else None,
    }
