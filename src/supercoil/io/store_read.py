"""Reading result files: :func:`load` and :class:`Result`.

:func:`read_contents` opens the HDF5 file, checks every dataset and every
group's attributes against the SHA-256 digests of its manifest, then replays
the journal beside it (the changes made since the file was last written
whole, :mod:`supercoil.io.journal`). Anything missing, altered, truncated or
foreign is a :class:`ResultFileError` naming the file and what is wrong;
nothing is returned altered.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np

from supercoil.continuation.branch import Branch, SpecialPoint, jsonable
from supercoil.errors import InputError
from supercoil.io.checksums import array_digest, bytes_digest, mapping_digest
from supercoil.io.contents import (
    FORMAT,
    READABLE_VERSIONS,
    Contents,
    ContentsError,
    from_flat,
)
from supercoil.io.journal import JournalError, journal_path, read_journal

RESULT_NAME = "result.h5"  # the result file's name in an output folder
_ATTEMPTS = 5  # reads of a file and journal that a writer replaced meanwhile


class ResultFileError(InputError):
    """A result file that is missing, unreadable, damaged, not ours, or of another schema
    version. The message is one line naming the file and what is wrong."""


def _h5py():
    import h5py

    return h5py


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def resolve(path: str | Path) -> Path:
    """The result file at ``path``: the file itself, or ``result.h5`` in a folder."""
    path = Path(path)
    if path.is_dir():
        inside = path / RESULT_NAME
        if not inside.exists():
            raise ResultFileError(f"{path}: folder has no {RESULT_NAME}; give an output "
                                  "folder of supercoil or a result file")
        return inside
    if not path.exists():
        raise ResultFileError(f"{path}: no such result file")
    return path


def _text(value) -> str:
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def _read_snapshot(path: Path) -> Contents:
    h5py = _h5py()
    try:
        handle = h5py.File(path, "r", locking=False)
    except OSError as exc:
        raise ResultFileError(f"{path}: not a readable HDF5 result file "
                              f"({_one_line(exc)})") from None
    with handle:
        if _text(handle.attrs.get("format", "")) != FORMAT:
            raise ResultFileError(f"{path}: an HDF5 file but not a supercoil result file "
                                  f"(no format = {FORMAT!r} attribute)")
        version = _text(handle.attrs.get("schema_version", ""))
        if version not in READABLE_VERSIONS:
            raise ResultFileError(f"{path}: result schema version {version!r}; this "
                                  f"supercoil reads {', '.join(READABLE_VERSIONS)}")
        raw = handle["manifest"][()]
        if bytes_digest(raw) != _text(handle.attrs["manifest_sha256"]):
            raise ResultFileError(f"{path}: damaged: its manifest does not match its "
                                  "checksum")
        manifest = json.loads(raw.decode("utf-8"))
        groups, arrays, texts = {}, {}, {}
        for name, entry in manifest.items():
            if name.endswith("@"):
                gpath = name[:-1] or "/"
                obj = handle if gpath == "/" else handle[gpath]
                attrs = {k: v for k, v in obj.attrs.items()
                         if not (gpath == "/" and k == "manifest_sha256")}
                if mapping_digest(attrs) != entry["sha256"]:
                    raise ResultFileError(f"{path}: damaged: the attributes of {gpath} do "
                                          "not match their checksum")
                groups[gpath] = attrs
            elif "text_sha256" in entry:
                value = handle[name][()]
                if not isinstance(value, bytes) or len(value) != entry["nbytes"] \
                        or bytes_digest(value) != entry["text_sha256"]:
                    raise ResultFileError(f"{path}: damaged: {name} does not match its "
                                          "checksum")
                texts[name] = value.decode("utf-8")
            else:
                ds = handle[name]
                if list(ds.shape) != entry["shape"] or ds.dtype.str != entry["dtype"]:
                    raise ResultFileError(f"{path}: damaged: {name} has shape {ds.shape} "
                                          f"and type {ds.dtype.str}, the manifest says "
                                          f"{tuple(entry['shape'])} and {entry['dtype']}")
                a = np.asarray(ds[()])
                if array_digest(a) != entry["sha256"]:
                    raise ResultFileError(f"{path}: damaged: {name} does not match its "
                                          "checksum")
                arrays[name] = a
    return from_flat(groups, arrays, texts)


def read_contents(path: Path) -> Contents:
    """The file at ``path`` with its journal replayed (see the module docstring)."""
    for _ in range(_ATTEMPTS):
        try:
            contents = _read_snapshot(path)
        except ResultFileError:
            raise
        except Exception as exc:  # noqa: BLE001 (whatever damaged bytes make h5py raise)
            raise ResultFileError(f"{path}: damaged result file ({_one_line(exc)})") from None
        try:
            generation, records = read_journal(journal_path(path))
        except JournalError as exc:
            raise ResultFileError(str(exc)) from None
        if generation is None or generation == contents.header["journal_generation"]:
            break
        # a writer replaced the file between the two reads, or an old journal was left
        # behind by a writer stopped after its last snapshot: read both again
    else:
        records = []
    try:
        for op, args, arrays in records:
            contents.apply(op, args, arrays)
    except (ContentsError, KeyError, ValueError, TypeError) as exc:
        raise ResultFileError(f"{journal_path(path)}: damaged journal "
                              f"({_one_line(exc)})") from None
    return contents


@dataclass(frozen=True, eq=False)
class Result:
    """A result read into memory (:func:`load`).

    ``problem``: ``ring_diagram``, ``ring``, ``tweezers``; ``status``:
    ``running`` (being written, or the writer was killed), ``complete``,
    ``incomplete`` (computed, but a branch stopped early), ``interrupted`` or
    ``failed``; ``settings``: the computation's settings; ``attributes``: the
    plain numbers (``twist_ratio``, ``n_nodes``, ``diameter``, ``closed``, ...);
    ``summary``: the JSON summary of the finished run (``None`` before);
    ``branches``: name -> :class:`~supercoil.continuation.Branch`, in the order
    they were computed; ``complete_branches``: the names whose computation
    ended (the others can be continued by ``--resume``); ``extras``: named
    groups of arrays (the tweezers' quasi-static ``path``).
    """

    path: Path
    schema_version: str
    problem: str
    status: str
    message: str
    units: str
    settings: dict
    provenance: dict
    conventions: dict
    attributes: dict
    branches: Mapping[str, Branch]
    complete_branches: frozenset[str]
    contact_branches: frozenset[str]
    summary: dict | None = None
    study_text: str | None = None
    created: str = ""
    updated: str = ""
    extras: Mapping[str, Mapping[str, np.ndarray]] = field(default_factory=dict)

    def __repr__(self) -> str:
        head = (f"Result({str(self.path)!r}, problem={self.problem!r}, "
                f"status={self.status!r}, units={self.units!r})")
        lines = [head]
        names = list(self.branches)
        shown = [f"{n} ({len(self.branches[n])} points)" for n in names[:8]]
        if len(names) > 8:
            shown.append(f"... {len(names) - 8} more")
        lines.append(f"  branches: {', '.join(shown) or 'none'}")
        if self.message:
            lines.append(f"  message: {self.message}")
        return "\n".join(lines)

    @property
    def branch_names(self) -> tuple[str, ...]:
        return tuple(self.branches)

    def branch(self, name: str) -> Branch:
        """The branch called ``name`` (KeyError naming the stored ones otherwise)."""
        try:
            return self.branches[name]
        except KeyError:
            raise KeyError(f"{self.path}: no branch {name!r}; stored: "
                           f"{', '.join(self.branch_names) or 'none'}") from None

    @property
    def closed(self) -> bool:
        return bool(self.attributes.get("closed", True))

    @property
    def diameter(self) -> float | None:
        """Tube diameter D in units of L (None for a rod without a tube)."""
        d = self.attributes.get("diameter")
        return None if d is None or not math.isfinite(float(d)) else float(d)

    @property
    def n_nodes(self) -> int:
        return int(self.attributes["n_nodes"])

    def centreline(self, branch: str, index: int) -> np.ndarray:
        """(n_nodes, 3) node positions of point ``index`` of ``branch`` (units of L).

        A state's first ``3 n_nodes`` DOFs are the node coordinates (rings:
        all of them). Negative ``index`` counts from the end.
        """
        b = self.branch(branch)
        k = len(b)
        if not -k <= index < k:
            raise IndexError(f"{self.path}: branch {branch!r} has {k} points (0 .. {k - 1}); "
                             f"point {index} asked for")
        n = self.n_nodes
        return np.asarray(b.states[index][:3 * n], float).reshape(n, 3)

    def records(self, branch: str) -> dict[str, np.ndarray]:
        """name -> (k, ...) per-point arrays of ``branch``, with ``parameter`` (its
        values), ``unstable_count``, ``zero_modes``, ``determinant_sign``,
        ``arclength`` and ``stable`` beside the branch's own records."""
        b = self.branch(branch)
        out = {"parameter": b.parameter_values, "arclength": b.arclength,
               "unstable_count": b.unstable_count, "zero_modes": b.zero_modes,
               "determinant_sign": b.determinant_sign, "stable": b.stable}
        out.update(b.records)
        return out

    def points(self, branch: str | None = None) -> list[dict]:
        """One dict per point: the summary's when the run finished (contact lists
        included), else built from the stored records."""
        if self.summary is not None and "points" in self.summary:
            rows = self.summary["points"]
            if branch is not None:
                self.branch(branch)
                rows = [r for r in rows if r.get("branch") == branch]
            return [dict(r) for r in rows]
        out = []
        for b in self.branches.values() if branch is None else (self.branch(branch),):
            for i in range(len(b)):
                entry = {"branch": b.name, "index": i, b.parameter: float(b.parameter_values[i])}
                entry.update({k: jsonable(v[i]) for k, v in b.records.items()})
                entry.update(unstable_count=int(b.unstable_count[i]),
                             zero_modes=int(b.zero_modes[i]),
                             determinant_sign=int(b.determinant_sign[i]),
                             stable=bool(b.stable[i]))
                out.append(entry)
        return out

    def special_points(self) -> list[SpecialPoint]:
        return [p for b in self.branches.values() for p in b.special_points]


