"""The first point of a switched branch: where its corrector fails from the predictor at
``amplitude`` from the bifurcation, ``switch_branch(halvings=k)`` halves that distance
up to ``k`` times (:mod:`supercoil.continuation.switching`). The pitchfork of
``DiagonalQuartic`` at ``lambda = d_0`` (the new branch ``|x|^2 = lambda - d_0``,
``x = (x_0, 0, ...)``), with the corrector made to fail farther than ``REACH`` from the
bifurcation: the oracle is the first point's ``x_0``, the distance at which the
corrector first succeeds."""

import numpy as np
import pytest
from test_continuation_toys import DiagonalQuartic

from supercoil.continuation import (
    ContinuationOptions,
    ContinuationStatus,
    continuation,
    switch_branch,
    switching,
)
from supercoil.continuation.corrector import Correction

REACH = 0.02


@pytest.fixture
def pitchfork(monkeypatch):
    d = np.array([1.0, 2.0, 3.5, 5.0])
    p = DiagonalQuartic(d)
    opts = ContinuationOptions(parameter_bounds=(0.0, 1.5), max_step=0.3)
    b = continuation(p, np.zeros(4), parameter="lam", options=opts)
    point = b.points_of_kind("bifurcation")[0]
    real = switching.correct
    distances = []

    def correct(system, x_start, row, x_ref, sigma, *args, **kwargs):
        distances.append(abs(sigma))
        if abs(sigma) > REACH:
            return Correction(None, False, 2, 1.0, "corrector diverging (made so)")
        return real(system, x_start, row, x_ref, sigma, *args, **kwargs)

    monkeypatch.setattr(switching, "correct", correct)
    return p, b, point, opts, distances


def test_the_first_point_is_found_at_the_first_distance_halved_within_reach(pitchfork):
    p, b, point, opts, distances = pitchfork
    new = switch_branch(p, b, point, opts, amplitude=0.1, halvings=5)
    assert new.status is ContinuationStatus.PARAMETER_BOUND, new.message
    # 0.1, 0.05, 0.025 fail; 0.0125 is the first within reach
    assert distances[:4] == pytest.approx([0.1, 0.05, 0.025, 0.0125])
    assert new.states[0, 0] == pytest.approx(0.0125, abs=1e-12)
    assert new.parameter_values[0] == pytest.approx(1.0 + 0.0125**2, abs=1e-10)
    x, lam = new.states, new.parameter_values
    assert np.allclose(np.sum(x**2, axis=1), lam - 1.0, atol=1e-9, rtol=0)


def test_without_halvings_or_beyond_them_the_switch_does_not_start(pitchfork):
    p, b, point, opts, distances = pitchfork
    plain = switch_branch(p, b, point, opts, amplitude=0.1)
    assert plain.status is ContinuationStatus.START_FAILED and len(plain) == 0
    assert distances == [0.1]
    assert plain.message.endswith("(at the distances 0.1 to 0.1)")
    distances.clear()
    short = switch_branch(p, b, point, opts, amplitude=0.1, halvings=2)
    assert short.status is ContinuationStatus.START_FAILED
    assert distances == pytest.approx([0.1, 0.05, 0.025])
    assert "(at the distances 0.1 to 0.025)" in short.message
