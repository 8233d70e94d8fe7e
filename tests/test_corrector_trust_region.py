"""The corrector's trust region widened by the start point's own correction.

``E = s (u - lambda)^2 / 2 + k v^2 / 2`` has the branch ``u = lambda, v = 0``; its
soft direction (eigenvalue ``s``) takes a point accepted at a residual ``r`` a
distance ``r / s`` off the branch along ``u``; the corrector accepts points at
round-off above the tolerance (within ``FLOOR_MARGIN`` floors of the residual, where
Newton's next step raised it), and from such a point every step needs a Newton
step. From ``x_k = (lambda + e, 0, lambda)`` (residual ``s e``) the bordered Newton
correction with the row ``b = W t``
(``t`` the unit tangent) moves it by the component of ``(-e, 0, 0)`` across ``t``, of
norm ``|e| sqrt(W_u W_l / (W_u + W_l))`` in the metric ``W`` (closed form below). A
step ``ds`` much shorter than that lands, by one Newton step (the problem is linear),
on ``u = lambda`` at that distance from the predictor: a trust region of ``ds`` alone
would refuse every such step, however short, so that the run would stop at the minimum
step with the point as good as its tolerance allows.

Oracles: the closed forms of the own correction and of the corrected point.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from test_continuation_toys import Unconstrained, _no_rank_one

from supercoil.continuation.corrector import bordered_factor, correct, own_correction
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.problem import HessianParts

S, K, LAM, TOL = 1e-6, 1.0, 0.3, 1e-8


class SoftLine(Unconstrained):
    """The energy of the module doc; DOFs ``(u, v)``, parameter ``lam``."""

    n_dofs = 2
    fixed = np.zeros(0, dtype=np.int64)
    mass = np.ones(2)

    def __init__(self, lam: float = LAM):
        self.lam = lam

    def energy(self, q):
        return 0.5 * S * (q[0] - self.lam) ** 2 + 0.5 * K * q[1] ** 2

    def gradient(self, q):
        return np.array([S * (q[0] - self.lam), K * q[1]])

    def hessian(self, q):
        return HessianParts(sp.csr_matrix(np.diag([S, K])), *_no_rank_one(2))


def _setup(e: float):
    system = ExtendedSystem(SoftLine(), "lam", np.zeros(2))
    w = system.weights
    t = np.array([1.0, 0.0, 1.0])
    t /= system.norm(t)
    x_k = np.array([LAM + e, 0.0, LAM])
    return system, w, t, x_k


@pytest.mark.parametrize("e", [0.5 * TOL / S, -5 * TOL / S])
def test_the_own_correction_has_its_closed_form(e):
    system, w, t, x_k = _setup(e)
    row = w * t
    own = own_correction(system, bordered_factor(system, x_k, row), x_k, row)
    # dx = (a, 0, c) with a - c = -e (u = lambda) and w_u a + w_l c = 0 (across t)
    wu, wl = w[0], w[-1]
    a, c = -e * wl / (wu + wl), e * wu / (wu + wl)
    assert own == pytest.approx(np.sqrt(wu * a * a + wl * c * c), rel=1e-10)
    assert own == pytest.approx(abs(e) * np.sqrt(wu * wl / (wu + wl)), rel=1e-10)


@pytest.mark.parametrize("ds", [1e-4, 1e-7, 1e-12])
def test_a_short_step_from_a_point_off_the_branch_by_its_tolerance_converges(ds):
    """With the trust region at one step (``max_distance = ds``) every step shorter than
    the own correction lands beyond it; widened by that correction it converges, on the
    closed-form point. The start's residual, 5 tolerances, is one that the round-off
    margin accepts on long rods (``FLOOR_MARGIN`` floors of 1e-8 to 1e-7)."""
    e = 5 * TOL / S
    system, w, t, x_k = _setup(e)
    assert np.max(np.abs(system.residual(x_k))) > TOL
    row = w * t
    predicted = x_k + ds * t
    own = own_correction(system, bordered_factor(system, x_k, row), x_k, row)
    corr = correct(system, predicted, row, x_k, ds, TOL, 10, max_distance=ds,
                   center=predicted)
    assert corr.ok, corr.message
    # the exact point: u = lambda and row . (x - x_k) = ds
    lam = (ds + row[0] * (LAM + e) + row[-1] * LAM) / (row[0] + row[-1])
    np.testing.assert_allclose(corr.x, [lam, 0.0, lam], rtol=0, atol=1e-12)
    distance = system.norm(corr.x - predicted)
    assert distance > ds  # beyond the unwidened trust region ...
    assert distance <= ds + own * (1 + 1e-9)  # ... within the widened one


def test_a_jump_beyond_the_widened_region_is_still_refused():
    """From a point on the branch (no own correction) a start displaced across the
    branch by ten steps is stopped at its first iterate, as before."""
    system, w, t, x_k = _setup(0.0)
    ds = 1e-6
    row = w * t
    predicted = x_k + ds * t
    start = predicted.copy()
    start[1] = 10 * ds  # off the branch in the stiff direction v
    corr = correct(system, start, row, x_k, ds, TOL, 10, max_distance=ds,
                   center=start)
    assert not corr.ok
    assert "iterate 1 lies farther than 1.00e-06 from the predictor" in corr.message
