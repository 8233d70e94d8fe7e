"""numpy's lazily imported submodules left lazy by scipy's array-API namespace.

scipy 1.17's ``scipy.sparse`` (through ``scipy._lib._array_api``) imports
``scipy._lib.array_api_compat.numpy``, which copies numpy's namespace into its
own with ``from numpy import *`` and ``getattr`` on every name of
``dir(numpy)``. numpy 2 imports some submodules only when they are first
accessed (``numpy.f2py``, ``numpy.testing``, ``numpy.ma``, ``numpy.random``,
``numpy.polynomial``, ...: ``numpy.__numpy_submodules__``); the copy accesses
them all, so that ``import scipy.sparse`` imports ``numpy.f2py`` (and through
it a Fortran parser's regular expressions), ``numpy.testing`` (``unittest``,
``importlib.metadata``, ``email``), ``numpy.ma`` and the rest, none of which
the command uses. Measured on this project's machine (``python -X importtime``,
slow hour): ``scipy._lib.array_api_compat.numpy`` 95 ms of which those
submodules about 82 ms.

:func:`install` (called by the ``supercoil`` command's entry point, never by the
library: a user's own process imports as usual) registers a one-time import
hook for that module: while it runs, numpy's ``__all__`` and ``dir()`` leave
out the lazy submodules not imported yet, and afterwards the module gets them
back as lazy attributes (a module ``__getattr__``, PEP 562, that returns
numpy's own, importing it then) and in its ``__all__``. Every name of the
namespace thus resolves to the same object as without the hook; only the
moment the unused submodules are imported changes (never, in the command).
Where numpy or scipy look different from what the hook expects (no
``__numpy_submodules__``, the module already imported, no loader to wrap) it does
nothing.
"""

from __future__ import annotations

import importlib.abc
import sys

TARGET = "scipy._lib.array_api_compat.numpy"


def lazy_submodules() -> frozenset[str]:
    """The names of numpy's lazily imported submodules not imported yet (none if numpy
    does not declare them)."""
    import numpy

    declared = getattr(numpy, "__numpy_submodules__", None)
    if not isinstance(declared, (set, frozenset)):
        return frozenset()
    return frozenset(n for n in declared if f"numpy.{n}" not in sys.modules)


def _run_narrowed(exec_module, module) -> None:
    """``exec_module(module)`` with numpy's lazy submodules hidden from ``from numpy import
    *`` and ``dir(numpy)``; then given back to ``module`` as lazy attributes."""
    import numpy

    hidden = lazy_submodules()
    names = vars(numpy)
    old_all, old_dir = names.get("__all__"), names.get("__dir__")
    if not hidden or not isinstance(old_all, list) or not callable(old_dir):
        exec_module(module)
        return
    names["__all__"] = [n for n in old_all if n not in hidden]
    names["__dir__"] = lambda: [n for n in old_dir() if n not in hidden]
    try:
        exec_module(module)
    finally:
        names["__all__"], names["__dir__"] = old_all, old_dir
    own = vars(module)
    # the names the copy left out and the module did not define itself
    missing = frozenset(n for n in hidden if n not in own)
    previous = own.get("__getattr__")

    def __getattr__(name: str):
        if name in missing:
            return getattr(numpy, name)
        if previous is not None:
            return previous(name)
        raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")

    own["__getattr__"] = __getattr__
    if isinstance(own.get("__all__"), list):
        own["__all__"] = sorted(set(own["__all__"]) | missing)


class _Hook(importlib.abc.MetaPathFinder):
    """Finds :data:`TARGET` with the other finders and wraps its loader (once)."""

    def find_spec(self, fullname, path, target=None):
        if fullname != TARGET:
            return None
        remove()
        for finder in sys.meta_path:
            find = getattr(finder, "find_spec", None)
            spec = find(fullname, path, target) if find is not None else None
            if spec is not None:
                break
        else:
            return None
        loader = spec.loader
        exec_module = getattr(loader, "exec_module", None)
        if exec_module is None:
            return spec

        class _Narrowing(type(loader)):
            def exec_module(self, module):
                _run_narrowed(exec_module, module)

        try:
            loader.__class__ = _Narrowing
        except TypeError:  # a loader whose class cannot be swapped: left as it is
            return spec
        return spec


_hook = _Hook()


def install() -> None:
    """Register the hook (module doc) unless :data:`TARGET` is imported already."""
    if TARGET not in sys.modules and _hook not in sys.meta_path:
        sys.meta_path.insert(0, _hook)


def remove() -> None:
    """Unregister the hook (it removes itself when it fires)."""
    if _hook in sys.meta_path:
        sys.meta_path.remove(_hook)
