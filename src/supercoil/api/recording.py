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


# the point limits a resumed run may raise: the branches the stored run stopped at its
# limit are then continued up to the new one (a limit is never lowered on resume)
POINT_LIMITS = frozenset({"max_points", "free_max_points", "contact_max_points",
                          "secondary_max_points"})


def settings_mismatch(have, want, where: str = "") -> str | None:
    """The first difference between stored settings ``have`` and ``want`` (plain data;
    floats equal to 1e-12 relative), or None. A point limit (``POINT_LIMITS``) may be
    raised: a larger one now is no difference, a smaller one is."""
    if isinstance(have, dict) and isinstance(want, dict):
        for key in sorted(set(have) | set(want)):
            found = settings_mismatch(have.get(key), want.get(key), f"{where}.{key}"
                                      if where else str(key))
            if found:
                return found
        return None
    if where.rpartition(".")[2] in POINT_LIMITS and _is_int(have) and _is_int(want):
        if want >= have:
            return None
        return (f"{where} = {have!r} in the file, {want!r} now; a resumed run may raise a "
                "point limit, not lower it")
    if isinstance(have, float) or isinstance(want, float):
        try:
            if math.isclose(float(have), float(want), rel_tol=1e-12, abs_tol=0.0):
                return None
        except (TypeError, ValueError):
            pass
    elif have == want:
        return None
    return f"{where} = {have!r} in the file, {want!r} now"


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def raised_limits(have, limits: Mapping) -> dict | None:
    """``have`` (stored settings, plain data) with each point limit (``POINT_LIMITS``,
    at any depth) that ``limits`` (a run's options or settings: the limits at any
    depth) raises set to its new value; None when none is raised."""
    changed = False
    limits = _limit_values(limits)

    def walk(node):
        nonlocal changed
        if not isinstance(node, dict):
            return node
        out = {}
        for key, value in node.items():
            new = limits.get(key) if key in POINT_LIMITS else None
            if _is_int(value) and _is_int(new) and new > value:
                out[key], changed = new, True
            else:
                out[key] = walk(value)
        return out

    updated = walk(have)
    return updated if changed else None


def _limit_values(settings) -> dict:
    """The point limits in ``settings`` (plain data) at any depth, by name."""
    if not isinstance(settings, Mapping):
        return {}
    out = {}
    for key, value in settings.items():
        if key in POINT_LIMITS and _is_int(value):
            out[key] = value
        else:
            out.update(_limit_values(value))
    return out


def reopened(branches: Mapping) -> tuple[list[str], list[str]]:
    """For a run that raised a point limit, ``(reopen, drop)`` among the stored
    ``branches`` (name -> ``(branch, complete)``, in the order they were computed): the
    first finished branch that ended at its point limit is reopened (continued up to
    the new limit; it stops again at once if its own limit did not change), and every
    branch computed after it is dropped, to be computed again: what the drivers compute
    next, and the names they give it (a secondary branch numbered by its point, a
    deflated start), depends on the branches before."""
    from supercoil.continuation.options import ContinuationStatus

    names = list(branches)
    for k, name in enumerate(names):
        b, complete = branches[name]
        if complete and b.status is ContinuationStatus.MAX_POINTS:
            return [name], names[k + 1:]
    return [], []


def raise_limits(writer, limits: Mapping) -> list[str]:
    """In the result ``writer`` continues, raise the stored point limits that
    ``limits`` (a run's options or settings) raises, reopen the first branch that ended
    at its limit and remove the branches computed after it (:func:`reopened`). Returns
    the reopened branch's name (or none)."""
    updated = raised_limits(writer.stored_settings(), limits)
    if updated is None:
        return []
    writer.set_settings(updated)
    reopen, drop = reopened(writer.stored_branches())
    for name in reopen:
        writer.mark_complete(name, False)
    for name in drop:
        writer.remove_branch(name)
    return reopen


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
    Kirchhoff rod, which records none). A point limit may be raised: the branches are
    then those :func:`reopened` keeps, the first that ended at its limit unfinished."""
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
    branches = {name: (b, name in result.complete_branches)
                for name, b in result.branches.items()}
    if raised_limits(have, want) is None:
        return branches
    reopen, drop = reopened(branches)
    return {name: (b, complete and name not in reopen) for name, (b, complete) in
            branches.items() if name not in drop}


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
        writer = ResultWriter.reopen(path)
        raise_limits(writer, plain(dataclasses.asdict(options)))
        return writer
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
