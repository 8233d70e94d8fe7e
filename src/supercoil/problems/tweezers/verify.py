"""Verification of the bifurcations located along the tweezers' branches.

A bifurcation is a change of the unstable count that a fold does not explain
(:mod:`supercoil.continuation.events`). Along a long rod's branches the count also
changes where an eigenvalue that the discretisation does not resolve changes
sign: the sliding of a localised loop or plectoneme, nearly free in the continuum,
takes the sign of the mesh's ripple, and the count flickers by one between
neighbouring points (measured at L/D = 100, F L^2/A = 1200, N = 160: 1 -> 2 -> 1
over two points, seven times on the localised loop). Such a change is no crossing:
at a transversal crossing of a simple eigenvalue (its derivative along the branch
nonzero) the eigenvalue keeps its new sign over a neighbourhood of the crossing
that does not shrink with the step, so the count stays changed over the points
that follow; a change undone a few points later, with no fold between to undo it,
has an eigenvalue that grazes zero within the discretisation's error.

:func:`verify_bifurcations` keeps a located ``bifurcation`` when the counts are
constant over ``VERIFY_POINTS`` points on either side of it (up to a fold or a
branch end, which end the window), the count before being its ``count_before`` and
after its ``count_after``; any other is reported with the kind ``count_change``.
The straight rod's bifurcations are certified otherwise (by the pencil of
:mod:`~supercoil.problems.tweezers.straight`) and are not passed here. A change that no
eigenvalue crossing zero makes is a ``count_change`` (label ``sliding``) from its
localisation on (:func:`~supercoil.continuation.events.locate_count_change`) and is
not looked at here either.

Given the mesh's segment, :func:`verify_bifurcations` also reads the branch's snakes
(:func:`~supercoil.problems.tweezers.coarse.snakes_on`: the plectoneme growing a node
of each strand at a time across a pair of events): the count changes within a snake
are the mesh's, verified or not, and are reported as ``count_change`` with the label
``snake``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation import Branch, SpecialPoint
from supercoil.continuation.branch import COUNT_KINDS
from supercoil.problems.tweezers.coarse import snakes_on

# points on either side over which a verified bifurcation's counts stay constant
VERIFY_POINTS = 3


def verified(branch: Branch, point: SpecialPoint, folds: np.ndarray) -> bool:
    """The count change ``point`` (a located ``bifurcation`` of ``branch`` between its
    points ``point.index`` and ``point.index + 1``) persists (module doc); ``folds``:
    the indices of the branch's folds."""
    counts = np.asarray(branch.unstable_count)
    k = point.index
    if not point.located or point.count_before < 0 or point.count_after < 0 \
            or point.count_before == point.count_after:
        return False
    low = max(0, k - VERIFY_POINTS + 1)
    high = min(len(counts), k + 1 + VERIFY_POINTS)
    before = [f for f in folds if low <= f < k]
    after = [f for f in folds if k < f < high]
    if before:
        low = max(before) + 1
    if after:
        high = min(after) + 1
    return (bool(np.all(counts[low:k + 1] == point.count_before))
            and bool(np.all(counts[k + 1:high] == point.count_after)))


def verify_bifurcations(branch: Branch, segment: float | None = None) -> Branch:
    """``branch`` with each located ``bifurcation`` that :func:`verified` does not confirm
    reported as a ``count_change`` (its label too); given the mesh's ``segment`` (h/L),
    each bifurcation or count change within one of the branch's snakes reported as a
    ``count_change`` labelled ``snake`` (module doc)."""
    folds = np.array([p.index for p in branch.special_points if p.kind == "fold"],
                     dtype=np.int64)
    snakes = snakes_on(branch, segment) if segment is not None else []
    points = []
    for p in branch.special_points:
        if p.kind in COUNT_KINDS and p.label != "sliding" \
                and any(snake.holds(p.index) for snake in snakes):
            p = dataclasses.replace(p, kind="count_change", label="snake")
        elif p.kind == "bifurcation" and not verified(branch, p, folds):
            p = dataclasses.replace(p, kind="count_change", label="count_change")
        points.append(p)
    return dataclasses.replace(branch, special_points=tuple(points))
