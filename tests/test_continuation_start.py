"""Starting a continuation where the parameter cannot be held: a fold, and a point of a
computed run in that run's gauge.

Oracles: the equilibria of :class:`CircleOfEquilibria` are the circle
``x_0^2 + lambda^2 = 1`` with folds at ``lambda = +-1``, stable where ``x_0 > 0``;
a run started in the gauge of a computed run retraces it.
"""

from __future__ import annotations

import numpy as np
from test_continuation_toys import CircleOfEquilibria

from supercoil.continuation import ContinuationOptions, ContinuationStatus, continuation


def _fold_start(guess):
    problem = CircleOfEquilibria(lam=1.0)
    opts = ContinuationOptions(parameter_bounds=(-2.0, 2.0), initial_step=0.05,
                               max_step=0.1, max_points=12)
    return continuation(problem, np.zeros(problem.n_dofs), parameter="lam", options=opts,
                        guess=guess)


def test_a_start_at_a_fold_converges_on_the_hyperplane_of_a_guessed_tangent():
    """At the fold (x = 0, lambda = 1) the Hessian is singular and the parameter cannot be
    held: the plain start fails. With the fold's tangent (the critical mode e_0, no change
    of lambda) as ``guess`` it converges at the fold itself and follows the circle on the
    side the guess points to: x_0 > 0 stable, x_0 < 0 one unstable direction, lambda
    falling from 1 on both; every point on the circle to the tolerance."""
    plain = _fold_start(None)
    assert plain.status is ContinuationStatus.START_FAILED, plain.message
    assert len(plain) == 0
    for sign in (1.0, -1.0):
        guess = np.array([sign, 0.0, 0.0, 0.0])  # [dq (3), dlambda]
        branch = _fold_start(guess)
        assert branch.status is ContinuationStatus.MAX_POINTS, branch.message
        x0, lam = branch.states[:, 0], branch.parameter_values
        np.testing.assert_allclose(x0**2 + lam**2, 1.0, atol=1e-8)
        assert abs(lam[0] - 1.0) < 1e-12 and abs(x0[0]) < 1e-12
        assert np.all(np.diff(lam) < 0)
        assert np.all(sign * x0[1:] > 0)
        assert np.all(branch.unstable_count[1:] == (0 if sign > 0 else 1))
        np.testing.assert_allclose(branch.states[:, 1:], 0.0, atol=1e-14)


def test_a_run_started_in_the_gauge_of_a_computed_run_retraces_it():
    """A knotted ring's points are equilibria with its material sliding held by a phase row,
    whose multiplier is the discretisation's small force along the sliding. A run started
    at a computed point with that run's phase rows and tangent (``phase``, ``guess``, as
    ``segments.follow`` starts again where a fresh gauge fails) starts at the point itself
    and retraces the uninterrupted run (oracle: that run, to round-off); a fresh gauge
    chosen at the point moves it (the sliding's force now held elsewhere)."""
    import dataclasses

    from supercoil.continuation.carry import frames_at
    from supercoil.problems.branch_options import CONTACT_MIN_STEP
    from supercoil.problems.knot_branch import MAX_STEP, relaxed_knot
    from supercoil.problems.segments import set_pin
    from supercoil.solvers.carried import carried

    cp, q0, _knot, _message = relaxed_knot("3_1", 1.4, 40.0, 3.0, 36)
    D = cp.diameter
    set_pin(cp, cp.base, q0)
    cp.accept(q0)
    opts = ContinuationOptions(
        initial_step=0.05 * D, min_step=CONTACT_MIN_STEP, max_step=MAX_STEP * D, max_points=6,
        parameter_bounds=(2.0, 5.0), parameter_weight=D, tolerance=1e-8,
        near_symmetry_gauge=True, regauge=True, factor_refinement=True)
    first = continuation(cp, q0, parameter="excess_link", start=3.0, options=opts)
    whole = continuation(cp, q0, parameter="excess_link", start=3.0,
                         options=dataclasses.replace(opts, max_points=12))
    assert len(first) == 6 and len(whole) == 12
    q = first.states[-1]
    carrying = carried(frames_at(cp, first, len(first) - 1), q)
    more = dataclasses.replace(opts, max_points=7, initial_step=float(first.next_step[-1]))

    def restart(**gauge):
        return continuation(carrying, q, first.multipliers[-1], parameter="excess_link",
                            start=float(first.parameter_values[-1]), options=more, **gauge)

    again = restart(phase=(first.phase_modes, first.phase_state), guess=first.tangents[-1])
    assert len(again) == 7, again.message
    assert np.max(np.abs(again.states[0] - q)) < 1e-12 * D  # measured 3e-15 D
    np.testing.assert_allclose(again.states, whole.states[5:], rtol=0, atol=1e-10 * D)
    np.testing.assert_allclose(again.parameter_values, whole.parameter_values[5:], atol=1e-12)
    fresh = restart()
    assert np.max(np.abs(fresh.states[0] - q)) > 1e-6 * D  # measured 9e-6 D


