"""Figures of ``supercoil tweezers``: hat curve, torque, writhe, tube pictures.

Plotting never computes: the figures are drawn from the ``branch.json``
payload (:mod:`supercoil.problems.tweezers_output`) and stored states, with
the house builders of :mod:`supercoil.plotting.figures` (stable parts heavy,
special points marked).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from supercoil.plotting.dna import DNAScales, caveat_text
from supercoil.plotting.figures import (
    configurations_figure,
    diagram_figure,
    through_special_points,
)

FIGURES = {"hat_curve.png": "extension", "torque.png": "torque", "writhe.png": "writhe"}
# the figures' resolution, and zlib level 1 for their PNG files (the pixels of the
# default level, files about a sixth larger, encoded several times faster)
SAVE_OPTIONS = {"dpi": 150, "pil_kwargs": {"compress_level": 1}}


def _branches(payload: Mapping, y: str, x: str = "turns") -> list[dict]:
    """The branches' lines of ``y`` against turns, each with its located special points
    inserted (:func:`~supercoil.plotting.figures.through_special_points`), so that a
    stable stretch is drawn heavy up to the located point: the straight rod up to its
    buckling, not only up to its last stable sample (1.6 of 2.2 turns on the
    benchmark's rod, whose straight branch steps by up to one turn)."""
    out = []
    for b in payload["branches"]:
        rows = [p for p in payload["points"] if p["branch"] == b["name"]]
        if not rows:
            continue
        line = {"name": b["name"], x: [p[x] for p in rows],
                y: [p[y] for p in rows], "stable": [p["stable"] for p in rows]}
        specials = [p for p in payload["special_points"] if p.get("branch") == b["name"]]
        out.append(through_special_points(line, specials, (x, y)))
    if payload.get("path"):
        rows = payload["path"]
        out.append({"name": "experiment path", x: [p[x] for p in rows],
                    y: [p[y] for p in rows], "stable": [True] * len(rows), "color": "0.15"})
    return out


def _in_dna_units(payload: Mapping) -> tuple[Mapping, DNAScales | None]:
    """``payload`` with the DNA keys in every point (:class:`DNAScales`), and its scales;
    unchanged and None when it is not in DNA units."""
    scales = DNAScales.of(payload)
    if scales is None:
        return payload, None
    out = dict(payload)
    for key in ("points", "special_points", "path"):
        if out.get(key):
            out[key] = [scales.in_dna_units(p) for p in out[key]]
    return out, scales


def _title(payload: Mapping) -> str:
    parts = [f"C/A = {payload['twist_ratio']:.4g}"]
    if payload.get("force") is not None:
        parts.append(f"F L²/A = {payload['force']:.4g}")
    if payload.get("end_distance") is not None:
        parts.append(f"z/L = {payload['end_distance']:.4g}")
    if payload.get("length_over_diameter") is not None:
        parts.append(f"L/D = {payload['length_over_diameter']:.4g}")
    parts.append(f"N = {payload['n_nodes']}")
    return "clamped rod, " + ", ".join(parts)


def figure_jobs(payload: Mapping, configurations: Sequence[Mapping],
                folder: str | os.PathLike) -> list[tuple[Path, str, dict]]:
    """The PNG figures of :func:`write_figures`, each ``(path, builder, keyword
    arguments)`` for :func:`draw_job`."""
    folder = Path(folder)
    jobs = []
    payload, dna = _in_dna_units(payload)
    title = _title(payload) if dna is None else dna.title(payload.get("n_nodes"))
    if configurations:
        jobs.append((folder / "configurations.png", "configurations", {
            "configurations": list(configurations), "diameter": payload.get("diameter"),
            "title": title, "closed": False}))
    figures = dict(FIGURES)
    if payload.get("control") == "displacement":
        # the extension is held: the end force against turns replaces the hat curve
        del figures["hat_curve.png"]
        figures["tension.png"] = "tension"
    for name, y in figures.items():
        x, y, secondary = ("turns", y, {}) if dna is None else dna.axes("turns", y)
        specials = [p for p in payload["special_points"] if y in p and x in p]
        lines = _branches(payload, y, x) + _ply_plateau(payload, dna, x, y)
        jobs.append((folder / name, "diagram", {
            "branches": lines, "special_points": specials, "title": title,
            "x": x, "y": y, **_dna_extras(dna, secondary, y)}))
    ramp = [p for p in payload.get("path") or [] if p.get("ramp") == "tension"]
    if ramp:
        x, y, secondary = (("tension", "extension", {}) if dna is None
                           else dna.axes("tension", "extension"))
        rows = {"name": "force ramp", x: [p[x] for p in ramp], y: [p[y] for p in ramp],
                "stable": [p["stable"] for p in ramp], "color": "0.15"}
        specials = [j for j in payload["special_points"] if j.get("ramp") == "tension"
                    and x in j and y in j]
        jobs.append((folder / "force_extension.png", "diagram", {
            "branches": [rows], "special_points": specials, "title": title, "x": x,
            "y": y, **_dna_extras(dna, secondary, y)}))
    return jobs


def _ply_plateau(payload: Mapping, dna: DNAScales | None, x: str, y: str) -> list[dict]:
    """On the torque's figure, the hard-core ply's torque plateau (``hard_core_ply``,
    :mod:`supercoil.problems.ply`) as a grey dashed line: from the turns at which the
    straight rod's twist carries that torque to those at which the ply spans the rod, or
    to the run's last turn if that comes first."""
    ply = payload.get("hard_core_ply")
    if not ply or x != "turns" or y not in ("torque", "torque_pN_nm"):
        return []
    torque = ply["torque"] * (1.0 if dna is None else dna.torque_scale_pN_nm)
    drawn = [p["turns"] for p in payload["points"] if "turns" in p]
    last = max(payload.get("turns_range") or drawn or [ply["spanning_turns"]])
    end = min(ply["spanning_turns"], last)
    if not end > ply["twist_turns"]:
        return []
    return [{"name": "hard-core ply", x: [ply["twist_turns"], end],
             y: [torque, torque], "stable": [False, False], "color": "0.55",
             "linestyle": (0, (4, 3))}]


def _dna_extras(dna: DNAScales | None, secondary: dict, y: str) -> dict:
    """The secondary axes and, on the figures of the extension and the torque, the
    athermal caveat (:data:`~supercoil.plotting.dna.CAVEAT`)."""
    if dna is None:
        return {}
    extras = {"secondary": secondary}
    if y in ("extension_nm", "torque_pN_nm"):
        extras["caption"] = caveat_text()
    return extras


def draw_job(job: tuple[Path, str, dict]) -> Path:
    """Build the figure of one of :func:`figure_jobs` and save it; returns its path."""
    import matplotlib

    path, builder, kwargs = job
    kwargs = dict(kwargs)
    # made at the resolution it is saved at: the layout's text measurements are then
    # the drawing's, and the save does not rescale the figure
    with matplotlib.rc_context({"figure.dpi": SAVE_OPTIONS["dpi"]}):
        if builder == "diagram":
            fig = diagram_figure(kwargs.pop("branches"), kwargs.pop("special_points"),
                                 **kwargs)
        else:
            fig = configurations_figure(kwargs.pop("configurations"), **kwargs)
    fig.savefig(path, **SAVE_OPTIONS)
    return Path(path)


def write_figures(payload: Mapping, configurations: Sequence[Mapping],
                  folder: str | os.PathLike) -> list[Path]:
    """Write the PNG figures into ``folder``; returns the paths written.

    Extension (load control) or the end's axial force (displacement control),
    torque and writhe against turns; extension against force for a force ramp;
    tube pictures. ``configurations``: ``{label, points (n, 3), contact_points,
    contact_intervals}`` of the states to draw as tubes.
    """
    return [draw_job(job) for job in figure_jobs(payload, configurations, folder)]


def pick_configurations(payload: Mapping, states: Mapping[str, np.ndarray],
                        count: int = 6) -> list[dict]:
    """Up to ``count`` states spread along the branches (first and last of each included)."""
    picks = []
    for name, i, p in picked_points(payload, states, count):
        label = f"{name}, {p['turns']:.3g} turns, z/L = {p['extension']:.3g}"
        if "superhelical_density" in p and "extension_nm" in p:
            label = (f"{name}, σ = {p['superhelical_density']:.3g}, z = "
                     f"{p['extension_nm']:.4g} nm")
        picks.append({"label": label, "points": states[name][i].reshape(-1, 3),
                      "contact_points": p.get("contact_points", []),
                      "contact_intervals": p.get("contact_intervals", [])})
    return picks


def picked_points(payload: Mapping, states: Mapping[str, np.ndarray],
                  count: int = 6) -> list[tuple[str, int, dict]]:
    """The states :func:`pick_configurations` draws: ``(branch name, index on the branch,
    its entry of payload["points"])``."""
    picks = []
    names = [b["name"] for b in payload["branches"] if b["name"] != "straight"]
    per = max(1, count // max(1, len(names)))
    for name in names:
        rows = [p for p in payload["points"] if p["branch"] == name]
        if not rows or name not in states:
            continue
        for i in np.unique(np.linspace(0, len(rows) - 1, per).astype(int)):
            picks.append((name, int(i), rows[i]))
    return picks[:count]
