"""Writing a verb's branches durably while it computes, and continuing a stored result.

:func:`supercoil.ring_diagram` and :func:`supercoil.tweezers` take ``out=`` (an
output folder, or an open :class:`~supercoil.io.store.ResultWriter`) and
``resume=``; this module does what those need:

* :func:`open_folder`: the folder's ``result.h5``, started (refused if it exists,
  unless overwritten) or continued;
* :func:`stored_branches`: the branches of a stored result to continue, checked
  against the options of the new run;
* :func:`recording`: the callbacks that append every accepted point to the
  result as it comes (each in the operating system's hands before the caller's
  ``on_point`` sees it) and store each branch when it is final, and the closing
  of the result as ``interrupted`` (Ctrl-C) or ``failed`` (an exception), which
  is then raised again;
* :func:`finish`: the final branches, the JSON summary and the status.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path

from supercoil.errors import InputError

RESULT_FILE = "result.h5"  # supercoil.io.store.RESULT_NAME (h5py is imported on use only)


def plain(value):
    """``value`` as JSON would give it back (tuples as lists, numpy numbers as numbers)."""
    from supercoil.io.results import to_jsonable

    return json.loads(json.dumps(to_jsonable(value)))


def settings_mismatch(have, want, where: str = "") -> str | None:
    """The first difference between stored settings ``have`` and ``want`` (plain data;
    floats equal to 1e-12 relative), or None."""
    if isinstance(have, dict) and isinstance(want, dict):
        for key in sorted(set(have) | set(want)):
            found = settings_mismatch(have.get(key), want.get(key), f"{where}.{key}"
                                      if where else str(key))
            if found:
                return found
        return None
    if isinstance(have, float) or isinstance(want, float):
        try:
            if math.isclose(float(have), float(want), rel_tol=1e-12, abs_tol=0.0):
                return None
        except (TypeError, ValueError):
            pass
    elif have == want:
        return None
    return f"{where} = {have!r} in the file, {want!r} now"


def kept(writer) -> str:
    """The branches stored in ``writer`` and their points, as a phrase."""
    stored = {name: len(b) for name, (b, _) in writer.stored_branches().items()}
    return ", ".join(f"{name} ({k} points)" for name, k in stored.items()) or "no branch"


def _options_record(settings: Mapping, kind: str) -> dict:
    """The options a stored result was computed with, by their library names: those of
    ``{"options": ...}`` (the verbs, ``diagram ring``, ``demo``) or the flat settings of
    ``supercoil tweezers`` (``nodes`` for ``n_nodes``)."""
    if isinstance(settings.get("options"), dict):
        return dict(settings["options"])
    out = {k: v for k, v in settings.items() if k not in ("command", "verb")}
    if kind == "tweezers" and "nodes" in out:
        out["n_nodes"] = out.pop("nodes")
    return out


def stored_branches(stored, kind: str, options, model: dict | None = None) -> dict:
    """name -> ``(branch, complete)`` of the stored result ``stored`` (a
    :class:`~supercoil.io.store.Result`, a result file or its folder), which must be a
    ``kind`` result computed with ``options`` (an options dataclass): the options both
    record must agree, and the rod model (``model``: a Cosserat rod's keys, None for the
    Kirchhoff rod, which records none)."""
    import dataclasses

    from supercoil.io.store import Result, load

    result = stored if isinstance(stored, Result) else load(Path(stored))
    if result.problem != kind:
        raise InputError(f"resume: {result.path} holds a {result.problem!r} result, not a "
                         f"{kind!r} one")
    have = _options_record(result.settings, kind)
    want = plain(dataclasses.asdict(options))
    common = set(have) & set(want)
    mismatch = settings_mismatch({k: have[k] for k in common}, {k: want[k] for k in common})
    if mismatch:
        raise InputError(f"resume: {result.path} was computed with other options "
                         f"({mismatch}); give the same options, or start anew")
    mismatch = settings_mismatch(result.settings.get("rod"), plain(model), "rod")
    if mismatch:
        raise InputError(f"resume: {result.path} was computed with another rod "
                         f"({mismatch}); give the same rod, or start anew")
    return {name: (b, name in result.complete_branches) for name, b in result.branches.items()}


def announce(stored: Mapping, say: Callable[[str], None]) -> None:
    """Say which stored branches are kept and which are continued."""
    done = [n for n, (b, complete) in stored.items() if complete]
    partial = [f"{n} ({len(b)} points)" for n, (b, complete) in stored.items()
               if not complete and len(b)]
    say(f"resume: kept {', '.join(done) or 'no branch'}; continuing "
        f"{', '.join(partial) or 'no branch'}")


def open_folder(out, *, kind: str, options, attributes: dict, provenance: dict,
                overwrite: bool, resume: bool, model: dict | None = None):
    """The :class:`~supercoil.io.store.ResultWriter` of ``out/result.h5``: continued with
    ``resume`` (it must exist), else started, the folder created. An existing result is
    refused unless ``overwrite``; so is a result another process writes. ``model``: a
    Cosserat rod's keys, stored in the settings as ``rod`` (None: the Kirchhoff rod)."""
    import dataclasses

    from supercoil.io.store import ResultFileError, ResultWriter

    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"out: {folder} is a file; give a folder")
    path = folder / RESULT_FILE
    if resume:
        if not path.is_file():
            raise InputError(f"resume: {path} does not exist; nothing to resume (start without "
                             "resume)")
        return ResultWriter.reopen(path)
    if path.exists() and not overwrite:
        raise InputError(f"out: {path} exists; give another folder, resume=True to continue "
                         "it, or overwrite=True to replace it")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"out: cannot create {folder} ({exc.strerror or exc})") from None
    try:
        rod = {} if model is None else {"rod": plain(model)}
        return ResultWriter.create(path, problem=kind, settings={
            "verb": kind, "options": plain(dataclasses.asdict(options)), **rod},
            attributes=attributes, provenance=provenance, overwrite=True)
    except ResultFileError:
        raise
    except OSError as exc:
        raise InputError(f"out: cannot write {path} ({exc.strerror or exc})") from None


