"""Figures of the ring's bifurcation diagram (Coleman & Swigon 2002, Figures 1-4), as PNG files.

Plotting never computes: every value drawn is passed in (see
:meth:`supercoil.problems.ring_diagram.RingDiagram.payload` for the data).
The drawing is :mod:`supercoil.plotting.figures`' (one house style with
``supercoil plot``); these functions keep the names ``supercoil diagram ring``
calls.

* :func:`plot_link_writhe`: excess link against writhe, stable stretches
  heavy, special points marked by kind (Figures 1 and 2);
* :func:`plot_contact_map`: arc-length positions s/L of the contacts against
  the writhe (Figure 4), contact points as dots, intervals as vertical bars;
* :func:`plot_configurations`: a few centrelines drawn as tubes of diameter D
  (Figure 3), as thick lines in projection (line width = D in data units).

Each figure can also be a *job* ``(path, builder, keyword arguments)``, plain
data that :func:`draw_job` draws (builders named ``ring:...``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from supercoil.plotting import figures, style


def plot_link_writhe(path: str | os.PathLike, *, branches: Sequence[Mapping],
                     special_points: Sequence[Mapping], title: str) -> None:
    """ΔLk against Wr. ``branches``: ``{name, writhe (k,), excess_link (k,), stable (k,)}``;
    ``special_points``: ``{kind, writhe, excess_link}``. Stable parts heavy, unstable thin."""
    fig = figures.link_writhe_figure(branches, special_points, title=title)
    style.save(fig, path)


def plot_contact_map(path: str | os.PathLike, *, branches: Sequence[Mapping],
                     title: str) -> None:
    """s/L of the contacts against Wr. ``branches``: ``{name, writhe (k,), contact_points
    (k lists of {s1, s2}), contact_intervals (k lists of {s1_start, s1_end, s2_start,
    s2_end})}``."""
    style.save(figures.contact_map_figure(branches, title=title), path)


def plot_configurations(path: str | os.PathLike, *, configurations: Sequence[Mapping],
                        diameter: float, title: str) -> None:
    """Centrelines ``{label, points (n, 3)}`` (optionally ``contact_points``,
    ``contact_intervals``) drawn as tubes of ``diameter`` (units of L), projected on
    the plane of their two largest principal axes, far segments first."""
    fig = figures.configurations_figure(configurations, diameter=diameter, title=title)
    style.save(fig, path)


BUILDERS = {"ring:link_writhe": plot_link_writhe, "ring:contact_map": plot_contact_map,
            "ring:configurations": plot_configurations}


def draw_job(job: tuple[str | os.PathLike, str, dict]) -> Path:
    """Draw one job ``(path, builder, keyword arguments)`` (builders: :data:`BUILDERS`)."""
    path, builder, kwargs = job
    BUILDERS[builder](path, **kwargs)
    return Path(path)


def draw_jobs(jobs: Sequence[tuple]) -> None:
    """Draw ``jobs`` one after the other (:func:`draw_job`)."""
    for job in jobs:
        draw_job(job)