def load(path: str | Path) -> Result:
    """Read a result: ``result.h5`` or the output folder that holds it, with the points
    its journal holds (a run still writing it, or stopped). Raises
    :class:`ResultFileError` (an :class:`~supercoil.errors.InputError`) naming the file
    and what is wrong when it is missing, not a supercoil result, of an unknown schema
    version, damaged or truncated."""
    path = resolve(path)
    contents = read_contents(path)
    try:
        header = contents.header
        branches = {name: e.get() for name, e in contents.branches.items()}
        summary = None if contents.summary is None else json.loads(contents.summary)
        return Result(
            path=path, schema_version=header["schema_version"], problem=header["problem"],
            status=header["status"], message=header["message"], units=header["units"],
            settings=header["settings"], provenance=header["provenance"],
            conventions=header["conventions"], attributes=dict(contents.attributes),
            branches=MappingProxyType(branches),
            complete_branches=frozenset(n for n, e in contents.branches.items()
                                        if e.complete),
            contact_branches=frozenset(n for n, e in contents.branches.items() if e.contact),
            summary=summary, study_text=contents.study, created=header["created"],
            updated=header["updated"],
            extras=MappingProxyType({k: MappingProxyType(v)
                                     for k, v in contents.extras.items()}))
    except (ContentsError, KeyError, ValueError, TypeError) as exc:
        raise ResultFileError(f"{path}: damaged result file ({_one_line(exc)})") from None
