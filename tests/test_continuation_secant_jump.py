"""A step along the branch's chord past a point where the tangent is lost.

``E = (u - lam)^2 / 2 + v^2 / 2`` has the exact branch ``u = lam, v = 0``. Within a
window of ``lam`` the toy reports a parameter derivative that points across the branch,
so that every tangent computed there is wrong while the residual, and with it every
corrected point, stays exact: the tracer refuses each step landing in the window for
its tangent's turn, down to the minimum step, as on a long rod's contact branch whose
tangent is lost in round-off (continuation/secant_jump.py). Oracles: the exact branch,
and the window's edges, which the chord step must bracket.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from test_continuation_toys import Unconstrained, _no_rank_one

from supercoil.continuation import ContinuationOptions, ContinuationStatus, continuation
from supercoil.continuation.secant_jump import GROWTH, chord_direction, jump_lengths
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.problem import HessianParts


class LostTangent(Unconstrained):
    """The energy of the module doc; DOFs ``(u, v)``, parameter ``lam``; the parameter
    derivative is wrong for ``low < lam < high``."""

    n_dofs = 2
    fixed = np.zeros(0, dtype=np.int64)
    mass = np.ones(2)

    def __init__(self, low: float, high: float, lam: float = 0.0):
        self.low, self.high, self.lam = low, high, lam

    def energy(self, q):
        return 0.5 * (q[0] - self.lam) ** 2 + 0.5 * q[1] ** 2

    def gradient(self, q):
        return np.array([q[0] - self.lam, q[1]])

    def hessian(self, q):
        return HessianParts(sp.csr_matrix(np.eye(2)), *_no_rank_one(2))

    def parameter_derivative(self, q, multipliers, name):
        if self.low < self.lam < self.high:
            return np.array([-1.0, 5.0])  # across the branch
        return np.array([-1.0, 0.0])


OPTIONS = ContinuationOptions(initial_step=0.01, max_step=0.05, parameter_bounds=(0.0, 1.0),
                              max_points=500, detect_bifurcations=False)


def _follow(low, high):
    return continuation(LostTangent(low, high), np.zeros(2), parameter="lam",
                        options=OPTIONS)


def test_a_chord_step_passes_a_window_where_the_tangent_is_lost():
    low, high = 0.48, 0.52
    branch = _follow(low, high)
    assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
    assert "1 step along the chord past a lost tangent" in branch.message
    lam = branch.parameter_values
    np.testing.assert_allclose(branch.states[:, 0], lam, rtol=0, atol=1e-9)
    np.testing.assert_allclose(branch.states[:, 1], 0.0, rtol=0, atol=1e-9)
    # no point inside the window; the step across it is the chord step
    assert not np.any((lam > low) & (lam < high))
    k = int(np.searchsorted(lam, low))
    assert lam[k - 1] < low and lam[k] > high
    assert f"from point {k - 1}" in branch.message


def test_where_every_chord_step_fails_the_run_stops_and_says_so():
    """The window reaches past the bound: no step along the chord lands outside it."""
    branch = _follow(0.5, 1.5)
    assert branch.status is ContinuationStatus.STEP_TOO_SMALL
    assert "the tangent turned by more than" in branch.message
    assert "steps along the chord of the last points" in branch.message
    assert "failed too" in branch.message
    assert branch.parameter_values[-1] < 0.5


def test_the_chord_and_the_lengths_tried():
    system = ExtendedSystem(LostTangent(2.0, 3.0), "lam", np.zeros(2))
    line = np.array([1.0, 0.0, 1.0]) / system.norm(np.array([1.0, 0.0, 1.0]))
    # points along the line with steps 0.1, 0.2, 0.05, 0.01: the largest is 0.2, and the
    # latest point at least 0.2 back is the one before the 0.2 step
    s = np.cumsum([0.0, 0.1, 0.2, 0.05, 0.01])
    xs = [float(a) * line for a in s]
    d, big = chord_direction(system, xs, list(s))
    assert big == pytest.approx(0.2, rel=1e-12)
    np.testing.assert_allclose(d, line, rtol=0, atol=1e-12)
    lengths = jump_lengths(0.01, big, 1e-6)
    assert lengths[0] == pytest.approx(0.04) and lengths[-1] <= 4 * big
    assert lengths[-1] * GROWTH > 4 * big
    np.testing.assert_allclose(np.diff(np.log(lengths)), np.log(GROWTH), rtol=1e-12)
    assert chord_direction(system, xs[:2], list(s[:2])) is None
