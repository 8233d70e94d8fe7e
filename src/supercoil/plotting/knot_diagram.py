"""Figures of a knotted ring's diagram (``supercoil diagram knot``), as PNG files.

Plotting never computes: the values are those of :func:`supercoil.knot_diagram`'s
summary. ``link_writhe.png`` is the ring diagram's figure (dLk against Wr),
``energy.png`` the energy against dLk (stable parts heavy, special points
marked by kind), ``configurations.png`` a few states drawn as tubes of
diameter D (:mod:`supercoil.plotting.figures`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from supercoil.plotting import figures, style


def draw_knot_figures(out: Path, link_rows: Sequence[Mapping], energy_rows: Sequence[Mapping],
                      special_points: Sequence[Mapping], configurations: Sequence[Mapping],
                      diameter: float, title: str) -> None:
    """``link_writhe.png``, ``energy.png`` and ``configurations.png`` in ``out``."""
    style.save(figures.link_writhe_figure(link_rows, special_points, title=title),
               Path(out) / "link_writhe.png")
    style.save(figures.diagram_figure(energy_rows, special_points, title=title,
                                      x="excess_link", y="energy"),
               Path(out) / "energy.png")
    style.save(figures.configurations_figure(configurations, diameter=diameter, title=title),
               Path(out) / "configurations.png")
