"""The sweep's dataset: every task's summary in one labelled array per quantity.

:func:`build_dataset` gathers the outcomes of a sweep's tasks into an
``xarray.Dataset`` with one dimension per swept key (a ``zip`` group's keys share
one dimension, named by the keys joined with ``+``; each key is a coordinate
along it). Its data variables:

* ``task`` (the task key: the task's result file is ``tasks/<task>/result.h5``
  beside the dataset), ``status`` (``complete``, ``incomplete``, ``failed``,
  ``interrupted``, or ``not run`` when the sweep stopped first) and ``message``;
* every summary of :mod:`supercoil.sweeps.summary` (the union over the tasks,
  sorted by name): numbers as float64 (NaN where a task has no value), strings
  ("" where it has none).

Timings, hosts and the time of writing go in the attributes only
(``task_timings`` as JSON, ``created``, ...), so two equal sweeps give equal
datasets (``xarray.Dataset.equals``). :func:`write_dataset` writes netCDF-4
(engine ``h5netcdf``) through a temporary file and a rename, so ``sweep.nc`` is
always whole; :func:`load_sweep` reads it back.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from supercoil.errors import InputError

DATASET_NAME = "sweep.nc"
TASKS_FOLDER = "tasks"
NOT_RUN = "not run"
RESERVED = ("task", "status", "message")


def _values_array(values: tuple) -> np.ndarray:
    if all(isinstance(v, bool) for v in values):
        return np.array(values, dtype=bool)
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=np.int64)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=np.float64)
    return np.array([str(v) for v in values], dtype=object)


def build_dataset(sweep, outcomes: dict, attrs: dict | None = None):
    """The dataset of ``sweep`` (a :class:`~supercoil.sweeps.grid.SweepStudy`) from
    ``outcomes``: task key -> ``{"status", "message", "values"}`` (a task without an
    outcome is ``not run``); ``attrs`` are added to the dataset's attributes."""
    import xarray as xr

    dims = tuple(d.name for d in sweep.dimensions)
    shape = sweep.shape
    coords = {}
    for d in sweep.dimensions:
        for key, values in zip(d.keys, d.values, strict=True):
            coords[key] = (d.name, _values_array(values))
    names: dict[str, str] = {}  # summary name -> "number" or "string"
    for outcome in outcomes.values():
        for name, value in outcome.get("values", {}).items():
            kind = "string" if isinstance(value, str) else "number"
            if names.get(name) != "string":
                names[name] = kind
    data = {name: np.full(shape, "", dtype=object) for name in RESERVED}
    for name, kind in names.items():
        data[name] = (np.full(shape, "", dtype=object) if kind == "string"
                      else np.full(shape, math.nan))
    for task in sweep.tasks:
        outcome = outcomes.get(task.key)
        data["task"][task.index] = task.key
        if outcome is None:
            data["status"][task.index] = NOT_RUN
            data["message"][task.index] = "not run: the sweep stopped first; --resume runs it"
            continue
        data["status"][task.index] = outcome["status"]
        data["message"][task.index] = outcome["message"]
        for name, value in outcome.get("values", {}).items():
            data[name][task.index] = str(value) if names[name] == "string" else float(value)
    variables = {name: (dims, data[name]) for name in (*RESERVED, *sorted(names))}
    dataset = xr.Dataset(variables, coords=coords)
    dataset.attrs.update({"title": "supercoil sweep", "problem": sweep.kind,
                          "sweep": json.dumps(sweep.record()), "study_file": sweep.source,
                          "study": sweep.text, "tasks_folder": TASKS_FOLDER})
    dataset.attrs.update(attrs or {})
    return dataset


def write_dataset(dataset, path: str | Path) -> Path:
    """Write ``dataset`` to ``path`` (netCDF-4 by h5netcdf) through a temporary file in
    the same folder, renamed over ``path`` once complete."""
    path = Path(path)
    partial = path.with_name(f".{path.name}.partial")
    dataset.to_netcdf(partial, engine="h5netcdf")
    os.replace(partial, path)
    return path


def load_sweep(path: str | Path):
    """The ``xarray.Dataset`` of a sweep: ``path`` is its ``sweep.nc`` or the folder
    holding it (the ``--out`` folder of ``supercoil sweep``)."""
    import xarray as xr

    path = Path(path)
    if path.is_dir():
        path = path / DATASET_NAME
    if not path.is_file():
        raise InputError(f"{path}: no such sweep dataset (supercoil sweep writes "
                         f"DIR/{DATASET_NAME})")
    try:
        return xr.load_dataset(path, engine="h5netcdf")
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: not a readable sweep dataset ({' '.join(str(exc).split())})"
                         ) from None
