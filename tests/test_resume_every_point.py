"""A branch interrupted after any accepted point and resumed ends where the uninterrupted
run ends.

Oracle: the uninterrupted run itself. The partial branch the run hands to ``on_point``
at every accepted point k (what a signal stopping it after point k would leave written)
is copied as it is handed out, resumed on a fresh problem, and the whole branch, its
special points and its last state must equal the uninterrupted run's to 1e-8. That the
copy taken during the uninterrupted run is the partial branch of a run really stopped
in ``on_point`` after point k is checked bit for bit at a few k (one run stopped at
every k would repeat the uninterrupted run's first k points each time). The cases are built so
that steps fail right after some of the points a run is stopped at (the halved step
must be found again), with the predictor shortened at an obstacle, a fold, a user
event, and on the ring with moved and re-anchored phase rows.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest
from test_continuation_toys import Bratu

from supercoil.continuation import (
    ContinuationOptions,
    UserEvent,
    continuation,
    switch_branch,
)
from supercoil.continuation.resume import head, resume_branch
from supercoil.io.branch_codec import BranchBuilder, flatten, unflatten

TOL = 1e-8


class GuardedBratu(Bratu):
    """Bratu's problem with a collision-guard stand-in: no predictor moves a value by more
    than 0.1 (the tracer shortens it; the corrector covers the rest)."""

    def step_bound(self, q, dq):
        largest = float(np.max(np.abs(dq)))
        return 1.0 if largest <= 0.1 else 0.1 / largest


THRESHOLD = UserEvent("threshold", lambda q, mu, lam: {"u_mid_minus_1": q[16] - 1.0})


def bratu_records(q, mu, lam):
    return {"u_mid": q[16]}


class Rejections(logging.Handler):
    """The number of stored points whenever the tracer rejects a step or moves a gauge."""

    def __init__(self):
        super().__init__(logging.DEBUG)
        self.points = 0
        self.after: list[int] = []

    def emit(self, record):
        message = record.getMessage()
        if "rejected" in message or "gauge moved" in message:
            self.after.append(self.points)

    def __enter__(self):
        log = logging.getLogger("supercoil.continuation.tracer")
        self.level = log.level
        log.addHandler(self)
        log.setLevel(logging.DEBUG)
        return self

    def __exit__(self, *exc):
        log = logging.getLogger("supercoil.continuation.tracer")
        log.removeHandler(self)
        log.setLevel(self.level)


def interrupted_after(k, run):
    """The partial branch ``run(on_point)`` had handed out when stopped after point ``k``."""
    saved = []

    def stop(branch):
        saved.append(branch)
        if len(branch) == k:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(stop)
    assert len(saved[-1]) == k
    return saved[-1]


def uninterrupted(run, rejections):
    """``(full, partials)``: the branch of ``run(on_point)`` and a copy of each partial
    branch it handed to ``on_point``, as it was then (a partial branch's arrays are
    views of the growing columns, whose last row a regauge or a rephase may replace
    later; a point corrected again in moved phase rows is handed out again), counting
    points for ``rejections``."""
    partials = []

    def keep(branch):
        arrays = {f.name: np.array(getattr(branch, f.name)) for f in dataclasses.fields(branch)
                  if isinstance(getattr(branch, f.name), np.ndarray)}
        partials.append(dataclasses.replace(
            branch, **arrays, records={k: np.array(v) for k, v in branch.records.items()}))
        rejections.points = len(branch)

    full = run(keep)
    lengths = [len(p) for p in partials]
    assert lengths == sorted(lengths) and set(lengths) == set(range(1, len(full) + 1))
    return full, partials


def assert_same_bits(a, b):
    """Two branches equal as the result files store them (attributes and every array)
    and in the frames carried at each point, to the bit."""
    meta_a, groups_a, arrays_a = flatten(a)
    meta_b, groups_b, arrays_b = flatten(b)
    assert meta_a == meta_b and groups_a == groups_b
    assert sorted(arrays_a) == sorted(arrays_b)
    for name in arrays_a:
        np.testing.assert_array_equal(arrays_a[name], arrays_b[name], err_msg=name)
    assert len(a.frames) == len(b.frames)
    assert all(f is g is None or f.equals(g) for f, g in zip(a.frames, b.frames))


def assert_copies_are_interrupted_partials(partials, run, ks):
    """A run stopped in ``on_point`` the first time it had k points left the partial
    branch copied then in the uninterrupted run, for each k in ``ks``."""
    for k in ks:
        assert_same_bits(interrupted_after(k, run),
                         next(p for p in partials if len(p) == k))


def assert_same_end(resumed, full, k):
    assert len(resumed) == len(full), (k, resumed.message)
    assert resumed.status is full.status, (k, resumed.message)
    np.testing.assert_allclose(resumed.states, full.states, rtol=0, atol=TOL, err_msg=str(k))
    np.testing.assert_allclose(resumed.parameter_values, full.parameter_values, rtol=0,
                               atol=TOL, err_msg=str(k))
    np.testing.assert_array_equal(resumed.unstable_count, full.unstable_count)
    assert [(p.kind, p.index) for p in resumed.special_points] == \
        [(p.kind, p.index) for p in full.special_points], k
    for p, q in zip(resumed.special_points, full.special_points):
        assert abs(p.parameter - q.parameter) < TOL, k
        np.testing.assert_allclose(p.q, q.q, rtol=0, atol=TOL, err_msg=str(k))
    # the step controller's state is the uninterrupted run's, point by point
    np.testing.assert_allclose(resumed.next_step, full.next_step, rtol=1e-12, err_msg=str(k))
    np.testing.assert_array_equal(resumed.gauge_moved, full.gauge_moved)


@pytest.mark.parametrize("predictor", ["tangent", "secant", "quadratic"])
def test_bratu_resumed_after_every_point_ends_as_the_uninterrupted_run(predictor):
    """Through the fold and a user event, steps doubling up to 0.8 and failing (tangent
    turns above 10 degrees) after many points, predictors shortened by the step bound."""
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.05, max_step=0.8,
                               growth=2.0, max_turn_degrees=10.0, max_points=60,
                               predictor=predictor)

    def run(on_point=None):
        return continuation(GuardedBratu(32, 1.0), np.zeros(33), parameter="lam",
                            options=opts, events=[THRESHOLD], records=bratu_records,
                            on_point=on_point)

    with Rejections() as rejections:
        full, partials = uninterrupted(run, rejections)
    assert full.status.name == "PARAMETER_BOUND"
    assert [p.kind for p in full.special_points] == ["threshold", "fold"]
    # steps failed right after several points the run is resumed from below
    assert len(set(rejections.after)) >= 5, rejections.after
    assert np.all(np.isfinite(full.next_step)) and not full.gauge_moved.any()
    # really stopped: at the first point, after a failed step, at the last point
    assert_copies_are_interrupted_partials(
        partials, run, {1, min(k for k in rejections.after if k), len(full) - 1})
    for partial in (p for p in partials if len(p) < len(full)):
        resumed = resume_branch(GuardedBratu(32, 1.0), partial, opts, events=[THRESHOLD],
                                records=bratu_records)
        assert_same_end(resumed, full, len(partial))


def ring_alpha():
    from supercoil.problems.ring_branches import circle_branch

    circle, problem = circle_branch(0.6667, 24, 3.0)
    (point, *_) = circle.points_of_kind("bifurcation")
    return problem, circle, point


def test_ring_branch_resumed_after_every_point_ends_as_the_uninterrupted_run():
    """The ring's alpha branch off the circle with the sliding gauge's integral phase row,
    moved after a failed step and re-anchored at every point, steps doubling and failing:
    resumed after any point on a fresh problem (its reference frames carried along the
    stored points again), the same branch to 1e-8."""
    from supercoil.problems.ring import twisted_circle_problem
    from supercoil.problems.ring_branches import ring_records

    opts = ContinuationOptions(initial_step=0.005, max_step=1.0, max_points=20, growth=2.0,
                               max_turn_degrees=10.0, parameter_bounds=(0.0, 3.0),
                               gauge="integral", near_symmetry_gauge=True, regauge=True,
                               rephase=True, factor_refinement=True)

    def run(on_point=None):
        problem, circle, point = ring_alpha()
        return switch_branch(problem, circle, point, opts, amplitude=0.005, name="alpha",
                             records=ring_records(problem), on_point=on_point)

    with Rejections() as rejections:
        full, partials = uninterrupted(run, rejections)
    assert len(full) == 20 and full.phase_modes.shape[0] == 1
    assert full.gauge_moved.any()  # a gauge moved after a failed step
    assert {1, 2} <= set(rejections.after), rejections.after
    # the steps grew, then were cut where the branch nears its figure-eight (a step
    # through the rod itself refused)
    assert np.max(full.next_step) > 10 * full.next_step[0]
    # really stopped: after a failed step near the start and near the end
    assert_copies_are_interrupted_partials(partials, run, {1, max(rejections.after)})
    for partial in (p for p in partials if len(p) < len(full)):
        # a fresh problem, as after a restart (the circle's continuation leaves its
        # problem unchanged)
        problem, _ = twisted_circle_problem(0.6667, 0.0, 24, "angle")
        resumed = resume_branch(problem, partial, opts, records=ring_records(problem))
        assert_same_end(resumed, full, len(partial))
        np.testing.assert_allclose(resumed.records["writhe"], full.records["writhe"],
                                   rtol=0, atol=TOL)


def test_a_branch_stored_without_the_step_state_still_resumes():
    """A branch from a file written before the step controller's state was kept (its
    arrays absent) reads it as unknown and resumes with an estimated step: away from
    failed steps the estimate is the step taken."""
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.02, max_step=0.1,
                               max_points=60)

    def run(on_point=None):
        return continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts,
                            events=[THRESHOLD], records=bratu_records, on_point=on_point)

    full = run()
    partial = interrupted_after(20, run)
    meta, groups, arrays = flatten(partial)
    del arrays["next_step"], arrays["gauge_moved"]
    old = unflatten(meta, groups, arrays)
    assert np.isnan(old.next_step).all() and old.next_step.shape == (20,)
    assert not old.gauge_moved.any()
    resumed = resume_branch(Bratu(32, 1.0), old, opts, events=[THRESHOLD],
                            records=bratu_records)
    np.testing.assert_allclose(resumed.states, full.states, rtol=0, atol=TOL)
    assert [(p.kind, p.index) for p in resumed.special_points] == \
        [(p.kind, p.index) for p in full.special_points]


def test_the_step_state_survives_the_result_files_codec_and_truncation():
    """Kept through flatten/unflatten whole and by additions; arrays of the wrong length
    (a branch cut without them) read as unknown, never as another point's state."""
    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.02, max_step=0.1,
                               max_points=12)
    full = continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts)
    again = unflatten(*flatten(full))
    np.testing.assert_array_equal(again.next_step, full.next_step)
    np.testing.assert_array_equal(again.gauge_moved, full.gauge_moved)
    grown = BranchBuilder(*flatten(head(full, 5)))
    grown.extend(*flatten(full, 5, len(head(full, 5).special_points), origin=False))
    np.testing.assert_array_equal(grown.build().next_step, full.next_step)
    cut = dataclasses.replace(full, parameter_values=full.parameter_values[:5],
                              states=full.states[:5])
    assert cut.next_step.shape == (5,) and np.isnan(cut.next_step).all()
