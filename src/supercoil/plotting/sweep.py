"""Figures of a sweep (``supercoil sweep``'s folder): hat curves, maps, buckling torque.

Plotting never computes: the curves are the tasks' stored branches
(``DIR/tasks/<key>/result.h5``), the maps the dataset's cells (``DIR/sweep.nc``).

* ``hat-curves`` (tweezers sweeps): extension against end rotation of every task
  on one axes, a colour per task (labelled by its swept values), stable
  stretches heavy;
* ``curve-map`` (a sweep of one key whose tasks compute branches): a record of
  the branches over the branch parameter and the swept key as a coloured grid:
  extension(turns, force) for tweezers, writhe(dLk, ...) for ring diagrams
  (against the superhelical density sigma = dLk / Lk0 when the tasks are DNA
  plasmids, so that plasmids of different lengths share the axis). A cell holds
  the value of the stable state of least energy at that parameter (energy plus
  the load's potential under a force), linear along each stable stretch of
  the stored points; blank where no stored state is stable;
* ``map``: a scalar of the dataset (``variable``, e.g. ``end_extension``,
  ``buckling_turns``) over the sweep's two dimensions as a coloured grid, or
  against its one dimension as a line; cells without a value (a failed task, a
  branch that never formed) are left blank;
* ``buckling-torque`` (tweezers sweeps over the force): the straight rod's
  torque at buckling against the force, a line per value of the other swept key.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from supercoil.plotting import style

SWEEP_KINDS = ("hat-curves", "curve-map", "map", "buckling-torque")
DEFAULT_MAP_VARIABLE = {"tweezers": "end_extension", "ring_diagram": "folds",
                        "ring": "ring.end.writhe"}
CURVE_RECORD = {"tweezers": "extension", "ring_diagram": "writhe"}  # drawn by curve-map
FORCE_KEYS = ("tension", "force_pN")  # swept keys that are the force
CURVE_MAP_COLUMNS = 200  # cells along the branch parameter


_KEY_LABELS = {"tension": style.LABELS["force"], "twist_ratio": r"twist ratio $C/A$",
               "length_over_diameter": r"$L/D$", "force_pN": r"force $F$ (pN)",
               "salt_mM": "salt (mM)", "superhelical_density": r"superhelical density $\sigma$",
               "base_pairs": "length (bp)", "buckling_torque": style.LABELS["torque"]
               + " at buckling"}


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
    """The figure kinds a sweep has data for, in :data:`SWEEP_KINDS` order."""
    problem = dataset.attrs.get("problem")
    dims = dataset["task"].dims
    kinds = []
    if problem == "tweezers":
        kinds.append("hat-curves")
    if problem in CURVE_RECORD and len(dims) == 1:
        kinds.append("curve-map")
    if 1 <= len(dims) <= 2:
        kinds.append("map")
    if (problem == "tweezers" and "buckling_torque" in dataset.data_vars
            and _force_dim(dataset) is not None and len(dims) <= 2):
        kinds.append("buckling-torque")
    return tuple(kinds)


def _force_dim(dataset) -> str | None:
    """The swept dimension that carries the force (``problem.tension`` or ``force_pN``)."""
    for dim in dataset["task"].dims:
        for coord in (c for c in dataset.coords if dataset[c].dims == (dim,)):
            if coord.rsplit(".", 1)[-1] in FORCE_KEYS:
                return dim
    return None


def _finished(dataset) -> list[tuple[int, ...]]:
    """The cells whose task stored branches (``complete`` or ``incomplete``)."""
    return [index for index in np.ndindex(dataset["task"].shape)
            if str(dataset["status"].values[index]) in ("complete", "incomplete")]


def _task_result(dataset, folder, index):
    from supercoil import load

    tasks = Path(folder) / dataset.attrs.get("tasks_folder", "tasks")
    return load(tasks / str(dataset["task"].values[index]) / "result.h5")


def hat_curves_figure(dataset, folder: str | os.PathLike):
    """Extension against turns of every finished task of the sweep in ``folder``: one
    labelled line per task (its swept values), its stable stretches heavy."""
    from matplotlib.figure import Figure

    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.4, style.SINGLE[1] * 1.2))
        ax = fig.subplots()
        n = 0
        for index in _finished(dataset):
            result = _task_result(dataset, folder, index)
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


def _branch_samples(branch, record: str):
    """``(parameter, record, energy, stable)`` along ``branch``: its stored points with its
    special points between them. A bifurcation or a fold is where the stability changes,
    and counts as stable (a stable stretch reaches it); another special point is stable
    where both its neighbours are. The energy is the elastic energy plus the load's
    potential when the branch has one (the Gibbs energy under a dead load)."""
    def energy(records):
        return sum(float(np.asarray(records[name])) if np.ndim(records[name]) == 0
                   else np.asarray(records[name], float)
                   for name in ("energy", "load_potential") if name in records)

    x = list(np.asarray(branch.parameter_values, float))
    y = list(np.asarray(branch.records[record], float))
    e = list(np.broadcast_to(energy(branch.records), (len(x),)).astype(float))
    stable = list(np.asarray(branch.unstable_count) == 0)
    extra = []
    for p in branch.special_points:
        i = int(p.index)
        if record not in p.records or not 0 <= i < len(x) - 1:
            continue
        marginal = p.kind in ("bifurcation", "fold") or (stable[i] and stable[i + 1])
        extra.append((i, float(p.arclength), float(p.parameter),
                      float(np.asarray(p.records[record])), float(energy(p.records)), marginal))
    for i, _s, px, py, pe, ps in sorted(extra, key=lambda t: (t[0], t[1]), reverse=True):
        x.insert(i + 1, px)
        y.insert(i + 1, py)
        e.insert(i + 1, pe)
        stable.insert(i + 1, ps)
    return np.array(x), np.array(y), np.array(e), np.array(stable, dtype=bool)


def _stable_curve(result, record: str, grid: np.ndarray, scale: float) -> np.ndarray:
    """``record`` of the stable state of least energy at each ``grid`` value of the branch
    parameter (times ``scale``), linear along the stable stretches; NaN where none."""
    best = np.full(grid.shape, np.inf)
    out = np.full(grid.shape, np.nan)
    for branch in result.branches.values():
        if record not in branch.records or len(branch) < 2:
            continue
        x, y, energy, stable = _branch_samples(branch, record)
        x = x * scale
        for i in np.flatnonzero(stable[:-1] & stable[1:]):
            lo, hi = sorted((x[i], x[i + 1]))
            cells = np.flatnonzero((grid >= lo) & (grid <= hi))
            if not cells.size:
                continue
            t = (grid[cells] - x[i]) / (x[i + 1] - x[i]) if hi > lo else np.zeros(cells.size)
            e = energy[i] + t * (energy[i + 1] - energy[i])
            lower = e < best[cells]
            best[cells[lower]] = e[lower]
            out[cells[lower]] = (y[i] + t * (y[i + 1] - y[i]))[lower]
    return out


def curve_map_figure(dataset, folder: str | os.PathLike, record: str | None = None):
    """``record`` of the stored branches over (branch parameter, swept key): a grid of
    the stable state of least energy (module docstring); the sweep has one dimension."""
    from matplotlib.figure import Figure

    problem = str(dataset.attrs.get("problem"))
    record = record or CURVE_RECORD.get(problem, "")
    dims = dataset["task"].dims
    if len(dims) != 1:
        raise ValueError(f"a curve map needs a sweep of one key; this one has {len(dims)} "
                         f"({', '.join(dims)})")
    rows = _axis_values(dataset, dims[0])
    results = {index: _task_result(dataset, folder, index) for index in _finished(dataset)}
    curves = [b for r in results.values() for b in r.branches.values()
              if record in b.records and len(b)]
    if not curves:
        raise ValueError(f"no finished task of this sweep has branches with {record!r}")
    parameter = curves[0].parameter
    scales = {}
    for index, result in results.items():
        relaxed = result.attributes.get("relaxed_link")
        scales[index] = (1.0 / float(relaxed) if parameter == "excess_link" and relaxed
                         else 1.0)
    sigma = parameter == "excess_link" and all(v != 1.0 for v in scales.values())
    if not sigma:
        scales = dict.fromkeys(scales, 1.0)
    low = min(float(np.min(b.parameter_values)) * scales[i] for i, r in results.items()
              for b in r.branches.values() if len(b))
    high = max(float(np.max(b.parameter_values)) * scales[i] for i, r in results.items()
               for b in r.branches.values() if len(b))
    grid = np.linspace(low, high, CURVE_MAP_COLUMNS)
    cells = np.full((len(rows), len(grid)), np.nan)
    for index, result in results.items():
        cells[index[0]] = _stable_curve(result, record, grid, scales[index])
    order = np.argsort(rows, kind="stable")
    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.3, style.SINGLE[1] * 1.2))
        ax = fig.subplots()
        mesh = ax.pcolormesh(_edges(grid), _edges(rows[order]), np.ma.masked_invalid(
            cells[order]), shading="flat", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=style.LABELS.get(record, record))
        ax.set_xlabel(r"superhelical density $\sigma$" if sigma
                      else style.LABELS.get(parameter, parameter))
        ax.set_ylabel(_label(dims[0]))
        ax.grid(False)
        ax.set_title(f"{record} of the stable state of least energy")
    return fig


def buckling_torque_figure(dataset):
    """The straight rod's torque at buckling against the force: one line, or one per value
    of the other swept key."""
    from matplotlib.figure import Figure

    force = _force_dim(dataset)
    if force is None or "buckling_torque" not in dataset.data_vars:
        raise ValueError("buckling torque against force needs a tweezers sweep over the "
                         "force (problem.tension or problem.force_pN)")
    data = dataset["buckling_torque"]
    others = [d for d in data.dims if d != force]
    if len(others) > 1:
        raise ValueError(f"buckling torque against force needs a sweep of at most two keys; "
                         f"this one has {len(data.dims)} ({', '.join(data.dims)})")
    x = _axis_values(dataset, force)
    order = np.argsort(x, kind="stable")
    with style.styled():
        fig = Figure(figsize=(style.SINGLE[0] * 1.3, style.SINGLE[1] * 1.2))
        ax = fig.subplots()
        if not others:
            ax.plot(x[order], data.values[order], marker="o", color=style.BRANCH_COLORS[0])
        else:
            other = others[0]
            values = data.transpose(other, force).values
            for k, value in enumerate(_axis_values(dataset, other)):
                ax.plot(x[order], values[k][order], marker="o",
                        color=style.BRANCH_COLORS[k % len(style.BRANCH_COLORS)],
                        label=f"{_label(other)} = {value:g}")
            ax.legend(loc="best")
        ax.set_xlabel(_label(force))
        ax.set_ylabel(_label("buckling_torque"))
        ax.set_title("torque at buckling")
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


def sweep_stem(dataset, kind: str, variable: str | None = None) -> str:
    """The file name (without suffix) of ``kind`` for ``dataset``."""
    if kind == "map":
        return f"map_{map_variable(dataset, variable).replace('.', '_')}"
    return kind.replace("-", "_")


def map_variable(dataset, variable: str | None = None) -> str:
    """``variable``, or the default map variable of the sweep's problem."""
    return variable or DEFAULT_MAP_VARIABLE.get(str(dataset.attrs.get("problem")), "")


