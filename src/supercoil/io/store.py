"""Result files: one self-describing HDF5 file per study (``docs/results.md``).

Layout (``SCHEMA_VERSION`` "1.0")::

    /                        attrs: format = "supercoil-result", schema_version, problem,
                             units, status, message, settings (JSON), provenance (JSON),
                             conventions (JSON), created, updated, and the main numbers
                             as plain attributes (twist_ratio, length_over_diameter,
                             diameter, n_nodes, closed, ...)
    /study                   the study file's text (TOML), when the run came from one
    /summary                 the JSON summary of the finished run (e.g. diagram.json's
                             payload, with the per-point contact lists)
    /branches/<key>/         the branch's name with % and / percent-encoded (and a leading .)
                             attrs: name, parent, parameter, status, message, n_points,
                             n_special, complete, contact, order
        parameter_values     (k,)           resizable along the first axis ("point")
        states               (k, n_dofs)    full states (a ring: flat node coordinates)
        multipliers          (k, m)
        unstable_count, zero_modes, determinant_sign   (k,) int64
        nearest_eigenvalue, arclength                  (k,)
        tangents             (k, n_dofs + m + 1)
        records/<record>     (k, ...)       the branch's per-point records
        phase_modes (r, n_dofs), phase_state (n_dofs,)
        point, dof, multiplier, tangent_component, phase_mode   dimension scales
        special_points/<i>/  one group per special point: scalars as attributes,
                             q, multipliers, tangent, critical_eigenvalues,
                             critical_modes as datasets, records/<record>
        origin/              the special point the branch starts from (same layout)

Appending a point resizes the datasets by one row and writes it, then the
branch's ``n_points`` (the count a reader trusts; rows beyond it are ignored),
then flushes the file, so a run that is interrupted (Ctrl-C, a failure, a
kill) leaves a readable file with every point computed so far. Within one
append a Ctrl-C is held back until the point is written. A branch replaced at
the end of its computation (:meth:`ResultWriter.write_branch`) is written
under a temporary name and then moved into place.

:func:`load` reads a file into a :class:`Result` (branches as
:class:`~supercoil.continuation.Branch` objects, settings, per-point records).
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import threading
from dataclasses import dataclass, field, fields
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Self

import numpy as np

from supercoil.continuation.branch import Branch, SpecialPoint, jsonable
from supercoil.continuation.options import ContinuationStatus
from supercoil.io.results import CONVENTIONS, to_jsonable

FORMAT = "supercoil-result"
RESULT_NAME = "result.h5"  # the result file's name in an output folder (supercoil run)
SCHEMA_VERSION = "1.0"
READABLE_VERSIONS = ("1.0",)
RUN_STATUSES = ("running", "complete", "incomplete", "interrupted", "failed")

_POINT_ARRAYS = ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                 "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")
_INT_ARRAYS = ("unstable_count", "zero_modes", "determinant_sign")
_SPECIAL_SCALARS = ("kind", "label", "branch", "index", "parameter", "arclength",
                    "unstable_count", "count_before", "count_after", "located", "tolerance")
_SPECIAL_ARRAYS = ("q", "multipliers", "tangent", "critical_eigenvalues", "critical_modes")
_CHUNK_ROWS = 16


class ResultFileError(ValueError):
    """A result file that is missing, unreadable, not ours, or of another schema version.

    The message is one line naming the file and what is wrong.
    """


def _h5py():
    import h5py

    return h5py


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _json(value) -> str:
    return json.dumps(to_jsonable(value), allow_nan=False)


def _fixed(text: str):
    """``text`` as a fixed-length UTF-8 string value and its HDF5 type.

    Fixed-length strings live inside their attribute or dataset; variable-length
    ones go to the file's global heap, which a writer killed during a flush can
    leave inconsistent (measured: "bad heap index" on reading).
    """
    raw = str(text).encode("utf-8")
    n = max(1, len(raw))
    return np.bytes_(raw), _h5py().string_dtype("utf-8", n)


def _set_text(attrs, key: str, text: str) -> None:
    value, dtype = _fixed(text)
    attrs.create(key, data=value, dtype=dtype)


def _text_dataset(parent, key: str, text: str) -> None:
    value, dtype = _fixed(text)
    parent.create_dataset(key, data=value, dtype=dtype)


@contextlib.contextmanager
def _hold_interrupts():
    """Defer SIGINT (Ctrl-C) until the block is done (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received = []
    previous = signal.getsignal(signal.SIGINT)

    def handler(signum, frame):
        received.append(signum)

    try:
        signal.signal(signal.SIGINT, handler)
    except (ValueError, TypeError):  # not installable here: no deferral
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            if callable(previous):
                previous(signal.SIGINT, None)
            elif previous != signal.SIG_IGN:
                raise KeyboardInterrupt


# ============================================================================ writing
class ResultWriter:
    """Writes (or continues) one result file. Use :meth:`create` or :meth:`reopen`.

    Every public method leaves the file flushed and readable. Close it with
    :meth:`close` (or use the writer as a context manager).
    """

    def __init__(self, path: Path, handle):
        self.path = path
        self._file = handle
        self._order = len(handle.get("branches", {}))

    # -- opening ----------------------------------------------------------------------------
    @classmethod
    def create(cls, path: str | Path, *, problem: str, settings: dict,
               units: str = "nondimensional", provenance: dict | None = None,
               attributes: dict | None = None, study_text: str | None = None,
               overwrite: bool = False) -> ResultWriter:
        """Start a new result file at ``path``.

        ``settings``: the study's validated settings (plain data, stored as
        JSON); ``attributes``: scalars stored as plain HDF5 attributes
        (``twist_ratio``, ``n_nodes``, ...); ``provenance``: versions,
        tolerances, contact treatment (``supercoil_version``, ``h5py_version``
        and a timestamp are added). An existing file is refused
        (:class:`FileExistsError`) unless ``overwrite``.
        """
        path = Path(path)
        if path.exists():
            if not overwrite:
                raise FileExistsError(f"{path}: exists; give another path or allow "
                                      "overwriting")
            # HDF5 truncates before it takes the lock: make sure no run is writing the
            # old file (its lock), then replace it by a new file
            try:
                _open_for_writing(path, "r+").close()
            except OSError:
                pass  # not an HDF5 file: nobody writes it
            path.unlink()
        handle = _open_for_writing(path, "w-")
        try:
            attrs = handle.attrs
            _set_text(attrs, "format", FORMAT)
            _set_text(attrs, "schema_version", SCHEMA_VERSION)
            _set_text(attrs, "problem", str(problem))
            _set_text(attrs, "units", str(units))
            _set_text(attrs, "status", "running")
            _set_text(attrs, "message", "")
            _set_text(attrs, "settings", _json(settings))
            _set_text(attrs, "conventions", _json(CONVENTIONS))
            _set_text(attrs, "provenance", _json(_provenance(provenance)))
            _set_text(attrs, "created", _now())
            _set_text(attrs, "updated", _now())
            for key, value in (attributes or {}).items():
                if isinstance(value, str):
                    _set_text(attrs, str(key), value)
                else:
                    attrs[str(key)] = value
            if study_text is not None:
                _text_dataset(handle, "study", study_text)
            handle.create_group("branches")
            handle.flush()
        except BaseException:
            handle.close()
            raise
        return cls(path, handle)

    @classmethod
    def reopen(cls, path: str | Path) -> ResultWriter:
        """Open an existing result file to continue it (``--resume``); status -> running."""
        path = Path(path)
        _check(path).close()  # one-line errors for missing, corrupt or foreign files
        handle = _open_for_writing(path, "r+")
        _set_text(handle.attrs, "status", "running")
        _set_text(handle.attrs, "updated", _now())
        handle.flush()
        return cls(path, handle)

    def close(self) -> None:
        if self._file is not None and self._file.id.valid:
            self._file.close()
        self._file = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- branches --------------------------------------------------------------------------
    def branch_names(self) -> list[str]:
        """Names of the branches in the file, in the order they were started."""
        groups = [g for key, g in self._file["branches"].items() if not key.startswith(".")]
        return [_text(g.attrs["name"]) for g in sorted(groups, key=lambda g: int(g.attrs["order"]))]

    def stored_branches(self) -> dict[str, tuple[Branch, bool]]:
        """name -> (branch as stored, whether its computation ended)."""
        groups = {name: self._file["branches"][_key(name)] for name in self.branch_names()}
        return {name: (_read_branch(g), bool(g.attrs["complete"])) for name, g in groups.items()}

    def stored_points(self, name: str) -> int:
        """Number of points of branch ``name`` in the file (0 if absent)."""
        group = self._file["branches"].get(_key(name))
        return 0 if group is None else int(group.attrs["n_points"])

    def append(self, branch: Branch, *, contact: bool = False) -> int:
        """Store the points of ``branch`` (a partial branch, growing) not stored yet.

        The first call for a name creates the branch's group (marked
        incomplete); later calls append the new rows and special points. The
        stored points are assumed to be a prefix of ``branch``. Returns the
        number of points now stored.
        """
        with _hold_interrupts():
            key = _key(branch.name)
            group = self._file["branches"].get(key)
            if group is not None and not _continues(group, branch):
                # another run of the same name (a restarted or recomputed branch)
                order = int(group.attrs["order"])
                del self._file["branches"][key]
                group = self._new_group(self._file["branches"], key, branch,
                                        complete=False, contact=contact, order=order)
            if group is None:
                group = self._new_group(self._file["branches"], key, branch,
                                        complete=False, contact=contact)
            stored = int(group.attrs["n_points"])
            k = len(branch)
            if k > stored:
                _write_rows(group, branch, stored, k)
                group.attrs["n_points"] = k
            n_special = int(group.attrs["n_special"])
            for i in range(n_special, len(branch.special_points)):
                _write_special(group["special_points"], f"{i:04d}", branch.special_points[i])
            group.attrs["n_special"] = len(branch.special_points)
            _update_phase(group, branch)
            if _text(group.attrs["status"]) != branch.status.name:
                _set_text(group.attrs, "status", branch.status.name)
            if _text(group.attrs["message"]) != branch.message:
                _set_text(group.attrs, "message", branch.message)
            self._file.flush()
        return max(k, stored)

    def write_branch(self, branch: Branch, *, complete: bool = True,
                     contact: bool = False) -> None:
        """Store ``branch`` whole, replacing any stored version of the same name.

        Written under a temporary name, then moved into place, so an
        interruption leaves either the old or the new version.
        """
        with _hold_interrupts():
            branches = self._file["branches"]
            key = _key(branch.name)
            temporary = f".{key}.new"
            if temporary in branches:
                del branches[temporary]
            old = branches.get(key)
            order = int(old.attrs["order"]) if old is not None else None
            group = self._new_group(branches, temporary, branch, complete=complete,
                                    contact=contact, order=order)
            _write_rows(group, branch, 0, len(branch))
            group.attrs["n_points"] = len(branch)
            for i, p in enumerate(branch.special_points):
                _write_special(group["special_points"], f"{i:04d}", p)
            group.attrs["n_special"] = len(branch.special_points)
            self._file.flush()
            if old is not None:
                del branches[key]
            branches.move(temporary, key)
            self._touch()

    def mark_complete(self, name: str, complete: bool = True) -> None:
        group = self._file["branches"][_key(name)]
        group.attrs["complete"] = bool(complete)
        self._touch()

    def remove_branch(self, name: str) -> None:
        with _hold_interrupts():
            branches = self._file["branches"]
            if _key(name) in branches:
                del branches[_key(name)]
            self._touch()

    # -- the run -----------------------------------------------------------------------------
    def set_summary(self, summary: dict) -> None:
        """Store the run's JSON summary (e.g. ``diagram.json``'s payload)."""
        with _hold_interrupts():
            if "summary" in self._file:
                del self._file["summary"]
            _text_dataset(self._file, "summary", _json(summary))
            self._touch()

    def set_status(self, status: str, message: str = "") -> None:
        """``status``: one of ``RUN_STATUSES``; ``message`` says what happened."""
        if status not in RUN_STATUSES:
            raise ValueError(f"run status {status!r}: give one of {', '.join(RUN_STATUSES)}")
        with _hold_interrupts():
            _set_text(self._file.attrs, "status", status)
            _set_text(self._file.attrs, "message", str(message))
            self._touch()

    def set_attribute(self, key: str, value) -> None:
        self._file.attrs[key] = value
        self._touch()

    # -- internals -------------------------------------------------------------------------------
    def _touch(self) -> None:
        _set_text(self._file.attrs, "updated", _now())
        self._file.flush()

    def _new_group(self, parent, key: str, branch: Branch, *, complete: bool, contact: bool,
                   order: int | None = None):
        group = parent.create_group(key)
        a = group.attrs
        _set_text(a, "name", branch.name)
        _set_text(a, "parent", "" if branch.parent is None else branch.parent)
        _set_text(a, "parameter", branch.parameter)
        _set_text(a, "status", branch.status.name)
        _set_text(a, "message", branch.message)
        a["n_points"] = 0
        a["n_special"] = 0
        a["complete"] = bool(complete)
        a["contact"] = bool(contact)
        if order is None:
            order = self._order
            self._order += 1
        a["order"] = int(order)
        n_dofs = branch.states.shape[1] if branch.states.ndim == 2 else 0
        m = branch.multipliers.shape[1] if branch.multipliers.ndim == 2 else 0
        widths = {"states": n_dofs, "multipliers": m, "tangents": n_dofs + m + 1}
        scales = {"point": _scale(group, "point", np.zeros(0, np.int64), resizable=True),
                  "dof": _scale(group, "dof", np.arange(n_dofs)),
                  "multiplier": _scale(group, "multiplier", np.arange(m)),
                  "tangent_component": _scale(group, "tangent_component",
                                              np.arange(n_dofs + m + 1))}
        second = {"states": "dof", "multipliers": "multiplier", "tangents": "tangent_component"}
        for name in _POINT_ARRAYS:
            width = widths.get(name)
            dtype = np.int64 if name in _INT_ARRAYS else np.float64
            shape = (0,) if width is None else (0, width)
            ds = _resizable(group, name, shape, dtype)
            ds.dims[0].attach_scale(scales["point"])
            if width is not None:
                ds.dims[1].attach_scale(scales[second[name]])
        records = group.create_group("records")
        for name, values in branch.records.items():
            values = np.asarray(values)
            if values.dtype.kind not in "biuf":
                raise TypeError(f"branch {branch.name}: record {name!r} is not numeric "
                                f"(dtype {values.dtype}); records must be numbers")
            dtype = {"b": np.bool_, "i": np.int64, "u": np.int64}.get(values.dtype.kind,
                                                                      np.float64)
            ds = _resizable(records, name, (0, *values.shape[1:]), dtype)
            ds.dims[0].attach_scale(scales["point"])
        phase = np.asarray(branch.phase_modes, float)
        phase = phase.reshape(-1, n_dofs) if phase.size else np.zeros((0, n_dofs))
        scales["phase_mode"] = _scale(group, "phase_mode", np.arange(phase.shape[0]))
        pm = group.create_dataset("phase_modes", data=phase)
        pm.dims[0].attach_scale(scales["phase_mode"])
        pm.dims[1].attach_scale(scales["dof"])
        ps = np.asarray(branch.phase_state, float)
        group.create_dataset("phase_state", data=ps if ps.size else np.zeros(0))
        group.create_group("special_points")
        if branch.origin is not None:
            _write_special(group, "origin", branch.origin)
        return group


def _key(name: str) -> str:
    """The group name of branch ``name``: ``%`` and ``/`` percent-encoded, and a leading
    ``.`` (groups starting with ``.`` are replacements being written)."""
    key = str(name).replace("%", "%25").replace("/", "%2F")
    if key.startswith("."):
        key = "%2E" + key[1:]
    return key or "%00"


def _open_for_writing(path: Path, mode: str):
    try:
        return _h5py().File(path, mode)
    except OSError as exc:
        reason = " ".join(str(exc).split())
        if "unable to lock file" in reason:
            raise ResultFileError(f"{path}: another running process is writing it (it holds "
                                  "the file lock); wait for it to end or stop it") from None
        raise


def _continues(group, branch: Branch) -> bool:
    """Whether ``branch`` extends the points stored in ``group`` (first and last stored
    points equal)."""
    stored = int(group.attrs["n_points"])
    if stored == 0:
        return True
    if len(branch) < stored:
        return False
    values = group["parameter_values"]
    return (values[0] == branch.parameter_values[0]
            and values[stored - 1] == branch.parameter_values[stored - 1]
            and np.array_equal(group["states"][stored - 1], branch.states[stored - 1]))


def _provenance(extra: dict | None) -> dict:
    import platform

    from supercoil import __version__

    out = {"supercoil_version": __version__, "h5py_version": _h5py().__version__,
           "numpy_version": np.__version__, "python_version": platform.python_version(),
           "timestamp": _now()}
    out.update(extra or {})
    return out


def _scale(group, name: str, values: np.ndarray, resizable: bool = False):
    if resizable:
        ds = group.create_dataset(name, shape=values.shape, maxshape=(None,),
                                  chunks=(_CHUNK_ROWS * 4,), dtype=values.dtype)
    else:
        ds = group.create_dataset(name, data=values)
    ds.make_scale(name)
    return ds


def _resizable(group, name: str, shape: tuple, dtype):
    if 0 in shape[1:]:  # e.g. the multipliers of a problem without constraints
        return group.create_dataset(name, shape=shape, maxshape=(None, *shape[1:]),
                                    dtype=dtype)
    chunks = (_CHUNK_ROWS, *shape[1:])
    return group.create_dataset(name, shape=shape, maxshape=(None, *shape[1:]),
                                chunks=chunks, dtype=dtype)


def _update_phase(group, branch: Branch) -> None:
    """Rewrite the phase rows when the branch moved its gauge (``regauge``): a resume
    must start from the gauge the last point satisfies."""
    phase = np.asarray(branch.phase_modes, float)
    state = np.asarray(branch.phase_state, float)
    stored = group["phase_modes"]
    if phase.size == 0 or (stored.shape == phase.shape
                           and np.array_equal(stored[()], phase)
                           and np.array_equal(group["phase_state"][()], state)):
        return
    if stored.shape != phase.shape:
        return  # another number of rows: not a moved gauge; left as written
    stored[...] = phase
    if group["phase_state"].shape == state.shape:
        group["phase_state"][...] = state
    else:
        del group["phase_state"]
        group.create_dataset("phase_state", data=state)


def _write_rows(group, branch: Branch, start: int, stop: int) -> None:
    if stop <= start:
        return
    for name in _POINT_ARRAYS:
        _put(group[name], np.asarray(getattr(branch, name))[start:stop], start, stop)
    for name, values in branch.records.items():
        if name not in group["records"]:
            raise ValueError(f"branch {branch.name}: record {name!r} appeared after the "
                             "first point; records must be the same at every point")
        _put(group["records"][name], np.asarray(values)[start:stop], start, stop)
    point = group["point"]
    point.resize((stop,))
    point[start:stop] = np.arange(start, stop)


def _put(ds, rows: np.ndarray, start: int, stop: int) -> None:
    ds.resize((stop, *ds.shape[1:]))
    ds[start:stop] = rows.reshape((stop - start, *ds.shape[1:]))


def _write_special(parent, key: str, p: SpecialPoint) -> None:
    if key in parent:
        del parent[key]
    group = parent.create_group(key)
    for name in _SPECIAL_SCALARS:
        value = getattr(p, name)
        if isinstance(value, str):
            _set_text(group.attrs, name, value)
        else:
            group.attrs[name] = value if not isinstance(value, np.generic) else value.item()
    for name in _SPECIAL_ARRAYS:
        group.create_dataset(name, data=np.asarray(getattr(p, name), dtype=float))
    records = group.create_group("records")
    for name, value in p.records.items():
        records.create_dataset(name, data=np.asarray(value))


# ============================================================================ reading
@dataclass(frozen=True, eq=False)
class Result:
    """A result file read into memory (:func:`load`).

    ``problem``: ``ring_diagram``, ``ring``, ...; ``status``: ``running``
    (still being written, or the writer was killed), ``complete``,
    ``incomplete`` (computed, but a branch stopped early), ``interrupted``
    (Ctrl-C) or ``failed``; ``settings``: the study's validated settings
    (``rod``, ``units``, ``problem``, ``continuation``, ``outputs`` tables);
    ``attributes``: the plain numbers (``twist_ratio``, ``n_nodes``,
    ``diameter``, ``closed``, ...); ``summary``: the JSON summary of the
    finished run (``None`` while running); ``branches``: in the order they
    were computed; ``complete_branches``: the names whose computation ended
    (the others were interrupted and can be continued by ``--resume``).
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
    branches: tuple[Branch, ...]
    complete_branches: frozenset[str]
    contact_branches: frozenset[str]
    summary: dict | None = None
    study_text: str | None = None
    created: str = ""
    updated: str = ""
    _by_name: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        self._by_name.update({b.name: b for b in self.branches})

    @property
    def branch_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.branches)

    def branch(self, name: str) -> Branch:
        """The branch called ``name`` (KeyError naming the stored ones otherwise)."""
        try:
            return self._by_name[name]
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
        """One dict per point (JSON keys of DESIGN.md): the summary's when the run
        finished (contact lists included), else built from the stored records."""
        if self.summary is not None and "points" in self.summary:
            rows = self.summary["points"]
            if branch is not None:
                self.branch(branch)
                rows = [r for r in rows if r.get("branch") == branch]
            return [dict(r) for r in rows]
        out = []
        for b in self.branches if branch is None else (self.branch(branch),):
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
        return [p for b in self.branches for p in b.special_points]


def _check(path: Path):
    """Open ``path`` read-only after one-line checks; returns the h5py File."""
    if not path.exists():
        raise ResultFileError(f"{path}: no such result file")
    if path.is_dir():
        raise ResultFileError(f"{path}: is a folder, not a result file (give the .h5 file "
                              "inside it)")
    h5py = _h5py()
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        reason = " ".join(str(exc).split())
        if "unable to lock file" not in reason:
            raise ResultFileError(f"{path}: not a readable HDF5 result file ({reason})"
                                  ) from None
        # a run is writing it (it holds the lock): read what it has flushed so far
        try:
            handle = h5py.File(path, "r", locking=False)
        except OSError:
            raise ResultFileError(f"{path}: being written by a running process and not "
                                  "readable at this moment; try again") from None
    try:
        if _text(handle.attrs.get("format", "")) != FORMAT:
            raise ResultFileError(f"{path}: an HDF5 file but not a supercoil result file "
                                  f"(no format = {FORMAT!r} attribute)")
        version = _text(handle.attrs.get("schema_version", ""))
        if version not in READABLE_VERSIONS:
            raise ResultFileError(f"{path}: result schema version {version!r}; this supercoil "
                                  f"reads {', '.join(READABLE_VERSIONS)}")
    except BaseException:
        handle.close()
        raise
    return handle


def load(path: str | Path) -> Result:
    """Read the result file at ``path`` (written by ``supercoil run`` or a
    :class:`ResultWriter`) into a :class:`Result`.

    A file that a run is still writing (status ``running``) is read without the
    HDF5 file lock: the points flushed so far.

    Raises :class:`ResultFileError` (one line naming the file) if it is
    missing, not HDF5, not a supercoil result, of an unknown schema version,
    or damaged.
    """
    path = Path(path)
    handle = _check(path)
    try:
        with handle:
            return _read(path, handle)
    except ResultFileError:
        raise
    except (OSError, KeyError, ValueError, TypeError, json.JSONDecodeError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ResultFileError(f"{path}: damaged result file, or caught in the middle of a "
                              f"write by a running process ({reason})") from None


def _text(value) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def _read(path: Path, handle) -> Result:
    attrs = handle.attrs
    reserved = {"format", "schema_version", "problem", "units", "status", "message",
                "settings", "conventions", "provenance", "created", "updated"}
    plain = {k: _text(v) if isinstance(v, (bytes, str)) else jsonable(v)
             for k, v in attrs.items() if k not in reserved}
    groups = [g for key, g in handle["branches"].items() if not key.startswith(".")]
    groups.sort(key=lambda g: int(g.attrs["order"]))
    branches, complete, contact = [], set(), set()
    for group in groups:
        branch = _read_branch(group)
        branches.append(branch)
        if bool(group.attrs["complete"]):
            complete.add(branch.name)
        if bool(group.attrs["contact"]):
            contact.add(branch.name)
    summary = json.loads(_text(handle["summary"][()])) if "summary" in handle else None
    study = _text(handle["study"][()]) if "study" in handle else None
    return Result(path=path, schema_version=_text(attrs["schema_version"]),
                  problem=_text(attrs["problem"]), status=_text(attrs["status"]),
                  message=_text(attrs["message"]), units=_text(attrs["units"]),
                  settings=json.loads(_text(attrs["settings"])),
                  provenance=json.loads(_text(attrs["provenance"])),
                  conventions=json.loads(_text(attrs["conventions"])),
                  attributes=plain, branches=tuple(branches),
                  complete_branches=frozenset(complete), contact_branches=frozenset(contact),
                  summary=summary, study_text=study, created=_text(attrs.get("created", "")),
                  updated=_text(attrs.get("updated", "")))


def _read_branch(group) -> Branch:
    k = int(group.attrs["n_points"])
    arrays = {name: np.asarray(group[name][:k]) for name in _POINT_ARRAYS}
    records = {name: np.asarray(ds[:k]) for name, ds in group["records"].items()}
    n_special = int(group.attrs["n_special"])
    specials = tuple(_read_special(group["special_points"][f"{i:04d}"])
                     for i in range(n_special))
    origin = _read_special(group["origin"]) if "origin" in group else None
    parent = _text(group.attrs["parent"]) or None
    return Branch(name=_text(group.attrs["name"]), parent=parent, origin=origin,
                  parameter=_text(group.attrs["parameter"]), special_points=specials,
                  status=ContinuationStatus[_text(group.attrs["status"])],
                  message=_text(group.attrs["message"]), records=records,
                  phase_modes=np.asarray(group["phase_modes"][()]),
                  phase_state=np.asarray(group["phase_state"][()]), **arrays)


def _read_special(group) -> SpecialPoint:
    kwargs: dict[str, Any] = {}
    for name in _SPECIAL_SCALARS:
        value = group.attrs[name]
        if isinstance(value, (bytes, str)):
            value = _text(value)
        elif isinstance(value, np.generic):
            value = value.item()
        kwargs[name] = value
    for name in _SPECIAL_ARRAYS:
        kwargs[name] = np.asarray(group[name][()])
    kwargs["records"] = {name: np.asarray(ds[()]) for name, ds in group["records"].items()}
    kwargs["located"] = bool(kwargs["located"])
    for name in ("index", "unstable_count", "count_before", "count_after"):
        kwargs[name] = int(kwargs[name])
    return SpecialPoint(**kwargs)


def branch_fields() -> tuple[str, ...]:
    """Names of the :class:`Branch` fields a result file stores (all of them)."""
    return tuple(f.name for f in fields(Branch))
