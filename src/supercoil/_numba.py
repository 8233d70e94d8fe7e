"""The project's one ``numba.njit`` wrapper, and its cache lookup without numba's set-up.

Numba looks a compiled function up in its on-disk cache only after refreshing its
compilation target: on the first lookup of a process that imports numba's whole
library of typing and lowering rules (``BaseContext.refresh``, 0.14-0.2 s on the
benchmark's two-core machine, measured), which a function loaded from the cache does
not use: the cache file holds its machine code, signature and environment. Here the
cached function is looked up first, with only what loading machine code needs (numba's
runtime, whose initialisation registers the memory-management symbols the code calls,
and the hash-secret symbols that :mod:`numba.cpython.hashing` registers on import); on
a miss, or if loading fails, numba's own lookup runs, with its set-up, and compiles as
usual. Numba itself uses the same two steps (its ``Cache.load_overload`` is the
refresh followed by ``_load_overload``); the cached kernels are the same machine code
either way, so results are identical bit for bit (``tests/test_numba_cache.py``). Part of
what the refresh imported is imported by the loads themselves: over the tweezers
command's 41 kernel loads the net saving measured 0.05-0.1 s (docs/benchmarks.md,
"Session 14").

Set ``SUPERCOIL_NUMBA_PLAIN_CACHE=1`` to use numba's own lookup everywhere (e.g. if a
numba release changes these internals in a way the fallback does not catch).
"""

from __future__ import annotations

import os

import numba

try:
    from numba.core.caching import FunctionCache as _FunctionCache
except ImportError:  # a numba without it: its own cache, as it is
    _FunctionCache = None

QUICK_LOOKUP = _FunctionCache is not None and not os.environ.get("SUPERCOIL_NUMBA_PLAIN_CACHE")

if _FunctionCache is not None:

    class _CachedFirst(_FunctionCache):
        """Numba's function cache, looked up before numba's target set-up (module doc)."""

        def load_overload(self, sig, target_context):
            try:
                from numba.core.runtime import rtsys
                from numba.cpython import hashing  # noqa: F401  (registers symbols)

                rtsys.initialize(target_context)
                data = self._load_overload(sig, target_context)
            except Exception:  # noqa: BLE001  (stale entry, other internals: numba decides)
                data = None
            if data is not None:
                return data
            return super().load_overload(sig, target_context)


def njit(**options: object):
    """``numba.njit(cache=True, **options)``, or without cache if none is usable.

    Numba raises ``RuntimeError`` at decoration time when neither the source
    tree's ``__pycache__`` nor a user-wide cache directory is writable; the
    kernels then simply compile in memory on each new process. With a cache, it is
    looked up before numba's set-up (module doc).

    Numba's cache checks only the file of the function it caches: a kernel that
    calls a compiled function of another module keeps that callee's code as it was
    when the kernel was cached (a documented numba limitation). Two do
    (``contact.ccd._segment_advance_kernel`` calls ``contact.distance._closest``;
    ``continuation.bordered._sorted_entries`` calls ``solvers.kkt._permuted_kkt_entries``):
    after editing such a callee, delete the caller module's cached ``*.nbi`` / ``*.nbc``
    files in its ``__pycache__`` (a fresh checkout has none).
    """

    def decorate(function):
        try:
            dispatcher = numba.njit(cache=True, **options)(function)
        except RuntimeError:
            return numba.njit(cache=False, **options)(function)
        cache = getattr(dispatcher, "_cache", None)
        if QUICK_LOOKUP and type(cache) is _FunctionCache:
            # the same object, its lookup ours: a second cache object would locate (and
            # test-write) the cache folder again, a temporary file per kernel at import
            cache.__class__ = _CachedFirst
        return dispatcher

    return decorate
