"""The project's one ``numba.njit`` wrapper: numba's own on-disk cache (``cache=True``).

Numba compiles a kernel at its first call and keeps the machine code in its cache:
the ``__pycache__`` folder beside the module, or ``NUMBA_CACHE_DIR`` when set. A
first run on a fresh install compiles every kernel it calls (under a minute for
the demo); later runs load them. :func:`cache_is_cold` lets a command say so before it
starts.

Numba's cache checks only the file of the function it caches: a kernel that calls a
compiled function of another module keeps that callee's code as it was when the kernel
was cached (a documented numba limitation). Three do
(``contact.ccd._segment_advance_kernel`` calls ``contact.distance_kernels.closest_pair``;
``continuation.bordered_matrix._sorted_entries`` calls
``solvers.kkt_matrix.permuted_kkt_entries``; ``topology.linking._linking_half_angle_rows``
calls ``topology.solid_angles.row_half_angles``):
after editing such a callee, delete the caller module's cached ``*.nbi`` / ``*.nbc``
files in its ``__pycache__`` (a fresh checkout has none).
"""

from __future__ import annotations

import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def cache_is_cold() -> bool | None:
    """Whether numba's on-disk cache holds no compiled kernel of this package yet (its
    index files, ``*.nbi``): True on a fresh install, False once a run has compiled
    kernels, None when the cache is where this cannot look (the package's folder is not
    writable and ``NUMBA_CACHE_DIR`` is not set: numba then uses a folder of its own)."""
    import numba

    if numba.config.CACHE_DIR:
        # numba keeps the kernels of a source folder in a folder of NUMBA_CACHE_DIR named
        # after it and a hash of its path (``rod_<hash>``)
        folders = {p.parent.name for p in PACKAGE.rglob("*.py")}
        return not any(p.parent.name.rsplit("_", 1)[0] in folders
                       for p in Path(numba.config.CACHE_DIR).glob("*/*.nbi"))
    if not os.access(PACKAGE, os.W_OK):
        return None
    return next(PACKAGE.rglob("__pycache__/*.nbi"), None) is None


def njit(**options: object):
    """``numba.njit(cache=True, **options)``, or without cache if none is usable.

    Numba raises ``RuntimeError`` at decoration time when neither the source tree's
    ``__pycache__`` nor a user-wide cache directory is writable; the kernels then
    compile in memory in each new process.
    """
    import numba

    def decorate(function):
        try:
            return numba.njit(cache=True, **options)(function)
        except RuntimeError:
            return numba.njit(cache=False, **options)(function)

    return decorate
