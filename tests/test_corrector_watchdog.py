"""The corrector's watchdog step (``corrector._watchdog``) on a curved soft valley.

``E = k (v - c u^2)^2 / 2 + s (u - lambda)^2 / 2`` with ``k >> s``: its minimum
``(u, v) = (lambda, c lambda^2)`` lies in a parabolic valley along which the energy is
soft (eigenvalue about ``s``) while across it the stiffness is ``k``, the shape of a
localised loop's sliding on a rod under tension. From a point on the valley at
``u = lambda + delta`` Newton's step is exactly ``(-delta, -2 c u delta)``: it lands
at ``u = lambda`` but ``c delta^2`` below the valley, where ``max |F|`` is
``k c delta^2 >> s delta`` (the Maratos effect), and the step halved ``j`` times
leaves the valley by ``c delta^2 / 4^j``, so no halving lowers ``max |F|`` either.

Oracles: the exact minimum and the closed forms above (the full step's residual
``k c delta^2``); and the same correction with the watchdog switched off, which by
those closed forms cannot lower ``max |F|``: it keeps the last halving, whose residual
rose, and takes it for divergence.
"""

from __future__ import annotations

import importlib

import numpy as np
import scipy.sparse as sp
from test_continuation_toys import Unconstrained, _no_rank_one

from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.problem import HessianParts

corrector = importlib.import_module("supercoil.continuation.corrector")

K, C, S, LAM, DELTA = 1e6, 1.0, 1.0, 0.5, 1e-2


class CurvedValley(Unconstrained):
    """The energy of the module doc; DOFs ``(u, v)``, parameter ``lam``."""

    n_dofs = 2
    fixed = np.zeros(0, dtype=np.int64)
    mass = np.ones(2)

    def __init__(self, lam: float = LAM):
        self.lam = lam

    def energy(self, q):
        u, v = q
        return 0.5 * K * (v - C * u * u) ** 2 + 0.5 * S * (u - self.lam) ** 2

    def gradient(self, q):
        u, v = q
        w = v - C * u * u
        return np.array([-2.0 * C * u * K * w + S * (u - self.lam), K * w])

    def hessian(self, q):
        u, v = q
        w = v - C * u * u
        H = np.array([[4.0 * C * C * K * u * u - 2.0 * C * K * w + S, -2.0 * C * K * u],
                      [-2.0 * C * K * u, K]])
        return HessianParts(sp.csr_matrix(H), *_no_rank_one(2))


def _start():
    problem = CurvedValley()
    system = ExtendedSystem(problem, "lam", np.zeros(2))
    row = np.zeros(system.size)
    row[-1] = 1.0  # the parameter held at LAM
    u0 = LAM + DELTA
    start = np.array([u0, C * u0 * u0, LAM])
    return system, row, start


def test_the_toy_has_the_closed_forms_of_the_module_doc():
    system, _row, start = _start()
    np.testing.assert_allclose(np.max(np.abs(system.residual(start))), S * DELTA, rtol=1e-12)
    newton = np.array([LAM, C * (LAM + DELTA) ** 2 - 2.0 * C * (LAM + DELTA) * DELTA, LAM])
    np.testing.assert_allclose(np.abs(system.residual(newton)[1]), K * C * DELTA**2,
                               rtol=1e-9)
    for j in range(corrector.BACKTRACKS + 1):  # no halving lowers max |F|
        alpha = 0.5**j
        x = start + alpha * (newton - start)
        assert np.max(np.abs(system.residual(x))) > S * DELTA


def test_the_watchdog_keeps_newtons_full_step_and_converges():
    system, row, start = _start()
    result = corrector.correct(system, start, row, start, 0.0, 1e-10, 10)
    assert result.ok, result.message
    assert result.iterations == 2  # the full step and the watchdog's
    np.testing.assert_allclose(result.x, [LAM, C * LAM * LAM, LAM], rtol=0, atol=1e-12)


def test_without_the_watchdog_the_damped_corrector_crawls(monkeypatch):
    monkeypatch.setattr(corrector, "_watchdog", lambda *args: None)
    system, row, start = _start()
    result = corrector.correct(system, start, row, start, 0.0, 1e-10, 10)
    assert not result.ok
    assert "diverging" in result.message
    assert result.residual > S * DELTA
