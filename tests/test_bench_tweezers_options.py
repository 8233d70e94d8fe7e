"""The options of ``benchmarks/bench_tweezers.py`` that are refused before anything runs:
each exits with argparse's status 2 and names the option and what would be valid."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_tweezers.py"


def refused(*args: str) -> str:
    run = subprocess.run([sys.executable, str(BENCH), *args], capture_output=True,
                         text=True, timeout=60, check=False)
    assert run.returncode == 2, run.stdout + run.stderr
    assert "Traceback" not in run.stderr
    return run.stderr


@pytest.mark.parametrize("seconds", ["0", "-1", "nan", "inf"])
def test_against_seconds_must_be_a_positive_time(seconds):
    err = refused("--repeat", "1", "--against", "/tmp/x/src", "--against-seconds", seconds)
    assert "--against-seconds" in err and "positive number of seconds" in err


def test_against_seconds_needs_a_reference_tree():
    assert "--against-seconds needs --against SRC and --repeat K" in refused(
        "--against-seconds", "2.81")


def test_pyelastica_repeats_are_not_alternated_with_another_tree():
    err = refused("--repeat", "1", "--pyelastica", sys.executable, "--against", "/tmp/x/src")
    assert "--pyelastica with --repeat" in err and "drop --against" in err
