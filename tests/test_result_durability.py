"""Result files on any signal: a command killed mid-run leaves a result that opens and holds
every point it reported; --resume ends where the uninterrupted run ends; an interrupt
while the figures are drawn leaves complete data that 'supercoil plot' draws.

Oracle: the uninterrupted run of the same command (points equal to 1e-10 on the stored
prefix; special points and last states to 1e-8 after --resume)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import interruptible
import numpy as np
import pytest

import supercoil
from supercoil.cli.main import run as cli

SRC = str(Path(__file__).resolve().parent.parent / "src")
DIAGRAM = ["diagram", "ring", "--twist-ratio", "0.6667", "--length-over-diameter", "20",
           "--nodes", "24", "--modes", "2", "--max-excess-link", "4",
           "--contact-max-points", "40"]
TWEEZERS = ["tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "20", "--nodes",
            "24", "--tension", "20", "--turns", "0:1.6"]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted runs: command name -> loaded result."""
    out = {}
    for name, args in (("diagram", DIAGRAM), ("tweezers", TWEEZERS)):
        folder = tmp_path_factory.mktemp(name)
        status = cli([*args, "--out", str(folder / "full"), "--quiet"])
        assert status in (0, 1)
        out[name] = supercoil.load(folder / "full")
        assert out[name].status in ("complete", "incomplete")
    return out


def start(args, out: Path) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=SRC, OPENBLAS_NUM_THREADS="1")
    return interruptible.popen([sys.executable, "-m", "supercoil.cli.main", *args, "--out",
                                str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, env=env)


def reported(line: str) -> tuple[str, int] | None:
    """``(branch, points)`` of a plain progress line ``  NAME: PARAM = X, ..., K points``."""
    words = line.strip().split()
    if len(words) >= 3 and words[0].endswith(":") and "points" in words:
        count = words[words.index("points") - 1]
        if count.isdigit():
            return words[0][:-1], int(count)
    return None


def kill_after(proc: subprocess.Popen, branch: str, points: int, sig) -> dict[str, int]:
    """Send ``sig`` once the command has reported ``points`` points of ``branch``; return
    the largest count reported per branch before the signal."""
    seen: dict[str, int] = {}
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        found = reported(line)
        if found:
            seen[found[0]] = max(seen.get(found[0], 0), found[1])
            if found[0] == branch and found[1] >= points:
                proc.send_signal(sig)
                break
    else:
        proc.kill()
    proc.communicate(timeout=60)
    assert seen.get(branch, 0) >= points, f"the command did not reach {branch}: {seen}"
    return seen


def assert_prefix(cut, full, atol=1e-10):
    for name, b in cut.branches.items():
        ref = full.branch(name)
        assert len(b) <= len(ref), name
        np.testing.assert_allclose(b.states, ref.states[:len(b)], atol=atol, err_msg=name)
        np.testing.assert_allclose(b.parameter_values, ref.parameter_values[:len(b)],
                                   atol=atol, err_msg=name)


def assert_same_end(resumed, full, atol=1e-8):
    assert list(resumed.branches) == list(full.branches)
    for name, ref in full.branches.items():
        b = resumed.branch(name)
        assert len(b) == len(ref), name
        np.testing.assert_allclose(b.states[-1], ref.states[-1], atol=atol, err_msg=name)
        assert b.parameter_values[-1] == pytest.approx(ref.parameter_values[-1], abs=atol)
        assert [p.kind for p in b.special_points] == [p.kind for p in ref.special_points]
        for p, q in zip(b.special_points, ref.special_points):
            assert p.parameter == pytest.approx(q.parameter, abs=atol), (name, p.kind)
            np.testing.assert_allclose(p.q, q.q, atol=atol, err_msg=f"{name} {p.kind}")
    assert resumed.status == full.status
    assert resumed.summary["ok"] == full.summary["ok"]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL])
def test_diagram_killed_mid_run_keeps_its_points_and_resumes(tmp_path, reference, sig):
    full = reference["diagram"]
    out = tmp_path / "cut"
    seen = kill_after(start(DIAGRAM, out), "alpha_contact", 10, sig)
    cut = supercoil.load(out)
    assert cut.status == ("running" if sig == signal.SIGKILL else "interrupted"), cut.message
    assert cut.summary is None and not (out / "diagram.json").exists()
    # every point reported before the signal is stored, and is the uninterrupted run's
    for name, k in seen.items():
        assert len(cut.branch(name)) >= k, name
    assert len(cut.branch("alpha_contact")) < len(full.branch("alpha_contact"))
    assert_prefix(cut, full)
    assert cli([*DIAGRAM, "--out", str(out), "--resume", "--quiet"]) in (0, 1)
    resumed = supercoil.load(out)
    assert_same_end(resumed, full)
    assert not (out / "result.h5.journal").exists()


