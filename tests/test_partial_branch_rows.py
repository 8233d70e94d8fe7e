"""The tracer's branch (also every partial branch handed to ``on_point``) from rows
converted once per point, against the direct conversion of every point at every call:
every array of every partial branch equal bit for bit, through rephased tangents and
records of several types; a point is handed out once complete (its tangent rephased),
so every partial branch is a prefix of the final one."""

from __future__ import annotations

import numpy as np

from supercoil.continuation import tracer as tracing
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.switching import switch_branch
from supercoil.problems.ring_branches import circle_branch


def _reference(tracer) -> dict:
    """The arrays of the branch, every point converted at this call."""
    system = tracer.system
    n_dofs, m, k = system.problem.n_dofs, system.m, len(tracer.xs)
    records = {name: np.array([np.asarray(r[name]) for r in tracer.recs])
               for name in tracer.recs[0]} if k and tracer.recs[0] else {}
    return {
        "parameter_values": np.array([x[-1] for x in tracer.xs]),
        "states": np.array([system.q(x) for x in tracer.xs]).reshape(k, n_dofs),
        "multipliers": np.array([system.multipliers(x) for x in tracer.xs]).reshape(k, m),
        "nearest_eigenvalue": np.array([s.nearest_eigenvalue for s in tracer.stabs]),
        "tangents": np.array([system.full_tangent(t) for t in tracer.ts]).reshape(
            k, n_dofs + m + 1),
        "records": records}


def test_partial_branches_equal_the_per_point_conversion(monkeypatch):
    circle, problem = circle_branch(2 / 3, 24, 3.0)
    point = circle.points_of_kind("bifurcation")[0]
    checked = []
    original_branch = tracing.Tracer.branch

    def compared(tracer, status, message, partial=False):
        built = original_branch(tracer, status, message, partial=partial)
        expected = _reference(tracer)
        for name, value in expected.items():
            if name == "records":
                assert set(value) == set(built.records)
                for key, column in value.items():
                    assert column.dtype == built.records[key].dtype
                    assert np.array_equal(column, built.records[key]), key
            else:
                assert np.array_equal(value, getattr(built, name), equal_nan=True), name
        checked.append(len(tracer.xs))
        return built

    def records(q, multipliers, excess_link):
        return {"excess_link": excess_link, "big": bool(excess_link > 3.5),
                "count": round(10 * excess_link), "end": q[:3].copy()}

    monkeypatch.setattr(tracing.Tracer, "branch", compared)
    partial = []
    opts = ContinuationOptions(initial_step=0.01, max_step=0.05, max_points=8,
                               gauge="integral", rephase=True)
    branch = switch_branch(problem, circle, point, opts, records=records,
                           on_point=partial.append)
    assert len(branch) == 8 and checked[-1] == 8 and len(partial) >= 7
    # the rephased tangents: every partial branch's last tangent is the final one
    for p in partial:
        assert np.array_equal(p.tangents, branch.tangents[:len(p)])
        assert np.array_equal(p.next_step, branch.next_step[:len(p)])
    assert branch.status is ContinuationStatus.MAX_POINTS
