"""The project's one ``numba.njit`` wrapper."""

from __future__ import annotations

import numba


def njit(**options: object):
    """``numba.njit(cache=True, **options)``, or without cache if none is usable.

    Numba raises ``RuntimeError`` at decoration time when neither the source
    tree's ``__pycache__`` nor a user-wide cache directory is writable; the
    kernels then simply compile in memory on each new process.
    """

    def decorate(function):
        try:
            return numba.njit(cache=True, **options)(function)
        except RuntimeError:
            return numba.njit(cache=False, **options)(function)

    return decorate
