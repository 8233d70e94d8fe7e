"""``supercoil --log FILE``: the computation's log, each continuation step in it.

Oracle: every accepted step adds one point to its branch, so the log's accepted steps
are the stored points after each branch's first, in order and at the same parameter
values; a refused input writes no log (the file is opened at its first record)."""

from __future__ import annotations

import json
import re

import pytest
from cli_helpers import invoke
from typer.testing import CliRunner

ACCEPTED = re.compile(r"step (\S+) accepted at turns = (\S+) after (\d+) corrector iterations")
# a straight rod below its buckling (F L^2/A = 100 buckles above 2 turns at C/A = 1.5)
STRAIGHT = ("tweezers", "--turns", "0:1", "--tension", "100", "--twist-ratio", "1.5",
            "--length-over-diameter", "30", "--nodes", "24")


@pytest.fixture
def runner():
    return CliRunner()


def test_the_log_holds_one_accepted_step_per_stored_point(runner, tmp_path):
    log = tmp_path / "steps.log"
    result = invoke(runner, "--log", log, *STRAIGHT, "--out", tmp_path / "run")
    assert result.exit_code == 0, result.output
    stored = json.loads((tmp_path / "run" / "branch.json").read_text())["points"]
    turns = [p["turns"] for p in stored if p["branch"] == "straight"]
    assert len(turns) >= 3
    text = log.read_text()
    steps = ACCEPTED.findall(text)
    assert [float(t) for _, t, _ in steps] == pytest.approx(turns[1:], abs=1e-9)
    # the branch's heading comes before its steps
    assert text.index("straight: turns = 0,") < text.index("accepted")


def test_the_log_is_released_after_the_command(runner, tmp_path):
    """A second command in the same process writes its own log only."""
    first, second = tmp_path / "a.log", tmp_path / "b.log"
    assert invoke(runner, "--log", first, *STRAIGHT, "--out", tmp_path / "a").exit_code == 0
    size = first.stat().st_size
    assert invoke(runner, *STRAIGHT, "--out", tmp_path / "b").exit_code == 0
    assert invoke(runner, "--log", second, *STRAIGHT, "--out", tmp_path / "c").exit_code == 0
    assert first.stat().st_size == size
    assert len(ACCEPTED.findall(second.read_text())) == len(ACCEPTED.findall(first.read_text()))


@pytest.mark.parametrize("where, words", [
    ("missing/steps.log", "does not exist"),
    (".", "is a directory"),
])
def test_a_bad_log_path_is_refused_before_any_write(runner, tmp_path, where, words):
    result = invoke(runner, "--log", tmp_path / where, *STRAIGHT, "--out", tmp_path / "run")
    assert result.exit_code == 2
    line = result.output.strip().splitlines()[-1]
    assert line.startswith("error: --log") and words in line
    assert not (tmp_path / "run").exists() and not (tmp_path / "missing").exists()


def test_a_refused_command_writes_no_log(runner, tmp_path):
    log = tmp_path / "steps.log"
    result = invoke(runner, "--log", log, "tweezers", "--turns", "0:1", "--tension", "100",
                    "--out", tmp_path / "run")  # --twist-ratio is missing
    assert result.exit_code == 2
    assert not log.exists()
