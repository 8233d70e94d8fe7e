"""The special points of a branch between two of its points: search and record.

Between consecutive points the segment is searched for folds (a sign change
of ``dlambda/ds``), bifurcations (each change of the unstable count that is
not the fold's own) and user events (sign changes of named scalars); each is
located (:mod:`supercoil.continuation.events`) and recorded as a
:class:`~supercoil.continuation.branch.SpecialPoint` with its stability and
critical modes. A located bifurcation where the equations continued have no
branch point (their extended Jacobian's determinant the same at both ends) is a
``count_change`` labelled ``determinant`` (:func:`_without_branch_point`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from supercoil.continuation.branch import COUNT_KINDS, SpecialPoint
from supercoil.continuation.events import (
    Located,
    Segment,
    UserEvent,
    locate_count_change,
    locate_fold,
    locate_user_event,
)
from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.stability import point_stability
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.carried import frames_of
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.kkt import KKTFactor


def locate_events(system: ExtendedSystem, opts: ContinuationOptions,
                  events: Sequence[UserEvent], x_a: np.ndarray, x_b: np.ndarray,
                  t_a: np.ndarray, t_b: np.ndarray, count_a: int, count_b: int,
                  user_a: Sequence[Mapping[str, float]], user_b: Sequence[Mapping[str, float]]
                  ) -> tuple[Segment, list[Located]]:
    """The segment from ``x_a`` to ``x_b`` (tangents ``t_a``, ``t_b``, unstable counts
    ``count_a``, ``count_b``, the user events' values ``user_a``, ``user_b``) and the
    events located on it, in the order of their place on it."""
    # the ends' tangents for the user events' first trial start, on a problem whose
    # coordinates are rotation coordinates re-based at every point (a Cosserat rod's:
    # Segment.start)
    curved = getattr(system.problem, "accept_moves_coordinates", False)
    segment = Segment(system, x_a, x_b, opts.tolerance, opts.max_corrector_iterations,
                      opts.zero_tolerance, tangents=(t_a, t_b) if curved else None)
    xtol = opts.event_tolerance / segment.length
    found = []
    fold = (opts.detect_folds and t_a[-1] * t_b[-1] < 0)
    fold_u = None
    if fold:
        found.append(locate_fold(segment, xtol))
        fold_u = found[-1].u if found[-1].located else None
    jump = count_b - count_a
    if opts.detect_bifurcations and jump != 0 and not (fold and abs(jump) == 1):
        # each change of the count on the segment, one after the other; a change by
        # one where the fold is, is the fold's own (its eigenvalue crosses there)
        start = 0.0
        for _ in range(abs(jump) + 2):
            located = locate_count_change(segment, xtol, opts.switch_below, start)
            if located is None:
                break
            at_fold = (fold_u is not None and located.located
                       and abs(located.count_after - located.count_before) == 1
                       and abs(located.u - fold_u) <= max(opts.switch_below, 100 * xtol))
            if not at_fold:
                found.append(located)
            if located.resume is None or located.resume >= 1.0:
                break
            start = located.resume
        found = _without_branch_point(segment, found, t_a, t_b)
    for event, before, after in zip(events, user_a, user_b):
        for label in before:
            if label in after and before[label] * after[label] < 0:
                found.append(locate_user_event(segment, event, label, xtol, (before, after)))
    return segment, sorted(found, key=lambda e: e.u)


def continued_parity(system: ExtendedSystem, x: np.ndarray, t: np.ndarray,
                     hessian=None) -> int:
    """``(n_K + [t_lambda < 0]) mod 2`` at the point ``x`` of tangent ``t`` (its last
    component ``t_lambda``), which :func:`branch_points_odd` compares between points;
    ``n_K``: the negative eigenvalues of the continued system's Hessian on ``ker J``
    (its constraint and phase rows, without the count's rows). ``hessian``:
    ``system.hessian(x)`` if already known. Raises on a singular KKT matrix."""
    H = system.hessian(x) if hessian is None else hessian
    negative = KKTFactor(H, sp.csr_matrix(system.jacobian(x))).reduced_negative_count
    return (negative + int(t[-1] < 0)) % 2


def branch_points_odd(segment: Segment, t_a: np.ndarray, t_b: np.ndarray) -> bool | None:
    """Whether ``segment`` holds an odd number of branch points of the system continued
    (None where a factor is singular): whether the sign of the determinant of its
    extended Jacobian ``[K, F_lambda; t^T]`` differs at the segment's two ends.

    With ``K`` the KKT matrix of the continued system (its Hessian on the free DOFs,
    its constraint and phase rows, without the rows that take the approximate
    symmetries out of the count) and ``t`` the unit tangent, ``K t_x + F_lambda
    t_lambda = 0`` gives ``det [K, F_lambda; t^T] = det K / t_lambda``: its sign is
    ``(-1)^(n_K + m) sign(t_lambda)`` (:func:`continued_parity`). A fold changes both
    factors, a simple branch point only ``det K`` (Keller 1977's test function).
    ``t_a``, ``t_b``: the ends' tangents, oriented along the branch."""
    try:
        return (continued_parity(segment.system, segment.x_a, t_a)
                != continued_parity(segment.system, segment.x_b, t_b))
    except (SingularMatrixError, InertiaError):
        return None


def _without_branch_point(segment: Segment, found: list[Located], t_a: np.ndarray,
                          t_b: np.ndarray) -> list[Located]:
    """``found`` with its bifurcation relabelled a ``count_change`` (label
    ``determinant``) where it is the segment's only located bifurcation, changes the
    count by an odd number, and the segment holds no branch point of the system
    continued (:func:`branch_points_odd`).

    A simple eigenvalue crossing zero off a fold changes the sign of the extended
    Jacobian's determinant. The count (of the constrained Hessian on the complement
    of the approximate symmetries) is not the continued system's: where the two
    differ, the count can change with no branch point of the equations solved, and
    no branch to switch to (docs/continuation.md, "A count change that no eigenvalue
    makes is no bifurcation").
    """
    located = [e for e in found if e.kind == "bifurcation" and e.located]
    if (len(located) != 1 or (located[0].count_after - located[0].count_before) % 2 == 0
            or branch_points_odd(segment, t_a, t_b) is not False):
        return found
    return [dataclasses.replace(e, kind="count_change", label="determinant")
            if e is located[0] else e for e in found]


def special_point(system: ExtendedSystem, opts: ContinuationOptions, ev: Located,
                  segment: Segment, branch: str, index: int, arclength: float,
                  t_after: np.ndarray, count_before: int, count_after: int,
                  records: Callable[[np.ndarray], dict]) -> SpecialPoint:
    """The :class:`~supercoil.continuation.branch.SpecialPoint` of the event ``ev``
    located on ``segment``, which starts at point ``index`` of ``branch`` (arclength
    ``arclength``, unstable count ``count_before``) and ends at a point of tangent
    ``t_after`` and count ``count_after``; ``records(x)`` are the caller's records."""
    x = ev.x
    t = ev.tangent if ev.tangent is not None else t_after
    stab = point_stability(system, x, opts.zero_tolerance, opts.n_modes)
    values = modes = np.zeros(0)
    if ev.kind in ("bifurcation", "fold"):
        n_critical = max(1, abs(ev.count_after - ev.count_before))
        values, modes = stab.critical_modes(n_critical)
    else:
        modes = np.zeros((0, system.problem.n_dofs))
    return SpecialPoint(
        kind=ev.kind, label=ev.label, branch=branch, index=index,
        parameter=float(x[-1]), arclength=arclength + ev.u * segment.length,
        q=system.q(x), multipliers=system.multipliers(x), tangent=system.full_tangent(t),
        unstable_count=stab.unstable_count,
        count_before=ev.count_before if ev.kind in COUNT_KINDS else count_before,
        count_after=ev.count_after if ev.kind in COUNT_KINDS else count_after,
        critical_eigenvalues=values, critical_modes=modes, located=ev.located,
        tolerance=(opts.event_tolerance if ev.accuracy is None
                   else max(ev.accuracy, opts.event_tolerance)),
        records=records(x), frames=frames_of(system.problem))