def test_start_branch_starts_off_a_fold_and_off_a_pitchfork_along_the_critical_mode():
    """``start_branch`` at a singular point: at the fold of the circle of equilibria the
    start is the fold itself (on the hyperplane orthogonal to the critical mode), the side
    chosen by ``direction``; at the pitchfork of the diagonal quartic at lambda = d_0
    (x = 0, where the two branches' tangents span the kernel) the start lies at one first
    step along the critical mode e_0, on the bifurcating branch x = a e_0, a^2 = lambda -
    d_0 (its known solution). Away from singular points it is the plain start (no note)."""
    from test_continuation_toys import DiagonalQuartic

    from supercoil.continuation.singular_start import start_branch

    circle = CircleOfEquilibria(lam=1.0)
    for direction in (1, -1):
        opts = ContinuationOptions(parameter_bounds=(-2.0, 2.0), initial_step=0.05,
                                   max_step=0.1, max_points=8, direction=direction)
        branch, note = start_branch(circle, np.zeros(circle.n_dofs), parameter="lam",
                                    start=1.0, options=opts)
        assert branch.status is ContinuationStatus.MAX_POINTS, branch.message
        assert "singular point" in note and "fold" in note
        x0, lam = branch.states[:, 0], branch.parameter_values
        assert abs(lam[0] - 1.0) < 1e-12 and abs(x0[0]) < 1e-12
        np.testing.assert_allclose(x0**2 + lam**2, 1.0, atol=1e-8)
        assert np.all(direction * x0[1:] > 0)  # side + for direction +1

    d = np.array([1.0, 2.0, 3.5])
    quartic = DiagonalQuartic(d, lam=1.0)
    opts = ContinuationOptions(parameter_bounds=(0.0, 3.0), initial_step=0.05, max_step=0.2,
                               max_points=10)
    branch, note = start_branch(quartic, np.zeros(3), parameter="lam", start=1.0,
                                options=opts)
    assert branch.status is ContinuationStatus.MAX_POINTS, branch.message
    assert "along its critical mode" in note
    x, lam = branch.states, branch.parameter_values
    np.testing.assert_allclose(np.sum(x**2, axis=1), lam - d[0], atol=1e-9)
    assert np.all(x[:, 0] > 0) and np.max(np.abs(x[:, 1:])) < 1e-12
    assert np.all(branch.unstable_count == 0)

    plain, note = start_branch(quartic, np.zeros(3), parameter="lam", start=0.5, options=opts)
    assert note is None and plain.ok and plain.parameter_values[0] == 0.5


def test_follow_starts_a_run_again_in_the_last_runs_gauge_when_a_fresh_gauge_fails(
        monkeypatch):
    """``segments.follow``: a run whose start in a gauge chosen afresh fails (as at the
    trefoil ring's bifurcation point at L/D 170, made to happen here at every run
    boundary) starts again in the last run's gauge and goes on. Oracles: the branch in
    runs of 4 points with every fresh start failing reaches as far as one run of the
    same points does, along the same curve (writhe against dLk, interpolated), with
    Lk = Tw + Wr and the knot type at every point."""
    import dataclasses

    from scipy.interpolate import CubicSpline

    from supercoil.continuation.resume import head
    from supercoil.problems import knot_branch, segments
    from supercoil.problems.knot_branch import follow_knot, relaxed_knot
    from supercoil.problems.knot_switching import RETRACE_WRITHE

    cp, q0, _knot, _message = relaxed_knot("3_1", 1.4, 40.0, 3.0, 36)
    whole = follow_knot(cp, q0.copy(), 3.0, 5.0, 13, 1e-8, "whole")
    plain = segments.continuation
    failed = []

    def fresh_fails(*args, **kwargs):
        run = plain(*args, **kwargs)
        if "phase" in kwargs:
            return run
        failed.append(kwargs["start"])  # a start in a fresh gauge: made to fail (no point)
        return dataclasses.replace(head(run, 0), status=ContinuationStatus.START_FAILED,
                                   message="the starting point did not converge")

    monkeypatch.setattr(segments, "continuation", fresh_fails)
    monkeypatch.setattr(knot_branch, "SEGMENT_POINTS", 4)
    runs = follow_knot(cp, q0.copy(), 3.0, 5.0, 13, 1e-8, "runs")
    assert len(failed) >= 3  # every run after the first
    assert len(runs) == len(whole) == 13, runs.message
    lam, wr = np.asarray(whole.parameter_values), np.asarray(whole.records["writhe"])
    inside = np.asarray(runs.parameter_values) <= lam[-1]
    keep = np.concatenate([[True], np.diff(lam) > 1e-12])  # a point repeated once
    spline = CubicSpline(lam[keep], wr[keep])
    # the same family to the criterion of a switch that ran along a computed one: the two
    # gauges hold the material sliding at different places, and copies of one state slid
    # along the mesh differ by its ripple (measured 3e-4 turns here)
    np.testing.assert_allclose(np.asarray(runs.records["writhe"])[inside],
                               spline(np.asarray(runs.parameter_values)[inside]),
                               atol=RETRACE_WRITHE)
    assert np.max(np.abs(runs.records["link_error"])) < 1e-10
    assert np.all(runs.records["knot_determinant"] == 3)
