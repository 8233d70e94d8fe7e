"""Branch switching in the knotted ring's diagram (``diagram knot --branch-depth 2``).

The trefoil at C/A = 1.4, L/D = 40, N = 48 followed down from dLk = 1: the doubly
covered circle (D3) loses stability to a pair of modes at dLk 0.34 (the unstable count
0 -> 2, a double eigenvalue of the D3 symmetry), and the two half-branches switched
there are followed. Oracles:

- the switch leaves the bifurcation point along its critical modes: the first point's
  displacement from it (0.2 D), rigid motions removed, lies in the span of the two
  critical modes to 5 % of its length (measured 1.7 %: the branch's curvature over
  the first step; a direction independent of the modes would leave about
  sqrt(1 - 2/144) of it outside), the two sides opposite, and the D3 symmetry is
  broken to a two-fold axis (the combination of the critical modes that keeps one);
- Lk = Tw + Wr at every point (the writhe recomputed from the stored state by the
  double sum) and the knot type (name and chirality) the start's;
- the unstable count of a switched branch at its first point lies between the
  parent's counts on the two sides of the crossing;
- a switch that runs along a computed branch is told apart from one that leaves it
  (curves sampled by hand);
- an interrupted run resumed ends with the uninterrupted run's branches (the
  switched ones included) to 1e-8.
"""

from __future__ import annotations

import numpy as np
import pytest
from knot_toys import SHORT_RUN, short_knot_diagram

import supercoil as sc
from supercoil.cli.main import run as cli
from supercoil.geometry.symmetry import curve_symmetry
from supercoil.problems import knot_branch
from supercoil.topology.knots import identify

CASE = {"knot": "3_1", "twist_ratio": 1.4, "length_over_diameter": 40.0,
        "excess_link": (0.0, 1.2), "nodes": 48, "max_points": 25, "start": 1.0,
        "deflation": 0, "branch_depth": 2, "secondary_max_points": 4}
SWITCHED = ("knot_I+", "knot_I-")
TOL = 1e-8


@pytest.fixture(autouse=True)
def short_runs(monkeypatch):
    monkeypatch.setattr(knot_branch, "SEGMENT_POINTS", SHORT_RUN)


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    return short_knot_diagram(CASE, tmp_path_factory.mktemp("full"))


