"""A traced branch's points as growing columns, and the branch read from them.

:class:`BranchRows` converts each point a :class:`~supercoil.continuation.tracer.Tracer`
accepts into per-point columns (:mod:`~supercoil.continuation.columns`) once, and builds
the :class:`~supercoil.continuation.branch.Branch` from them: a partial branch (the one
handed to ``on_point`` at every point) has read-only views of the columns for arrays,
O(1) a point; the final one copies the points. Only the tracer's last point is ever
replaced (by a regauge or a rephase); it is converted again where it changed.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation.branch import POINT_ARRAYS, Branch
from supercoil.continuation.columns import Columns
from supercoil.continuation.options import ContinuationStatus


def _owned(view: np.ndarray) -> np.ndarray:
    """A read-only copy of ``view`` (a branch then holds only its own points)."""
    copy = view.copy()
    copy.flags.writeable = False
    return copy


class BranchRows:
    """The columns of a traced branch: ``prefix``'s points (those before the run's on the
    branch, e.g. a resumed branch's stored points; their arclength is ``prefix_arclength``
    at the run's first point), then the run's as they are converted."""

    def __init__(self, prefix: Branch | None = None, prefix_arclength: float = 0.0):
        self.columns = Columns()
        # the (x, tangent, stability, next step, gauge moved) each row was written from
        self.keys: list[tuple] = []
        self.unknown_frames = 0  # written points without frames
        self.prefix, self.prefix_arclength = prefix, float(prefix_arclength)
        self.k0 = 0 if prefix is None else len(prefix)
        if self.k0:
            for name in POINT_ARRAYS:
                self.columns.fill(name, getattr(prefix, name))
            for record, values in prefix.records.items():
                self.columns.fill("record:" + record, values)

    def branch(self, tracer, status: ContinuationStatus, message: str,
               partial: bool = False) -> Branch:
        """The branch so far, after the ``prefix`` if given. Each point is converted
        once into growing columns (:mod:`~supercoil.continuation.columns`; only the
        last point is ever replaced, by a regauge or a rephase, and converted again).
        A ``partial`` branch (the one handed to ``on_point`` at every point) has
        read-only views of them for arrays: it costs O(1) a point, not a stacking of
        every point. Otherwise the arrays are copies of the points only (a column
        holds up to twice as many rows as it has points)."""
        system = tracer.system
        n_dofs, m = system.problem.n_dofs, system.m
        k, k0 = len(tracer.xs), self.k0
        if k == 0 and self.prefix is not None:
            return dataclasses.replace(self.prefix, status=status, message=message,
                                       phase_modes=system.phase_modes,
                                       phase_state=system.q_phase_full)
        if k == 0:
            return Branch(
                name=tracer.name, parent=tracer.parent, origin=tracer.origin,
                parameter=system.parameter, parameter_values=np.zeros(0),
                states=np.zeros((0, n_dofs)), multipliers=np.zeros((0, m)),
                unstable_count=np.zeros(0, dtype=np.int64),
                zero_modes=np.zeros(0, dtype=np.int64),
                determinant_sign=np.zeros(0, dtype=np.int64), nearest_eigenvalue=np.zeros(0),
                tangents=np.zeros((0, n_dofs + m + 1)), arclength=np.zeros(0),
                special_points=tuple(tracer.specials), status=status, message=message,
                records={}, phase_modes=system.phase_modes, phase_state=system.q_phase_full)
        self._convert(tracer, k)
        cols, total = self.columns, k0 + k
        view = cols.view if partial else (lambda name, rows: _owned(cols.view(name, rows)))
        names = [name for name in tracer.recs[0]
                 if self.prefix is None or not k0 or name in self.prefix.records]
        records = {name: view("record:" + name, total) for name in names}
        specials = tuple(tracer.specials)
        frames = tuple(tracer.frames[:k]) if self.unknown_frames == 0 else ()
        if self.prefix is not None:
            specials = self.prefix.special_points + tuple(
                dataclasses.replace(p, index=p.index + k0,
                                    arclength=p.arclength + self.prefix_arclength)
                for p in specials)
            frames = (tuple(self.prefix.frames) + frames
                      if frames and (self.prefix.frames or not k0) else ())
        return Branch(
            name=tracer.name, parent=tracer.parent, origin=tracer.origin,
            parameter=system.parameter,
            parameter_values=view("parameter_values", total),
            states=view("states", total), multipliers=view("multipliers", total),
            unstable_count=view("unstable_count", total),
            zero_modes=view("zero_modes", total),
            determinant_sign=view("determinant_sign", total),
            nearest_eigenvalue=view("nearest_eigenvalue", total),
            tangents=view("tangents", total), arclength=view("arclength", total),
            special_points=specials, status=status, message=message,
            records=records, phase_modes=system.phase_modes,
            phase_state=system.q_phase_full, next_step=view("next_step", total),
            gauge_moved=view("gauge_moved", total), frames=frames)

    def _convert(self, tracer, count: int) -> None:
        """Write the first ``count`` points into the columns: the points not written
        yet, and the last one written before if its ``x``, tangent or step controller
        state changed since (the only point ever replaced is the last)."""
        system, cols, keys, k0 = tracer.system, self.columns, self.keys, self.k0
        for i in range(max(len(keys) - 1, 0), count):
            x, t, stab, r = tracer.xs[i], tracer.ts[i], tracer.stabs[i], k0 + i
            old = keys[i] if i < len(keys) else (None, None, None, None, None)
            if old[0] is not x:
                cols.put("parameter_values", r, x[-1])
                cols.put("states", r, system.q(x))
                cols.put("multipliers", r, system.multipliers(x))
            if old[1] is not t:
                cols.put("tangents", r, system.full_tangent(t))
            if old[2] is not stab:
                cols.put("unstable_count", r, np.int64(stab.unstable_count))
                cols.put("zero_modes", r, np.int64(stab.zero_modes))
                cols.put("determinant_sign", r, np.int64(stab.determinant_sign))
                cols.put("nearest_eigenvalue", r, float(stab.nearest_eigenvalue))
                cols.put("arclength", r, float(tracer.s[i]) + self.prefix_arclength)
                for name, value in tracer.recs[i].items():
                    cols.put("record:" + name, r, value)
            if old[3] != tracer.steps[i]:
                cols.put("next_step", r, float(tracer.steps[i]))
            if old[4] != tracer.moved[i]:
                cols.put("gauge_moved", r, bool(tracer.moved[i]))
            key = (x, t, stab, tracer.steps[i], tracer.moved[i])
            if i < len(keys):
                keys[i] = key
            else:
                keys.append(key)
                self.unknown_frames += tracer.frames[i] is None
