"""A :class:`~supercoil.continuation.Branch` as named arrays and attribute groups.

One flat form serves the result file (each array a dataset, each attribute
group an HDF5 group's attributes) and its journal (a record of the arrays
added since the last record): :func:`flatten` and :func:`unflatten`, and
:class:`BranchBuilder`, which grows a branch from such records.

Names inside a branch (``docs/results.md``, "Layout")::

    parameter_values, states, multipliers, unstable_count, zero_modes,
    determinant_sign, nearest_eigenvalue, tangents, arclength   per point
    next_step, gauge_moved                      per point, optional (the step
                                                controller's state; absent: unknown)
    frames/<name>                               per point, optional: the carried frames
                                                of a problem that stores them
                                                (Frames.stored: a Cosserat rod's
                                                reference_rotations (k, N, 3, 3) and
                                                centres (k, N, 3)); absent: carried
                                                again along the states when continued
    records/<record>                                            per point
    phase_modes, phase_state
    special_points/<iiii>/{q, multipliers, tangent, critical_eigenvalues,
                           critical_modes, records/<record>,
                           frames/<name> (stored frames only)}  (+ scalar attributes)
    origin/...                                                  the same
"""

from __future__ import annotations

import numpy as np

from supercoil.continuation.branch import Branch, SpecialPoint
from supercoil.continuation.options import ContinuationStatus
from supercoil.solvers.carried import Frames

POINT_ARRAYS = ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")
INT_ARRAYS = ("unstable_count", "zero_modes", "determinant_sign")
# per point, optional: a record without them (a file written before they were kept)
# reads as unknown (NaN, False)
STEP_ARRAYS = {"next_step": (np.float64, np.nan), "gauge_moved": (np.bool_, False)}
SPECIAL_SCALARS = {"kind": str, "label": str, "branch": str, "index": int, "parameter": float,
                   "arclength": float, "unstable_count": int, "count_before": int,
                   "count_after": int, "located": bool, "tolerance": float}
SPECIAL_ARRAYS = ("q", "multipliers", "tangent", "critical_eigenvalues", "critical_modes")


class CodecError(ValueError):
    """Stored arrays that do not make a branch (a name, shape or type out of place)."""


def key(name: str) -> str:
    """A name as one path component: ``%`` and ``/`` percent-encoded, a leading ``.`` too."""
    out = str(name).replace("%", "%25").replace("/", "%2F")
    if out.startswith("."):
        out = "%2E" + out[1:]
    return out or "%00"


def unkey(text: str) -> str:
    """The name of a :func:`key`."""
    if text == "%00":
        return ""
    if text.startswith("%2E"):
        text = "." + text[3:]
    return text.replace("%2F", "/").replace("%25", "%")


def _record_array(branch_name: str, name: str, values) -> np.ndarray:
    values = np.asarray(values)
    if values.dtype.kind not in "biuf":
        raise TypeError(f"branch {branch_name}: record {name!r} is not numeric (dtype "
                        f"{values.dtype}); records must be numbers")
    dtype = {"b": np.bool_, "i": np.int64, "u": np.int64}.get(values.dtype.kind, np.float64)
    return np.asarray(values, dtype=dtype, order="C")


def _special(prefix: str, p: SpecialPoint, groups: dict, arrays: dict) -> None:
    groups[prefix] = {name: kind(getattr(p, name)) for name, kind in SPECIAL_SCALARS.items()}
    for name in SPECIAL_ARRAYS:
        arrays[f"{prefix}/{name}"] = np.asarray(getattr(p, name), dtype=float, order="C")
    for name, value in p.records.items():
        arrays[f"{prefix}/records/{key(name)}"] = _record_array(p.branch, name, value)
    if p.frames is not None and p.frames.stored:
        for name, value in p.frames.values.items():
            arrays[f"{prefix}/frames/{key(name)}"] = np.asarray(value, dtype=float,
                                                                order="C")


