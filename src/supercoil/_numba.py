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

A cached kernel is machine code plus the LLVM bitcode of its module, which numba parses
at every load (to link the kernel into a caller compiled later, and to list the symbols
the code defines): 1.7 MB for the tweezers command's 41 kernels, 0.11-0.12 s of parsing
and 0.07 s of listing symbols through LLVM's API, measured, against 0.27-0.38 s for the
whole loads. Here the symbols are read from the machine code's own ELF symbol table
(:func:`elf_defined_symbols`, a superset of numba's list: every kernel checked) and the
bitcode is parsed only when a caller is compiled against the kernel
(:class:`_LazyLinking`); machine code other than ELF (macOS, Windows) loads as numba
loads it.

Set ``SUPERCOIL_NUMBA_PLAIN_CACHE=1`` to use numba's own lookup and loading everywhere
(e.g. if a numba release changes these internals in a way the fallback does not catch).
"""

from __future__ import annotations

import os
import struct

import numba
import numpy as np

try:
    from numba.core.caching import FunctionCache as _FunctionCache
except ImportError:  # a numba without it: its own cache, as it is
    _FunctionCache = None

QUICK_LOOKUP = _FunctionCache is not None and not os.environ.get("SUPERCOIL_NUMBA_PLAIN_CACHE")

# ELF64 section header and symbol table entry (little endian): what
# elf_defined_symbols reads
_ELF_SECTION = np.dtype([("name", "<u4"), ("type", "<u4"), ("flags", "<u8"), ("addr", "<u8"),
                         ("offset", "<u8"), ("size", "<u8"), ("link", "<u4"), ("info", "<u4"),
                         ("addralign", "<u8"), ("entsize", "<u8")])
_ELF_SYMBOL = np.dtype([("name", "<u4"), ("info", "u1"), ("other", "u1"), ("shndx", "<u2"),
                        ("value", "<u8"), ("size", "<u8")])
_SHT_SYMTAB, _STT_FILE = 2, 4


def elf_defined_symbols(code: bytes) -> set[str] | None:
    """The names of the symbols a relocatable ELF64 little-endian object ``code`` defines
    (its symbol tables' named entries with a section, source-file entries excluded), or
    None if ``code`` is not such an object (or is truncated)."""
    try:
        if code[:6] != b"\x7fELF\x02\x01":
            return None
        (offset,) = struct.unpack_from("<Q", code, 0x28)
        size, count = struct.unpack_from("<HH", code, 0x3A)
        if size != _ELF_SECTION.itemsize or count == 0:
            return None
        sections = np.frombuffer(code, _ELF_SECTION, count, offset)
        names = set()
        for table in sections[sections["type"] == _SHT_SYMTAB]:
            symbols = np.frombuffer(code, _ELF_SYMBOL, int(table["size"]) // _ELF_SYMBOL.itemsize,
                                    int(table["offset"]))
            strings = sections[int(table["link"])]
            start = int(strings["offset"])
            text = code[start:start + int(strings["size"])]
            keep = ((symbols["shndx"] != 0) & (symbols["name"] != 0)
                    & ((symbols["info"] & 0xF) != _STT_FILE))
            for at in symbols["name"][keep].tolist():
                names.add(text[at:text.index(b"\0", at)].decode())
    except (ValueError, IndexError, struct.error, UnicodeDecodeError):
        return None
    return names


class _LazyLinking:
    """A code library loaded from the cache whose module for linking (numba's
    ``_shared_module``) is parsed from its bitcode when first asked for: when a
    function compiled later links the kernel in, or the library is serialised."""

    @property
    def _shared_module(self):
        module = self.__dict__.get("_supercoil_shared")
        if module is None:
            bitcode = self.__dict__.pop("_supercoil_bitcode", None)
            if bitcode is not None:
                from llvmlite import binding

                module = self.__dict__["_supercoil_shared"] = binding.parse_bitcode(bitcode)
        return module

    @_shared_module.setter
    def _shared_module(self, module):
        self.__dict__["_supercoil_shared"] = module


_LAZY_CLASSES: dict[type, type] = {}


def _unserialize_lazily(codegen, state):
    """Numba's ``CPUCodeLibrary._unserialize`` for a library of machine code, without
    parsing its bitcode (module doc); numba's own for anything else."""
    name, kind, data = state
    names = elf_defined_symbols(data[0]) if kind == "object" else None
    if names is None:
        return codegen._library_class._unserialize(codegen, state)
    library = codegen.create_library(name)
    try:  # nothing is in numba's engine before _finalize_final_module
        cls = type(library)
        if cls not in _LAZY_CLASSES:
            _LAZY_CLASSES[cls] = type(f"Lazy{cls.__name__}", (_LazyLinking, cls), {})
        library.__class__ = _LAZY_CLASSES[cls]
        library.__dict__.pop("_shared_module", None)  # the property answers now
        library.enable_object_caching()
        library._set_compiled_object(data[0])
        library.__dict__["_supercoil_bitcode"] = data[1]
    except (TypeError, AttributeError, ValueError):  # a library class unlike numba 0.68's
        return codegen._library_class._unserialize(codegen, state)
    library._finalize_final_module()
    codegen._engine._defined_symbols |= names
    return library


def _load_lazily(codegen) -> None:
    """Make ``codegen`` (numba's CPU JIT code generator) load cached libraries by
    :func:`_unserialize_lazily`, if it has the internals that relies on."""
    if "unserialize_library" in codegen.__dict__:
        return
    engine = getattr(codegen, "_engine", None)
    library = getattr(codegen, "_library_class", None)
    if (isinstance(getattr(engine, "_defined_symbols", None), set) and library is not None
            and hasattr(library, "_set_compiled_object")
            and hasattr(library, "_finalize_final_module")):
        codegen.unserialize_library = lambda state: _unserialize_lazily(codegen, state)


if _FunctionCache is not None:

    class _CachedFirst(_FunctionCache):
        """Numba's function cache, looked up before numba's target set-up (module doc)."""

        def load_overload(self, sig, target_context):
            try:
                from numba.core.runtime import rtsys
                from numba.cpython import hashing  # noqa: F401  (registers symbols)

                rtsys.initialize(target_context)
                _load_lazily(target_context.codegen())
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
