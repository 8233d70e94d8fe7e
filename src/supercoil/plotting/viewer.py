"""The interactive viewer: one self-contained HTML file (no server, works offline).

Left, the bifurcation diagram (ΔLk against Wr for a ring, extension against
turns for tweezers; stable parts heavy, special points by kind); right, the
selected state as a tube of diameter D to scale, contacts in red; beside
them, the state's numbers. Clicking the diagram, the slider, the arrow keys
or the URL hash (``#branch=NAME&point=K``) select a state; the tube turns
with the mouse.

Why vanilla JavaScript on a 2D canvas, not plotly or three.js: the page must
work offline from one file, so a library would be inlined into every file
(plotly.min.js is about 3.5 MB, for a 2D line plot and one tube); a tube
drawn as depth-sorted shaded segments (the painter's algorithm, as in the
PNG figures) needs no WebGL, which headless and remote browsers often lack.
The template is ``viewer_template.html`` beside this module; the data go
into it as one JSON block. Plotting never computes: the numbers shown are the
result's.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Mapping
from importlib import resources
from pathlib import Path

import numpy as np

from supercoil.plotting import style
from supercoil.plotting.figures import through_special_points
from supercoil.plotting.result_data import ResultData, stable_mask

COORDINATE_DECIMALS = 5  # centreline coordinates in units of L: 1e-5 L on the screen

# (key, label) of the numbers listed for the selected state, in this order
NUMBERS = (
    ("excess_link", "excess link ΔLk (turns)"),
    ("turns", "end rotation n (turns)"),
    ("writhe", "writhe Wr (turns)"),
    ("twist", "excess twist Tw (turns)"),
    ("link_error", "|Tw + Wr − ΔLk| (turns)"),
    ("energy", "energy E·L/A"),
    ("extension", "extension z/L"),
    ("torque", "torque M·L/A"),
    ("force", "force F·L²/A"),
    ("unstable_count", "unstable count"),
    ("zero_modes", "zero modes"),
    ("n_contact_points", "contact points"),
    ("n_contact_intervals", "contact intervals"),
    ("min_gap_over_diameter", "min gap / D"),
    # the DNA preset's keys (suffixed, beside the nondimensional ones)
    ("superhelical_density", "superhelical density σ"),
    ("energy_kT", "energy (kT)"),
    ("extension_nm", "extension (nm)"),
    ("torque_pN_nm", "torque (pN·nm)"),
    ("min_gap_nm", "min gap (nm)"),
)
_NOT_LISTED = {"branch", "index", "stable", "contact_points", "contact_intervals", "contacts",
               "centreline", "determinant_sign"}

AXES = {
    "ring": {"x": "writhe", "y": "excess_link", "x_label": "writhe Wr (turns)",
             "y_label": "excess link ΔLk (turns)", "x_short": "Wr", "y_short": "ΔLk"},
    "tweezers": {"x": "turns", "y": "extension", "x_label": "end rotation n (turns)",
                 "y_label": "extension z/L", "x_short": "n", "y_short": "z/L"},
}


def _clean(value):
    """JSON-safe copy: numpy scalars to Python, non-finite floats to None."""
    if isinstance(value, Mapping):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _point(p: Mapping, stable: bool) -> dict:
    out = {k: _clean(v) for k, v in p.items() if k not in ("centreline",)}
    out["stable"] = bool(stable)
    return out


def _isolated(result: ResultData, axes: Mapping, avoid: int) -> dict:
    """The point (branch index, point index) farthest, in the diagram's unit box, from
    every other point, preferring branches other than ``avoid``: a click on it
    can select only it (the browser test clicks there)."""
    xs, ys, keys = [], [], []
    for bi, b in enumerate(result.branches):
        for i, p in enumerate(b.points):
            x, y = p.get(axes["x"]), p.get(axes["y"])
            if isinstance(x, int | float) and isinstance(y, int | float) \
                    and math.isfinite(x) and math.isfinite(y):
                xs.append(x)
                ys.append(y)
                keys.append((bi, i))
    if len(keys) < 2:
        return {"branch": 0, "index": 0}
    xy = np.column_stack([xs, ys])
    span = np.ptp(xy, axis=0)
    xy = (xy - xy.min(axis=0)) / np.where(span > 0, span, 1.0)
    from scipy.spatial import cKDTree

    nearest = cKDTree(xy).query(xy, k=2)[0][:, 1]  # O(P log P): results can be long
    other = np.array([bi != avoid for bi, _ in keys])
    if other.any():
        nearest = np.where(other, nearest, -1.0)
    bi, i = keys[int(np.argmax(nearest))]
    return {"branch": bi, "index": i}


def _finite(values) -> list:
    return [float(v) if np.isfinite(v) else None for v in np.asarray(values, dtype=float)]


def viewer_payload(result: ResultData) -> dict:
    """The JSON data the page draws (numbers as stored, coordinates rounded to 1e-5 L)."""
    axes = AXES.get(result.kind, AXES["ring"])
    branches = []
    extent = 0.0
    for index, b in enumerate(result.branches):
        stable = stable_mask(b.points)
        states = b.states()
        flat = None
        if states is not None:
            centred = states - states.mean(axis=1, keepdims=True)
            extent = max(extent, float(np.linalg.norm(centred, axis=2).max(initial=0.0)))
            flat = np.round(states.reshape(len(states), -1), COORDINATE_DECIMALS).tolist()
        keys = (axes["x"], axes["y"])
        line = None
        if b.points and all(k in p for p in b.points for k in keys):
            drawn = through_special_points(
                {"name": b.name, "stable": stable, **{k: b.values(k) for k in keys}},
                result.special_points, keys)
            line = {"x": _finite(drawn[keys[0]]), "y": _finite(drawn[keys[1]]),
                    "stable": [bool(v) for v in drawn["stable"]]}
        branches.append({"name": b.name, "parent": b.parent, "contact": b.contact,
                         "color": style.branch_color(index),
                         "points": [_point(p, s) for p, s in zip(b.points, stable,
                                                                 strict=True)],
                         "line": line, "states": flat})
    if not any(b["points"] for b in branches):
        raise ValueError(f"{result.path}: the result has no points to show")
    branches = [b for b in branches if b["points"]]
    listed = [{"key": k, "label": label} for k, label in NUMBERS]
    known = {k for k, _ in NUMBERS}
    extra = sorted({k for b in branches for p in b["points"] for k, v in p.items()
                    if k not in known and k not in _NOT_LISTED
                    and isinstance(v, int | float) and not isinstance(v, bool)})
    listed += [{"key": k, "label": k.replace("_", " ")} for k in extra]
    start_branch = next((i for i, b in enumerate(branches) if b["contact"]),
                        len(branches) - 1)
    specials = [_clean(dict(s)) for s in result.special_points
                if all(isinstance(s.get(k), int | float) for k in (axes["x"], axes["y"]))]
    click = _isolated(ResultData(result.path, result.kind, result.title, result.parameter,
                                 result.diameter, result.closed, result.units,
                                 tuple(b for b in result.branches if b.points),
                                 result.special_points), axes, start_branch)
    return {"title": result.title, "kind": result.kind, "units": result.units,
            "closed": result.closed, "diameter": result.diameter,
            "extent": extent or 0.5, "axes": axes, "numbers": listed,
            "branches": branches, "special_points": specials,
            "style": style.viewer_style(),
            "start": {"branch": start_branch,
                      "index": len(branches[start_branch]["points"]) // 2, "click": click}}


def _template() -> str:
    return resources.files("supercoil.plotting").joinpath("viewer_template.html") \
        .read_text(encoding="utf-8")


def _html_escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def viewer_html(result: ResultData) -> str:
    """The page as one string: template + data (``</`` escaped inside the script)."""
    payload = viewer_payload(result)
    data = json.dumps(payload, separators=(",", ":"), allow_nan=False, ensure_ascii=False)
    data = data.replace("</", "<\\/")
    return _template().replace("__TITLE__", _html_escape(f"supercoil: {result.title}")) \
        .replace("__DATA__", data)


def write_viewer(result: ResultData, path: str | os.PathLike) -> Path:
    """Write the page to ``path`` atomically (temporary file + rename)."""
    path = Path(path)
    html = viewer_html(result)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(html)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
