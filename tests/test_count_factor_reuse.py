"""The count's factor made by the check of a count change without a fold
(:meth:`~supercoil.continuation.tracer.Tracer._count_jumped`) serves the accepted
point's stability (:func:`~supercoil.continuation.stability.point_stability`'s
``factor``). Oracle: the same run with that factor thrown away, each point's count
factorised again, gives the same branches bit for bit (every per-point array and
special point, through the tweezers' buckling, contact and its bifurcations), with
fewer factorisations of the count's matrix."""

from __future__ import annotations

import importlib

import numpy as np

from supercoil.continuation.branch import POINT_ARRAYS
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

stability = importlib.import_module("supercoil.continuation.stability")
tracer = importlib.import_module("supercoil.continuation.tracer")

OPTIONS = TweezersOptions(4 / 3, 33.0, tension=75.0, turns=(0, 5), n_nodes=40,
                          max_points=100)


def _run(monkeypatch, reuse: bool):
    made = []

    class Counted(stability.KKTFactor):
        def __init__(self, *args, **kwargs):
            made.append(kwargs.get("shift", 0.0))
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(stability, "KKTFactor", Counted)
    if not reuse:
        original = tracer.Tracer.add_point

        def add_point(self, *args, counted=None, **kwargs):
            return original(self, *args, **kwargs)

        monkeypatch.setattr(tracer.Tracer, "add_point", add_point)
    result = tweezers_branches(OPTIONS)
    monkeypatch.undo()
    return result, made


def test_the_reused_count_factor_gives_the_same_branches_with_fewer_factorisations(
        monkeypatch):
    reused, made_reused = _run(monkeypatch, reuse=True)
    again, made_again = _run(monkeypatch, reuse=False)
    assert [b.name for b in reused.branches] == [b.name for b in again.branches]
    points = 0
    for built, expected in zip(reused.branches, again.branches, strict=True):
        points += len(built)
        for name in POINT_ARRAYS:
            assert np.array_equal(getattr(built, name), getattr(expected, name),
                                  equal_nan=True), (built.name, name)
        assert [(p.kind, p.index, p.parameter) for p in built.special_points] == [
            (p.kind, p.index, p.parameter) for p in expected.special_points]
        assert (built.status, built.message) == (expected.status, expected.message)
    assert any(b.name in reused.contact_branches and len(b) > 20 for b in reused.branches)
    assert any(p.kind == "bifurcation" for b in reused.branches for p in b.special_points)
    # about one factorisation fewer per point where the check ran (most points)
    assert len(made_again) - len(made_reused) > points // 2
