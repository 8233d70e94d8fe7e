"""The figure helper process (supercoil.plotting.painter): same files, fallback, clean-up."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from supercoil.plotting.painter import Painter, usable_cores
from supercoil.plotting.tweezers import figure_jobs, write_figures

needs_two_cores = pytest.mark.skipif(usable_cores() < 2, reason="no helper on one core")


def _payload_and_configurations():
    """A small tweezers payload (two branches, a fold) and two tube configurations."""
    turns = np.linspace(0.0, 3.0, 25)
    points = []
    for name, shift in (("buckled", 0.0), ("buckled_contact", 0.02)):
        for n in turns:
            points.append({"branch": name, "turns": float(n),
                           "extension": float(1.0 - 0.05 * n**2 - shift),
                           "torque": float(0.3 * n), "writhe": float(0.4 * n + shift),
                           "stable": bool(n < 2.0)})
    payload = {"twist_ratio": 4 / 3, "force": 75.0, "length_over_diameter": 33.0,
               "n_nodes": 30, "diameter": 1 / 33, "points": points,
               "branches": [{"name": "buckled"}, {"name": "buckled_contact"}],
               "special_points": [{"kind": "fold", "branch": "buckled_contact",
                                   "turns": 2.0, "extension": 0.78, "torque": 0.6,
                                   "writhe": 0.82}]}
    s = np.linspace(0.0, 1.0, 30)
    configurations = [{"label": f"state {k}",
                       "points": np.stack([0.1 * k * np.sin(np.pi * s),
                                           0.05 * np.sin(2 * np.pi * s), s], axis=1),
                       "contact_points": [{"s1": 0.3, "s2": 0.7}] if k else [],
                       "contact_intervals": []} for k in (1, 2)]
    return payload, configurations


def _pixels(path):
    from matplotlib.image import imread

    return imread(path)


def _drawn_here_and_jobs(tmp_path, other: str):
    """``(payload, configurations, paths drawn in this process into tmp_path/here, the
    same figures' jobs into tmp_path/<other>)``."""
    payload, configurations = _payload_and_configurations()
    (tmp_path / "here").mkdir()
    (tmp_path / other).mkdir()
    here = write_figures(payload, configurations, tmp_path / "here")
    return payload, configurations, here, figure_jobs(payload, configurations,
                                                      tmp_path / other)


@needs_two_cores
def test_the_helper_draws_the_files_the_command_would(tmp_path):
    """Oracle: the figures drawn in this process. The helper's files hold the same
    pixels, and it drew every job (none left to the caller)."""
    _payload, _configurations, here, jobs = _drawn_here_and_jobs(tmp_path, "helper")
    with Painter(1) as painter:
        assert painter.ready(timeout=120.0)
        assert painter.draw(jobs) == []
    assert [p.name for p in here] == [job[0].name for job in jobs]
    assert len(here) == 4
    for path in here:
        np.testing.assert_array_equal(_pixels(tmp_path / "helper" / path.name),
                                      _pixels(path))


@needs_two_cores
def test_meanwhile_runs_once_after_the_jobs_are_handed_over(tmp_path):
    """write_figures(meanwhile=f) calls f once, after the helper took the jobs (it has
    none left to take) and before the figures are waited for; the files are the ones
    drawn without a painter, pixel for pixel. Without a painter f runs once too."""
    payload, configurations, here, _jobs = _drawn_here_and_jobs(tmp_path, "helper")
    calls = []
    with Painter(1) as painter:
        assert painter.ready(timeout=120.0)
        helpers = list(painter._helpers)
        written = write_figures(payload, configurations, tmp_path / "helper", painter,
                                meanwhile=lambda: calls.append(
                                    [h.stdin.closed for h in helpers]))
    assert calls == [[True]]  # once, the jobs already written to the helper
    assert [p.name for p in written] == [p.name for p in here]
    for path in here:
        np.testing.assert_array_equal(_pixels(tmp_path / "helper" / path.name),
                                      _pixels(path))
    calls.clear()
    (tmp_path / "alone").mkdir()
    write_figures(payload, configurations, tmp_path / "alone",
                  meanwhile=lambda: calls.append(1))
    assert calls == [1]


@needs_two_cores
def test_a_dead_helper_leaves_its_figures_to_the_caller(tmp_path):
    """A helper that is gone before the jobs are sent draws nothing: draw returns every
    job and write_figures draws them itself (the same pixels as without a painter)."""
    payload, configurations, here, jobs = _drawn_here_and_jobs(tmp_path, "fallback")
    with Painter(1) as painter:
        for helper in painter._helpers:
            helper.kill()
            helper.wait()
        assert painter.draw(jobs) == jobs
    with Painter(1) as painter:
        for helper in painter._helpers:
            helper.kill()
            helper.wait()
        written = write_figures(payload, configurations, tmp_path / "fallback", painter)
    assert [p.name for p in written] == [p.name for p in here]
    for path in here:
        np.testing.assert_array_equal(_pixels(tmp_path / "fallback" / path.name),
                                      _pixels(path))


def test_unused_helpers_end_with_the_painter(tmp_path):
    """A command that stops before its figures (an error, Ctrl-C) leaves no helper
    running, and the helper wrote nothing."""
    with Painter(1) as painter:
        helpers = list(painter._helpers)
    assert all(h.returncode is not None for h in helpers)
    assert painter.draw([("never", "diagram", {})]) == [("never", "diagram", {})]
    assert not any(tmp_path.iterdir())


@needs_two_cores
@pytest.mark.skipif(not hasattr(os, "getpriority"), reason="no process priorities")
def test_the_helper_runs_at_the_lowest_priority():
    """Exact value: niceness 19 (os.nice caps there whatever the parent's), so that the
    helper never takes time from the computation on a busy machine."""
    with Painter(1) as painter:
        helper = painter._helpers[0]
        deadline = time.monotonic() + 30.0
        while os.getpriority(os.PRIO_PROCESS, helper.pid) != 19 and \
                time.monotonic() < deadline and helper.poll() is None:
            time.sleep(0.01)
        assert os.getpriority(os.PRIO_PROCESS, helper.pid) == 19


@needs_two_cores
def test_a_helper_not_ready_is_ended_and_its_figures_drawn_here(tmp_path):
    """Figures due before the helper warmed up (its imports take a few tenths of a
    second): draw hands it nothing and ends it; write_figures draws every file."""
    payload, configurations = _payload_and_configurations()
    with Painter(1) as painter:
        helpers = list(painter._helpers)
        assert not painter.ready()
        written = write_figures(payload, configurations, tmp_path, painter)
    assert all(h.returncode is not None for h in helpers)
    assert sorted(p.name for p in written) == sorted(p.name for p in tmp_path.iterdir())
    assert len(written) == 4


def _ring_jobs(folder):
    """The three ring-diagram jobs of cli.diagram_output.write_diagram on small data."""
    w = np.linspace(0.0, 1.5, 20)
    branch = {"name": "alpha_contact", "linestyle": "-", "writhe": w, "excess_link": 1 + w,
              "stable": w < 1.0, "contact_points": [[{"s1": 0.2, "s2": 0.7}]] * 20,
              "contact_intervals": [[]] * 20}
    s = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    ring = np.stack([np.cos(s), np.sin(2 * s) / 3, 0.1 * np.sin(s)], axis=1)
    specials = [{"kind": "fold", "branch": "alpha_contact", "writhe": 1.0, "excess_link": 2.0}]
    return [(folder / "link_writhe.png", "ring:link_writhe",
             {"branches": [branch], "special_points": specials, "title": "ring"}),
            (folder / "contact_map.png", "ring:contact_map",
             {"branches": [branch], "title": "ring"}),
            (folder / "configurations.png", "ring:configurations",
             {"configurations": [{"label": "a", "points": ring}], "diameter": 0.05,
              "title": "ring"})]


@needs_two_cores
def test_the_helper_draws_the_ring_diagram_figures_as_the_command_would(tmp_path):
    """The ring diagram's jobs (builders ``ring:...``): drawn by the helper, every one of
    them, with the pixels of the same jobs drawn in this process."""
    from supercoil.plotting.ring_diagram import draw_jobs

    (tmp_path / "here").mkdir()
    (tmp_path / "helper").mkdir()
    draw_jobs(_ring_jobs(tmp_path / "here"))
    jobs = _ring_jobs(tmp_path / "helper")
    with Painter(1) as painter:
        assert painter.ready(timeout=120.0)
        assert painter.draw(jobs) == []
    for path, _builder, _kwargs in jobs:
        np.testing.assert_array_equal(_pixels(path), _pixels(tmp_path / "here" / path.name))


_SHARED = """
import os, pickle, sys
from supercoil.plotting import painter
jobs = pickle.loads(open(sys.argv[1], "rb").read())
parent, draw = os.getpid(), painter._draw
def logged(job):
    if sys.argv[2] == "fail" and os.getpid() != parent:
        raise RuntimeError("a job that fails in the fork")
    draw(job)
    with open(sys.argv[3], "a") as f:  # one short append per job: atomic between processes
        f.write(job[0].name + " " + str(os.getpid()) + "\\n")
painter._draw = logged
painter.draw_shared(jobs, fork=True)
"""


def _shared_in_a_fresh_process(tmp_path, jobs, mode: str) -> list[str]:
    """Run draw_shared(jobs, fork=True) in a fresh interpreter (this one may hold threads,
    e.g. JAX's from other tests, that a fork must not copy); the names of the files
    drawn, one line per job drawn, from both processes."""
    import pickle
    import subprocess
    import sys

    (tmp_path / "jobs.pkl").write_bytes(pickle.dumps(jobs))
    log = tmp_path / "drawn.log"
    subprocess.run([sys.executable, "-c", _SHARED, str(tmp_path / "jobs.pkl"), mode, str(log)],
                   check=True, capture_output=True)
    return [line.split()[0] for line in log.read_text().splitlines()]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_jobs_shared_with_a_fork_are_drawn_once_with_the_same_pixels(tmp_path):
    """draw_shared with a fork: every job drawn exactly once (by the process or its
    fork, whichever took it from the queue), and the files hold the pixels of the same
    figures drawn here without a fork (the oracle)."""
    _payload, _configurations, here, jobs = _drawn_here_and_jobs(tmp_path, "shared")
    names = _shared_in_a_fresh_process(tmp_path, jobs, "log")
    assert sorted(names) == sorted(job[0].name for job in jobs)
    for path in here:
        np.testing.assert_array_equal(_pixels(tmp_path / "shared" / path.name), _pixels(path))


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_the_jobs_of_a_failed_fork_are_drawn_by_the_process(tmp_path):
    """A fork that fails on its jobs (here: every job it takes raises) ends with a
    non-zero status; the process then draws what it did not draw itself, so every
    file is written once in all, with the pixels of the figures drawn here."""
    _payload, _configurations, here, jobs = _drawn_here_and_jobs(tmp_path, "shared")
    names = _shared_in_a_fresh_process(tmp_path, jobs, "fail")
    assert sorted(names) == sorted(job[0].name for job in jobs)
    for path in here:
        np.testing.assert_array_equal(_pixels(tmp_path / "shared" / path.name), _pixels(path))


def test_no_fork_in_a_process_with_other_threads():
    """_can_fork counts the process's threads, native ones too: with a Python thread
    running (any thread would do) it refuses, after it ends it allows again (on Linux
    with two cores)."""
    import threading

    from supercoil.plotting import painter

    before = painter._can_fork()
    release = threading.Event()
    thread = threading.Thread(target=release.wait)
    thread.start()
    try:
        assert not painter._can_fork()
    finally:
        release.set()
        thread.join()
    assert painter._can_fork() == before


_FORK_RENDERERS = """
import os, sys
from supercoil.plotting import figures, painter
painter._warm_up()
assert figures._RENDERERS
pid = os.fork()
if pid == 0:
    fresh = not figures._RENDERERS
    painter._warm_up()  # draws on a renderer of its own
    os._exit(0 if fresh and figures._RENDERERS else 1)
assert os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) == 0, "the fork had its parent's"
assert figures._RENDERERS
"""


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_a_fork_draws_on_renderers_of_its_own():
    """The diagrams' shared renderers (figures._shared_canvas_class) are the process's
    own: a fork starts without its parent's. Their cached mathtext parses hold the
    parent's fonts, whose files a fork would read through descriptors sharing the
    parent's file positions (with them, 4 of 20 forks drawing beside their parent failed
    or drew other pixels). In a fresh interpreter, as the other fork tests."""
    import subprocess
    import sys

    subprocess.run([sys.executable, "-c", _FORK_RENDERERS], check=True, capture_output=True)
