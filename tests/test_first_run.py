"""The first run's notice (supercoil._numba): said once, before the first kernel is
compiled, when numba's cache holds no kernel of the package; never on a warm cache."""

from __future__ import annotations

import numba

from supercoil import _numba


def _kernel_module(calls):
    """What a module of kernels does at its import: decorate its functions."""

    @_numba.njit()
    def double(x):
        return 2 * x

    @_numba.njit()
    def triple(x):
        return 3 * x

    return double, triple


def test_a_cold_cache_is_announced_once_and_a_warm_one_never(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert _numba.cache_is_cold() is True
    calls = []
    _numba.announce_compilation(lambda: calls.append("compiling"))
    double, triple = _kernel_module(calls)
    _kernel_module(calls)
    assert calls == ["compiling"]
    assert double(2) == 4 and triple(2) == 6  # compiled into the cache folder
    other = tmp_path / "elsewhere"
    other.mkdir()
    (other / "other.f-1.py311.nbi").write_bytes(b"")  # another package's kernel
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(other))
    assert _numba.cache_is_cold() is True
    (other / "supercoil").mkdir()
    (other / "supercoil" / "kernels.f-1.py311.nbi").write_bytes(b"")
    assert _numba.cache_is_cold() is False
    _numba.announce_compilation(lambda: calls.append("again"))
    _kernel_module(calls)
    assert calls == ["compiling"]
