"""Publication figures of a result: diagram, contact map, hat curve, configurations.

Plotting never computes: every value drawn comes from the result
(:mod:`supercoil.plotting.result_data`). Each ``*_figure`` builds a matplotlib
:class:`~matplotlib.figure.Figure` in the house style
(:mod:`supercoil.plotting.style`); :func:`plot_result` draws one kind of
figure of a result and saves it as PNG and SVG.

* ``diagram``: the branch parameter against the writhe (ring: ΔLk against Wr,
  Coleman & Swigon 2002, Figures 1-2), stable stretches heavy, special points by kind;
* ``contact-map``: s/L of the contacts against the writhe (Coleman & Swigon
  2002, Figure 4),
  contact points as dots, contact intervals as bars;
* ``hat-curve``: extension against end rotation (tweezers), stable heavy;
* ``configurations``: a few centrelines as tubes of diameter D, contacts in red.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from supercoil.plotting import style
from supercoil.plotting.result_data import ResultData, stable_mask

KINDS = ("diagram", "contact-map", "hat-curve", "configurations")


def _label(key: str) -> str:
    return style.LABELS.get(key, key.replace("_", " "))


# ------------------------------------------------------------------- builders


DIAGRAM_SIZE = (style.SINGLE[0] * 1.5, style.SINGLE[1] * 1.25)  # inches


def diagram_figure(branches: Sequence[Mapping], special_points: Sequence[Mapping], *,
                   title: str, x: str = "writhe", y: str = "excess_link",
                   legend_title: str | None = None,
                   secondary: Mapping[str, tuple[str, float]] | None = None,
                   caption: str | None = None):
    """``y`` against ``x``. ``branches``: ``{name, <x> (k,), <y> (k,), stable (k,)}`` and
    optionally ``color`` and ``linestyle`` (a matplotlib dash pattern);
    ``special_points``: ``{kind, <x>, <y>}``. Stable parts heavy, unstable thin.
    ``secondary``: ``{"x" or "y": (label, factor)}``, a second axis (top or right) reading
    the values times ``factor`` (σ beside turns); ``caption``: text under the axes."""
    from matplotlib.figure import Figure

    with style.styled():
        fig = Figure(figsize=DIAGRAM_SIZE)
        ax = fig.subplots()
        _draw_diagram(fig, ax, branches, special_points, title=title, x=x, y=y,
                      legend_title=legend_title, secondary=secondary, caption=caption)
    return fig


def _secondary_axes(ax, secondary: Mapping[str, tuple[str, float]]) -> list:
    """The top (``x``) or right (``y``) axes reading the values times a factor."""
    made = []
    for axis, (label, factor) in secondary.items():
        functions = (lambda v, f=factor: v * f, lambda v, f=factor: v / f)
        if axis == "x":
            ax.tick_params(axis="x", top=False)
            made.append(ax.secondary_xaxis("top", functions=functions))
            made[-1].set_xlabel(label)
        else:
            ax.tick_params(axis="y", right=False)
            made.append(ax.secondary_yaxis("right", functions=functions))
            made[-1].set_ylabel(label)
    return made


def _draw_diagram(fig, ax, branches: Sequence[Mapping], special_points: Sequence[Mapping], *,
                  title: str, x: str, y: str, legend_title: str | None,
                  secondary: Mapping[str, tuple[str, float]] | None = None,
                  caption: str | None = None) -> None:
    """Draw :func:`diagram_figure`'s lines, labels and legend on ``ax`` of ``fig`` (an
    axes without lines, at its subplot position) and lay them out."""
    from matplotlib.lines import Line2D

    handles = []
    for index, b in enumerate(branches):
        xs = np.asarray(b[x], float)
        ys = np.asarray(b[y], float)
        stable = np.asarray(b["stable"], bool)
        color = b.get("color") or style.branch_color(index)
        ls = b.get("linestyle", "-")  # secondary / tertiary dashed (Coleman & Swigon 2002)
        ax.plot(xs, ys, ls=ls, lw=style.UNSTABLE_WIDTH, color=color)
        # a stable stretch includes the segments joining two stable points
        ax.plot(xs, np.where(stable, ys, np.nan), ls=ls, lw=style.STABLE_WIDTH, color=color)
        handles.append(Line2D([], [], color=color, lw=2.0, ls=ls, label=b["name"]))
    seen: set[str] = set()
    for p in special_points:
        marker, color = style.special_marker(p["kind"])
        ax.plot(p[x], p[y], marker, color=color, ms=6, mfc="none", mew=1.4, zorder=5)
        if p["kind"] not in seen:
            seen.add(p["kind"])
            handles.append(Line2D([], [], ls="", marker=marker, color=color, mfc="none",
                                  mew=1.4, label=p["kind"].replace("_", " ")))
    handles += [Line2D([], [], color="0.3", lw=style.STABLE_WIDTH, label="stable"),
                Line2D([], [], color="0.3", lw=style.UNSTABLE_WIDTH, label="unstable")]
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    ax.set_title(title)
    extra = _secondary_axes(ax, secondary or {})
    # beside the axes: branches cross the whole diagram, so no corner is free
    legend = fig.legend(handles=handles, loc="upper left", title=legend_title)
    note = None if caption is None else fig.text(0, 0, caption, ha="left", va="bottom",
                                                 fontsize="small", color="0.25")
    _fit_beside_legend(fig, ax, legend, note, extra)


LAYOUT_PAD = 6.0  # points between the figure's edge, the axes' decorations and the legend


def _fit_beside_legend(fig, ax, legend, caption=None, extra=()) -> None:
    """Place ``ax`` to fill ``fig`` with its tick labels, axis labels and title inside,
    and ``legend`` beside it on the right, top-aligned (what matplotlib's constrained
    layout does with ``loc="outside right upper"``, from the axes' decorations alone).

    The decorations are measured once at the first position, the axes moved so that
    they fit with :data:`LAYOUT_PAD` around them, then measured again at the new
    position (the tick locator may choose other ticks for another length) and the
    margins widened where they grew. Constrained layout solves the same margins in two
    passes of its own over the whole figure, about half of the time a figure takes to
    save. A ``caption`` (a figure text) goes under everything, at the left; ``extra``:
    artists whose extent counts with the decorations (secondary axes).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    pad = LAYOUT_PAD * fig.dpi / 72.0
    legend_width = legend.get_window_extent(renderer).width
    below = 0.0  # pixels under the axes' decorations taken by the caption
    if caption is not None:
        caption.set_position((pad / width, pad / height))
        below = caption.get_window_extent(renderer).height + pad
    # margins (pixels) of the decorations around the axes box: left, right, bottom, top
    margins = np.zeros(4)
    for _ in range(2):
        box = ax.get_position().transformed(fig.transFigure)
        tight = ax.get_tightbbox(renderer, bbox_extra_artists=list(extra))
        grown = np.array([box.x0 - tight.x0, tight.x1 - box.x1, box.y0 - tight.y0,
                          tight.y1 - box.y1])
        if np.all(grown <= margins):
            break
        margins = np.maximum(margins, grown)
        left = margins[0] + pad
        right = width - pad - legend_width - pad - margins[1]
        bottom = margins[2] + pad + below
        top = height - pad - margins[3]
        if right - left < 0.3 * width or top - bottom < 0.3 * height:
            break  # a legend or labels too wide for the figure: keep what fits
        ax.set_position([left / width, bottom / height, (right - left) / width,
                         (top - bottom) / height])
    box = ax.get_position().transformed(fig.transFigure)
    legend.set_bbox_to_anchor(((box.x1 + margins[1] + pad) / width, box.y1 / height),
                              transform=fig.transFigure)


def link_writhe_figure(branches: Sequence[Mapping], special_points: Sequence[Mapping], *,
                       title: str):
    """ΔLk against Wr (Coleman & Swigon 2002, Figures 1-2); see :func:`diagram_figure`."""
    return diagram_figure(branches, special_points, title=title, x="writhe", y="excess_link")


def contact_map_figure(branches: Sequence[Mapping], *, title: str, x: str = "writhe"):
    """s/L of the contacts against ``x``. ``branches``: ``{name, <x> (k,), contact_points
    (k lists of {s1, s2}), contact_intervals (k lists of {s1_start, s1_end, s2_start,
    s2_end})}``."""
    from matplotlib.figure import Figure

    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.25, style.SINGLE[1] * 1.2),
                     layout="constrained")
        ax = fig.subplots()
        drawn = False
        for index, b in enumerate(branches):
            color = b.get("color") or style.branch_color(index)
            xs, ys, bars = [], [], []
            for xv, points, intervals in zip(b[x], b["contact_points"],
                                             b["contact_intervals"], strict=True):
                for p in points:
                    xs += [xv, xv]
                    ys += [p["s1"], p["s2"]]
                for iv in intervals:
                    for start, end in ((iv["s1_start"], iv["s1_end"]),
                                       (iv["s2_start"], iv["s2_end"])):
                        pieces = [(start, end)] if start <= end else [(start, 1.0), (0.0, end)]
                        bars += [[(xv, a), (xv, e)] for a, e in pieces]
            if bars:
                from matplotlib.collections import LineCollection

                ax.add_collection(LineCollection(bars, colors=color, linewidths=1.5))
            if xs or bars:
                ax.plot(xs, ys, ".", ms=3.5, color=color, label=b["name"])
                drawn = True
        if not drawn:
            ax.text(0.5, 0.5, "no contacts on the computed branches", ha="center",
                    transform=ax.transAxes)
        ax.autoscale_view()
        ax.set_ylim(0, 1)
        ax.set_xlabel(_label(x))
        ax.set_ylabel("contact positions " + _label("arclength"))
        ax.set_title(title + "\ndots: contact points, bars: contact intervals")
        if drawn:
            ax.legend(loc="best")
    return fig


