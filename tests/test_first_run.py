"""The first run's notice: a command that runs the compiled kernels says, before it
starts, that it compiles them when numba's cache holds no kernel of the package; never
on a warm cache, for a help, or for a command that only draws a result."""

from __future__ import annotations

import os
import subprocess
import sys

import numba
import numpy as np
import pytest

from supercoil import _numba
from supercoil.cli.main import COMPILE_TIME, run

NOTICE = "first run: compiling the numerical kernels"


@pytest.fixture
def curve(tmp_path):
    path = tmp_path / "curve.txt"
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    np.savetxt(path, np.c_[np.cos(t), np.sin(t), 0.1 * np.sin(2 * t)])
    return path


def test_a_fresh_cache_folder_is_cold_until_a_command_has_compiled_into_it(tmp_path, curve):
    """End to end, in new processes with numba's own cache in a fresh NUMBA_CACHE_DIR: the
    first ``supercoil writhe`` says it compiles, the second loads and says nothing."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    program = "import sys; from supercoil.cli.main import run; sys.exit(run(sys.argv[1:]))"
    said = []
    for _ in range(2):
        done = subprocess.run([sys.executable, "-c", program, "writhe", str(curve), "-q"],
                              env=env, capture_output=True, text=True, timeout=600, check=True)
        said.append(NOTICE in done.stderr)
    assert said == [True, False]
    (tmp_path / "other_0123").mkdir()
    (tmp_path / "other_0123" / "f-1.py311.nbi").write_bytes(b"")  # another package's
    with pytest.MonkeyPatch.context() as m:
        m.setattr(numba.config, "CACHE_DIR", str(tmp_path))
        assert _numba.cache_is_cold() is True


def test_a_computing_command_on_a_cold_cache_says_it_compiles(monkeypatch, tmp_path, curve,
                                                               capsys):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "cache"))
    assert run(["writhe", str(curve), "--quiet"]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"supercoil: {NOTICE} ({COMPILE_TIME}; cached for later runs)"]
    for args in (["writhe", "--help"], ["--version"], ["--help"], ["plot", "--help"]):
        assert run(args) == 0, args
        assert capsys.readouterr().err == "", args


def test_a_warm_cache_says_nothing(monkeypatch, tmp_path, curve, capsys):
    (tmp_path / "rod_0123").mkdir()  # numba's folder of the kernels of supercoil/rod
    (tmp_path / "rod_0123" / "kernels.f-1.py311.nbi").write_bytes(b"")
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert run(["writhe", str(curve), "--quiet"]) == 0
    assert capsys.readouterr().err == ""

