"""The first run's notice: a command that runs the compiled kernels says, before it
starts, that it compiles them when numba's cache holds no kernel of the package; never
on a warm cache, for a help, or for a command that only draws a result."""

from __future__ import annotations

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


def test_the_cache_is_cold_until_it_holds_a_kernel_of_the_package(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert _numba.cache_is_cold() is True
    (tmp_path / "other.f-1.py311.nbi").write_bytes(b"")  # another package's kernel
    assert _numba.cache_is_cold() is True
    (tmp_path / "supercoil").mkdir()
    (tmp_path / "supercoil" / "kernels.f-1.py311.nbi").write_bytes(b"")
    assert _numba.cache_is_cold() is False


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
    (tmp_path / "supercoil").mkdir()
    (tmp_path / "supercoil" / "kernels.f-1.py311.nbi").write_bytes(b"")
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert run(["writhe", str(curve), "--quiet"]) == 0
    assert capsys.readouterr().err == ""

