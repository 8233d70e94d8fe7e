"""Two ways through a stall at round-off, on the case that needs one: the tweezers at
lambda = 150, C/A = 1.5, N = 302, where the buckled helix localises into a loop near
32.56 turns with two soft modes (the loop's sliding and one of eigenvalue 0.4 against
2.2e5 for the next). There the corrector reaches about one round-off floor
(``eps ||H|| ||q||``) and Newton's next step, moving the state along the soft modes by
the noise over their eigenvalues, raises the residual by four decades (docs/continuation.md,
"Corrector"). The corrector's watchdog keeps that step and the next, which lands below
the floor; where the watchdog does not help, an iterate within
:data:`~supercoil.continuation.corrector.FLOOR_MARGIN` floors whose Newton step raised
the residual is accepted. Each is tested with the other switched off; with neither,
every step failed down to the minimum step at 32.5587 turns with one BLAS build.

Oracles: each point accepted by the margin is the iterate whose residual was measured
(recomputed from the returned state: above one floor, within ``FLOOR_MARGIN``); and the
branch goes on through the localisation as one branch: its count one and its
determinant's sign negative at every point, the turns decreasing at every point (no
fold), consecutive tangents within 10 degrees, and the loop localising (the sliding's
tail ratio, the outer nodes' motion over the largest, falling below 1e-4)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from supercoil.problems.greenhill import critical_turns
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.problems.tweezers.problem import clamped_problem
from supercoil.solvers.newton import roundoff_floor

corrector = importlib.import_module("supercoil.continuation.corrector")
step = importlib.import_module("supercoil.continuation.step")
OPTIONS = TweezersOptions(loop_sliding=True, twist_ratio=1.5, length_over_diameter=100,
                          tension=150.0**2, n_nodes=302,
                          turns=(0.0, 1.5 * critical_turns(1.5, 150.0**2)), max_points=60)


def _buckled(result):
    return next(b for b in result.branches if b.name == "buckled")


def _accepted_by_the_margin(monkeypatch):
    accepted = []
    original = step.correct

    def correct(system, *args, **kwargs):
        result = original(system, *args, **kwargs)
        if result.ok and "of the floor estimate" in result.message:
            residual = float(np.max(np.abs(system.residual(result.x))))
            floor = roundoff_floor(system.hessian(result.x), system.q(result.x))
            accepted.append((float(result.x[-1]), residual / floor))
        return result

    monkeypatch.setattr(step, "correct", correct)
    return accepted


@pytest.mark.parametrize("way", ["watchdog", "margin"])
def test_the_localising_loop_passes_a_stall_at_round_off(monkeypatch, way):
    accepted = _accepted_by_the_margin(monkeypatch)
    if way == "watchdog":
        monkeypatch.setattr(corrector, "FLOOR_MARGIN", 0.0)
    else:
        monkeypatch.setattr(corrector, "_watchdog", lambda *args: None)
    buckled = _buckled(tweezers_branches(OPTIONS))
    assert buckled.parameter_values[-1] < 30.0  # past 32.5587, where it stopped
    if way == "margin":
        assert any(32.4 < turns < 32.6 for turns, _ in accepted)  # as the loop localises
        assert all(1.0 < ratio <= corrector.FLOOR_MARGIN for _, ratio in accepted)
    else:
        assert not accepted
    assert np.all(buckled.unstable_count == 1)
    assert np.all(buckled.determinant_sign == -1)
    assert np.all(np.diff(buckled.parameter_values) < 0)
    assert np.all(buckled.tangents[:, -1] < 0)
    t = buckled.tangents[:, :-1]
    cosines = np.sum(t[1:] * t[:-1], axis=1) / (np.linalg.norm(t[1:], axis=1)
                                                 * np.linalg.norm(t[:-1], axis=1))
    assert np.all(cosines > np.cos(np.radians(10.0)))
    rod, _q0 = clamped_problem(OPTIONS)
    assert rod.sliding(buckled.states[-1])[1] < 1e-4
