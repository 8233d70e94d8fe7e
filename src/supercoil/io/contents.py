"""What a result file holds, in memory: :class:`Contents`.

The writer (:mod:`supercoil.io.store_write`) keeps one, changes it through
the operations of :meth:`Contents.apply` (each also a journal record,
:mod:`supercoil.io.journal`) and writes it whole as the HDF5 file; the reader
(:mod:`supercoil.io.store_read`) rebuilds one from the file and replays the
journal on it. :func:`to_flat` and :func:`from_flat` convert between a
:class:`Contents` and the file's tree: group attributes by path and arrays
(or texts) by path.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from supercoil.continuation.branch import Branch
from supercoil.io.branch_codec import BranchBuilder, CodecError, flatten, key, unkey

FORMAT = "supercoil-result"
SCHEMA_VERSION = "2.0"
READABLE_VERSIONS = ("2.0",)
RUN_STATUSES = ("running", "complete", "incomplete", "interrupted", "failed")
HEADER_TEXT = ("format", "schema_version", "problem", "units", "status", "message", "created",
               "updated", "journal_generation")
HEADER_JSON = ("settings", "provenance", "conventions")


class ContentsError(ValueError):
    """Stored pieces that do not fit together (a damaged or foreign file)."""


@dataclass
class Entry:
    """One stored branch: the branch (or its builder, while a journal is replayed) and
    its flags."""

    builder: BranchBuilder | None = None
    branch: Branch | None = None
    complete: bool = False
    contact: bool = False

    def get(self) -> Branch:
        if self.branch is None:
            self.branch = self.builder.build()
        return self.branch


@dataclass
class Contents:
    """``header``: format, schema version, problem, units, status, message, created,
    updated, journal generation (texts) and settings, provenance, conventions (plain
    data); ``attributes``: plain numbers and texts; ``branches``: name -> Entry in the
    order they were started; ``summary`` and ``study``: texts; ``extras``: named groups
    of arrays (e.g. the quasi-static path of the tweezers)."""

    header: dict
    attributes: dict = field(default_factory=dict)
    branches: dict[str, Entry] = field(default_factory=dict)
    summary: str | None = None
    study: str | None = None
    extras: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)

    # -- operations (each one a journal record) -------------------------------------------
    def apply(self, op: str, args: dict, arrays: dict) -> None:
        """Apply one operation (see :mod:`supercoil.io.journal`)."""
        if op == "branch":
            meta, groups = args["meta"], args["groups"]
            name = str(meta["name"])
            entry = self.branches.get(name)
            start = int(meta.get("start", 0))
            if entry is None or start == 0:
                builder = BranchBuilder(meta, groups, arrays)
                self.branches[name] = entry = Entry(builder=builder)
            else:
                if entry.builder is None:
                    entry.builder = BranchBuilder(*flatten(entry.get()))
                entry.builder.extend(meta, groups, arrays)
                entry.branch = None
            entry.complete, entry.contact = bool(args["complete"]), bool(args["contact"])
        elif op == "complete":
            self.branches[str(args["name"])].complete = bool(args["complete"])
        elif op == "remove":
            self.branches.pop(str(args["name"]), None)
        elif op == "summary":
            self.summary = str(args["text"])
        elif op == "header":
            for name in HEADER_TEXT:
                if name in args:
                    self.header[name] = str(args[name])
        elif op == "settings":
            self.header["settings"] = args["settings"]
        elif op == "attribute":
            self.attributes[str(args["key"])] = args["value"]
        elif op == "extra":
            self.extras[str(args["name"])] = dict(arrays)
        else:
            raise ContentsError(f"unknown operation {op!r}")

    def put_branch(self, branch: Branch, complete: bool, contact: bool) -> None:
        """Store ``branch`` as it is (the writer's side of a ``branch`` operation)."""
        entry = self.branches.get(branch.name)
        if entry is None:
            self.branches[branch.name] = entry = Entry()
        entry.branch, entry.builder = branch, None
        entry.complete, entry.contact = complete, contact


# ------------------------------------------------------------------------- file tree
def to_flat(contents: Contents) -> tuple[dict, dict, dict]:
    """``(groups, arrays, texts)``: attributes by group path (``/`` is the root), arrays
    and texts by dataset path."""
    root = {name: str(contents.header[name]) for name in HEADER_TEXT}
    root.update({name: json.dumps(contents.header[name], allow_nan=False, sort_keys=True)
                 for name in HEADER_JSON})
    for k, v in contents.attributes.items():
        if k in root or k in ("manifest", "manifest_sha256"):
            raise ValueError(f"attribute {k!r} is reserved")
        root[str(k)] = v
    groups = {"/": root, "/branches": {}, "/extras": {}}
    arrays: dict[str, np.ndarray] = {}
    texts: dict[str, str] = {}
    for order, (name, entry) in enumerate(contents.branches.items()):
        base = f"/branches/{key(name)}"
        meta, sub, data = flatten(entry.get())
        meta = {k: v for k, v in meta.items() if k not in ("start", "special_start")}
        groups[base] = {**meta, "complete": bool(entry.complete),
                        "contact": bool(entry.contact), "order": order}
        groups.update({f"{base}/{p}": attrs for p, attrs in sub.items()})
        arrays.update({f"{base}/{p}": a for p, a in data.items()})
    for name, data in contents.extras.items():
        groups[f"/extras/{key(name)}"] = {"name": name}
        arrays.update({f"/extras/{key(name)}/{key(k)}": np.asarray(a) for k, a in data.items()})
    if contents.summary is not None:
        texts["/summary"] = contents.summary
    if contents.study is not None:
        texts["/study"] = contents.study
    return groups, arrays, texts


def _text(value) -> str:
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def from_flat(groups: dict, arrays: dict, texts: dict) -> Contents:
    """The inverse of :func:`to_flat` (raises :class:`ContentsError` on pieces that do not
    fit)."""
    try:
        root = dict(groups["/"])
        header = {name: _text(root.pop(name)) for name in HEADER_TEXT}
        for name in HEADER_JSON:
            header[name] = json.loads(_text(root.pop(name)))
    except KeyError as exc:
        raise ContentsError(f"root attribute {exc.args[0]!r} missing") from None
    except json.JSONDecodeError as exc:
        raise ContentsError(f"root attribute not valid JSON ({exc.msg})") from None
    attributes = {k: _text(v) if isinstance(v, (bytes, str)) else
                  (v.item() if isinstance(v, np.generic) else v) for k, v in root.items()}
    contents = Contents(header=header, attributes=attributes, summary=texts.get("/summary"),
                        study=texts.get("/study"))
    found = []
    for path, attrs in groups.items():
        parts = path.split("/")
        if len(parts) == 3 and parts[1] == "branches":
            found.append((int(attrs["order"]), parts[2], attrs))
    for _, k, attrs in sorted(found):
        base = f"/branches/{k}/"
        meta = {n: _text(v) if isinstance(v, (bytes, str)) else v for n, v in attrs.items()}
        sub = {p[len(base):]: {n: _text(v) if isinstance(v, (bytes, str)) else v
                               for n, v in a.items()}
               for p, a in groups.items() if p.startswith(base)}
        data = {p[len(base):]: a for p, a in arrays.items() if p.startswith(base)}
        try:
            builder = BranchBuilder(meta, sub, data)
        except (CodecError, KeyError, TypeError, ValueError) as exc:
            raise ContentsError(f"branch {unkey(k)!r}: {exc}") from None
        name = str(meta["name"])
        contents.branches[name] = Entry(builder=builder, complete=bool(meta["complete"]),
                                        contact=bool(meta["contact"]))
    for path, attrs in groups.items():
        parts = path.split("/")
        if len(parts) == 3 and parts[1] == "extras":
            base = f"{path}/"
            contents.extras[_text(attrs["name"])] = {
                unkey(p[len(base):]): a for p, a in arrays.items() if p.startswith(base)}
    return contents