def sweep_figure(dataset, folder: str | os.PathLike, kind: str, variable: str | None = None):
    """The figure ``kind`` of the sweep ``dataset`` stored in ``folder``."""
    if kind == "hat-curves":
        return hat_curves_figure(dataset, folder)
    if kind == "curve-map":
        return curve_map_figure(dataset, folder)
    if kind == "map":
        return map_figure(dataset, map_variable(dataset, variable))
    if kind == "buckling-torque":
        return buckling_torque_figure(dataset)
    raise ValueError(f"figure kind {kind!r}: give one of {', '.join(SWEEP_KINDS)}")


def is_sweep(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a sweep's folder (holding ``sweep.nc``) or its dataset file."""
    from supercoil.sweeps.dataset import DATASET_NAME

    path = Path(path)
    return (path / DATASET_NAME).is_file() if path.is_dir() else path.suffix == ".nc"


def plot_sweep(folder: str | os.PathLike, kind: str, out: str | os.PathLike,
               formats: Sequence[str] = style.FORMATS, variable: str | None = None
               ) -> list[Path]:
    """Draw ``kind`` of the sweep in ``folder`` into ``out`` (created if missing):
    ``hat_curves``, ``curve_map``, ``map_<variable>`` or ``buckling_torque`` with each
    format's suffix."""
    from supercoil.sweeps.dataset import load_sweep

    dataset = load_sweep(folder)
    folder = Path(folder)
    if folder.is_file():
        folder = folder.parent
    fig = sweep_figure(dataset, folder, kind, variable)
    Path(out).mkdir(parents=True, exist_ok=True)
    return style.save(fig, Path(out) / sweep_stem(dataset, kind, variable), formats)


__all__ = ["SWEEP_KINDS", "buckling_torque_figure", "curve_map_figure", "hat_curves_figure",
           "is_sweep", "map_figure", "plot_sweep", "sweep_figure", "sweep_kinds", "sweep_stem"]
