"""Results of continuation: :class:`SpecialPoint` and :class:`Branch`.

States are kept in full (every DOF), so that any point can be redrawn or
continued from. Branches are stored in result files
(:func:`supercoil.io.store.save`, :func:`supercoil.load`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from supercoil.continuation.options import ContinuationStatus

SCHEMA_VERSION = 1

SPECIAL_KINDS = ("fold", "bifurcation", "count_change", "endpoint")
# the kinds of a change of the unstable count: a bifurcation, or a count_change that is
# none (its verification failed, no eigenvalue of the count's crossed zero, or the
# equations continued have no branch point there; docs/model.md, "Special points and
# branches")
COUNT_KINDS = ("bifurcation", "count_change")


# a Branch's per-point arrays, one row per point
POINT_ARRAYS = ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                "determinant_sign", "nearest_eigenvalue", "tangents", "arclength",
                "next_step", "gauge_moved")


def _frozen(a) -> np.ndarray:
    """``a`` as a read-only array: copied unless it is a read-only array already (a
    partial branch's views of its tracer's columns, which never change:
    :mod:`~supercoil.continuation.columns`)."""
    if isinstance(a, np.ndarray) and not a.flags.writeable:
        return a
    a = np.array(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False, repr=False)
class SpecialPoint:
    """A located event on a branch.

    ``kind``: ``fold``, ``bifurcation`` or a user event's kind (e.g.
    ``contact_onset``); ``label`` names the user scalar that changed sign (or
    repeats the kind). The point lies between points ``index`` and
    ``index + 1`` of ``branch``, at arclength ``arclength``; ``q`` (n_dofs,),
    ``multipliers`` (m,), ``parameter`` its state, ``tangent`` (n_dofs + m + 1,)
    the branch tangent there. For folds and bifurcations ``critical_eigenvalues``
    (k,) and ``critical_modes`` (k, n_dofs) are the eigenpairs nearest zero (``k``
    = the jump of the unstable count, at least 1) and ``count_before`` /
    ``count_after`` the unstable counts on either side. ``located`` is False
    when a trial correction failed during localisation (the point is then
    the last bracket midpoint). ``tolerance`` is the arclength accuracy.
    """

    kind: str
    label: str
    branch: str
    index: int
    parameter: float
    arclength: float
    q: np.ndarray
    multipliers: np.ndarray
    tangent: np.ndarray
    unstable_count: int = -1
    count_before: int = -1
    count_after: int = -1
    critical_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0))
    critical_modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    located: bool = True
    tolerance: float = float("nan")
    records: dict = field(default_factory=dict)
    # the frames the problem carried when the point was located (None: unknown)
    frames: object = None

    def entry(self, parameter_key: str) -> dict:
        """The special point in a result file's ``special_points`` (the keys of docs/model.md): the
        parameter value under ``parameter_key`` (``excess_link``, ``turns``, ...), its
        place on the branch, counts, localisation, and its records."""
        out = {"kind": self.kind, "label": self.label, "branch": self.branch,
               "index": int(self.index), parameter_key: float(self.parameter),
               "arclength": float(self.arclength), "unstable_count": int(self.unstable_count),
               "count_before": int(self.count_before), "count_after": int(self.count_after),
               "located": bool(self.located), "tolerance": float(self.tolerance)}
        for k, v in self.records.items():
            if k != parameter_key:
                out[k] = jsonable(v)
        return out

    def __repr__(self) -> str:
        counts = "" if self.count_before < 0 else f", count {self.count_before} -> {self.count_after}"
        return (f"SpecialPoint({self.kind} on {self.branch!r} at parameter "
                f"{self.parameter:.8g}{counts})")

    def summary(self) -> dict:
        """JSON-serialisable description (no states)."""
        out = {"kind": self.kind, "label": self.label, "branch": self.branch,
               "index": int(self.index), "parameter": float(self.parameter),
               "arclength": float(self.arclength), "unstable_count": int(self.unstable_count),
               "count_before": int(self.count_before), "count_after": int(self.count_after),
               "critical_eigenvalues": [float(v) for v in self.critical_eigenvalues],
               "located": bool(self.located), "tolerance": float(self.tolerance)}
        out.update({k: jsonable(v) for k, v in self.records.items()})
        return out


def jsonable(v):
    """A numpy scalar or array as a plain Python number or (nested) list."""
    a = np.asarray(v)
    return a.item() if a.ndim == 0 else a.tolist()


@dataclass(frozen=True, eq=False, repr=False)
class Branch:
    """A computed branch (immutable; arrays are read-only).

    Per point (``k`` points): ``parameter_values`` (k,), ``states`` (k, n_dofs),
    ``multipliers`` (k, m), ``unstable_count`` (k,), ``zero_modes`` (k,),
    ``determinant_sign`` (k,) (the test of Chamekh, Mani-Aouadi & Moakher 2014),
    ``nearest_eigenvalue`` (k,) (the signed eigenvalue nearest zero), ``tangents`` (k, n_dofs + m + 1)
    (``[dq, dmu, dlambda]``, unit in the arclength metric), ``arclength``
    (k,), ``records`` (name -> (k, ...) arrays from the caller's record
    function). ``phase_modes`` (r, n_dofs) and ``phase_state`` (n_dofs,) are
    the phase conditions the branch was computed with (``r = 0`` if none).

    The step controller's state after each point, which a resumed run starts
    from: ``next_step`` (k,) the arclength step the tracer tries first from the
    point (NaN where unknown, e.g. a branch stored without it), ``gauge_moved``
    (k,) whether the point is the last one corrected in moved phase rows after
    a failed step (the step from it is then retried once without moving them
    again). Arrays of another length than the branch are read as unknown.

    ``frames`` (k,): what the problem carried at each point (its ``frames``,
    :mod:`supercoil.solvers.carried`), so that switching, checks and resumption start
    from a point's own frames; empty where unknown (a branch read from a file, whose
    frames are carried again along its states, unless its problem stores them:
    :class:`~supercoil.solvers.carried.Frames` ``stored``).
    """

    name: str
    parent: str | None
    origin: SpecialPoint | None
    parameter: str
    parameter_values: np.ndarray
    states: np.ndarray
    multipliers: np.ndarray
    unstable_count: np.ndarray
    zero_modes: np.ndarray
    determinant_sign: np.ndarray
    nearest_eigenvalue: np.ndarray
    tangents: np.ndarray
    arclength: np.ndarray
    special_points: tuple[SpecialPoint, ...]
    status: ContinuationStatus
    message: str
    records: dict = field(default_factory=dict)
    phase_modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    phase_state: np.ndarray = field(default_factory=lambda: np.zeros(0))
    next_step: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gauge_moved: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    frames: tuple = ()

    def __post_init__(self):
        k = int(np.size(self.parameter_values))
        object.__setattr__(self, "frames", tuple(self.frames) if len(self.frames) == k else ())
        if np.shape(self.next_step) != (k,):
            object.__setattr__(self, "next_step", np.full(k, np.nan))
        if np.shape(self.gauge_moved) != (k,):
            object.__setattr__(self, "gauge_moved", np.zeros(k, dtype=bool))
        object.__setattr__(self, "next_step", np.asarray(self.next_step, dtype=float))
        object.__setattr__(self, "gauge_moved", np.asarray(self.gauge_moved, dtype=bool))
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray):
                object.__setattr__(self, f.name, _frozen(value))
        object.__setattr__(self, "records",
                           {k: _frozen(v) for k, v in dict(self.records).items()})

    def __len__(self) -> int:
        return int(self.parameter_values.size)

    def __repr__(self) -> str:
        span = ("no points" if not len(self) else
                f"{self.parameter} from {self.parameter_values[0]:.6g} to "
                f"{self.parameter_values[-1]:.6g}")
        special = special_point_counts(self.special_points)
        return (f"Branch({self.name!r}: {len(self)} points, {span}, {self.status.name}\n"
                f"  special points: {special}; records: {', '.join(self.records) or 'none'})")

    @property
    def ok(self) -> bool:
        return self.status.ok

    @property
    def stable(self) -> np.ndarray:
        """(k,) bool: strictly stable points (no negative and no zero eigenvalue)."""
        return (self.unstable_count == 0) & (self.zero_modes == 0)

    def points_of_kind(self, kind: str) -> tuple[SpecialPoint, ...]:
        return tuple(p for p in self.special_points if p.kind == kind)

    def summary(self) -> dict:
        """JSON-serialisable summary: names, status, and one entry per point (no states)."""
        points = []
        for i in range(len(self)):
            entry = {"branch": self.name, "index": i,
                     self.parameter: float(self.parameter_values[i]),
                     "arclength": float(self.arclength[i]),
                     "unstable_count": int(self.unstable_count[i]),
                     "zero_modes": int(self.zero_modes[i]),
                     "determinant_sign": int(self.determinant_sign[i])}
            entry.update({k: jsonable(v[i]) for k, v in self.records.items()})
            points.append(entry)
        return {"schema_version": SCHEMA_VERSION, "name": self.name, "parent": self.parent,
                "origin": None if self.origin is None else self.origin.summary(),
                "parameter": self.parameter, "status": self.status.name,
                "message": self.message, "points": points,
                "special_points": [p.summary() for p in self.special_points]}


def special_point_counts(points) -> str:
    """``"2 bifurcation, 1 fold"``: how many special ``points`` of each kind, kinds in
    alphabetical order (``"none"`` for none), as the results' short reprs say it."""
    kinds: dict[str, int] = {}
    for p in points:
        kinds[p.kind] = kinds.get(p.kind, 0) + 1
    return ", ".join(f"{n} {k}" for k, n in sorted(kinds.items())) or "none"
