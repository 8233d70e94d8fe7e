"""The order in which a contact branch's bifurcations are tried for the plectoneme
(:func:`supercoil.problems.tweezers.plectoneme.switch_order`), against the distances
computed directly: a branch that closed on itself tries the bifurcation nearest its last
state first, then the others the latest first; any other branch the latest first."""

from __future__ import annotations

import dataclasses

import numpy as np
from test_continuation_toys import CircleOfEquilibria

from supercoil.continuation import (
    ContinuationOptions,
    ContinuationStatus,
    SpecialPoint,
    continuation,
)
from supercoil.problems.tweezers.plectoneme import switch_order


def _with_bifurcations(branch, indices, status):
    """``branch`` with fake located bifurcations at its points ``indices`` (in order)."""
    points = tuple(SpecialPoint(kind="bifurcation", label="", branch=branch.name, index=i,
                                parameter=float(branch.parameter_values[i]),
                                arclength=float(branch.arclength[i]), q=branch.states[i],
                                multipliers=branch.multipliers[i], tangent=branch.tangents[i])
                   for i in indices)
    fold = [p for p in branch.special_points if p.kind == "fold"]
    return dataclasses.replace(branch, special_points=tuple(fold) + points, status=status)


def test_a_closed_branch_tries_the_bifurcation_nearest_its_closure_first():
    branch = continuation(CircleOfEquilibria(lam=0.0), np.array([1.0, 0.0, 0.0]),
                          parameter="lam",
                          options=ContinuationOptions(initial_step=0.05, max_step=0.05,
                                                      max_points=2000))
    assert branch.status is ContinuationStatus.CLOSED_LOOP, branch.message
    n = len(branch)
    indices = [3, n // 4, n // 2, n - 8]  # the second-to-last and the first lie near the end
    closed = _with_bifurcations(branch, indices, ContinuationStatus.CLOSED_LOOP)
    distances = {i: np.linalg.norm(branch.states[i] - branch.states[-1]) for i in indices}
    nearest = min(indices, key=distances.get)
    order = [p.index for p in switch_order(closed)]
    assert order[0] == nearest
    assert order[1:] == [i for i in reversed(indices) if i != nearest]
    assert sorted(order) == indices
    ended = _with_bifurcations(branch, indices, ContinuationStatus.STEP_TOO_SMALL)
    assert [p.index for p in switch_order(ended)] == list(reversed(indices))
    assert switch_order(_with_bifurcations(branch, [], ContinuationStatus.CLOSED_LOOP)) == []
