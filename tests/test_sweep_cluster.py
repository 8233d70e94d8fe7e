"""Sweeps on real Dask clusters: a LocalCluster of two worker processes, a scheduler and
a worker started as separate processes on 127.0.0.1, a worker killed mid-sweep and
the sweep interrupted and resumed.

Oracles: each task's result file equals the same study run alone in this process
(every stored array, to 1e-12), and its cells in the dataset equal the summary of
that lone run; the same sweep gives equal datasets on either cluster, and a sweep
that lost a worker, was interrupted and then resumed gives the dataset of the
sweep that ran straight through.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
xr = pytest.importorskip("xarray")

import interruptible
from test_sweep import sweep_text

from supercoil import load
from supercoil.api.study_run import run_study
from supercoil.io.study import parse_study
from supercoil.sweeps.dataset import load_sweep
from supercoil.sweeps.grid import load_sweep_study
from supercoil.sweeps.summary import summarize

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT = 300

RINGS = sweep_text('"problem.excess_link" = [1.0, 2.0, 3.0]\n"rod.twist_ratio" = [0.6667, 1.0]\n')

# open rods without contact, each a few seconds: long enough to kill a worker mid-task
TWEEZERS = """
[rod]
twist_ratio = 1.3333333333333333
nodes = 12
[problem]
kind = "tweezers"
tension = 10.0
turns = [0.0, 1.5]
[outputs]
figures = false
json = false
[sweep]
"problem.tension" = [4.0, 8.0, 12.0, 16.0]
"""


def _env() -> dict:
    path = os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)
    return dict(os.environ, PYTHONPATH=path)


def _sweep_command(study: Path, out: Path, *args: str) -> list[str]:
    return [sys.executable, "-m", "supercoil.cli.main", "sweep", str(study), "--out", str(out),
            "-q", *args]


def _sweep(study: Path, out: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(_sweep_command(study, out, *args), capture_output=True, text=True,
                          env=_env(), timeout=TIMEOUT, check=False)


def _branches(result) -> list:
    return list(result.branches.values())


def _assert_same_result(a, b) -> None:
    assert a.status == b.status and a.message == b.message
    assert [x.name for x in _branches(a)] == [x.name for x in _branches(b)]
    for x, y in zip(_branches(a), _branches(b), strict=True):
        for name in ("parameter_values", "states", "multipliers", "tangents", "arclength"):
            np.testing.assert_allclose(getattr(x, name), getattr(y, name), rtol=1e-12,
                                       atol=1e-12, err_msg=f"{x.name}.{name}")
        for name in ("unstable_count", "zero_modes", "determinant_sign"):
            np.testing.assert_array_equal(getattr(x, name), getattr(y, name))
        assert sorted(x.records) == sorted(y.records)
        for name in x.records:
            np.testing.assert_allclose(x.records[name], y.records[name], rtol=1e-12,
                                       atol=1e-12, err_msg=f"{x.name} record {name}")
        assert [(p.kind, p.index) for p in x.special_points] == [
            (p.kind, p.index) for p in y.special_points]


@pytest.fixture(scope="module")
def rings(tmp_path_factory):
    """The ring sweep run on a LocalCluster of two workers: (study, out, process)."""
    folder = tmp_path_factory.mktemp("rings")
    study = folder / "rings.toml"
    study.write_text(RINGS, encoding="utf-8")
    out = folder / "local"
    with _held_port(8787):  # dask's default port, as another cluster would hold it
        return study, out, _sweep(study, out, "--workers", "2")


@contextlib.contextmanager
def _held_port(port: int):
    """Listen on ``port`` (if it is free; else someone else holds it already)."""
    holder = socket.socket()
    try:
        holder.bind(("", port))
        holder.listen()
    except OSError:
        pass
    try:
        yield
    finally:
        holder.close()


def test_local_cluster_tasks_equal_the_studies_run_alone(rings, tmp_path):
    study, out, done = rings
    assert done.returncode == 0, done.stderr
    assert "already in use" not in done.stderr  # the cluster's ports are free ones
    dataset = load_sweep(out)
    sweep = load_sweep_study(study)
    assert dataset["status"].shape == (3, 2) and set(dataset["status"].values.ravel()) == {
        "complete"}
    assert "LocalCluster, 2 worker(s)" == dataset.attrs["cluster"]
    for task in sweep.tasks:
        alone = tmp_path / task.key
        alone.mkdir()
        spec = parse_study(task.text, str(study))
        run_study(spec, alone)
        expected = load(alone / "result.h5")
        _assert_same_result(load(out / "tasks" / task.key / "result.h5"), expected)
        cell = dataset.isel({"problem.excess_link": task.index[0],
                             "rod.twist_ratio": task.index[1]})
        assert str(cell["task"].values) == task.key
        for name, value in summarize(expected).items():
            if isinstance(value, str):
                assert str(cell[name].values) == value
            else:
                np.testing.assert_allclose(float(cell[name]), value, rtol=1e-12, atol=1e-12,
                                           err_msg=name)
    assert {"ring.end.writhe", "ring.end.twist", "ring.end.unstable_count"} <= set(dataset)


def _start(args: list[str], log: Path) -> subprocess.Popen:
    with log.open("w") as handle:
        return subprocess.Popen(args, stdout=handle, stderr=subprocess.STDOUT, env=_env())


def _stop(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def test_a_scheduler_and_a_worker_on_the_loopback_address(rings, tmp_path):
    study, local, done = rings
    assert done.returncode == 0, done.stderr
    address_file = tmp_path / "scheduler.json"
    dask = [sys.executable, "-m", "dask"]
    scheduler = _start([*dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                        "--no-dashboard", "--scheduler-file", str(address_file)],
                       tmp_path / "scheduler.log")
    worker = None
    try:
        deadline = time.monotonic() + 60
        while not address_file.is_file() and time.monotonic() < deadline:
            assert scheduler.poll() is None, (tmp_path / "scheduler.log").read_text()
            time.sleep(0.2)
        address = json.loads(address_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        worker = _start([*dask, "worker", address, "--nthreads", "1", "--nworkers", "1",
                         "--host", "127.0.0.1", "--no-dashboard"], tmp_path / "worker.log")
        out = tmp_path / "remote"
        run = _sweep(study, out, "--scheduler", address)
        assert run.returncode == 0, run.stderr
    finally:
        for process in (worker, scheduler):
            if process is not None:
                _stop(process)
    remote = load_sweep(out)
    assert remote.attrs["cluster"] == address
    xr.testing.assert_equal(remote, load_sweep(local))  # equal sweeps, equal datasets


def _wait_for(condition, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + TIMEOUT
    while not condition():
        assert process.poll() is None, "the sweep ended before it could be interrupted"
        assert time.monotonic() < deadline
        time.sleep(0.1)


def _started(tasks: Path) -> int:
    return len(list(tasks.iterdir())) if tasks.is_dir() else 0


def _completed(tasks: Path) -> int:
    done = 0
    for folder in tasks.iterdir() if tasks.is_dir() else ():
        try:
            done += load(folder / "result.h5").status == "complete"
        except ValueError:  # not there yet, or caught in the middle of a write
            pass
    return done


def _worker_processes(pid: int) -> list:
    import psutil

    children = psutil.Process(pid).children(recursive=True)
    return [p for p in children if "spawn_main" in " ".join(p.cmdline())]


def test_killed_worker_and_interrupted_sweep_resume_to_the_same_dataset(tmp_path):
    study = tmp_path / "tweezers.toml"
    study.write_text(TWEEZERS, encoding="utf-8")
    straight = _sweep(study, tmp_path / "straight", "--workers", "2")
    assert straight.returncode == 0, straight.stderr
    expected = load_sweep(tmp_path / "straight")

    out = tmp_path / "interrupted"
    process = interruptible.popen(_sweep_command(study, out, "--workers", "2"), env=_env(),
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: _started(out / "tasks") >= 2, process)  # both workers busy
        workers = _worker_processes(process.pid)
        assert len(workers) == 2
        workers[0].send_signal(signal.SIGKILL)  # its task is lost and run again
        _wait_for(lambda: _completed(out / "tasks") >= 1, process)
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=TIMEOUT)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 1, err
    assert "interrupted" in err and "--resume" in err
    partial = load_sweep(out)
    statuses = list(partial["status"].values)
    assert "not run" in statuses

    resumed = _sweep(study, out, "--workers", "2", "--resume")
    assert resumed.returncode == 0, resumed.stderr
    final = load_sweep(out)
    # every task complete before the interruption is kept, not run again
    assert final.attrs["tasks_resumed"] >= max(1, statuses.count("complete"))
    xr.testing.assert_equal(final, expected)


def test_a_local_cluster_leaves_the_callers_environment_as_it_was(monkeypatch):
    """The workers get one thread each through their environment, which distributed's
    nanny sets in the calling process too before it spawns them; the caller's own
    environment is restored when the cluster closes (oracle: the variables before and
    after, one of them set to another value and one absent before)."""
    import os

    from supercoil.sweeps import driver

    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    names = [*driver.ONE_THREAD, "PYTHONHASHSEED"]
    before = {name: os.environ.get(name) for name in names}
    with driver._client(1, None, 0) as client:
        assert client.submit(os.environ.get, "NUMBA_NUM_THREADS", pure=False).result() == "1"
    assert {name: os.environ.get(name) for name in names} == before