def test_diagram_killed_in_a_later_run_of_its_contact_branch_resumes(tmp_path):
    """A contact branch is computed in runs of 40 points, each starting afresh from the
    last point of the previous (pins, phase rows, step): killed in its second run and
    resumed, the rest of that run and the later ones are the uninterrupted run's."""
    args = ["diagram", "ring", "--twist-ratio", "2/3", "--length-over-diameter", "122",
            "--nodes", "24", "--modes", "2", "--max-excess-link", "4",
            "--contact-max-points", "100"]
    assert cli([*args, "--out", str(tmp_path / "full"), "--quiet"]) in (0, 1)
    full = supercoil.load(tmp_path / "full")
    assert len(full.branch("alpha_contact")) > 80  # three runs
    out = tmp_path / "cut"
    kill_after(start(args, out), "alpha_contact", 50, signal.SIGKILL)
    cut = supercoil.load(out)
    assert 50 <= len(cut.branch("alpha_contact")) < 79  # stopped in the second run
    assert_prefix(cut, full)
    assert cli([*args, "--out", str(out), "--resume", "--quiet"]) in (0, 1)
    assert_same_end(supercoil.load(out), full)


def test_tweezers_killed_mid_run_keeps_its_points_and_resumes(tmp_path, reference):
    full = reference["tweezers"]
    out = tmp_path / "cut"
    seen = kill_after(start(TWEEZERS, out), "buckled", 10, signal.SIGKILL)
    cut = supercoil.load(out)
    assert cut.status == "running"
    for name, k in seen.items():
        assert len(cut.branch(name)) >= k, name
    assert_prefix(cut, full)
    assert cli([*TWEEZERS, "--out", str(out), "--resume", "--quiet"]) in (0, 1)
    assert_same_end(supercoil.load(out), full)


def test_resume_refuses_other_options_and_touches_nothing(tmp_path, reference, capsys):
    out = tmp_path / "cut"
    kill_after(start(DIAGRAM, out), "alpha", 10, signal.SIGKILL)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    other = [w if w != "40" else "39" for w in DIAGRAM]
    assert cli([*other, "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --resume: ") and "contact_max_points = 40" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert cli([*DIAGRAM, "--out", str(out), "--resume", "--overwrite"]) == 2
    assert "exclude each other" in capsys.readouterr().err


def test_interrupt_while_drawing_leaves_complete_data(tmp_path, reference, capsys,
                                                      monkeypatch):
    from supercoil.plotting import ring_diagram as drawing

    def interrupted(jobs):
        raise KeyboardInterrupt

    monkeypatch.setattr(drawing, "draw_jobs", interrupted)
    out = tmp_path / "d"
    assert cli([*DIAGRAM, "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "interrupted while drawing the figures" in err and "supercoil plot" in err
    result = supercoil.load(out)
    assert result.status == reference["diagram"].status and result.summary is not None
    assert_same_end(result, reference["diagram"], atol=1e-12)
    assert (out / "diagram.json").exists() and not (out / "link_writhe.png").exists()
    monkeypatch.undo()
    assert cli(["plot", str(out), "--out", str(out), "--format", "png"]) == 0
    assert (out / "diagram.png").stat().st_size > 1000


class StatusWriter:
    """The parts of a result writer that :func:`~supercoil.api.recording.recording` uses
    when a run ends: its status and message, and that it was closed."""

    def __init__(self):
        self.status, self.message, self.closed = "running", "", False

    def set_status(self, status, message):
        self.status, self.message = status, message

    def close(self):
        self.closed = True

    def stored_branches(self):
        return {}


def interrupt_in_kernel():
    """What Ctrl-C or SIGTERM arriving while a compiled kernel returns raises: the
    interpreter's SystemError, caused by the KeyboardInterrupt."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as interrupt:
        raise SystemError("CPUDispatcher(<function kernel>) returned a result with an "
                          "exception set") from interrupt


def interrupt():
    raise KeyboardInterrupt


def bug():
    raise ValueError("a bug")


@pytest.mark.parametrize("raise_it, status, raised", [
    (interrupt_in_kernel, "interrupted", KeyboardInterrupt),
    (interrupt, "interrupted", KeyboardInterrupt),
    (bug, "failed", ValueError)])
def test_an_interrupt_inside_a_kernel_closes_the_result_as_interrupted(raise_it, status,
                                                                       raised):
    """An interrupt is an interrupt wherever it arrives (the result closed as
    ``interrupted``, KeyboardInterrupt raised, so the command line says how to resume);
    any other exception closes it as ``failed`` and propagates."""
    from supercoil.api.recording import from_interrupt, recording

    writer = StatusWriter()
    with pytest.raises(raised) as caught, recording(writer, None, lambda name: False):
        raise_it()
    assert writer.status == status and writer.closed
    assert from_interrupt(caught.value) is (raised is KeyboardInterrupt)
