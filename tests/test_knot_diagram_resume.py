"""The knotted ring's diagram saved point by point, and resumed.

Oracle: the uninterrupted run. A run stopped in ``on_point`` (as Ctrl-C or a signal
stops it after a point was written) keeps in ``result.h5`` every point it reported,
and that result continued with ``resume`` ends with the uninterrupted run's branches:
the same points and special points to 1e-8. The runs of a branch are made short
(three points) so that the cases stop within a run, right after a run boundary
(where the rigid pins may be re-picked) and within the second half; the command's
``--resume`` refuses other options before computing and continues an interrupted
folder to the same ``diagram.json``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from knot_toys import SHORT_RUN, short_knot_diagram

import supercoil as sc
from supercoil.cli.main import run as cli
from supercoil.problems import knot_branch

CASE = {"knot": "3_1", "twist_ratio": 1.4, "length_over_diameter": 40.0,
        "excess_link": (3.0, 3.6), "nodes": 40, "max_points": 8, "deflation": 0}
ARGS = ["diagram", "knot", "--knot", "3_1", "--twist-ratio", "1.4",
        "--length-over-diameter", "40", "--excess-link", "3:3.6", "--nodes", "40",
        "--max-points", "8", "--deflation", "0", "-q"]
TOL = 1e-8


@pytest.fixture(autouse=True)
def short_runs(monkeypatch):
    monkeypatch.setattr(knot_branch, "SEGMENT_POINTS", SHORT_RUN)


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    return short_knot_diagram(CASE, tmp_path_factory.mktemp("full"))


def interrupted(folder, calls: int):
    """Run into ``folder`` and stop it in the ``calls``-th ``on_point``; the stored result."""
    seen = []

    def stop(branch):
        seen.append(len(branch))
        if len(seen) == calls:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sc.knot_diagram(**CASE, out=folder, on_point=stop)
    return sc.load(folder)


def assert_same_branches(resumed, full):
    assert [b.name for b in resumed] == [b.name for b in full]
    for a, b in zip(resumed, full):
        assert len(a) == len(b) and a.status is b.status, (a.name, a.message)
        np.testing.assert_allclose(a.states, b.states, rtol=0, atol=TOL, err_msg=a.name)
        np.testing.assert_allclose(a.parameter_values, b.parameter_values, rtol=0, atol=TOL)
        np.testing.assert_array_equal(a.unstable_count, b.unstable_count)
        np.testing.assert_array_equal(a.records["run_start"], b.records["run_start"])
        assert [(p.kind, p.index) for p in a.special_points] == \
            [(p.kind, p.index) for p in b.special_points], a.name


def test_the_run_has_several_runs_per_branch(full):
    assert [b.name for b in full.branches] == ["knot_up", "knot_down"]
    for branch in full.branches:
        assert branch.status.complete and len(branch) >= 4, branch.message
        assert len(set(branch.records["run_start"])) >= 2


@pytest.mark.parametrize("calls", [2, 5, 9])
def test_an_interrupted_diagram_resumed_ends_as_the_uninterrupted_one(full, tmp_path, calls):
    stored = interrupted(tmp_path, calls)
    assert stored.status == "interrupted"
    kept = {name: len(b) for name, b in stored.branches.items()}
    assert kept and sum(kept.values()) < sum(len(b) for b in full.branches)
    for name, branch in stored.branches.items():  # every point as it was computed
        whole = next(b for b in full.branches if b.name == name)
        np.testing.assert_allclose(branch.states, whole.states[:len(branch)], rtol=0,
                                   atol=TOL)
    resumed = sc.knot_diagram(**CASE, out=tmp_path, resume=True)
    assert_same_branches(resumed.branches, full.branches)
    assert sc.load(tmp_path).status == "complete"
    on_disk = json.loads((tmp_path / "diagram.json").read_text())
    assert [p["excess_link"] for p in on_disk["points"]] == pytest.approx(
        [p["excess_link"] for p in full.summary["points"]], abs=TOL)


def test_the_command_resumes_with_the_same_options_only(full, tmp_path):
    interrupted(tmp_path, 5)
    status = cli([*ARGS[:-1], "--max-points", "7", "-q", "--out", str(tmp_path), "--resume"])
    assert status == 2
    assert sc.load(tmp_path).status == "interrupted"  # nothing was computed or written
    assert cli([*ARGS, "--out", str(tmp_path), "--resume"]) == 0
    assert_same_branches(tuple(sc.load(tmp_path).branches.values()), full.branches)
    assert json.loads((tmp_path / "diagram.json").read_text())["ok"]
    assert cli([*ARGS, "--out", str(tmp_path), "--resume"]) == 0  # nothing to resume


def test_a_diagram_stopped_at_its_point_limit_resumed_with_a_higher_one(full, tmp_path):
    """``--resume`` may raise ``--max-points``: the halves that stopped at 4 points are
    continued to the uninterrupted run's with 8 (and the file records 8); a lower limit
    is refused before anything is computed."""
    short = [*ARGS[:ARGS.index("--max-points")], "--max-points", "4",
             *ARGS[ARGS.index("--max-points") + 2:]]
    assert cli([*short, "--out", str(tmp_path)]) == 1
    stopped = sc.load(tmp_path)
    assert [len(b) for b in stopped.branches.values()] == [4, 4]
    assert all(b.status is sc.ContinuationStatus.MAX_POINTS
               for b in stopped.branches.values())
    assert cli([*short[:-2], "--max-points", "3", "-q", "--out", str(tmp_path),
                "--resume"]) == 2
    assert cli([*ARGS, "--out", str(tmp_path), "--resume"]) == 0
    resumed = sc.load(tmp_path)
    assert resumed.settings["options"]["max_points"] == 8 and resumed.status == "complete"
    assert_same_branches(tuple(resumed.branches.values()), full.branches)