def flatten(branch: Branch, start: int = 0, special_start: int = 0,
            origin: bool = True) -> tuple[dict, dict, dict]:
    """``(meta, groups, arrays)`` of ``branch``: its attributes; the scalar attributes of
    its special points (and origin) by path; its arrays by path. Only the points from
    ``start`` on and the special points from ``special_start`` on are included (a
    journal record of what was added); the origin only if ``origin``."""
    n_dofs = branch.states.shape[1] if branch.states.ndim == 2 else 0
    meta = {"name": branch.name, "parent": "" if branch.parent is None else branch.parent,
            "parameter": branch.parameter, "status": branch.status.name,
            "message": branch.message, "n_points": len(branch),
            "n_special": len(branch.special_points), "start": int(start),
            "special_start": int(special_start)}
    arrays: dict[str, np.ndarray] = {}
    for name in POINT_ARRAYS:
        dtype = np.int64 if name in INT_ARRAYS else np.float64
        arrays[name] = np.asarray(getattr(branch, name)[start:], dtype=dtype, order="C")
    for name, (dtype, _) in STEP_ARRAYS.items():
        arrays[name] = np.asarray(getattr(branch, name)[start:], dtype=dtype, order="C")
    for name, values in branch.records.items():
        arrays[f"records/{key(name)}"] = _record_array(branch.name, name,
                                                       np.asarray(values)[start:])
    arrays.update(_frames_arrays(branch, start))
    phase = np.asarray(branch.phase_modes, float)
    # the phase rows act on the problem's unknowns, which a branch stored as centrelines
    # (a Cosserat rod's) has more of than its states
    arrays["phase_modes"] = (phase if phase.ndim == 2 and phase.size
                             else phase.reshape(-1, n_dofs) if phase.size
                             else np.zeros((0, n_dofs)))
    arrays["phase_state"] = np.asarray(branch.phase_state, dtype=float, order="C")
    groups: dict[str, dict] = {}
    for i in range(special_start, len(branch.special_points)):
        _special(f"special_points/{i:04d}", branch.special_points[i], groups, arrays)
    if origin and branch.origin is not None:
        _special("origin", branch.origin, groups, arrays)
    return meta, groups, arrays


def _frames_arrays(branch: Branch, start: int) -> dict:
    """``frames/<name>`` (k - start, ...) of the points from ``start`` on, when every
    point's frames are known and stored (:class:`~supercoil.solvers.carried.Frames`)."""
    frames = branch.frames
    if not frames or not all(f is not None and f.stored for f in frames):
        return {}
    return {f"frames/{key(name)}": np.asarray([f.values[name] for f in frames[start:]],
                                              dtype=float, order="C").reshape(
                                                  (len(frames) - start,)
                                                  + np.shape(frames[0].values[name]))
            for name in frames[0].values}


def _read_special(prefix: str, groups: dict, arrays: dict) -> SpecialPoint:
    try:
        scalars = groups[prefix]
        kwargs = {name: kind(scalars[name]) for name, kind in SPECIAL_SCALARS.items()}
        for name in SPECIAL_ARRAYS:
            kwargs[name] = arrays[f"{prefix}/{name}"]
    except KeyError as exc:
        raise CodecError(f"special point {prefix}: {exc.args[0]} missing") from None
    head = f"{prefix}/records/"
    kwargs["records"] = {unkey(p[len(head):]): a for p, a in arrays.items()
                         if p.startswith(head)}
    head = f"{prefix}/frames/"
    frames = {unkey(p[len(head):]): a for p, a in arrays.items() if p.startswith(head)}
    if frames:
        kwargs["frames"] = Frames(frames, stored=True)
    return SpecialPoint(**kwargs)


