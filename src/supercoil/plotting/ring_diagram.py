"""Figures of the ring's bifurcation diagram (seed 001, Figures 1-4).

Plotting never computes: every value drawn is passed in (see
:meth:`supercoil.problems.ring_diagram.RingDiagram.payload` for the data).

* :func:`plot_link_writhe`: excess link against writhe, stable stretches
  heavy, special points marked by kind (Figures 1 and 2);
* :func:`plot_contact_map`: arc-length positions s/L of the contacts against
  the writhe (Figure 4), contact points as dots, intervals as vertical bars;
* :func:`plot_configurations`: a few centrelines drawn as tubes of diameter D
  (Figure 3), as thick lines in projection (line width = D in data units).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np

_MARKERS = {"bifurcation": ("o", "C3"), "fold": ("s", "C2"), "contact_onset": ("v", "C1"),
            "contact_release": ("^", "C4"), "contact_split": ("D", "C5"),
            "contact_interval_onset": ("P", "C6"), "endpoint": ("x", "k")}


def plot_link_writhe(path: str | os.PathLike, *, branches: Sequence[Mapping],
                     special_points: Sequence[Mapping], title: str) -> None:
    """ΔLk against Wr. ``branches``: ``{name, writhe (k,), excess_link (k,), stable (k,)}``;
    ``special_points``: ``{kind, writhe, excess_link}``. Stable parts heavy, unstable thin."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 5.5), layout="constrained")
    ax = fig.subplots()
    for index, b in enumerate(branches):
        wr = np.asarray(b["writhe"], float)
        lk = np.asarray(b["excess_link"], float)
        stable = np.asarray(b["stable"], bool)
        color = f"C{index % 10}"
        ax.plot(wr, lk, "-", lw=0.8, color=color, label=b["name"])
        heavy_lk = np.where(stable, lk, np.nan)
        # a stable stretch includes the segments joining two stable points
        ax.plot(wr, heavy_lk, "-", lw=3.0, color=color)
    seen = set()
    for p in special_points:
        marker, color = _MARKERS.get(p["kind"], ("*", "k"))
        ax.plot(p["writhe"], p["excess_link"], marker, color=color, ms=6, mfc="none",
                label=None if p["kind"] in seen else p["kind"])
        seen.add(p["kind"])
    ax.set_xlabel("writhe Wr")
    ax.set_ylabel(r"excess link $\Delta Lk$ (turns)")
    ax.set_title(title + "\nheavy: stable (unstable_count = 0, no zero modes)",
                 fontsize="medium")
    ax.legend(fontsize="small", loc="best")
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=120)


def plot_contact_map(path: str | os.PathLike, *, branches: Sequence[Mapping],
                     title: str) -> None:
    """s/L of the contacts against Wr. ``branches``: ``{name, writhe (k,), contact_points
    (k lists of {s1, s2}), contact_intervals (k lists of {s1_start, s1_end, s2_start,
    s2_end})}``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 5), layout="constrained")
    ax = fig.subplots()
    drawn = False
    for index, b in enumerate(branches):
        color = f"C{index % 10}"
        xs, ys = [], []
        for wr, points, intervals in zip(b["writhe"], b["contact_points"],
                                         b["contact_intervals"], strict=True):
            for p in points:
                xs += [wr, wr]
                ys += [p["s1"], p["s2"]]
            for iv in intervals:
                for start, end in ((iv["s1_start"], iv["s1_end"]),
                                   (iv["s2_start"], iv["s2_end"])):
                    pieces = [(start, end)] if start <= end else [(start, 1.0), (0.0, end)]
                    for a, e in pieces:
                        ax.plot([wr, wr], [a, e], "-", color=color, lw=2)
        if xs or any(b["contact_intervals"]):
            ax.plot(xs, ys, ".", ms=3, color=color, label=b["name"])
            drawn = True
    if not drawn:
        ax.text(0.5, 0.5, "no contacts on the computed branches", ha="center",
                transform=ax.transAxes)
    ax.set_ylim(0, 1)
    ax.set_xlabel("writhe Wr")
    ax.set_ylabel("s / L of the contacts")
    ax.set_title(title + "\ndots: contact points, bars: contact intervals", fontsize="medium")
    if drawn:
        ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=120)


def plot_configurations(path: str | os.PathLike, *, configurations: Sequence[Mapping],
                        diameter: float, title: str) -> None:
    """Centrelines ``{label, points (n, 3)}`` drawn as tubes of ``diameter`` (units of L).

    Each is projected on the plane of its two largest principal axes and drawn
    as a closed thick line whose width is ``diameter`` in data units; depth
    (the third axis) shades the line so crossings read as over or under.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    n = max(1, len(configurations))
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig = Figure(figsize=(3.3 * cols, 3.3 * rows + 0.5), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    for ax, conf in zip(axes, configurations, strict=False):
        x = np.asarray(conf["points"], float).reshape(-1, 3)
        x = x - x.mean(axis=0)
        _, _, vt = np.linalg.svd(x, full_matrices=False)
        p = x @ vt.T
        closed = np.vstack([p, p[:1]])
        segs = np.stack([closed[:-1, :2], closed[1:, :2]], axis=1)
        depth = 0.5 * (closed[:-1, 2] + closed[1:, 2])
        order = np.argsort(depth)  # far segments first, near ones drawn over them
        span = float(np.ptp(closed[:, :2], axis=0).max()) * 1.15 + diameter
        ax.set_xlim(-span / 2, span / 2)
        ax.set_ylim(-span / 2, span / 2)
        ax.set_aspect("equal")
        fig.canvas.draw() if hasattr(fig.canvas, "draw") else None
        width_pt = diameter / span * ax.bbox.height * 72.0 / fig.dpi
        shade = (depth - depth.min()) / (np.ptp(depth) or 1.0)
        colors = [(0.15 + 0.6 * s, 0.35 + 0.4 * s, 0.8, 1.0) for s in shade[order]]
        ax.add_collection(LineCollection(segs[order], linewidths=max(width_pt, 0.5),
                                         colors=colors, capstyle="round"))
        ax.set_title(conf["label"], fontsize="small")
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in axes[len(configurations):]:
        ax.axis("off")
    fig.suptitle(title + f" (tubes of diameter D = {diameter:.3g} L, projected)",
                 fontsize="medium")
    fig.savefig(path, dpi=120)
