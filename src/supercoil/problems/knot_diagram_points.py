"""Per-point keys of the knotted-ring diagram: sections touching two others, lowest energy.

:func:`sections_touching_two`: the cross-sections of a state that touch two
others (a knotted ring can press one strand against two, Coleman & Swigon
2000). Every contact reported by
:func:`~supercoil.contact.report.contact_summary` occupies arcs on its two
strands: an interval ``[start, end]`` of s/L on each (a seam-crossing one has
``start > end``), a point the arc of one segment length centred on its ``s1``
and on its ``s2``. A node (a cross-section at ``s = i/N``) lies on a number of
such arcs; it touches two others when it lies on at least two (of different
contacts, or of both strands of one interval when a strand folds back on
itself, which a tube cannot do). The key ``n_sections_touching_two`` counts
those nodes, ``sections_touching_two`` gives them as arcs ``[s_start,
s_end]`` of s/L (consecutive nodes merged).

:func:`lowest_energy`: a point is the lowest-energy state found at its ``dLk``
when no other computed state at that ``dLk`` has a lower energy. The other
states at ``dLk`` are read on every segment between consecutive points of the
branches that ``dLk`` falls on (the segments ending at the point itself, and
at its copy at the start of the other half, left out), their energy linearly
interpolated: the comparison is exact between branches far apart in energy
and to O(step^2) between branches that cross. :func:`states_by_excess_link`
counts the states on a grid of ``dLk``, with the stable ones and the lowest.
"""

from __future__ import annotations

import numpy as np

# two states of one dLk whose energies agree to this (relative) are the same state
SAME_STATE = 1e-9


def _on_arc(s: np.ndarray, start: float, end: float) -> np.ndarray:
    """Which of ``s`` (in [0, 1)) lie on the arc from ``start`` to ``end`` (s/L, periodic)."""
    start, end = start % 1.0, end % 1.0
    if start <= end:
        return (s >= start) & (s <= end)
    return (s >= start) | (s <= end)


def sections_touching_two(n_nodes: int, contact_points, contact_intervals
                          ) -> tuple[int, list[list[float]]]:
    """How many nodes lie on at least two contact arcs, and their arcs ``[s_start,
    s_end]`` (s/L; ``s_start > s_end`` across the seam) (module doc)."""
    s = np.arange(n_nodes) / n_nodes
    half = 0.5 / n_nodes
    hits = np.zeros(n_nodes, dtype=np.int64)
    for p in contact_points:
        for key in ("s1", "s2"):
            hits += _on_arc(s, p[key] - half - 1e-12, p[key] + half + 1e-12)
    for c in contact_intervals:
        for strand in ("s1", "s2"):
            hits += _on_arc(s, c[f"{strand}_start"] - 1e-12, c[f"{strand}_end"] + 1e-12)
    touching = hits >= 2
    count = int(np.count_nonzero(touching))
    if count == 0:
        return 0, []
    if count == n_nodes:
        return count, [[0.0, 1.0]]
    # arcs of consecutive touching nodes, starting after a node that does not touch
    first = int(np.argmin(touching))
    arcs, current = [], None
    for k in range(1, n_nodes + 1):
        i = (first + k) % n_nodes
        if touching[i]:
            current = [float(s[i]), float(s[i])] if current is None else [current[0],
                                                                         float(s[i])]
        elif current is not None:
            arcs.append(current)
            current = None
    if current is not None:
        arcs.append(current)
    return count, arcs


def _segments(branches):
    """``(branch index, j, dLk_j, dLk_j+1, E_j, E_j+1, stable_j and stable_j+1)``."""
    out = []
    for b, (lam, energy, stable) in enumerate(branches):
        for j in range(len(lam) - 1):
            out.append((b, j, lam[j], lam[j + 1], energy[j], energy[j + 1],
                        bool(stable[j] and stable[j + 1])))
    return out


def _at(segment, value: float) -> float | None:
    """The segment's interpolated energy at ``dLk = value``, None when off it."""
    _, _, l0, l1, e0, e1, _ = segment
    low, high = min(l0, l1), max(l0, l1)
    if not low <= value <= high:
        return None
    if l1 == l0:
        return min(e0, e1)
    t = (value - l0) / (l1 - l0)
    return (1 - t) * e0 + t * e1


def lowest_energy(branches) -> list[np.ndarray]:
    """Per branch, per point: the lowest-energy state found at its dLk (module doc).
    ``branches``: ``(dLk (k,), energy (k,), stable (k,))`` per branch."""
    segments = _segments(branches)
    out = []
    for b, (lam, energy, _stable) in enumerate(branches):
        flags = np.zeros(len(lam), dtype=bool)
        for i, (value, e) in enumerate(zip(lam, energy)):
            scale = SAME_STATE * max(1.0, abs(e))
            others = []
            for seg in segments:
                sb, j = seg[0], seg[1]
                if sb == b and j in (i - 1, i):
                    continue
                ends = ((seg[2], seg[4]), (seg[3], seg[5]))
                if any(abs(lv - value) <= 1e-12 and abs(ev - e) <= scale for lv, ev in ends):
                    continue  # a segment ending at this very state (its copy on the other half)
                found = _at(seg, value)
                if found is not None:
                    others.append(found)
            flags[i] = not others or e <= min(others) + scale
        out.append(flags)
    return out


def states_by_excess_link(branches, grid: np.ndarray, names) -> list[dict]:
    """At each ``dLk`` of ``grid``: the states found there (segments crossing it, the same
    state on two segments counted once), how many stable (both ends of its segment
    stable), and the lowest energy with its branch and stability."""
    segments = _segments(branches)
    table = []
    for value in grid:
        found = []
        for seg in segments:
            e = _at(seg, float(value))
            if e is None:
                continue
            if any(abs(e - f[0]) <= SAME_STATE * max(1.0, abs(e)) for f in found):
                continue
            found.append((e, seg[6], names[seg[0]]))
        found.sort()
        table.append({
            "excess_link": float(value), "n_states": len(found),
            "n_stable": sum(1 for f in found if f[1]),
            "lowest_energy": float(found[0][0]) if found else None,
            "lowest_branch": found[0][2] if found else None,
            "lowest_stable": bool(found[0][1]) if found else None})
    return table