@contextlib.contextmanager
def recording(writer, on_point: Callable | None, contact: Callable[[str], bool]):
    """``(on_point, on_branch)`` for a problem's driver: each accepted point appended to
    ``writer`` before ``on_point(branch)`` is called, each final branch stored. Within
    the block, Ctrl-C (KeyboardInterrupt) closes the result as ``interrupted`` and an
    exception as ``failed``; either is raised again. Without a writer, ``on_point``
    alone."""
    user = on_point or (lambda branch: None)
    if writer is None:
        yield user, None
        return

    def point(branch) -> None:
        writer.append(branch, contact=contact(branch.name))
        user(branch)

    def final(branch, is_contact: bool) -> None:
        writer.write_branch(branch, complete=True, contact=is_contact)

    try:
        yield point, final
    except KeyboardInterrupt:
        writer.set_status("interrupted", f"interrupted; kept {kept(writer)}")
        writer.close()
        raise
    except BaseException as exc:
        if from_interrupt(exc):
            writer.set_status("interrupted", f"interrupted; kept {kept(writer)}")
            writer.close()
            raise KeyboardInterrupt from exc
        writer.set_status("failed", f"{type(exc).__name__}: {' '.join(str(exc).split())}")
        writer.close()
        raise


def from_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is a KeyboardInterrupt or was raised because of one: Ctrl-C (or
    SIGTERM, turned into it) that arrives while a compiled kernel returns surfaces as a
    ``SystemError`` ("returned a result with an exception set") whose cause is the
    KeyboardInterrupt."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def store_branches(writer, branches, contact_names) -> None:
    """Store the final ``branches`` whole and remove the stored ones no longer computed."""
    for branch in branches:
        writer.write_branch(branch, complete=True, contact=branch.name in contact_names)
    for name in set(writer.branch_names()) - {b.name for b in branches}:
        writer.remove_branch(name)


def finish(writer, diagram) -> None:
    """Store ``diagram``'s final branches, its summary and its status in ``writer``, and
    close it."""
    computed = diagram.computed
    store_branches(writer, list(diagram.branches.values()),
                   getattr(computed, "contact_branches", frozenset()))
    writer.set_summary(diagram.summary)
    if diagram.ok:
        writer.set_status("complete", f"{len(diagram.branches)} branches computed")
    else:
        failed = [name for name, b in diagram.branches.items() if not b.status.complete]
        writer.set_status("incomplete", f"branch(es) {', '.join(failed)} stopped early"
                          if failed else diagram.message)
    writer.close()
