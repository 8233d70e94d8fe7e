"""Figures of a sweep (``supercoil sweep``'s folder): hat curves at every force, maps.

Plotting never computes: the curves are the tasks' stored branches
(``DIR/tasks/<key>/result.h5``), the maps the dataset's cells (``DIR/sweep.nc``).

* ``hat-curves`` (tweezers sweeps): extension against end rotation of every task
  on one axes, a colour per task (labelled by its swept values), stable
  stretches heavy;
* ``map``: a scalar of the dataset (``--variable``, e.g. ``end_extension``,
  ``buckling_turns``) over the sweep's two dimensions as a coloured grid, or
  against its one dimension as a line; cells without a value (a failed task, a
  branch that never formed) are left blank.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from supercoil.plotting import style

SWEEP_KINDS = ("hat-curves", "map")
DEFAULT_MAP_VARIABLE = {"tweezers": "end_extension", "ring_diagram": "folds",
                        "ring": "ring.end.writhe"}


_KEY_LABELS = {"tension": style.LABELS["force"], "twist_ratio": r"twist ratio $C/A$",
               "length_over_diameter": r"$L/D$", "force_pN": r"force $F$ (pN)",
               "salt_mM": "salt (mM)", "superhelical_density": r"superhelical density $\sigma$",
               "base_pairs": "length (bp)"}


def _label(key: str) -> str:
    name = key.rsplit(".", 1)[-1]
    return _KEY_LABELS.get(name) or style.LABELS.get(name, key)


def _cell_label(dataset, index: tuple[int, ...]) -> str:
    parts = []
    for name in dataset["task"].dims:
        for coord in (c for c in dataset.coords if dataset[c].dims == (name,)):
            value = dataset[coord].values[index[dataset["task"].dims.index(name)]]
            text = f"{value:g}" if isinstance(value, (float, np.floating)) else f"{value}"
            parts.append(f"{coord.rsplit('.', 1)[-1]} = {text}")
    return ", ".join(parts)


def sweep_kinds(dataset) -> tuple[str, ...]:
    """The figure kinds a sweep has data for."""
    kinds = ["map"] if 1 <= len(dataset["task"].dims) <= 2 else []
    if dataset.attrs.get("problem") == "tweezers":
        kinds.insert(0, "hat-curves")
    return tuple(kinds)


def hat_curves_figure(dataset, folder: str | os.PathLike):
    """Extension against turns of every finished task of the sweep in ``folder``."""
    from matplotlib.figure import Figure

    from supercoil import load

    tasks = Path(folder) / dataset.attrs.get("tasks_folder", "tasks")
    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.4, style.SINGLE[1] * 1.2))
        ax = fig.subplots()
        n = 0
        for index in np.ndindex(dataset["task"].shape):
            if str(dataset["status"].values[index]) not in ("complete", "incomplete"):
                continue
            result = load(tasks / str(dataset["task"].values[index]) / "result.h5")
            color = style.BRANCH_COLORS[n % len(style.BRANCH_COLORS)]
            branches = result.branches.values()
            label = _cell_label(dataset, index)
            for branch in branches:
                if "extension" not in branch.records or len(branch) == 0:
                    continue
                turns = np.asarray(branch.parameter_values, float)
                extension = np.asarray(branch.records["extension"], float)
                stable = np.asarray(branch.unstable_count) == 0
                ax.plot(turns, extension, color=color, lw=style.UNSTABLE_WIDTH, label=label)
                label = None
                ax.plot(turns, np.where(stable, extension, np.nan), color=color,
                        lw=style.STABLE_WIDTH)
            n += 1
        if n == 0:
            raise ValueError("no finished task with an extension to draw")
        ax.set_xlabel(style.LABELS["turns"])
        ax.set_ylabel(style.LABELS["extension"])
        ax.set_title("hat curves (stable heavy)")
        ax.legend(loc="best")
    return fig


def map_figure(dataset, variable: str):
    """``variable`` over the sweep's dimensions: a grid (two) or a line (one)."""
    from matplotlib.figure import Figure

    if variable not in dataset.data_vars or dataset[variable].dtype.kind != "f":
        numbers = [v for v in dataset.data_vars if dataset[v].dtype.kind == "f"]
        raise ValueError(f"--variable {variable!r} is not a number of this sweep; numbers: "
                         f"{', '.join(numbers[:12])}{', ...' if len(numbers) > 12 else ''}")
    data = dataset[variable]
    dims = data.dims
    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.3, style.SINGLE[1] * 1.2))
        ax = fig.subplots()
        if len(dims) == 1:
            x = _axis_values(dataset, dims[0])
            ax.plot(x, data.values, marker="o", color=style.BRANCH_COLORS[0])
            ax.set_xlabel(_label(dims[0]))
            ax.set_ylabel(_label(variable))
        elif len(dims) == 2:
            y, x = (_axis_values(dataset, d) for d in dims)
            mesh = ax.pcolormesh(_edges(x), _edges(y), np.ma.masked_invalid(data.values),
                                 shading="flat", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=_label(variable))
            ax.set_xlabel(_label(dims[1]))
            ax.set_ylabel(_label(dims[0]))
            ax.grid(False)
        else:
            raise ValueError(f"a map needs a sweep of one or two dimensions; this one has "
                             f"{len(dims)} ({', '.join(dims)})")
        ax.set_title(variable)
    return fig


def _axis_values(dataset, dim: str) -> np.ndarray:
    """The numbers along ``dim``: its coordinate, or for a zip group its first key's values,
    or the positions 0, 1, ... when they are not numbers."""
    names = [c for c in dataset.coords if dataset[c].dims == (dim,)]
    for name in names:
        if dataset[name].dtype.kind in "iuf":
            return np.asarray(dataset[name].values, float)
    return np.arange(dataset.sizes[dim], dtype=float)


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around ``centres`` (midpoints; half a step beyond the ends)."""
    c = np.asarray(centres, float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = (c[1:] + c[:-1]) / 2
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def plot_sweep(folder: str | os.PathLike, kind: str, out: str | os.PathLike,
               formats: Sequence[str] = style.FORMATS, variable: str | None = None
               ) -> list[Path]:
    """Draw ``kind`` of the sweep in ``folder`` into ``out`` (created if missing):
    ``hat_curves.<fmt>`` or ``map_<variable>.<fmt>`` for each format."""
    from supercoil.sweeps.dataset import load_sweep

    dataset = load_sweep(folder)
    folder = Path(folder)
    if folder.is_file():
        folder = folder.parent
    if kind == "hat-curves":
        fig, stem = hat_curves_figure(dataset, folder), "hat_curves"
    elif kind == "map":
        variable = variable or DEFAULT_MAP_VARIABLE.get(str(dataset.attrs.get("problem")), "")
        fig, stem = map_figure(dataset, variable), f"map_{variable.replace('.', '_')}"
    else:
        raise ValueError(f"figure kind {kind!r}: give one of {', '.join(SWEEP_KINDS)}")
    Path(out).mkdir(parents=True, exist_ok=True)
    return style.save(fig, Path(out) / stem, formats)


__all__ = ["SWEEP_KINDS", "hat_curves_figure", "map_figure", "plot_sweep", "sweep_kinds"]
