"""The generic continuation layer on the twisted ring: Michell's mode-2 pair crossing.

Oracle: the threshold located on the circle by :func:`michell_threshold`
(bisection on the inertia of the circle at fixed excess link, independent of
the branch machinery).
"""

import numpy as np
import pytest

from supercoil.continuation import ContinuationOptions, consistency_check, continuation
from supercoil.problems.ring import michell_threshold, twisted_circle_problem


def test_continuation_along_the_circle_finds_michells_pair_crossing():
    n = 40
    problem, q = twisted_circle_problem(2 / 3, 1.5, n)
    opts = ContinuationOptions(parameter_bounds=(1.5, 3.2), initial_step=0.2, max_step=0.5)
    branch = continuation(problem, q, parameter="excess_link", options=opts)
    assert branch.ok, branch.message
    (point,) = branch.points_of_kind("bifurcation")
    assert point.parameter == pytest.approx(michell_threshold(2 / 3, n, 2), abs=1e-8)
    assert (point.count_before, point.count_after) == (0, 2)
    # eigenvalues cross in a pair: the determinant keeps its sign, the count sees it
    assert np.all(branch.determinant_sign == branch.determinant_sign[0])
    assert np.abs(point.critical_eigenvalues).max() < 1e-6
    # the circle stays a circle: the state does not move away from the start's radius
    points = branch.states.reshape(len(branch), n, 3)
    radii = np.linalg.norm(points - points.mean(axis=1, keepdims=True), axis=2)
    assert np.ptp(radii) < 1e-10
    report = consistency_check(branch, problem)
    assert report.ok, report.problems
