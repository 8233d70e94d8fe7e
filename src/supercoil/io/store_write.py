"""Writing result files: :class:`ResultWriter` and :func:`write_snapshot`.

The HDF5 file is only ever written whole: to a temporary file in the same
folder, flushed to disk (``fsync``), then renamed over ``result.h5`` -- a
reader, or a process killed at any moment, sees the old file or the new one,
never a part. Between two such snapshots, every change is appended to the
journal beside the file (:mod:`supercoil.io.journal`) with one write, so it
reaches the operating system at once. A snapshot is taken when the writer
starts, when it closes, and when a branch is made final if the time since the
last snapshot is at least ``SNAPSHOT_COST_RATIO`` times what that snapshot
took (so snapshots cost at most a few per cent of a run).

Every dataset of a snapshot has its SHA-256 (of the decoded array) and every
group its attributes' SHA-256 in the root attribute ``manifest`` (JSON), whose
own SHA-256 is the root attribute ``manifest_sha256``
(:mod:`supercoil.io.checksums`); the reader checks them all.
"""

from __future__ import annotations

import json
import os
import secrets
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Self

import numpy as np

from supercoil.continuation.branch import Branch
from supercoil.io.branch_codec import flatten
from supercoil.io.checksums import array_digest, bytes_digest, mapping_digest
from supercoil.io.contents import (
    FORMAT,
    RUN_STATUSES,
    SCHEMA_VERSION,
    Contents,
    to_flat,
)
from supercoil.io.journal import Journal, JournalLocked, journal_path
from supercoil.io.results import CONVENTIONS, to_jsonable
from supercoil.io.store_read import ResultFileError, read_contents

SNAPSHOT_COST_RATIO = 20.0


def _h5py():
    import h5py

    return h5py


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _attribute(attrs, name: str, value) -> None:
    if isinstance(value, (str, bytes)):
        raw = value.encode("utf-8") if isinstance(value, str) else value
        attrs.create(name, data=np.bytes_(raw), dtype=_h5py().string_dtype("utf-8",
                                                                             max(1, len(raw))))
    elif isinstance(value, (bool, np.bool_)):
        attrs[name] = np.bool_(value)
    elif isinstance(value, (int, np.integer)):
        attrs[name] = np.int64(value)
    elif isinstance(value, (float, np.floating)):
        attrs[name] = np.float64(value)
    else:
        raise TypeError(f"attribute {name!r}: {type(value).__name__} is not a text or a number")


