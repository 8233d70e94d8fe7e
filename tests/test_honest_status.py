"""Honest statuses: a run is complete only when every branch ended where it was asked to.

A branch is complete when it reaches its bound, closes a loop, or is handed over as
designed (a contact-free branch cut at its first contact, continued by the contact
branch). Any other stop (the point limit, a failed step) makes the run incomplete in
every output: ``ok: false`` with each branch's reason in the JSON, exit status 1, and
the terminal's last line. No note states a conclusion that was not computed.

Oracles: the definition above, applied to the statuses of the continuation; the
clamped Greenhill threshold (the straight rod buckles at 1.40856 turns for C/A = 4/3,
F L^2/A = 20, so a run stopped at 0.4 turns has not shown that it does not buckle);
Michell's thresholds of the twisted circle (C/A = 1: stable below sqrt(3), two unstable
directions up to sqrt(8), four beyond).
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import pytest

from supercoil.cli.main import run
from supercoil.continuation import ContinuationStatus


def call(*args) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = run([str(a) for a in args])
    return status, out.getvalue(), err.getvalue()


def test_complete_statuses_are_those_that_ended_where_asked():
    complete = {s for s in ContinuationStatus if s.complete}
    assert complete == {ContinuationStatus.PARAMETER_BOUND, ContinuationStatus.MAX_ARCLENGTH,
                        ContinuationStatus.CLOSED_LOOP, ContinuationStatus.STOPPED}
    assert ContinuationStatus.MAX_POINTS.ok and not ContinuationStatus.MAX_POINTS.complete
    for failed in (ContinuationStatus.STEP_TOO_SMALL, ContinuationStatus.START_FAILED):
        assert not failed.complete


def test_tweezers_stopped_by_its_point_limit_is_incomplete_everywhere(tmp_path):
    """The straight rod stopped at --max-points 5 (0.4 turns), before its buckling at
    1.40856 turns: not 'does not buckle below 1.6 turns', but incomplete, exit 1."""
    out = tmp_path / "t"
    status, _, err = call("tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "20",
                          "--nodes", "40", "--tension", "20", "--turns", "0:1.6",
                          "--max-points", "5", "--out", out, "--quiet")
    assert status == 1, err
    data = json.loads((out / "branch.json").read_text())
    assert data["ok"] is False
    (straight,) = data["branches"]
    assert straight["ok"] is False and straight["status"] == "MAX_POINTS"
    assert "max_points" in straight["message"]
    assert not any("does not buckle" in note for note in data["notes"])
    assert any(note.startswith("incomplete: straight stopped at") for note in data["notes"])
    last = err.strip().splitlines()[-1]
    assert last.startswith("not complete:") and "straight" in last
    assert data["greenhill_turns"] == pytest.approx(1.40856, abs=1e-5)
    assert data["points"][-1]["turns"] < data["greenhill_turns"]


def test_ring_diagram_with_contact_branches_at_their_point_limit_is_incomplete(tmp_path):
    """The contact branches stop at --contact-max-points 3, far below dLk = 6: ok false
    for them (their status and message say why), true for the circle (at its bound) and
    the contact-free branches (handed over at their first contact); exit status 1."""
    out = tmp_path / "d"
    status, _, err = call("diagram", "ring", "--twist-ratio", "2/3", "--length-over-diameter",
                          "20", "--nodes", "24", "--modes", "2", "--contact-max-points", "3",
                          "--out", out, "--quiet")
    assert status == 1, err
    data = json.loads((out / "diagram.json").read_text())
    assert data["ok"] is False
    by_name = {b["name"]: b for b in data["branches"]}
    assert by_name["circle"]["status"] == "PARAMETER_BOUND" and by_name["circle"]["ok"]
    assert by_name["alpha"]["status"] == "STOPPED" and by_name["alpha"]["ok"]
    contact = by_name["alpha_contact"]
    assert contact["status"] == "MAX_POINTS" and contact["ok"] is False
    assert contact["n_points"] == 3 and "max_points" in contact["message"]
    last = err.strip().splitlines()[-1]
    assert last.startswith("incomplete:") and "alpha_contact" in last


@pytest.mark.parametrize(("excess_link", "unstable"), [(1.0, 0), (2.0, 2), (3.0, 4)])
def test_a_ring_that_is_not_stable_says_so_in_its_status(excess_link, unstable):
    """Without contact the answer is the twisted circle (its contract), with Michell's
    unstable count; the status names an unstable equilibrium, not just 'converged'."""
    from supercoil.problems.ring import solve_ring

    assert math.sqrt(3) < 2.0 < math.sqrt(8) < 3.0  # C/A = 1: Michell's thresholds
    result = solve_ring(1.0, excess_link, n_nodes=32)
    assert result.converged and result.unstable_count == unstable
    if unstable:
        assert result.status == (f"converged; unstable equilibrium ({unstable} unstable "
                                 "directions)")
        assert result.summary()["stable"] is False
    else:
        assert result.status == "converged"
    status, out, err = call("ring", "--twist-ratio", "1", "--excess-link", excess_link,
                            "--nodes", "32", "--json", "-")
    assert status == 0, err
    assert json.loads(out)["status"] == result.status
