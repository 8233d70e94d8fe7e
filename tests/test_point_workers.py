"""Point workers (supercoil._fork, _Tracer._hand_over): a fork that mirrors the continuation
and evaluates each accepted point must give the serial computation's branches bit for bit.

Oracle: the same run without workers (brute force against the fast path). Every test runs
in a fresh interpreter: pytest's process may hold other threads (JAX's), where nothing
forks by design (supercoil._fork.can_fork).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from supercoil._fork import usable_cores

TESTS = Path(__file__).resolve().parent

needs_fork = pytest.mark.skipif(not sys.platform.startswith("linux") or usable_cores() < 2,
                                reason="point workers fork only on Linux with two cores")

_TOY = r"""
import json, os, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from test_continuation_toys import Bratu
from supercoil import _fork
from supercoil.continuation import ContinuationOptions, UserEvent, continuation
from supercoil.continuation import pseudo_arclength
from supercoil.solvers.kkt import SingularMatrixError

case = sys.argv[2]
PARENT = os.getpid()
forks = []


class Counted(_fork.Worker):
    def __init__(self, serve):
        forks.append(1)
        super().__init__(serve)


pseudo_arclength.Worker = Counted


def records(q, mu, lam):
    umax = float(np.max(q))
    if case == "raise" and lam > 2.0:
        raise SingularMatrixError("records refused (test)")
    if case == "killed" and umax > 1.0 and os.getpid() != PARENT:
        os.kill(os.getpid(), 9)  # the worker dies; the parent evaluates in its place
    return {"u_max": umax, "energy": float(np.sum(q ** 2))}


event = UserEvent("u_max_one", lambda q, mu, lam: {"u_max_one": float(np.max(q)) - 1.0})


def run(workers):
    _fork.use_point_workers(workers)
    seen = []
    stop = None
    if case == "watch":  # ends one point after on_point saw the user event
        def stop(q):
            return "seen" if any(p.kind == "u_max_one" for b in seen[-1:]
                                 for p in b.special_points) else None
    problem = Bratu(30)
    branch = continuation(problem, np.zeros(problem.n_dofs), parameter="lam",
                          options=ContinuationOptions(initial_step=0.1, max_step=0.4,
                                                      parameter_bounds=(0.0, 4.0),
                                                      max_points=40, predictor="quadratic"),
                          records=records, events=(event,), on_point=seen.append, stop=stop)
    return branch, [len(b) for b in seen], [s.copy() for s in problem.accepted]


serial, seen_serial, accepted_serial = run(False)
n_forks = len(forks)
parallel, seen_parallel, accepted_parallel = run(True)
same = {
    name: bool(np.array_equal(getattr(serial, name), getattr(parallel, name), equal_nan=True))
    for name in ("states", "multipliers", "parameter_values", "tangents", "arclength",
                 "unstable_count", "zero_modes", "determinant_sign", "nearest_eigenvalue")}
same["records"] = all(np.array_equal(serial.records[k], parallel.records[k])
                      for k in serial.records)
key = lambda p: (p.kind, p.index, p.parameter, p.unstable_count, p.count_before,
                 p.count_after, p.q.tobytes())
same["special_points"] = [key(p) for p in serial.special_points] == \
    [key(p) for p in parallel.special_points]
same["on_point"] = seen_serial == seen_parallel
same["accepted"] = len(accepted_serial) == len(accepted_parallel) and all(
    np.array_equal(a, b) for a, b in zip(accepted_serial, accepted_parallel))
same["last_accepted"] = bool(np.array_equal(accepted_serial[-1], accepted_parallel[-1]))
print(json.dumps({"same": same, "status": [serial.status.name, parallel.status.name],
                  "message": [serial.message, parallel.message], "points": len(serial),
                  "kinds": sorted({p.kind for p in serial.special_points}),
                  "forks": [n_forks, len(forks) - n_forks]}))