def hat_curve_figure(branches: Sequence[Mapping], special_points: Sequence[Mapping], *,
                     title: str):
    """Extension against end rotation (turns), stable heavy; see :func:`diagram_figure`."""
    specials = [p for p in special_points if "turns" in p and "extension" in p]
    return diagram_figure(branches, specials, title=title, x="turns", y="extension")


def _arc_positions(points: np.ndarray, closed: bool) -> np.ndarray:
    """s/L of every node, shape ``(n,)`` (nodes equally spaced in arc length)."""
    n = len(points)
    return np.arange(n) / (n if closed else n - 1)


def _segment_contact(s_mid: np.ndarray, conf: Mapping) -> np.ndarray:
    """True for segments whose midpoint lies in a contact interval or near a contact point."""
    hit = np.zeros(len(s_mid), bool)
    step = 1.0 / max(len(s_mid), 1)
    for iv in conf.get("contact_intervals", ()):
        for a, e in ((iv["s1_start"], iv["s1_end"]), (iv["s2_start"], iv["s2_end"])):
            hit |= ((s_mid >= a) & (s_mid <= e)) if a <= e else ((s_mid >= a) | (s_mid <= e))
    for p in conf.get("contact_points", ()):
        for s in (p["s1"], p["s2"]):
            d = np.abs(s_mid - s)
            hit |= np.minimum(d, 1.0 - d) <= 1.5 * step
    return hit


