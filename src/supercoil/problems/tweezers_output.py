"""The ``branch.json`` payload of a tweezers run (:mod:`supercoil.problems.tweezers`).

Formatting only: per-point records with the keys of docs/model.md, contact lists
recomputed from the stored states, special points, branch metadata and the
conventions the file states.
"""

from __future__ import annotations

import numpy as np

from supercoil.contact.report import contact_summary
from supercoil.continuation import SpecialPoint
from supercoil.continuation.branch import jsonable
from supercoil.problems.model_keys import model_keys
from supercoil.problems.tweezers import TweezersResult


def special_summary(p: SpecialPoint) -> dict:
    """JSON entry of a special point: kind, branch, turns and its records (extension...)."""
    return p.entry("turns")


def result_points(result: TweezersResult, contacts: bool = True) -> list[dict]:
    """One entry per point of every branch (keys of docs/model.md), contact lists included;
    ``contacts=False``: the lists left empty, for :func:`add_contact_lists` to fill."""
    out = []
    for b in result.branches:
        for i in range(len(b)):
            entry = {"branch": b.name, "index": i,
                     **{k: jsonable(v[i]) for k, v in b.records.items()},
                     "unstable_count": int(b.unstable_count[i]),
                     "zero_modes": int(b.zero_modes[i]),
                     "determinant_sign": int(b.determinant_sign[i]),
                     "stable": bool(b.stable[i]),
                     "contact_points": [], "contact_intervals": []}
            out.append(entry)
    if contacts:
        add_contact_lists(result, out)
    return out


def add_contact_lists(result: TweezersResult, entries: list[dict]) -> None:
    """Fill ``contact_points`` and ``contact_intervals`` of ``entries`` (of
    :func:`result_points`) on the contact branches: 0.5 ms a state at N = 100 (the
    command draws its figures meanwhile)."""
    cp = result.contact_problem
    if cp is None:
        return
    branches = {b.name: b for b in result.branches if b.name in result.contact_branches}
    for entry in entries:
        b = branches.get(entry["branch"])
        if b is not None:
            i = entry["index"]
            summary = contact_summary(cp, b.states[i], b.multipliers[i])
            entry["contact_points"] = summary["contact_points"]
            entry["contact_intervals"] = summary["contact_intervals"]


def _closure_notes(result: TweezersResult) -> list[str]:
    """A note per branch on which turns = Tw + Wr fails (tail wrap or self-crossing)."""
    notes = []
    for b in result.branches:
        failed = np.flatnonzero(np.asarray(b.records.get("closure_failed", []), dtype=bool))
        if failed.size:
            notes.append(f"{b.name}: turns = twist + writhe fails at {failed.size} points "
                         f"(first at {b.parameter_values[failed[0]]:.6g} turns): the rod "
                         "wrapped around a tail or, without self-contact, passed through "
                         "itself; writhe there is not the axial closure's")
    return notes


def result_payload(result: TweezersResult, contacts: bool = True) -> dict:
    """The ``branch.json`` payload (without the envelope of :mod:`supercoil.io.results`);
    ``contacts=False``: the points' contact lists left empty (:func:`result_points`)."""
    opts = result.options
    branches = []
    for b in result.branches:
        branches.append({
            "name": b.name, "parent": b.parent,
            "origin": None if b.origin is None else special_summary(b.origin),
            "contact": b.name in result.contact_branches, "parameter": b.parameter,
            "n_points": len(b), "status": b.status.name, "ok": result.branch_ok(b),
            "message": b.message,
            "seconds": round(result.seconds.get(b.name, float("nan")), 3),
            "azimuth_pins": [{"from_index": i, "dofs": list(d)}
                             for i, d in result.pins.get(b.name, ())],
            "file": "result.h5"})
    payload = {
        "description": "rod clamped at both ends on the pulling axis, turned at one end: the "
        "straight rod, its buckling, the buckled branch without contact up to first contact, "
        "then with self-contact (plectoneme)",
        **model_keys(result.model, result.branches),
        "control": "load" if opts.load_control else "displacement",
        "twist_ratio": opts.twist_ratio,
        "length_over_diameter": opts.length_over_diameter,
        "diameter": opts.diameter,
        "force": opts.tension,
        "end_distance": opts.end_distance,
        "turns_range": list(opts.turns),
        "n_nodes": opts.n_nodes,
        "contact_curve": opts.contact_curve,
        "contact_formulation": opts.contact_formulation,
        "loop_sliding": opts.loop_sliding,  # as given: None, where it applies
        "loop_sliding_applied": opts.loop_slides,
        "loop_sliding_in_contact": opts.loop_slides_in_contact,
        "greenhill_turns": result.greenhill_turns,
        "hard_core_ply": None if result.ply is None else result.ply.summary(),
        "branches": branches,
        "special_points": [special_summary(p) for p in result.special_points()],
        "points": result_points(result, contacts),
        "notes": list(result.notes) + _closure_notes(result),
        "ok": result.ok,
    }
    return payload


TWEEZERS_CONVENTIONS = {
    "turns": "rotation of the turned end about the pulling axis +z, in turns; positive = "
    "right-handed (overwinding for DNA)",
    "extension": "end-to-end distance along the axis between the clamps, over L",
    "torque": "axial moment at the turned end, M L/A = 2 pi (C/A) twist (reduced twist: "
    "uniform at equilibrium); positive in the sense of positive turns",
    "twist": "excess twist in turns, from the reference frames carried along the branch",
    "writhe": "double-sum writhe of the rod closed by straight tails along the axis from both "
    "ends; turns = twist + writhe (closure_error = |twist + writhe - turns|; above 1/2 the "
    "rod has wrapped around a tail or, without self-contact, passed through itself (the "
    "writhe jumps by 2): closure_failed)",
    "energy": "elastic energy only (bending + twist), E L/A",
    "load_potential": "-F z of the dead load (F L^2/A times extension); 0 under displacement "
    "control",
    "tension": "axial force F L^2/A: the dead load, or the end reaction under displacement "
    "control",
    "contacts": "barrier self-contact of a tube of diameter D; min_gap_over_diameter = closest "
    "approach of non-neighbouring points over D (> 1: no penetration)",
    "special_points": "bifurcation (count change not explained by a fold: the straight rod's "
    "buckling, count +2), fold, contact_onset / contact_release / contact_split / "
    "contact_interval_onset, jump",
}