"""


def _toy(case: str) -> dict:
    # one OpenBLAS thread, as the command sets: a process with a BLAS pool does not fork
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", _TOY, str(TESTS), case], capture_output=True,
                          text=True, timeout=300, env=env, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@needs_fork
@pytest.mark.parametrize("case", ["plain", "watch", "raise", "killed"])
def test_workers_give_the_serial_branch(case):
    """Bratu's branch through its fold (a fold and a user event located), with workers and
    without: the same points, tangents, counts, records, special points, accepted states
    and partial branches handed to on_point. 'watch': a stop that watches on_point's
    branches (settled before every judgement); 'raise': a record that raises ends both
    runs at the same point with the same message; 'killed': the worker killed mid-run,
    its points evaluated by the parent."""
    result = _toy(case)
    same = result["same"]
    if case in ("raise", "killed"):
        # the parent accepted points ahead, then the failed or re-evaluated point again:
        # the history of accepted states differs, the state the problem is left in not
        same.pop("accepted")
    assert all(same.values()), result
    assert result["status"][0] == result["status"][1]
    assert result["message"][0] == result["message"][1]
    assert result["forks"][0] == 0 and result["forks"][1] >= 1  # the workers did run
    if case == "plain":
        assert {"fold", "u_max_one"} <= set(result["kinds"])
    if case == "watch":
        assert result["status"][0] == "STOPPED"
    if case == "raise":
        assert result["status"][0] == "STEP_TOO_SMALL"
        assert "records refused (test)" in result["message"][0]
    if case == "killed":
        assert result["forks"][1] >= 2  # a new worker followed the killed one


@needs_fork
def test_tweezers_command_with_workers_matches_the_serial_library_run(tmp_path):
    """The command (its process turns the workers on) against cli.main.run in a fresh
    process with workers off: branch.json's points and special points equal, and the
    branches' states bit for bit (a rod with contact: folds, contact events, a
    bifurcation on the straight rod)."""
    args = ["tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "20", "--tension",
            "20", "--turns", "0:1.6", "--nodes", "40", "--quiet"]
    command = subprocess.run([sys.executable, "-c",
                              "from supercoil.cli.main import main; main()", *args, "--out",
                              str(tmp_path / "workers")], capture_output=True, text=True,
                             timeout=600, check=False)
    assert command.returncode == 0, command.stderr[-2000:]
    serial = subprocess.run([sys.executable, "-c",
                             ("import sys; from supercoil.cli.main import run; "
                              "sys.exit(run(sys.argv[1:]))"), *args, "--out",
                             str(tmp_path / "serial")], capture_output=True, text=True,
                            timeout=600, check=False)
    assert serial.returncode == 0, serial.stderr[-2000:]
    a = json.loads((tmp_path / "serial" / "branch.json").read_text())
    b = json.loads((tmp_path / "workers" / "branch.json").read_text())
    assert a["points"] == b["points"]
    assert a["special_points"] == b["special_points"]
    assert {p["kind"] for p in a["special_points"]} >= {"bifurcation", "contact_onset"}
    import supercoil

    x, y = supercoil.load(tmp_path / "serial"), supercoil.load(tmp_path / "workers")
    assert list(x.branches) == list(y.branches)
    for name, branch in x.branches.items():
        assert np.array_equal(branch.states, y.branch(name).states)


_PROTOCOL = r"""
import os
from supercoil._fork import Worker, can_fork

assert can_fork()
state = []


def serve(request):
    if request == "boom":
        raise ValueError("boom in the worker")
    if request == "die":
        os._exit(3)
    state.append(request)
    return sum(state)


worker = Worker(serve)
try:
    # the request pipe's room: what is unanswered counts until its answer is read
    big = Worker.pack(b"x" * (worker.capacity // 2))
    assert worker.room(big) and not worker.room(big + big)
    for value in (1, 2, 3):
        worker.submit(value)
    assert [worker.result() for _ in range(3)] == [(True, 1), (True, 3), (True, 6)]
    assert state == []  # the parent's copy is untouched
    worker.submit("boom")
    try:
        worker.result()
        raise AssertionError("no exception")
    except ValueError as exc:
        assert "boom in the worker" in str(exc)
    worker.submit(4)
    assert worker.result() == (True, 10)  # the fork goes on after a failure
    worker.submit("die")
    assert worker.result() == (False, None)
    worker.submit(5)  # to a dead fork: no exception, and no answer
    assert worker.result() == (False, None)
finally:
    worker.close()
print("ok")
"""


@needs_fork
def test_worker_answers_in_order_and_returns_failures():
    """The Worker protocol alone (a fresh process): answers in the order of the requests,
    the fork's state changed only by what it serves, an exception raised by the caller's
    result() and the fork going on, a killed fork answering (False, None)."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", _PROTOCOL], capture_output=True, text=True,
                          timeout=120, env=env, check=False)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]
