"""The numbers a sweep keeps of one task: scalar summaries of its result file.

:func:`summarize` reads a :class:`~supercoil.io.store.Result` into a flat mapping
name -> number or string, the variables of the sweep's dataset. Every number
comes from the stored result (so a task summarised after a run and again when a
sweep is resumed gives the same values):

* per branch ``B`` (``B.points``, ``B.status``; ``B.end.R`` = record ``R`` at the
  branch's last point, with ``B.end.unstable_count`` and ``B.end.stable``;
  ``B.KIND`` = the continuation parameter at the branch's first special point of
  kind ``KIND`` (``fold``, ``bifurcation``, ``contact_onset``, ...) and
  ``B.KIND.count`` their number);
* over the whole result: ``folds`` and ``bifurcations`` (counts),
  ``first_contact_P`` (the parameter ``P``, turns or excess link, at the first
  contact onset, in the order the branches were computed);
* tweezers: ``buckling_turns`` (the straight rod's bifurcation, with
  ``buckling_torque`` and ``buckling_extension`` there), ``greenhill_turns`` (the
  clamped Greenhill value the run reports), ``ply_torque`` and ``ply_spanning_turns``
  (the hard-core ply's torque and the turns at which it spans the rod,
  :mod:`supercoil.problems.ply`), ``torque_plateau`` (the torque at the
  last point of the last contact branch: the plectoneme's plateau under a dead
  load) and ``end_extension``, ``end_writhe`` at the last point computed;
* ring diagrams: ``michell_excess_link.M`` per Michell mode ``M`` (Michell 1889).

Booleans become 0 and 1; counts are numbers. Branch names keep their spelling
(``/`` becomes ``_``).
"""

from __future__ import annotations

import math

import numpy as np

STRAIGHT_BRANCH = "straight"  # the tweezers' first branch (supercoil.problems.tweezers)


def _branches(result) -> list:
    return list(result.branches.values())


def _name(text: str) -> str:
    return str(text).replace("/", "_")


def _number(value) -> float | None:
    """A scalar record value as a float (booleans 0/1), or None if not a scalar number."""
    a = np.asarray(value)
    if a.ndim != 0 or a.dtype.kind not in "biuf":
        return None
    return float(a)


def _specials(branch) -> list:
    return sorted(branch.special_points, key=lambda p: (int(p.index), float(p.arclength)))


def branch_summary(branch) -> dict:
    """The ``B.*`` entries of one branch (see the module docstring)."""
    b = _name(branch.name)
    out: dict = {f"{b}.points": float(len(branch)), f"{b}.status": branch.status.name}
    if len(branch):
        ends = {branch.parameter: branch.parameter_values[-1]}
        ends.update({k: v[-1] for k, v in branch.records.items() if len(v)})
        ends["unstable_count"] = branch.unstable_count[-1]
        ends["stable"] = branch.unstable_count[-1] == 0
        for name, value in ends.items():
            number = _number(value)
            if number is not None:
                out[f"{b}.end.{_name(name)}"] = number
    counts: dict[str, int] = {}
    for p in _specials(branch):
        kind = _name(p.kind)
        if kind not in counts:
            out[f"{b}.{kind}"] = float(p.parameter)
        counts[kind] = counts.get(kind, 0) + 1
    for kind, n in counts.items():
        out[f"{b}.{kind}.count"] = float(n)
    return out


def summarize(result) -> dict:
    """name -> float or str of one result (see the module docstring)."""
    branches = _branches(result)
    out: dict = {}
    for branch in branches:
        out.update(branch_summary(branch))
    specials = [(branch, p) for branch in branches for p in _specials(branch)]
    out["folds"] = float(sum(p.kind == "fold" for _, p in specials))
    out["bifurcations"] = float(sum(p.kind == "bifurcation" for _, p in specials))
    parameter = branches[0].parameter if branches else None
    if parameter is not None:
        onsets = [p for _, p in specials if p.kind == "contact_onset"]
        out[f"first_contact_{_name(parameter)}"] = (float(onsets[0].parameter) if onsets
                                                     else math.nan)
    summary = result.summary or {}
    if result.problem == "tweezers":
        out.update(_tweezers(result, branches, summary))
    elif result.problem == "ring_diagram":
        for mode, value in (summary.get("michell_excess_link") or {}).items():
            out[f"michell_excess_link.{mode}"] = float(value)
    return out


def _tweezers(result, branches: list, summary: dict) -> dict:
    nan = math.nan
    out = {"buckling_turns": nan, "buckling_torque": nan, "buckling_extension": nan,
           "torque_plateau": nan, "end_extension": nan, "end_writhe": nan}
    greenhill = summary.get("greenhill_turns")
    out["greenhill_turns"] = float(greenhill) if isinstance(greenhill, (int, float)) else nan
    ply = summary.get("hard_core_ply")
    ply = ply if isinstance(ply, dict) else {}
    for key, name in (("torque", "ply_torque"), ("spanning_turns", "ply_spanning_turns")):
        value = ply.get(key)
        out[name] = float(value) if isinstance(value, (int, float)) else nan
    straight = [b for b in branches if b.name == STRAIGHT_BRANCH]
    buckling = [p for b in straight for p in _specials(b) if p.kind == "bifurcation"]
    if buckling:
        p = buckling[0]
        out["buckling_turns"] = float(p.parameter)
        for key in ("torque", "extension"):
            number = _number(p.records[key]) if key in p.records else None
            if number is not None:
                out[f"buckling_{key}"] = number
    contact = [b for b in branches if b.name in result.contact_branches and len(b)]
    if contact and "torque" in contact[-1].records:
        out["torque_plateau"] = float(contact[-1].records["torque"][-1])
    done = [b for b in branches if len(b)]
    if done:
        for key in ("extension", "writhe"):
            if key in done[-1].records:
                out[f"end_{key}"] = float(done[-1].records[key][-1])
    return out