CELL = 2.7  # inches: one configuration's cell
SUPTITLE = 0.32  # inches above the cells for the figure's title
CELL_PAD = 0.04  # inches around each axes
CELL_TITLE = 0.22  # inches above each axes for its label (font size "small")


def configurations_figure(configurations: Sequence[Mapping], *, diameter: float | None,
                          title: str, closed: bool = True):
    """Centrelines ``{label, points (n, 3), contact_points?, contact_intervals?}`` as tubes.

    Each is projected on the plane of its two largest principal axes and drawn
    as thick segments of width ``diameter`` in data units (units of L), far
    segments first so crossings read as over or under; depth shades the tube,
    a thin light line on top gives it relief, contacts are red.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgb
    from matplotlib.figure import Figure

    n = max(1, len(configurations))
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    base = np.array(to_rgb(style.TUBE_COLOR))
    red = np.array(to_rgb(style.CONTACT_COLOR))
    with style.styled():
        # a fixed grid (no tick labels to fit): cells of CELL inches under a band of
        # SUPTITLE inches, each axes a square below its title, so that the tubes' line
        # widths in data units follow from the layout without a layout pass
        cell, band, pad, title_band = CELL, SUPTITLE, CELL_PAD, CELL_TITLE
        width_in, height_in = cell * cols, cell * rows + band
        fig = Figure(figsize=(width_in, height_in))
        side = cell - 2 * pad - title_band  # inches: each axes' square
        axes = []
        for index in range(rows * cols):
            row, col = divmod(index, cols)
            left = col * cell + 0.5 * (cell - side)
            bottom = height_in - band - (row + 1) * cell + pad
            axes.append(fig.add_axes((left / width_in, bottom / height_in, side / width_in,
                                      side / height_in)))
        prepared = []
        for ax, conf in zip(axes, configurations, strict=False):
            x = np.asarray(conf["points"], float).reshape(-1, 3)
            x = x - x.mean(axis=0)
            _, _, vt = np.linalg.svd(x, full_matrices=False)
            p = x @ vt.T
            p[:, :2] -= 0.5 * (p[:, :2].min(axis=0) + p[:, :2].max(axis=0))  # box centred
            width = diameter if diameter else 0.01 * float(np.ptp(p[:, :2], axis=0).max())
            span = float(np.ptp(p[:, :2], axis=0).max()) * 1.1 + width
            ax.set_xlim(-span / 2, span / 2)
            ax.set_ylim(-span / 2, span / 2)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.grid(False)
            ax.set_title(conf["label"], fontsize="small")
            prepared.append((ax, conf, p, width, span))
        for ax in axes[len(configurations):]:
            ax.axis("off")
        for ax, conf, p, width, span in prepared:
            path = np.vstack([p, p[:1]]) if closed else p
            s_mid = _arc_positions(p, closed)[: len(path) - 1] + 0.5 / (
                len(p) if closed else len(p) - 1)
            segs = np.stack([path[:-1, :2], path[1:, :2]], axis=1)
            depth = 0.5 * (path[:-1, 2] + path[1:, 2])
            shade = (depth - depth.min()) / (np.ptp(depth) or 1.0)  # 1 = nearest
            contact = _segment_contact(s_mid, conf)
            body = np.where(contact[:, None], red, base) * (0.55 + 0.45 * shade[:, None])
            light = body + 0.55 * (1.0 - body)
            width_pt = max(width / span * side * 72.0, 0.6)  # the axes' side in points
            order = np.argsort(depth)  # far segments first, near ones drawn over them
            lines = np.empty((2 * len(order), 2, 2))
            lines[0::2] = segs[order]
            lines[1::2] = segs[order] + np.array([-0.18, 0.18]) * width
            colors = np.empty((2 * len(order), 3))
            colors[0::2] = body[order]
            colors[1::2] = light[order]
            widths = np.empty(2 * len(order))
            widths[0::2] = width_pt
            widths[1::2] = 0.3 * width_pt
            ax.add_collection(LineCollection(lines, linewidths=widths, colors=colors,
                                             capstyle="round"))
        suffix = (f" (tubes of diameter D = {diameter:.3g} L, projected)" if diameter
                  else " (centrelines, projected)")
        fig.suptitle(title + suffix, fontsize="medium")
    return fig


# -------------------------------------------------------------------- results


def supported_kinds(result: ResultData) -> tuple[str, ...]:
    """The figure kinds that ``result`` has data for."""
    kinds = ["diagram"] if result.kind == "ring" else ["hat-curve"]
    if any(p.get("contact_points") is not None for b in result.branches for p in b.points):
        kinds.append("contact-map")
    readable = [b.has_states for b in result.branches if b.points]  # reads every file
    if any(readable):
        kinds.append("configurations")
    if result.kind == "tweezers" and all(
            "writhe" in p for b in result.branches for p in b.points):
        kinds.insert(1, "diagram")
    return tuple(k for k in KINDS if k in kinds)


def branch_rows(result: ResultData, keys: Sequence[str]) -> list[dict]:
    """The branches of a stored result as the rows a figure draws: ``name``, ``stable``
    (per point), ``color`` (by the branch's place), ``linestyle`` (by its generation:
    secondary branches dashed) and the values of each of ``keys``."""
    rows = []
    for index, b in enumerate(result.branches):
        row = {"name": b.name, "stable": stable_mask(b.points),
               "color": style.branch_color(index),
               "linestyle": style.generation_style(b.generation)}
        for key in keys:
            row[key] = b.values(key)
        rows.append(row)
    return rows


def through_special_points(row: Mapping, specials: Sequence[Mapping],
                           keys: Sequence[str]) -> dict:
    """``row`` (a branch's ``keys`` and ``stable`` per point) with its located special
    points inserted where they lie (after point ``index``), each twice: with the
    stability before it (``count_before == 0``), then after it. A stable stretch is
    then drawn heavy up to the located point (the circle up to Michell's point), not
    only up to the last stable sample. Special points without ``index``,
    ``count_before``, ``count_after`` or one of ``keys`` are left out.
    """
    k = len(row["stable"])
    # sort keys (segment position, arclength within it, before/after): several special
    # points on one segment (two bifurcations between two widely spaced samples of a
    # straight rod) follow each other by arclength, each one's pair kept together
    entries = [((float(i), 0.0, 0), [row[key][i] for key in keys], bool(row["stable"][i]))
               for i in range(k)]
    for order, p in enumerate(specials):
        if p.get("branch", row.get("name")) != row.get("name"):
            continue
        try:
            at = int(p["index"]) + 0.5
            values = [float(p[key]) for key in keys]
            before, after = int(p["count_before"]), int(p["count_after"])
            along = float(p.get("arclength", order))
        except (KeyError, TypeError, ValueError):
            continue
        if not 0 <= at < k:
            continue
        entries.append(((at, along, 0), values, before == 0))
        entries.append(((at, along, 1), values, after == 0))
    entries.sort(key=lambda e: e[0])
    out = dict(row)
    for j, key in enumerate(keys):
        out[key] = np.array([e[1][j] for e in entries], dtype=float)
    out["stable"] = np.array([e[2] for e in entries], dtype=bool)
    return out


def _specials(result: ResultData, keys: Sequence[str]) -> list[Mapping]:
    return [p for p in result.special_points
            if all(isinstance(p.get(k), int | float) and math.isfinite(p[k]) for k in keys)]


def configuration_picks(result: ResultData) -> list[tuple[str, int]]:
    """(branch, index) of the configurations drawn: the contact branches (else every
    branch with states) at a third, two thirds and their end."""
    with_states = [b for b in result.branches if b.points and b.has_states]
    picked = [b for b in with_states if b.contact] or with_states
    out = []
    for b in picked:
        k = len(b.points)
        out += [(b.name, i) for i in sorted({k // 3, 2 * k // 3, k - 1})]
    return out


def figure_of(result: ResultData, kind: str):
    """The figure ``kind`` (one of :data:`KINDS`) of ``result``; ValueError if it has no data."""
    if kind not in supported_kinds(result):
        valid = ", ".join(supported_kinds(result)) or "none"
        raise ValueError(f"{result.path}: a {result.kind} result has no data for a {kind} "
                         f"figure; kinds it has: {valid}")
    param = result.parameter
    if kind in ("diagram", "hat-curve"):
        keys = ("writhe", param) if kind == "diagram" else ("turns", "extension")
        specials = _specials(result, keys)
        rows = [through_special_points(r, specials, keys) for r in branch_rows(result, keys)]
        if result.dna is None:
            return diagram_figure(rows, specials, title=result.title, x=keys[0], y=keys[1])
        from supercoil.plotting.dna import caveat_text

        x, y, secondary = result.dna.axes(*keys)
        return diagram_figure([result.dna.in_dna_units(r) for r in rows],
                              [result.dna.in_dna_units(p) for p in specials],
                              title=result.title, x=x, y=y, secondary=secondary,
                              caption=caveat_text() if kind == "hat-curve" else None)
    if kind == "contact-map":
        x = "writhe" if result.kind == "ring" else "turns"
        rows = []
        for index, b in enumerate(result.branches):
            if not any(p.get("contact_points") or p.get("contact_intervals")
                       for p in b.points):
                continue
            rows.append({"name": b.name, x: b.values(x), "color": style.branch_color(index),
                         "contact_points": [p.get("contact_points") or [] for p in b.points],
                         "contact_intervals": [p.get("contact_intervals") or []
                                               for p in b.points]})
        return contact_map_figure(rows, title=result.title, x=x)
    configurations = []
    for name, index in configuration_picks(result):
        b = result.branch(name)
        states = b.states()
        if states is None:
            continue
        p = b.points[index]
        label = (f"{name}, {'ΔLk' if param == 'excess_link' else 'n'} = "
                 f"{float(p[param]):.3f}, Wr = {_number_text(p.get('writhe'))}")
        if result.dna is not None:
            label = f"{name}, σ = {float(p[param]) / result.dna.relaxed_link:.4f}, " + \
                label.split(", ", 2)[-1]
        configurations.append({"label": label, "points": states[index],
                               "contact_points": p.get("contact_points") or [],
                               "contact_intervals": p.get("contact_intervals") or []})
    if not configurations:
        raise ValueError(f"{result.path}: the branch files with the states are missing; "
                         "configurations need them (result.h5 beside the summary)")
    return configurations_figure(configurations, diameter=result.diameter,
                                 title=result.title, closed=result.closed)


def _number_text(value) -> str:
    try:
        return f"{float(value):.3f}"
    except (TypeError, ValueError):
        return "?"


def output_stem(kind: str) -> str:
    """File name (without suffix) of a figure kind: ``contact-map`` -> ``contact_map``."""
    return kind.replace("-", "_")


def plot_result(result: ResultData, kind: str, folder: str | os.PathLike,
                formats: Sequence[str] = style.FORMATS) -> list[Path]:
    """Draw ``kind`` of ``result`` into ``folder/<kind>.<fmt>`` for each format."""
    fig = figure_of(result, kind)
    return style.save(fig, Path(folder) / output_stem(kind), formats)
