"""Running a sweep's tasks on Dask (``dask.distributed``).

:func:`run_sweep` submits one task per distinct study of the grid
(:class:`~supercoil.sweeps.grid.SweepStudy`) to a ``LocalCluster`` of
``workers`` processes (one thread each; OpenBLAS, MKL, OpenMP and numba set to one
thread before the process starts; the numba cache of this process, shared, so
kernels compiled once load everywhere) or to the scheduler at ``scheduler``
(an existing cluster: the workers import supercoil and see the output folder).

A task (:func:`run_task`) runs its study with ``supercoil run``'s code
(:func:`supercoil.api.study_run.run_study`) into ``DIR/tasks/<key>/`` and returns its
status, message and summary (:func:`supercoil.sweeps.summary.summarize` of the
result file it wrote). A failure inside the study is an outcome (status
``failed`` and the exception's message), not an error of the sweep. A worker that
dies (killed, out of memory) loses only the task it was running, which the
scheduler runs again on another worker, up to ``retries`` times; the task's
Dask key is derived from its task key and the output folder.

With ``resume``, a task whose result file is finished (``complete``, or
``incomplete``: a branch stopped early, which a new run would repeat) and was
computed from the same settings (its task key) is not run again: its summary is
read from the file. Results are written as tasks finish; the dataset
(:mod:`supercoil.sweeps.dataset`) is written at the end, or when the sweep is
interrupted (Ctrl-C), with the tasks not run marked so.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import logging
import os
import socket
import time
from datetime import UTC, datetime
from pathlib import Path

from supercoil.api.recording import RESULT_FILE
from supercoil.errors import InputError
from supercoil.sweeps.dataset import DATASET_NAME, TASKS_FOLDER, build_dataset, write_dataset
from supercoil.sweeps.grid import task_key
from supercoil.sweeps.summary import summarize

log = logging.getLogger(__name__)

FINISHED = ("complete", "incomplete")
ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1"}
DEFAULT_RETRIES = 3
CONNECT_TIMEOUT = "10s"
POLL_SECONDS = 0.5


@dataclasses.dataclass(frozen=True)
class SweepOutcome:
    """What :func:`run_sweep` did: the dataset's path, the number of grid points
    (``total``) and of tasks run, resumed and not finished (``failed``: any status
    but ``complete``), and whether the sweep was interrupted."""

    dataset: Path
    total: int
    run: int
    resumed: int
    failed: int
    interrupted: bool
    statuses: dict


class _Silent:
    """The progress interface of :func:`run_sweep`, doing nothing."""

    def start(self, total: int, resumed: int) -> None:
        pass

    def update(self, done: int, running: int, failed: int) -> None:
        pass

    def finished(self, label: str, status: str, message: str) -> None:
        pass


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}".rstrip(": ")


# ----------------------------------------------------------------------------- a task
def run_task(key: str, text: str, source: str, folder: str) -> dict:
    """Run one task (on a worker): the study ``text`` into ``folder``; its outcome
    ``{"key", "status", "message", "values", "seconds", "host"}``."""
    from threadpoolctl import threadpool_limits

    start = time.perf_counter()
    folder = Path(folder)
    try:
        from supercoil import load
        from supercoil.api.study_run import run_study
        from supercoil.io.study import parse_study

        spec = parse_study(text, source)
        folder.mkdir(parents=True, exist_ok=True)
        with threadpool_limits(limits=1, user_api="blas"):
            outcome = run_study(spec, folder)
        status, message = outcome["status"], outcome["message"]
        values = summarize(load(folder / RESULT_FILE))
    except Exception as exc:  # noqa: BLE001 - a failure of the study is the task's outcome
        status, message, values = "failed", _one_line(exc), {}
    return {"key": key, "status": status, "message": " ".join(str(message).split()),
            "values": values, "seconds": time.perf_counter() - start,
            "host": socket.gethostname()}


def stored_outcome(folder: Path, key: str) -> dict | None:
    """The outcome of a task already computed in ``folder`` (for ``--resume``): None
    unless its result file is readable, finished, and of the settings of ``key``."""
    path = Path(folder) / RESULT_FILE
    if not path.is_file():
        return None
    from supercoil import load

    try:
        stored = load(path)
        if stored.status not in FINISHED or task_key(stored.settings) != key:
            return None
        values = summarize(stored)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        log.info("%s: not reused (%s)", path, _one_line(exc))
        return None
    return {"key": key, "status": stored.status,
            "message": " ".join(str(stored.message).split()), "values": values}


# ----------------------------------------------------------------------------- the cluster
@contextlib.contextmanager
def _client(workers: int | None, scheduler: str | None, retries: int):
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"--scheduler {scheduler}: cannot reach a Dask scheduler there "
                             f"({_one_line(exc)}); give the address its scheduler prints, "
                             "like tcp://HOST:8786") from None
        with client:
            yield client
        return
    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.update(ONE_THREAD)
    if "NUMBA_CACHE_DIR" in os.environ:
        environ["NUMBA_CACHE_DIR"] = os.environ["NUMBA_CACHE_DIR"]
    config = {"distributed.nanny.pre-spawn-environ": environ,
              "distributed.scheduler.allowed-failures": retries}
    # the nanny sets its pre-spawn environment in this process too, before each worker
    # it spawns (distributed's Nanny documents it): without the restore the caller's
    # process keeps NUMBA_NUM_THREADS=1, and numba refuses its next compilation there
    # ("Cannot set NUMBA_NUM_THREADS to a different value once the threads have been
    # launched")
    with _environ_restored([*environ, "PYTHONHASHSEED"]):
        with dask.config.set(config):
            # no dashboard; the scheduler's own HTTP server (health, metrics) on a free
            # port, not on the default 8787, which a second sweep or another dask
            # cluster on the machine may hold
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR,
                                   scheduler_kwargs={"dashboard_address": ":0"})
        with cluster, Client(cluster, set_as_default=False) as client:
            yield client


@contextlib.contextmanager
def _environ_restored(names):
    """The environment variables ``names`` as they were on entry, restored on exit
    (set again, or removed where they were not set)."""
    before = {name: os.environ.get(name) for name in names}
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _folder_token(out: Path) -> str:
    return hashlib.sha256(str(out).encode("utf-8")).hexdigest()[:8]


def _future_outcome(future, key: str) -> dict:
    if future.status == "finished":
        return future.result()
    try:
        exc = future.exception()
    except BaseException as err:  # noqa: BLE001 - cancelled: the scheduler lost the task
        exc = err
    message = _one_line(exc)
    if type(exc).__name__ == "KilledWorker":
        message = (f"the workers running this task died repeatedly ({message}); "
                   "see the workers' logs (memory, time limits)")
    return {"key": key, "status": "failed", "message": message, "values": {}}


def _running(client, ours: set) -> int:
    try:
        processing = client.processing()
    except (OSError, TimeoutError):
        return 0
    return sum(1 for keys in processing.values() for k in keys if k in ours)


# ----------------------------------------------------------------------------- the sweep
def run_sweep(sweep, out: str | Path, *, workers: int | None = None,
              scheduler: str | None = None, resume: bool = False, progress=None,
              retries: int = DEFAULT_RETRIES) -> SweepOutcome:
    """Run ``sweep`` into folder ``out`` (``out/tasks/<key>/``, ``out/sweep.nc``):
    on a local cluster of ``workers`` processes, or on the cluster whose scheduler
    is at ``scheduler``. ``progress`` has ``start(total, resumed)``,
    ``update(done, running, failed)`` and ``finished(label, status, message)``."""
    progress = progress or _Silent()
    out = Path(out).resolve()
    tasks_dir = out / TASKS_FOLDER
    tasks_dir.mkdir(parents=True, exist_ok=True)
    unique = sweep.unique_tasks()
    outcomes: dict[str, dict] = {}
    todo = []
    for key, task in unique.items():
        stored = stored_outcome(tasks_dir / key, key) if resume else None
        if stored is None:
            todo.append(task)
        else:
            outcomes[key] = stored
    resumed = len(outcomes)
    failed = sum(o["status"] != "complete" for o in outcomes.values())
    progress.start(len(unique), resumed)
    started = time.perf_counter()
    interrupted = False
    timings = {}
    n_workers = None if scheduler is not None else max(1, min(workers or 1, len(todo)))
    if todo:
        token = _folder_token(out)
        with _client(n_workers, scheduler, retries) as client, client.as_current():
            futures = {}
            for task in todo:
                future = client.submit(run_task, task.key, task.text, sweep.source,
                                       str(tasks_dir / task.key), pure=False, retries=retries,
                                       key=f"supercoil-task-{task.key}-{token}")
                futures[future] = task
            ours = {f.key for f in futures}
            pending = set(futures)
            try:
                while pending:
                    try:
                        done, pending = _wait(pending)
                    except TimeoutError:
                        done = set()
                    for future in done:
                        task = futures[future]
                        outcome = _future_outcome(future, task.key)
                        future.release()
                        ours.discard(future.key)
                        outcomes[task.key] = outcome
                        timings[task.key] = {k: outcome[k] for k in ("seconds", "host")
                                             if k in outcome}
                        failed += outcome["status"] != "complete"
                        progress.finished(task.label(), outcome["status"], outcome["message"])
                    progress.update(len(outcomes), _running(client, ours), failed)
            except KeyboardInterrupt:
                interrupted = True
                client.cancel(list(pending))
    attrs = {"created": datetime.now(UTC).isoformat(timespec="seconds"),
             "host": socket.gethostname(),
             "cluster": scheduler or f"LocalCluster, {n_workers} worker(s)",
             "wall_seconds": round(time.perf_counter() - started, 3),
             "tasks_resumed": resumed, "task_timings": _json(timings)}
    from supercoil import __version__

    attrs["supercoil_version"] = __version__
    dataset = build_dataset(sweep, outcomes, attrs)
    path = write_dataset(dataset, out / DATASET_NAME)
    statuses: dict[str, int] = {}
    for value in dataset["status"].values.ravel():
        statuses[str(value)] = statuses.get(str(value), 0) + 1
    total = len(sweep.tasks)
    return SweepOutcome(path, total, len(outcomes) - resumed, resumed,
                        total - statuses.get("complete", 0), interrupted, statuses)


def _wait(pending: set):
    from distributed import wait

    done, not_done = wait(list(pending), timeout=POLL_SECONDS, return_when="FIRST_COMPLETED")
    return set(done), set(not_done)


def _json(value) -> str:
    import json

    return json.dumps(value, sort_keys=True)
