"""Branch-consistency checker (run on every branch of the test suite).

Checks, from the stored data and the problem alone:

* the arrays have one entry per point and the arclength increases;
* every stored point is an equilibrium (KKT residual below ``residual_tolerance``);
* the stored ``unstable_count`` and ``zero_modes`` equal those recomputed from
  the inertia and the eigenvalues, and ``determinant_sign`` equals the
  recomputed sign where no zero mode makes it meaningless;
* every special point lies between its neighbours (``arclength[index] <=
  s <= arclength[index + 1]``), is an equilibrium, and is what its kind says:
  a fold has ``dlambda/ds`` of opposite signs at its neighbours and a
  parameter value at or beyond both; a bifurcation changes the count, and the
  bifurcations between two points, in order, chain the stored counts of those
  points through their ``count_before`` / ``count_after`` (a fold between the
  same points accounts for a change by one).

The problem is never changed: each point is checked with the frames the branch
carried there (:mod:`supercoil.continuation.carry`), at its parameter value
(``problem.at``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from supercoil.continuation.branch import COUNT_KINDS, Branch
from supercoil.continuation.carry import branch_frames
from supercoil.continuation.stability import point_stability
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.carried import with_frames
from supercoil.solvers.problem import ConstrainedEnergy


@dataclass(frozen=True)
class ConsistencyReport:
    problems: tuple[str, ...]
    checked_points: int

    @property
    def ok(self) -> bool:
        return not self.problems


def consistency_check(branch: Branch, problem: ConstrainedEnergy, *,
                      residual_tolerance: float = 1e-7, zero_tolerance: float = 1e-6,
                      points: np.ndarray | None = None,
                      pin: Callable[[int, bool], None] | None = None) -> ConsistencyReport:
    """Check ``branch`` against ``problem`` (see module doc); ``points``: indices to recheck.

    ``pin(i, segment)``, if given, is called before point ``i`` (``segment``
    False) or a special point between points ``i`` and ``i + 1`` (True) is
    checked: it sets the problem's pinned DOFs (``fixed``) to those that point
    or segment was computed with (a branch continued in runs with its symmetry
    pins re-picked between them, :mod:`supercoil.problems.segments`).
    """
    problems: list[str] = []
    k = len(branch)
    for name in ("states", "multipliers", "unstable_count", "zero_modes", "determinant_sign",
                 "tangents", "arclength", "nearest_eigenvalue"):
        if getattr(branch, name).shape[0] != k:
            problems.append(f"{name} has {getattr(branch, name).shape[0]} entries for {k} points")
    if problems:
        return ConsistencyReport(tuple(problems), 0)
    if k > 1 and np.any(np.diff(branch.arclength) <= 0):
        problems.append("the arclength does not increase")
    phase = branch.phase_modes if branch.phase_modes.size else None
    system = ExtendedSystem(problem, branch.parameter, branch.states[0] if k else np.zeros(0),
                            phase, branch.phase_state if phase is not None else None)

    def x_of(q, mu, lam):
        return system.pack(q, mu, lam)

    def repin(i: int, segment: bool) -> None:
        nonlocal system
        if pin is None:
            return
        fixed = np.array(problem.fixed, copy=True)
        pin(i, segment)
        if not np.array_equal(fixed, problem.fixed):
            system = ExtendedSystem(problem, branch.parameter, branch.states[i], phase,
                                    branch.phase_state if phase is not None else None)

    def residual(x):
        F = system.residual(x)
        return float(np.max(np.abs(F[:system.n + system.m]))) if F.size else 0.0

    indices = np.arange(k) if points is None else np.asarray(points, dtype=np.int64)
    frames = branch_frames(problem, branch)
    for i in indices:
        repin(int(i), False)
        x = x_of(branch.states[i], branch.multipliers[i], branch.parameter_values[i])
        system.problem = with_frames(problem, frames[i])
        res = residual(x)
        if not res <= residual_tolerance:
            problems.append(f"point {i}: KKT residual {res:.2e} > {residual_tolerance:.1e}")
        stab = point_stability(system, x, zero_tolerance, 2)
        if stab.unstable_count != branch.unstable_count[i]:
            problems.append(f"point {i}: stored unstable_count {branch.unstable_count[i]}, "
                            f"recomputed {stab.unstable_count}")
        if stab.zero_modes != branch.zero_modes[i]:
            problems.append(f"point {i}: stored zero_modes {branch.zero_modes[i]}, "
                            f"recomputed {stab.zero_modes}")
        if stab.zero_modes == 0 and stab.determinant_sign != branch.determinant_sign[i]:
            problems.append(f"point {i}: stored determinant sign {branch.determinant_sign[i]:+d},"
                            f" recomputed {stab.determinant_sign:+d}")
    lam = branch.parameter_values
    for p in branch.special_points:
        where = f"{p.kind} at {branch.parameter} = {p.parameter:.10g}"
        i = p.index
        if not 0 <= i < k - 1:
            problems.append(f"{where}: index {i} outside the branch")
            continue
        if not branch.arclength[i] <= p.arclength <= branch.arclength[i + 1]:
            problems.append(f"{where}: arclength {p.arclength:.6g} not between its neighbours "
                            f"{branch.arclength[i]:.6g} and {branch.arclength[i + 1]:.6g}")
        repin(i, True)
        system.problem = with_frames(problem, p.frames if p.frames is not None else frames[i])
        res = residual(x_of(p.q, p.multipliers, p.parameter))
        if not res <= residual_tolerance:
            problems.append(f"{where}: KKT residual {res:.2e}")
        if p.kind == "fold":
            if branch.tangents[i, -1] * branch.tangents[i + 1, -1] >= 0:
                problems.append(f"{where}: dlambda/ds does not change sign at its neighbours")
            slack = 1e-12 * max(1.0, abs(p.parameter))
            if (p.parameter - lam[i]) * (p.parameter - lam[i + 1]) < -slack:
                problems.append(f"{where}: the fold lies between its neighbours' parameter "
                                "values (it must be an extremum)")
        elif p.kind in COUNT_KINDS:
            # the count changes of one segment (bifurcations and unverified ones), in
            # order, chain its neighbours' counts; a fold in the segment changes the
            # count by one where it lies
            chain = sorted((b for b in branch.special_points
                            if b.kind in COUNT_KINDS and b.index == i),
                           key=lambda b: b.arclength)
            folds = [f.arclength for f in branch.special_points
                     if f.kind == "fold" and f.index == i]
            before = (branch.unstable_count[i] if chain[0] is p
                      else chain[chain.index(p) - 1].count_after)
            after = (branch.unstable_count[i + 1] if chain[-1] is p
                     else chain[chain.index(p) + 1].count_before)
            slack_before = sum(f <= p.arclength for f in folds) if chain[0] is p else 0
            slack_after = sum(f >= p.arclength for f in folds) if chain[-1] is p else 0
            if p.kind == "count_change" and min(p.count_before, p.count_after) < 0:
                continue  # not located: no counts to chain
            if p.count_before == p.count_after:
                problems.append(f"{where}: the unstable count does not change across it")
            if (abs(p.count_before - before) > slack_before
                    or abs(p.count_after - after) > slack_after):
                problems.append(f"{where}: counts {p.count_before} -> {p.count_after} differ "
                                f"from its neighbours' {before} -> {after}")
        elif not lam.min() - 1e-12 <= p.parameter <= lam.max() + 1e-12:
            problems.append(f"{where}: outside the branch's parameter range")
    return ConsistencyReport(tuple(problems), int(indices.size))
