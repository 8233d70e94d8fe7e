"""Chord steps of the corrector (``correct(..., chord_below=...)``) against plain Newton.

Oracles: Newton's own correction from the same start (the same iteration count, a
point within the tolerance of the same solution), the residual recomputed at the
returned point, and the count of bordered factorisations (one fewer where the chord
step landed). On Bratu's problem (tests/test_continuation_toys.py), whose corrector
converges quadratically, so that the last step is taken from a residual far below
the one where the factor was made.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_continuation_toys import Bratu

from supercoil.continuation import corrector
from supercoil.continuation.corrector import correct
from supercoil.continuation.system import ExtendedSystem


def _start(lam: float = 2.0, push: float = 0.05):
    """A converged Bratu state at ``lam`` and a start pushed off it along the branch's
    parameter (a predictor's error), with the arclength row of the parameter."""
    problem = Bratu(40, lam=lam)
    system = ExtendedSystem(problem, "lam", np.zeros(problem.n_dofs))
    row = np.zeros(system.size)
    row[-1] = 1.0
    x0 = np.concatenate([np.zeros(system.n), [lam]])
    exact = correct(system, x0, row, x0, 0.0, 1e-12, 30)
    assert exact.ok
    x_ref = exact.x
    start = x_ref.copy()
    start[:-1] *= 1.0 + push
    start[-1] += push
    return system, row, x_ref, start


def _counted(monkeypatch):
    calls = []
    original = corrector.bordered_factor

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(corrector, "bordered_factor", counting)
    return calls


def _recorded_chords(monkeypatch):
    """A list that gets, for every chord step tried, whether it landed."""
    landed = []
    original = corrector._chord_step

    def recording(*args):
        out = original(*args)
        landed.append(out is not None)
        return out

    monkeypatch.setattr(corrector, "_chord_step", recording)
    return landed


@pytest.mark.parametrize("push", [0.02, 0.03, 0.05])
def test_chord_step_lands_with_newtons_iteration_count_and_one_factor_fewer(monkeypatch, push):
    system, row, x_ref, start = _start(push=push)
    sigma = push  # the parameter row lands the point at lam + push
    tolerance = 1e-8
    calls = _counted(monkeypatch)
    newton = correct(system, start, row, x_ref, sigma, tolerance, 20)
    newton_factors = len(calls)
    calls.clear()
    chord = correct(system, start, row, x_ref, sigma, tolerance, 20, chord_below=1e-2)
    assert newton.ok and chord.ok
    assert "chord step" in chord.message and "chord" not in newton.message
    assert chord.iterations == newton.iterations
    assert len(calls) == newton_factors - 1
    recomputed = float(np.max(np.abs(system.residual(chord.x))))
    assert recomputed <= tolerance and recomputed == pytest.approx(chord.residual, abs=0)
    # both within the tolerance of one solution: their distance is at most the
    # residuals times the inverse Jacobian's norm (about 1 here, far from the fold)
    assert np.max(np.abs(chord.x - newton.x)) <= 100 * tolerance


def test_chord_steps_that_do_not_land_are_dropped(monkeypatch):
    """A chord step tried where it cannot land within the tolerance (the thresholds
    opened: from 5e-5 with a tolerance of 1e-8) is dropped, and the Newton step is
    made from the same iterate: the correction is Newton's, bit for bit."""
    system, row, x_ref, start = _start(push=0.4)
    monkeypatch.setattr(corrector, "CHORD_REACH", 1e30)
    tried = _recorded_chords(monkeypatch)
    newton = correct(system, start, row, x_ref, 0.4, 1e-8, 20)
    chord = correct(system, start, row, x_ref, 0.4, 1e-8, 20, chord_below=1.0)
    assert tried and not any(tried)
    assert chord.ok and newton.ok and chord.iterations == newton.iterations
    assert np.array_equal(chord.x, newton.x)


def test_no_chord_step_without_the_option_or_near_the_round_off_floor(monkeypatch):
    system, row, x_ref, start = _start(push=0.05)
    tried = []
    monkeypatch.setattr(corrector, "_chord_step",
                        lambda *args: tried.append(1))  # would fail the run if used
    plain = correct(system, start, row, x_ref, 0.05, 1e-8, 20)
    assert plain.ok and not tried
    # a tolerance below round-off: the floor test decides, no chord step is tried there
    floor_only = correct(system, start, row, x_ref, 0.05, 1e-300, 20, chord_below=1e-2)
    assert floor_only.ok and not tried


def test_bratu_branch_with_chord_steps_has_the_same_points_and_fold(monkeypatch):
    """Continuation round Bratu's fold with and without chord steps (tolerance 1e-8, so
    that chord steps land): the same points to the tolerance, the same fold (Moore-Spence,
    tests/test_continuation.py), and a consistent branch."""
    from test_continuation import assert_consistent, bratu_branch, moore_spence_fold

    _, plain = bratu_branch(24, tolerance=1e-8)
    landed = _recorded_chords(monkeypatch)
    problem, chord = bratu_branch(24, tolerance=1e-8, chord_steps=True)
    assert sum(landed) >= 3  # chord steps were taken
    assert plain.ok and chord.ok and len(chord) == len(plain)
    assert np.max(np.abs(chord.states - plain.states)) <= 1e-6
    folds = [p for p in chord.special_points if p.kind == "fold"]
    plain_folds = [p for p in plain.special_points if p.kind == "fold"]
    assert len(folds) == len(plain_folds) == 1
    exact = moore_spence_fold(24)
    assert abs(folds[0].parameter - exact) <= 1e-8
    assert abs(plain_folds[0].parameter - exact) <= 1e-8
    assert_consistent(chord, problem)
