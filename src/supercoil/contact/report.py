"""Contact output of a state: touching pairs, contact points and contact intervals.

Conventions (DESIGN.md): arc-length positions are fractions of L, forces are
F·L²/A. ``contacts`` lists every touching segment pair as ``{s1, s2, force}``
with ``s1 < s2``; pairs whose closest points coincide (both segments of a
joint touching at the same node) are merged and their forces added.

A negative force (only the exact treatment's multipliers can have one) is
counted in ``negative_contact_forces`` and kept in the lists.

Grouping. Two contacts are linked when they lie within 1.5 segment lengths of
each other on both strands (i.e. they touch along neighbouring segments;
across the seam s = 0 of a closed rod too); chains are the connected groups
(O(n^2) in the number of touching pairs, which is small). A chain that extends over more than two segment
lengths on either strand is a contact interval (a line contact, seed 001's
"contact line"): ``{s1_start, s1_end, s2_start, s2_end, force_per_length}``
(on a closed rod an interval across the seam has ``start > end``)
with the force per length = total force / (extent + one segment length), the
length the chain's contacts stand for. Any other chain is an isolated contact
point ``{s1, s2, force}`` at the force-weighted mean position with the total
force (a point contact is spread over one or two segment pairs by the
discretisation). This is the data of seed 001's Figure 4.
"""

from __future__ import annotations

import numpy as np

from supercoil.contact.problem import ContactProblem


def _circular_gap(a: float, b: float, period: float | None) -> float:
    d = abs(a - b)
    return min(d, period - d) if period else d


def _close(c: dict, d: dict, reach: float, period: float | None) -> bool:
    """Whether two contacts touch along neighbouring segments (either pairing of ends)."""
    straight = (_circular_gap(c["s1"], d["s1"], period) <= reach
                and _circular_gap(c["s2"], d["s2"], period) <= reach)
    crossed = (_circular_gap(c["s1"], d["s2"], period) <= reach
               and _circular_gap(c["s2"], d["s1"], period) <= reach)
    return straight or crossed


def _chains(contacts: list[dict], reach: float, period: float | None) -> list[list[dict]]:
    """Connected groups of contacts (single linkage on :func:`_close`), each sorted by s1."""
    n = len(contacts)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if _close(contacts[i], contacts[j], reach, period):
                parent[root(i)] = root(j)
    groups: dict[int, list[dict]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(contacts[i])
    return sorted(groups.values(), key=lambda g: g[0]["s1"])


def _unwrap(values: np.ndarray) -> np.ndarray:
    """Arc-length fractions of one chain made contiguous across the seam at s = 0 = 1."""
    order = np.sort(values)
    gaps = np.diff(np.concatenate([order, [order[0] + 1.0]]))
    cut = order[(int(np.argmax(gaps)) + 1) % len(order)]  # start after the largest gap
    return np.where(values < cut, values + 1.0, values)


def contact_summary(problem: ContactProblem, q: np.ndarray,
                    multipliers: np.ndarray | None = None) -> dict:
    """The contact keys of DESIGN.md for the state ``q`` (see the module docstring)."""
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
    h = problem.edge_length / rod.length
    period = 1.0 if problem.closed else None
    chains = _chains(contacts, 1.5 * h, period)
    points, intervals = [], []
    for chain in chains:
        a = np.array([c["s1"] for c in chain])
        b = np.array([c["s2"] for c in chain])
        f = np.array([c["force"] for c in chain])
        if period:  # a chain may run across s = 0 on a closed rod: unwrap it
            a, b = _unwrap(a), _unwrap(b)
        extent = max(float(np.ptp(a)), float(np.ptp(b)))
        if extent > 2 * h:
            wrap = (lambda v: v % 1.0) if period else (lambda v: v)
            intervals.append({
                "s1_start": float(wrap(a.min())), "s1_end": float(wrap(a.max())),
                "s2_start": float(wrap(b.min())), "s2_end": float(wrap(b.max())),
                "force_per_length": float(f.sum() / (extent + h)),
            })
        else:
            w = f / f.sum() if f.sum() > 0 else np.full(len(f), 1.0 / len(f))
            s1, s2 = float(w @ a), float(w @ b)
            if period:
                s1, s2 = s1 % 1.0, s2 % 1.0
            points.append({"s1": s1, "s2": s2, "force": float(f.sum())})
    d_min = problem.min_distance(q)
    # Contact forces push apart (seed 001, eq. 10): a negative one (possible
    # only for the exact treatment's multipliers) is not an admissible
    # equilibrium and is flagged, never dropped.
    negative = [c for c in contacts if c["force"] < 0]
    return {
        "negative_contact_forces": len(negative),
        "contacts": contacts,
        "contact_points": points,
        "contact_intervals": intervals,
        "n_contact_points": len(points),
        "n_contact_intervals": len(intervals),
        # closest approach of non-neighbour centreline points in diameters
        # (1 = touching, below 1 = penetrating; None when no pair is within reach)
        "min_gap_over_diameter": float(d_min / problem.diameter) if np.isfinite(d_min) else None,
    }
