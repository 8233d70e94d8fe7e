"""``supercoil sweep STUDY.toml``: a study over a grid of parameters, on Dask.

Thin: reads and checks the sweep study (:mod:`supercoil.sweeps.grid`: every
point of the grid validated before anything runs), checks the output folder,
runs the tasks (:mod:`supercoil.sweeps.driver`) with a progress bar, and reports.
Dask and xarray are imported inside the command, so ``supercoil --help`` stays
fast.

Exit status: 0 every task complete; 1 the sweep finished (or was interrupted)
with tasks failed, stopped early or not run (the dataset says which, and why);
2 bad input (the study, its ``[sweep]`` table, the options, the folder).
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import EXIT_NOT_CONVERGED, fail, warn

DATASET_NAME = "sweep.nc"  # supercoil.sweeps.dataset (not imported: xarray is slow)
TASKS_FOLDER = "tasks"
MAX_WORKERS = 1024



def sweep_command(
    study: Annotated[Path, typer.Argument(
        metavar="STUDY.toml", help="A study file (as 'supercoil run' takes) with a \\[sweep] "
        "table mapping study keys (\"rod.twist_ratio\", \"problem.tension\", ...) to lists of "
        "values or to {start = ..., stop = ..., num = ...}; zip = [[\"KEY1\", \"KEY2\"]] pairs "
        "lists element by element instead of taking their product. See "
        "examples/sweep_hat_curves.toml.", show_default=False)],
    workers: Annotated[int | None, typer.Option(
        "--workers", metavar="K", help="Worker processes of the local Dask cluster, one "
        f"thread each, 1 to {MAX_WORKERS} (default: the usable cores).",
        show_default=False)] = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", metavar="ADDRESS", help="Run on an existing Dask cluster instead, "
        "reached at its scheduler's address (tcp://HOST:PORT); its workers must import "
        "supercoil and see DIR.", show_default=False)] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue the sweep in DIR: tasks whose result file is finished "
        "and of the same study are not run again.")] = False,
    out: Annotated[Path | None, typer.Option(
        "--out", metavar="DIR", help="Output folder (default: the study's file name without "
        ".toml): DIR/sweep.nc, the dataset, and DIR/tasks/<key>/, each task's result. An "
        "existing non-empty DIR is refused unless --resume or --overwrite.",
        show_default=False)] = None,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Start anew in an existing DIR: its tasks/ folder and sweep.nc "
        "are deleted first (other files are left alone).")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress output.")] = False,
) -> None:
    """Run a study over a grid of parameters, locally or on a Dask cluster: one dataset.

    Each point of the grid is one task, which writes its result file under DIR/tasks/;
    their scalar records and per-branch summaries are gathered into one xarray
    dataset, DIR/sweep.nc (supercoil.load(DIR) reads it), with a dimension per swept
    key and each task's status and message. Ctrl-C or a lost worker loses only the
    tasks that were running: --resume continues."""
    if workers is not None and scheduler is not None:
        fail("--workers and --scheduler exclude each other: --workers starts a local "
             "cluster, --scheduler uses an existing one")
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        fail(f"--workers {workers}: give a number of worker processes from 1 to {MAX_WORKERS}")
    if scheduler is not None and "://" not in scheduler:
        fail(f"--scheduler {scheduler!r}: give the scheduler's address with its protocol, "
             "like tcp://HOST:8786")
    if resume and overwrite:
        fail("--resume and --overwrite exclude each other: --resume keeps DIR's tasks, "
             "--overwrite deletes them")
    from supercoil.errors import InputError
    from supercoil.sweeps.grid import load_sweep_study

    try:
        sweep = load_sweep_study(study)
    except InputError as exc:
        fail(str(exc))
    out = Path(study.stem) if out is None else out
    _prepare_folder(out, resume, overwrite)
    if workers is None and scheduler is None:
        workers = usable_cores()

    from supercoil.sweeps.driver import run_sweep

    n_tasks = len(sweep.tasks)
    if not quiet:
        where = scheduler or f"{workers} local worker(s)"
        shape = " x ".join(f"{d.size} {d.name}" for d in sweep.dimensions)
        print(f"sweep: {n_tasks} tasks ({shape}) of a {sweep.kind} study on {where}",
              file=sys.stderr, flush=True)
    try:
        with SweepProgress(quiet=quiet) as progress:
            outcome = run_sweep(sweep, out, workers=workers, scheduler=scheduler,
                                resume=resume, progress=progress)
    except InputError as exc:
        fail(str(exc))
    counts = ", ".join(f"{n} {status}" for status, n in sorted(outcome.statuses.items()))
    if not quiet:
        resumed = f"; {outcome.resumed} kept from before" if outcome.resumed else ""
        print(f"wrote {DATASET_NAME} ({n_tasks} tasks: {counts}{resumed}) to {out.resolve()}")
    if outcome.interrupted:
        warn(f"interrupted: {outcome.failed} of {n_tasks} tasks not complete ({counts}); "
             f"continue with 'supercoil sweep {study} --out {out} --resume'")
        raise typer.Exit(EXIT_NOT_CONVERGED)
    if outcome.failed:
        warn(f"{outcome.failed} of {n_tasks} tasks failed or stopped early ({counts}); their "
             f"status and message are in {out / DATASET_NAME}")
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _prepare_folder(out: Path, resume: bool, overwrite: bool) -> None:
    """The folder checks (one-line errors, nothing written before they pass)."""
    if out.exists() and not out.is_dir():
        fail(f"--out {out}: is a file, not a folder; give a new folder")
    if resume:
        if not (out / TASKS_FOLDER).is_dir():
            fail(f"--resume: {out / TASKS_FOLDER} does not exist; nothing to resume (run "
                 "without --resume to start)")
        return
    if out.is_dir() and any(out.iterdir()):
        if not overwrite:
            fail(f"--out {out}: folder exists and is not empty; give a new folder, add "
                 "--resume to continue its sweep, or --overwrite to start anew")
        try:
            if (out / TASKS_FOLDER).is_dir():
                shutil.rmtree(out / TASKS_FOLDER)
            (out / DATASET_NAME).unlink(missing_ok=True)
        except OSError as exc:
            fail(f"--out {out}: cannot delete its previous sweep ({exc.strerror or exc})")
    try:
        (out / TASKS_FOLDER).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(f"--out {out}: cannot write there ({exc.strerror or exc}); give a folder in a "
             "writable location")


def usable_cores() -> int:
    """Cores this process may run on (the default number of local workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


class SweepProgress:
    """Tasks done, running and failed, and the time left: a rich bar on a terminal,
    one line per finished task otherwise (standard error); nothing when ``quiet``."""

    def __init__(self, quiet: bool = False, *, live: bool | None = None, stream=None):
        self.quiet = quiet
        self.stream = stream if stream is not None else sys.stderr
        self.live = (sys.stderr.isatty() if live is None else live) and not quiet
        self._bar = None
        self._task = None
        self.total = 0
        self.done = 0
        self._start = time.perf_counter()

    def __enter__(self):
        if self.live:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeRemainingColumn,
            )

            self._bar = Progress(TextColumn("tasks"), BarColumn(), MofNCompleteColumn(),
                                 TextColumn("{task.fields[running]} running, "
                                            "{task.fields[failed]} failed"),
                                 TextColumn("time left"), TimeRemainingColumn(),
                                 console=Console(stderr=True))
            self._bar.start()
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None

    def start(self, total: int, resumed: int) -> None:
        self.total, self.done = total, resumed
        if self._bar is not None:
            self._task = self._bar.add_task("tasks", total=total, completed=resumed,
                                            running=0, failed=0)
        elif not self.quiet and resumed:
            print(f"resume: {resumed} of {total} tasks kept", file=self.stream, flush=True)

    def update(self, done: int, running: int, failed: int) -> None:
        if self._bar is not None and self._task is not None:
            self._bar.update(self._task, completed=done, running=running, failed=failed)

    def finished(self, label: str, status: str, message: str) -> None:
        self.done += 1
        if self.quiet:
            return
        tail = "" if status == "complete" else f": {message}"
        line = f"[{self.done}/{self.total}] {label}: {status}{tail}"
        if self._bar is not None:
            if status != "complete":
                self._bar.console.print(line, highlight=False, markup=False)
            return
        elapsed = time.perf_counter() - self._start
        print(f"{line} ({elapsed:.0f} s)", file=self.stream, flush=True)
