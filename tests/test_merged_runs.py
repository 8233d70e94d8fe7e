"""The branch reported at every point of a continuation in runs
(:func:`supercoil.problems.segments.follow`), built by extending columns
(:class:`~supercoil.problems.segments.MergedRuns`), against the oracle: the runs so far
and the run in progress merged from scratch by ``merge_branches`` at that point. Every
array, record and special point equal bit for bit, through many short runs of the
tweezers' buckled and contact branches; and the runs' points are not copied again at
every point (successive reports share their memory, but where a column doubles)."""

from __future__ import annotations

import numpy as np

from supercoil.problems import segments
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

ARRAYS = ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
          "determinant_sign", "nearest_eigenvalue", "tangents", "arclength", "next_step",
          "gauge_moved")


def _same(built, expected) -> None:
    for name in ARRAYS:
        assert np.array_equal(getattr(built, name), getattr(expected, name),
                              equal_nan=True), name
        assert getattr(built, name).dtype == getattr(expected, name).dtype, name
    assert built.records.keys() == expected.records.keys()
    for key, column in expected.records.items():
        assert np.array_equal(built.records[key], column, equal_nan=True), key
    assert [(p.kind, p.index, p.parameter, p.arclength, p.branch)
            for p in built.special_points] == [
        (p.kind, p.index, p.parameter, p.arclength, p.branch)
        for p in expected.special_points]
    assert (built.status, built.message, built.name) == (
        expected.status, expected.message, expected.name)
    assert np.array_equal(built.phase_modes, expected.phase_modes)
    assert np.array_equal(built.phase_state, expected.phase_state)
    assert len(built.frames) == len(expected.frames)


def test_every_reported_branch_equals_the_runs_merged_from_scratch(monkeypatch):
    checked, shared = [], []
    original_call, original_commit = segments.MergedRuns.__call__, segments.MergedRuns.commit

    def call(merger, partial):
        runs = merger.__dict__.setdefault("runs", [merger.first])
        built = original_call(merger, partial)
        _same(built, segments.merge_branches([*runs, partial], merger.name))
        last = merger.__dict__.get("last")
        if last is not None and len(last) > 1 and len(built) > len(last):
            shared.append(np.shares_memory(last.states, built.states))
        merger.last = built
        checked.append(len(built))
        return built

    def commit(merger, run):
        original_commit(merger, run)  # checks the run's final branch once more
        merger.__dict__.setdefault("runs", [merger.first]).append(run)
        merger.last = None

    monkeypatch.setattr(segments.MergedRuns, "__call__", call)
    monkeypatch.setattr(segments.MergedRuns, "commit", commit)
    reported = []
    options = TweezersOptions(4 / 3, 33.0, tension=75.0, turns=(0, 5), n_nodes=40,
                              segment_points=7, max_points=120)
    result = tweezers_branches(options, on_point=reported.append)
    assert len(checked) > 100
    # runs of 7 points: the contact branch is merged from many of them
    contact = next(b for b in result.branches if b.name in result.contact_branches)
    assert len(contact) > 3 * options.segment_points
    # a report copies the points only when a column doubles its capacity (a few times
    # per branch), not at every point
    assert len(shared) > 50 and shared.count(False) <= len(shared) // 10


def test_a_branch_followed_in_runs_numbers_the_points_of_its_messages_on_the_whole_branch():
    """Oracle: the branch's own length. Runs of 7 points make the contact branch; the
    message of its last run (which reached the bound) counts the points of the whole
    branch, not those of that run."""
    import re

    options = TweezersOptions(4 / 3, 33.0, tension=75.0, turns=(0, 5), n_nodes=40,
                              segment_points=7, max_points=400)
    result = tweezers_branches(options)
    contact = next(b for b in result.branches if b.name in result.contact_branches)
    assert len(contact) > 3 * options.segment_points
    found = re.fullmatch(r"reached turns = 5 after (\d+) points", contact.message)
    assert found, contact.message
    assert int(found[1]) == len(contact)