def write_snapshot(path: Path, contents: Contents) -> None:
    """Write ``contents`` as the HDF5 file ``path`` (temporary file, fsync, rename)."""
    groups, arrays, texts = to_flat(contents)
    manifest: dict[str, dict] = {}
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    h5py = _h5py()
    try:
        with h5py.File(temporary, "w") as f:
            for gpath in sorted(groups, key=lambda p: p.count("/")):
                attrs = groups[gpath]
                group = f if gpath == "/" else f.require_group(gpath)
                for name, value in attrs.items():
                    _attribute(group.attrs, name, value)
                if gpath != "/":
                    manifest[f"{gpath}@"] = {"sha256": mapping_digest(attrs)}
            for dpath, a in arrays.items():
                f.create_dataset(dpath, data=a)
                manifest[dpath] = {"sha256": array_digest(a), "shape": list(a.shape),
                                   "dtype": a.dtype.str}
            for tpath, text in texts.items():
                raw = text.encode("utf-8")
                f.create_dataset(tpath, data=np.bytes_(raw),
                                 dtype=h5py.string_dtype("utf-8", max(1, len(raw))))
                manifest[tpath] = {"text_sha256": bytes_digest(raw), "nbytes": len(raw)}
            manifest["/@"] = {"sha256": mapping_digest(groups["/"])}
            text = json.dumps(manifest, sort_keys=True, separators=(",", ":"))
            f.create_dataset("manifest", data=np.bytes_(text.encode()),
                             dtype=h5py.string_dtype("utf-8", len(text)))
            _attribute(f.attrs, "manifest_sha256", bytes_digest(text.encode()))
        with open(temporary, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _provenance(extra: dict | None) -> dict:
    import platform

    from supercoil import __version__

    out = {"supercoil_version": __version__, "h5py_version": _h5py().__version__,
           "numpy_version": np.__version__, "python_version": platform.python_version(),
           "timestamp": _now()}
    out.update(extra or {})
    return out


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    return value


def _same_prefix(old: Branch, new: Branch) -> bool:
    """Whether ``new`` continues ``old``: at least as long, same first and last stored
    points, records and special points."""
    k = len(old)
    if len(new) < k or new.records.keys() != old.records.keys():
        return False
    if k and not (new.parameter_values[0] == old.parameter_values[0]
                  and new.parameter_values[k - 1] == old.parameter_values[k - 1]
                  and np.array_equal(new.states[k - 1], old.states[k - 1])):
        return False
    n = len(old.special_points)
    return len(new.special_points) >= n and all(
        (p.kind, p.index, p.parameter) == (q.kind, q.index, q.parameter)
        for p, q in zip(old.special_points, new.special_points[:n]))


class ResultWriter:
    """Writes (or continues) one result file and its journal. Use :meth:`create` or
    :meth:`reopen`, then close it (or use it as a context manager).

    Each method's change is in the operating system's hands when it returns
    (one journal write); :meth:`close` writes the file whole and removes the
    journal. While it is open the writer holds the journal's lock: a second
    writer of the same file is refused.
    """

    def __init__(self, path: Path, contents: Contents, journal: Journal):
        self.path = path
        self._contents = contents
        self._journal = journal
        self._snapshot_seconds = 0.0
        self._snapshot_at = time.monotonic()

    # -- opening -------------------------------------------------------------------------
    @staticmethod
    def _lock(path: Path) -> Journal:
        try:
            return Journal(journal_path(path))
        except JournalLocked:
            raise ResultFileError(f"{path}: another running process is writing it; wait "
                                  "for it to end or stop it") from None

    @classmethod
    def create(cls, path: str | Path, *, problem: str, settings: dict,
               units: str = "nondimensional", provenance: dict | None = None,
               attributes: dict | None = None, study_text: str | None = None,
               overwrite: bool = False) -> ResultWriter:
        """Start a new result file at ``path``.

        ``settings``: the computation's validated settings (plain data, stored
        as JSON); ``attributes``: texts and numbers stored as plain HDF5
        attributes (``twist_ratio``, ``n_nodes``, ...); ``provenance``:
        versions, tolerances, contact treatment (``supercoil_version``,
        ``h5py_version`` and a timestamp are added). An existing file is
        refused (:class:`FileExistsError`) unless ``overwrite``.
        """
        path = Path(path)
        if path.exists() and not overwrite:
            raise FileExistsError(f"{path}: exists; give another path or allow overwriting")

        def contents() -> Contents:
            now = _now()
            header = {"format": FORMAT, "schema_version": SCHEMA_VERSION,
                      "problem": str(problem), "units": str(units), "status": "running",
                      "message": "", "created": now, "updated": now,
                      "journal_generation": "",
                      "settings": to_jsonable(settings), "provenance":
                      to_jsonable(_provenance(provenance)), "conventions": dict(CONVENTIONS)}
            return Contents(header=header, study=study_text,
                            attributes={str(k): _plain(v)
                                        for k, v in (attributes or {}).items()})

        return cls._open(path, contents)

    @classmethod
    def reopen(cls, path: str | Path) -> ResultWriter:
        """Open an existing result file (and what its journal holds) to continue it
        (``--resume``); its status becomes ``running``."""
        path = Path(path)

        def contents() -> Contents:
            stored = read_contents(path)
            stored.header["status"] = "running"
            return stored

        return cls._open(path, contents)

    @classmethod
    def _open(cls, path: Path, contents: Callable[[], Contents]) -> ResultWriter:
        """The writer of ``path`` under its journal's lock, with ``contents()``, its first
        snapshot written; the lock is released if any of that fails."""
        journal = cls._lock(path)
        try:
            writer = cls(path, contents(), journal)
            writer._snapshot()
        except BaseException:
            journal.close()
            raise
        return writer

    def close(self) -> None:
        """Write the file whole and remove the journal."""
        if self._journal is None:
            return
        try:
            self._snapshot()
            self._journal.close(remove=True)
        finally:
            self._journal.close()
            self._journal = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- internals ------------------------------------------------------------------------
    def _snapshot(self) -> None:
        started = time.monotonic()
        generation = secrets.token_hex(8)
        self._contents.header["journal_generation"] = generation
        self._contents.header["updated"] = _now()
        write_snapshot(self.path, self._contents)
        self._journal.start(generation)
        self._snapshot_at = time.monotonic()
        self._snapshot_seconds = self._snapshot_at - started

    def _record(self, op: str, args: dict, arrays: dict | None = None) -> None:
        if self._journal is None:
            raise ValueError(f"{self.path}: the writer is closed")
        self._journal.append(op, args, arrays)

    def _maybe_snapshot(self) -> None:
        if time.monotonic() - self._snapshot_at >= SNAPSHOT_COST_RATIO * self._snapshot_seconds:
            self._snapshot()

    # -- branches -------------------------------------------------------------------------
    def branch_names(self) -> list[str]:
        """Names of the stored branches, in the order they were started."""
        return list(self._contents.branches)

    def stored_branches(self) -> dict[str, tuple[Branch, bool]]:
        """name -> (branch as stored, whether its computation ended)."""
        return {name: (e.get(), e.complete) for name, e in self._contents.branches.items()}

    def stored_points(self, name: str) -> int:
        """Number of stored points of branch ``name`` (0 if absent)."""
        entry = self._contents.branches.get(name)
        return 0 if entry is None else len(entry.get())

    def _put(self, branch: Branch, complete: bool, contact: bool) -> None:
        entry = self._contents.branches.get(branch.name)
        start = special = 0
        if entry is not None:
            old = entry.get()
            if old is branch and entry.complete == complete and entry.contact == contact:
                return
            if _same_prefix(old, branch):
                start, special = len(old), len(old.special_points)
        meta, groups, arrays = flatten(branch, start, special, origin=start == 0)
        self._record("branch", {"meta": meta, "groups": groups, "complete": bool(complete),
                                "contact": bool(contact)}, arrays)
        self._contents.put_branch(branch, complete, contact)

    def append(self, branch: Branch, *, contact: bool = False) -> int:
        """Store ``branch`` (a partial branch, growing; not final): the points not stored
        yet are appended. Returns the number of points stored."""
        self._put(branch, False, contact)
        return len(branch)

    def write_branch(self, branch: Branch, *, complete: bool = True,
                     contact: bool = False) -> None:
        """Store ``branch`` whole (final with ``complete``), replacing a stored version."""
        self._put(branch, complete, contact)
        if complete:
            self._maybe_snapshot()

    def mark_complete(self, name: str, complete: bool = True) -> None:
        self._record("complete", {"name": name, "complete": bool(complete)})
        self._contents.apply("complete", {"name": name, "complete": complete}, {})

    def remove_branch(self, name: str) -> None:
        if name in self._contents.branches:
            self._record("remove", {"name": name})
            self._contents.apply("remove", {"name": name}, {})

    def set_extra(self, name: str, arrays: dict) -> None:
        """Store named arrays beside the branches (e.g. the tweezers' quasi-static path)."""
        arrays = {str(k): np.asarray(v) for k, v in arrays.items()}
        self._record("extra", {"name": name}, arrays)
        self._contents.apply("extra", {"name": name}, arrays)

    # -- the run --------------------------------------------------------------------------
    def set_summary(self, summary: dict) -> None:
        """Store the run's JSON summary (e.g. ``diagram.json``'s payload)."""
        text = json.dumps(to_jsonable(summary), allow_nan=False)
        self._record("summary", {"text": text})
        self._contents.apply("summary", {"text": text}, {})

    def set_status(self, status: str, message: str = "") -> None:
        """``status``: one of ``RUN_STATUSES``; ``message`` says what happened."""
        if status not in RUN_STATUSES:
            raise ValueError(f"run status {status!r}: give one of {', '.join(RUN_STATUSES)}")
        args = {"status": status, "message": str(message), "updated": _now()}
        self._record("header", args)
        self._contents.apply("header", args, {})

    def stored_settings(self) -> dict:
        """The settings stored in the result (plain data)."""
        return json.loads(json.dumps(self._contents.header["settings"]))

    def set_settings(self, settings: dict) -> None:
        """Replace the stored settings (a resumed run that raised a point limit)."""
        args = {"settings": to_jsonable(settings)}
        self._record("settings", args)
        self._contents.apply("settings", args, {})

    def set_attribute(self, key: str, value) -> None:
        args = {"key": str(key), "value": _plain(value)}
        self._record("attribute", args)
        self._contents.apply("attribute", args, {})

    @property
    def status(self) -> str:
        return self._contents.header["status"]