def _without_rigid_motions(u: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``u`` (flat) less its least-squares fit by the rigid motions at ``x`` ``(n, 3)``."""
    r = x - x.mean(axis=0)
    rigid = np.array([np.tile(e, len(x)) for e in np.eye(3)]
                     + [np.cross(e, r).ravel() for e in np.eye(3)])
    u = np.ravel(u)
    return u - np.linalg.lstsq(rigid.T, u, rcond=None)[0] @ rigid


def test_the_switch_leaves_along_the_critical_modes(full):
    by_name = {b.name: b for b in full.branches}
    assert set(SWITCHED) <= set(by_name)
    starts = []
    for name in SWITCHED:
        branch = by_name[name]
        point = branch.origin
        assert branch.parent == "knot_down" and point.kind == "bifurcation" and point.located
        assert point in by_name["knot_down"].special_points
        x = point.q.reshape(-1, 3)
        modes = np.array([_without_rigid_motions(m, x) for m in point.critical_modes])
        assert modes.shape[0] == 2  # a double eigenvalue of D3
        d = _without_rigid_motions(branch.states[0] - point.q, x)
        fit = np.linalg.lstsq(modes.T, d, rcond=None)[0] @ modes
        assert np.linalg.norm(d - fit) <= 0.05 * np.linalg.norm(d)
        starts.append(d)
        tolerance = 0.05 / CASE["length_over_diameter"]
        assert curve_symmetry(x, tolerance).group == "D3"
        assert curve_symmetry(branch.states[0].reshape(-1, 3), tolerance).group == "C2"
    assert starts[0] @ starts[1] < 0  # the two sides


def test_link_and_knot_type_on_every_switched_point(full):
    reference = identify(full.branches[0].states[0].reshape(-1, 3))
    assert (reference.name, reference.chirality) == ("3_1", 1)
    for branch in full.branches:
        if branch.name not in SWITCHED:
            continue
        assert len(branch) >= 3, branch.message
        np.testing.assert_allclose(branch.records["twist"] + branch.records["writhe"],
                                   branch.parameter_values, atol=1e-9)
        for q, wr in zip(branch.states, branch.records["writhe"]):
            assert float(sc.writhe(q.reshape(-1, 3))) == pytest.approx(wr, abs=1e-9)
            assert identify(q.reshape(-1, 3)) == reference


def test_the_count_of_a_switched_branch_is_one_side_of_the_crossing(full):
    by_name = {b.name: b for b in full.branches}
    parent = by_name["knot_down"]
    for name in SWITCHED:
        point = by_name[name].origin
        before, after = point.count_before, point.count_after
        i = point.index
        assert (parent.unstable_count[i], parent.unstable_count[i + 1]) == (before, after)
        assert before != after
        count = int(by_name[name].unstable_count[0])
        assert min(before, after) <= count <= max(before, after)
    records = {b["name"]: b for b in full.summary["branches"]}
    notes = " ".join(full.summary["notes"])
    for name in SWITCHED:
        assert f"{name}: every point is a state of" not in notes  # they leave knot_down
        assert records[name]["parent"] == "knot_down" and records[name]["generation"] == 2
        assert records[name]["origin"]["kind"] == "bifurcation"
    assert {p["knot_type"] for p in full.summary["points"]} == {"3_1"}


@pytest.mark.parametrize("name, at", [("knot_I+", 2), ("knot_I-", 3)])
def test_an_interrupted_switch_resumed_ends_as_the_uninterrupted_one(full, tmp_path, name,
                                                                      at):
    def stop(branch):
        if branch.name == name and len(branch) == at:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sc.knot_diagram(**CASE, out=tmp_path, on_point=stop)
    stored = sc.load(tmp_path)
    assert stored.status == "interrupted" and len(stored.branches[name]) == at
    resumed = sc.knot_diagram(**CASE, out=tmp_path, resume=True)
    assert [b.name for b in resumed.branches] == [b.name for b in full.branches]
    for a, b in zip(resumed.branches, full.branches):
        assert len(a) == len(b) and a.status is b.status, (a.name, a.message)
        np.testing.assert_allclose(a.states, b.states, rtol=0, atol=TOL, err_msg=a.name)
        np.testing.assert_array_equal(a.unstable_count, b.unstable_count)
        assert a.parent == b.parent
    assert sc.load(tmp_path).status in ("complete", "incomplete")


@pytest.mark.parametrize("bad", [["--branch-depth", "4"], ["--secondary-max-points", "1"],
                                 ["--secondary-max-branches", "-1"]])
def test_bad_switching_options_exit_2_before_writing(tmp_path, bad, capsys):
    out = tmp_path / "out"
    args = ["diagram", "knot", "--knot", "3_1", "--twist-ratio", "1.4",
            "--length-over-diameter", "40", "--excess-link", "0:1.2", "--nodes", "48",
            *bad, "-q", "--out", str(out)]
    assert cli(args) == 2
    assert bad[0] in capsys.readouterr().err
    assert not out.exists()


def test_a_switch_along_a_computed_branch_is_told_apart():
    from types import SimpleNamespace

    from supercoil.problems.knot_switching import retraced

    def branch(name, lam, writhe, energy):
        return SimpleNamespace(name=name, parameter_values=np.asarray(lam, float),
                               records={"writhe": np.asarray(writhe, float),
                                        "energy": np.asarray(energy, float)})

    lam = np.linspace(0.0, 1.0, 11)
    known = branch("knot_up", lam, 3.0 + 0.1 * lam, 100.0 + 10.0 * lam**2)
    # the same curve sampled in between (linear interpolation exact in the writhe, the
    # energy's error 10 h^2 / 8 of 110 at most, well within 2 %)
    mid = lam[:-1] + 0.05
    along = branch("knot_I+", mid, 3.0 + 0.1 * mid, 100.0 + 10.0 * mid**2)
    assert "knot_up" in retraced(along, [known])
    # its writhe off by 2e-3 turns at one point: a branch of its own
    off = branch("knot_I-", mid, 3.0 + 0.1 * mid + 2e-3 * (mid > 0.5), 100.0 + 10.0 * mid**2)
    assert retraced(off, [known]) is None
    # beyond the computed range by less than 1e-3 in dLk, next to its end point: along
    past = branch("knot_II+", [1.0005], [3.1], [110.0])
    assert retraced(past, [known]) is not None
    assert retraced(branch("knot_II-", [1.01], [3.1], [110.0]), [known]) is None
