"""The project's one ``numba.njit`` wrapper: numba's own on-disk cache (``cache=True``).

Numba's cache checks only the file of the function it caches: a kernel that calls a
compiled function of another module keeps that callee's code as it was when the kernel
was cached (a documented numba limitation). Two do
(``contact.ccd._segment_advance_kernel`` calls ``contact.distance._closest``;
``continuation.bordered._sorted_entries`` calls ``solvers.kkt._permuted_kkt_entries``):
after editing such a callee, delete the caller module's cached ``*.nbi`` / ``*.nbc``
files in its ``__pycache__`` (a fresh checkout has none).
"""

from __future__ import annotations

import numba


def njit(**options: object):
    """``numba.njit(cache=True, **options)``, or without cache if none is usable.

    Numba raises ``RuntimeError`` at decoration time when neither the source tree's
    ``__pycache__`` nor a user-wide cache directory is writable; the kernels then
    compile in memory in each new process.
    """

    def decorate(function):
        try:
            return numba.njit(cache=True, **options)(function)
        except RuntimeError:
            return numba.njit(cache=False, **options)(function)

    return decorate
