"""Study files from Python: what ``supercoil run`` and ``supercoil sweep`` do.

* :func:`run`: one study (a TOML file, or its tables as a dict) into an output
  folder -- ``result.h5`` saved point by point, the JSON summary and the figures
  the study asks for -- returning the stored result;
* :func:`sweep`: a study with a ``[sweep]`` table over a grid of parameters, on
  a local Dask cluster or an existing one, returning the ``xarray`` dataset.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from supercoil.errors import InputError

log = logging.getLogger(__name__)


def _study_text(study) -> tuple[str, str]:
    """``(text, source)`` of a study given as a TOML file or as a dict of tables."""
    if isinstance(study, Mapping):
        from supercoil.sweeps.grid import toml_text

        return toml_text(dict(study)), "<study>"
    if isinstance(study, (str, Path)):
        path = Path(study)
        try:
            return path.read_text(encoding="utf-8"), str(path)
        except FileNotFoundError:
            raise InputError(f"study: {path}: no such study file", name="study") from None
        except IsADirectoryError:
            raise InputError(f"study: {path}: is a folder; give a study file (.toml)",
                             name="study") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"study: {path}: cannot read the study file ({exc})",
                             name="study") from None
    raise InputError(f"study: expected a TOML file or a dict of its tables, got "
                     f"{type(study).__name__}", name="study")


def study_mismatch(stored, spec) -> str | None:
    """The first computed setting that differs between a stored result and a study
    (:class:`~supercoil.io.study.Study`), or None; presentation keys aside."""
    from supercoil.api.recording import plain

    if stored.problem != spec.kind:
        return f"problem {stored.problem!r}, the study's {spec.kind!r}"
    have = {k: v for k, v in stored.settings.items() if k not in ("study", "outputs")}
    want = plain(spec.computed_settings())
    for table in sorted(set(have) | set(want)):
        a, b = have.get(table, {}), want.get(table, {})
        for key in sorted(set(a) | set(b)):
            x, y = a.get(key), b.get(key)
            if not _same(x, y):
                return f"[{table}] {key} = {x!r} in the file, {y!r} in the study"
    return None


def _same(x, y) -> bool:
    if isinstance(x, float) or isinstance(y, float):
        try:
            return math.isclose(float(x), float(y), rel_tol=1e-12, abs_tol=0.0)
        except (TypeError, ValueError):
            return False
    return x == y


def _default_folder(study) -> Path:
    if isinstance(study, (str, Path)):
        return Path(Path(study).stem)
    raise InputError("out: give the output folder (a study given as a dict has no name to "
                     "take it from)", name="out")


def run(study, out: str | Path | None = None, *, overrides: Iterable[str] = (),
        resume: bool = False, overwrite: bool = False,
        progress: Callable[[str], None] | None = None, on_point: Callable | None = None):
    """Run ``study`` -- a study file (TOML; ``examples/*.toml``) or its tables as a dict
    (``{"rod": {...}, "problem": {...}, ...}``) -- into the folder ``out`` (default: the
    file's name without ``.toml``) and return the stored result (:func:`supercoil.load`'s).

    ``result.h5`` is written point by point, then the JSON summary (``[outputs] json``)
    and the figures (``[outputs] figures``). ``overrides``: ``"TABLE.KEY=VALUE"``
    strings (TOML values) applied first. An existing non-empty ``out`` is refused unless
    ``overwrite`` (its result, summary and figures replaced) or ``resume`` (an
    interrupted run of the same study continued). ``progress(message)`` receives the
    lines worth showing; ``on_point(branch)`` is called after every stored point, as by
    :func:`supercoil.ring_diagram`. The result's ``status`` says how the run ended (``complete``, ``incomplete``,
    ``interrupted``); Ctrl-C during the run stores ``interrupted``.
    """
    from supercoil.api.recording import RESULT_FILE
    from supercoil.api.study_run import run_study
    from supercoil.io.store import load
    from supercoil.io.study import parse_study

    text, source = _study_text(study)
    spec = parse_study(text, source, tuple(overrides))
    folder = _default_folder(study) if out is None else Path(out)
    if resume and overwrite:
        raise InputError("resume and overwrite exclude each other: resume continues the "
                         "folder's result, overwrite replaces it")
    if folder.exists() and not folder.is_dir():
        raise InputError(f"out: {folder} is a file; give a folder", name="out")
    result_path = folder / RESULT_FILE
    if resume:
        stored = load(result_path)
        mismatch = study_mismatch(stored, spec)
        if mismatch:
            raise InputError(f"resume: {result_path} was computed with another study "
                             f"({mismatch})", name="resume")
        if stored.status in ("complete", "incomplete"):
            return stored
    elif folder.is_dir() and any(folder.iterdir()) and not overwrite:
        raise InputError(f"out: {folder} exists and is not empty; give a new folder, "
                         "resume=True or overwrite=True", name="out")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"out: cannot create {folder} ({exc.strerror or exc})",
                         name="out") from None
    outcome = run_study(spec, folder, resume=resume, progress=progress, on_point=on_point)
    if outcome["status"] == "interrupted" and not outcome.get("resumable", True):
        log.warning("interrupted while drawing the figures: the data are complete in %s; draw "
                    "the figures with supercoil.plot", result_path.resolve())
    return load(result_path)


def sweep(study, out: str | Path | None = None, *, workers: int | None = None,
          scheduler: str | None = None, resume: bool = False, overwrite: bool = False):
    """Run the sweep study ``study`` (a study file with a ``[sweep]`` table, or its tables
    as a dict) into the folder ``out`` (default: the file's name without ``.toml``) and
    return its dataset (``xarray.Dataset``, one dimension per swept key, with each task's
    status and message; also ``out/sweep.nc``).

    Each grid point is one task, computed as :func:`run` computes a study, into
    ``out/tasks/<key>/``; on ``workers`` local processes (default: the usable cores) or
    on the Dask cluster whose scheduler is at ``scheduler`` (``tcp://HOST:PORT``).
    ``resume``: tasks already finished in ``out`` are kept; ``overwrite``: ``out``'s
    previous sweep is deleted first.
    """
    import os
    import shutil

    from supercoil.sweeps.dataset import load_sweep
    from supercoil.sweeps.driver import run_sweep
    from supercoil.sweeps.grid import parse_sweep_study

    text, source = _study_text(study)
    plan = parse_sweep_study(text, source)
    folder = _default_folder(study) if out is None else Path(out)
    if workers is not None and scheduler is not None:
        raise InputError("workers and scheduler exclude each other: workers starts a local "
                         "cluster, scheduler uses an existing one")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise InputError(f"workers: got {workers!r}; give a number of processes, 1 or more",
                         name="workers")
    if scheduler is not None and "://" not in scheduler:
        raise InputError(f"scheduler: {scheduler!r}; give the scheduler's address with its "
                         "protocol, like tcp://HOST:8786", name="scheduler")
    if resume and overwrite:
        raise InputError("resume and overwrite exclude each other: resume keeps the folder's "
                         "tasks, overwrite deletes them")
    tasks = folder / "tasks"
    if folder.exists() and not folder.is_dir():
        raise InputError(f"out: {folder} is a file; give a folder", name="out")
    if resume and not tasks.is_dir():
        raise InputError(f"resume: {tasks} does not exist; nothing to resume", name="resume")
    if not resume and folder.is_dir() and any(folder.iterdir()):
        if not overwrite:
            raise InputError(f"out: {folder} exists and is not empty; give a new folder, "
                             "resume=True or overwrite=True", name="out")
        shutil.rmtree(tasks, ignore_errors=True)
        (folder / "sweep.nc").unlink(missing_ok=True)
    if workers is None and scheduler is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
            os.cpu_count() or 1)
    outcome = run_sweep(plan, folder, workers=workers, scheduler=scheduler, resume=resume)
    return load_sweep(outcome.dataset)