class BranchBuilder:
    """Grows a branch from :func:`flatten`'s pieces (a whole branch, then additions)."""

    def __init__(self, meta: dict, groups: dict, arrays: dict):
        self.meta = dict(meta)
        self.chunks = {name: [] for name in (*POINT_ARRAYS, *STEP_ARRAYS)}
        self.records: dict[str, list] = {}
        self.frames: dict[str, list] = {}
        self.specials: list[SpecialPoint] = []
        self.origin = None
        self.n_points = 0
        self.extend(meta, groups, arrays)

    def extend(self, meta: dict, groups: dict, arrays: dict) -> None:
        start, special_start = int(meta.get("start", 0)), int(meta.get("special_start", 0))
        if start == 0:  # a whole branch: anything stored before is replaced
            self.chunks = {name: [] for name in (*POINT_ARRAYS, *STEP_ARRAYS)}
            self.records, self.specials, self.origin = {}, [], None
            self.frames = {}
        elif start != self.n_points or special_start > len(self.specials):
            raise CodecError(f"branch {meta.get('name')!r}: an addition from point {start} "
                             f"to a branch of {self.n_points} points")
        self.specials = self.specials[:special_start]
        try:
            added = {name: arrays[name] for name in POINT_ARRAYS}
        except KeyError as exc:
            raise CodecError(f"branch {meta.get('name')!r}: {exc.args[0]} missing") from None
        k = len(added["parameter_values"])
        for name, a in added.items():
            if len(a) != k:
                raise CodecError(f"branch {meta.get('name')!r}: {name} has {len(a)} rows, "
                                 f"parameter_values {k}")
            self.chunks[name].append(a)
        for name, (dtype, unknown) in STEP_ARRAYS.items():
            a = arrays.get(name)
            self.chunks[name].append(np.full(k, unknown, dtype=dtype)
                                     if a is None or len(a) != k else a)
        records = {unkey(p[len("records/"):]): a for p, a in arrays.items()
                   if p.startswith("records/")}
        if start > 0 and set(records) != set(self.records):
            raise CodecError(f"branch {meta.get('name')!r}: records {sorted(records)} "
                             f"added to a branch with records {sorted(self.records)}")
        for name, a in records.items():
            if len(a) != k:
                raise CodecError(f"branch {meta.get('name')!r}: record {name} has {len(a)} "
                                 f"rows, parameter_values {k}")
            self.records.setdefault(name, []).append(a)
        frames = {unkey(p[len("frames/"):]): a for p, a in arrays.items()
                  if p.startswith("frames/")}
        if start > 0 and set(frames) != set(self.frames):
            frames = {}  # points added without their frames: the frames are unknown
            self.frames = {}
        for name, a in frames.items():
            if len(a) != k:
                raise CodecError(f"branch {meta.get('name')!r}: frames {name} has {len(a)} "
                                 f"rows, parameter_values {k}")
            self.frames.setdefault(name, []).append(a)
        self.n_points = start + k
        n_special = int(meta["n_special"])
        self.specials += [_read_special(f"special_points/{i:04d}", groups, arrays)
                          for i in range(special_start, n_special)]
        if "origin" in groups:
            self.origin = _read_special("origin", groups, arrays)
        self.phase = (arrays["phase_modes"], arrays["phase_state"])
        self.meta.update({k: v for k, v in meta.items() if k not in ("start",
                                                                     "special_start")})
        if int(meta["n_points"]) != self.n_points:
            raise CodecError(f"branch {meta.get('name')!r}: {self.n_points} points stored, "
                             f"{meta['n_points']} announced")

    def _arrays(self) -> dict:
        return {name: np.concatenate(c) if len(c) > 1 else c[0]
                for name, c in self.chunks.items()}

    def _records(self) -> dict:
        return {name: np.concatenate(c) if len(c) > 1 else c[0]
                for name, c in self.records.items()}

    def _frames(self) -> tuple:
        """The points' :class:`~supercoil.solvers.carried.Frames` (stored), or ()."""
        if not self.frames:
            return ()
        stacked = {name: np.concatenate(c) if len(c) > 1 else c[0]
                   for name, c in self.frames.items()}
        if any(len(a) != self.n_points for a in stacked.values()):
            return ()
        return tuple(Frames({name: a[i] for name, a in stacked.items()}, stored=True)
                     for i in range(self.n_points))

    def build(self) -> Branch:
        meta = self.meta
        try:
            status = ContinuationStatus[str(meta["status"])]
        except KeyError:
            raise CodecError(f"branch {meta.get('name')!r}: unknown status "
                             f"{meta.get('status')!r}") from None
        branch = Branch(name=str(meta["name"]), parent=str(meta["parent"]) or None,
                        origin=self.origin, parameter=str(meta["parameter"]),
                        special_points=tuple(self.specials), status=status,
                        message=str(meta["message"]), records=self._records(),
                        phase_modes=self.phase[0], phase_state=self.phase[1],
                        frames=self._frames(), **self._arrays())
        # the chunks are now one array each: later additions append to it
        self.chunks = {n: [getattr(branch, n)] for n in (*POINT_ARRAYS, *STEP_ARRAYS)}
        self.records = {n: [v] for n, v in branch.records.items()}
        if branch.frames:
            self.frames = {n: [np.asarray([f.values[n] for f in branch.frames])]
                           for n in branch.frames[0].values}
        return branch


def unflatten(meta: dict, groups: dict, arrays: dict) -> Branch:
    """The branch of :func:`flatten`'s pieces (``start`` = 0)."""
    return BranchBuilder(meta, groups, arrays).build()

