"""The knotted ring's diagram in dLk: ``supercoil diagram knot`` and ``sc.knot_diagram``.

Oracles:

- Lk = Tw + Wr at every point of both halves: the twist from the material
  frames, the writhe from the double sum (recomputed here from the stored
  state with ``sc.writhe``), their sum the continuation parameter;
- the knot type (name and chirality, :func:`~supercoil.topology.knots.identify`
  on each stored state) is the start's at every point;
- the lowest-energy marks against a brute-force comparison over all points of
  both halves at the same dLk, and against straight lines whose crossing is known;
- the cross-sections touching two others on contacts placed by hand (exact);
- deflation: the gradient of log M against central differences; a rigidly moved,
  relabelled copy of a ring aligned back onto it to round-off;
- the command's ``diagram.json`` equals the verb's summary, and its
  ``result.h5`` holds the verb's branches;
- bad input exits with status 2 and writes nothing.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import supercoil as sc
from supercoil.cli.main import run as cli
from supercoil.problems.knot_diagram_points import lowest_energy, sections_touching_two
from supercoil.topology.knots import identify

CASE = {"knot": "3_1", "twist_ratio": 1.4, "length_over_diameter": 40.0,
        "excess_link": (3.0, 4.3), "nodes": 48, "max_points": 30, "deflation": 1}
ARGS = ["diagram", "knot", "--knot", "3_1", "--twist-ratio", "1.4",
        "--length-over-diameter", "40", "--excess-link", "3:4.3", "--nodes", "48",
        "--max-points", "30", "--deflation", "1", "-q"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("knot_diagram")
    status = cli([*ARGS, "--out", str(root / "cli")])
    result = sc.knot_diagram(**CASE, out=root / "api")
    return root, status, result


def _numbers(summary: dict) -> dict:
    from supercoil.io.results import to_jsonable

    data = json.loads(json.dumps(to_jsonable(summary)))
    data.pop("provenance")
    for branch in data["branches"]:
        branch.pop("seconds")
    return data


def test_link_and_knot_type_on_every_point(runs):
    _root, _status, result = runs
    assert [b.name for b in result.branches][:2] == ["knot_up", "knot_down"]
    start = result.branches[0].states[0]
    reference = identify(start.reshape(-1, 3))
    assert reference.name == "3_1" and reference.chirality == 1
    for branch in result.branches:
        assert len(branch) >= 3
        records = branch.records
        lk = np.asarray(branch.parameter_values)
        np.testing.assert_allclose(records["twist"] + records["writhe"], lk, atol=1e-9)
        for q, wr in zip(branch.states, records["writhe"]):
            points = q.reshape(-1, 3)
            assert float(sc.writhe(points)) == pytest.approx(wr, abs=1e-9)
            assert identify(points) == reference
    points = result.summary["points"]
    assert {p["knot_type"] for p in points} == {"3_1"}
    assert {p["chirality"] for p in points} == {1}
    # both ways from the middle of the range, to its ends
    up, down = result.branches[:2]
    assert up.parameter_values[0] == down.parameter_values[0] == pytest.approx(3.65)
    assert max(up.parameter_values) == pytest.approx(4.3)
    assert min(down.parameter_values) == pytest.approx(3.0)


def test_lowest_energy_marks_by_brute_force(runs):
    _root, _status, result = runs
    points = result.summary["points"]
    # the start is one state on both halves; where both halves reach the same dLk
    # only through the start, each point is the only state there and is the lowest
    for p in points:
        others = [q["energy"] for q in points
                  if abs(q["excess_link"] - p["excess_link"]) < 1e-12
                  and abs(q["energy"] - p["energy"]) > 1e-9 * abs(p["energy"])]
        if p["lowest_energy"]:
            assert all(p["energy"] <= e + 1e-9 * abs(e) for e in others)
    for row in result.summary["by_excess_link"]:
        assert row["n_states"] >= 1 and 0 <= row["n_stable"] <= row["n_states"]


@pytest.mark.parametrize("knot", ["4_1", "5_1", "5_2"])
def test_diagrams_of_other_knots_keep_their_type_and_link(knot):
    """The diagram of the figure-eight knot, the (2, 5) torus knot and 5_2: the table's
    polynomials at every point (a state of 5_1 may have only views of ten or more
    crossings, where 10_132 has the same polynomials: the guarded branch keeps the
    built knot's name), Lk = Tw + Wr, the writhe against the double sum, and a repr of
    a few lines."""
    result = sc.knot_diagram(knot, 1.4, 100.0, (0.0, 1.5), nodes=80, max_points=4,
                             deflation=0)
    table = identify(sc.knot_curve(knot, 200))
    assert table.name == knot
    assert result.summary["knot_type"] == knot
    assert result.summary["chirality"] == table.chirality
    assert {p["knot_type"] for p in result.summary["points"]} == {knot}
    for branch in result.branches:
        assert len(branch) == 4
        np.testing.assert_allclose(branch.records["twist"] + branch.records["writhe"],
                                   branch.parameter_values, atol=1e-9)
        for q, wr in zip(branch.states, branch.records["writhe"]):
            points = q.reshape(-1, 3)
            assert identify(points).same_invariants(table)
            assert float(sc.writhe(points)) == pytest.approx(wr, abs=1e-9)
    text = repr(result)
    assert text.startswith(f"KnotDiagramResult({knot}") and len(text.splitlines()) <= 4


def test_lowest_energy_of_crossing_lines():
    lam = np.linspace(0.0, 2.0, 5)
    flags = lowest_energy([(lam, lam, np.ones(5, bool)), (lam, 2.0 - lam, np.ones(5, bool))])
    # E = dLk against E = 2 - dLk: the first is lower below 1, the second above, equal at 1
    np.testing.assert_array_equal(flags[0], lam <= 1.0)
    np.testing.assert_array_equal(flags[1], lam >= 1.0)


def test_sections_touching_two_placed_by_hand():
    n = 100
    intervals = [{"s1_start": 0.10, "s1_end": 0.30, "s2_start": 0.60, "s2_end": 0.80}]
    # a point contact of s = 0.2 (inside the interval's first strand) with s = 0.9
    count, arcs = sections_touching_two(n, [{"s1": 0.2, "s2": 0.9}], intervals)
    assert count == 1 and arcs == [[0.2, 0.2]]
    # a second interval over 0.25..0.40 against 0.95..0.05 (across the seam)
    more = intervals + [{"s1_start": 0.25, "s1_end": 0.40, "s2_start": 0.95, "s2_end": 0.05}]
    count, arcs = sections_touching_two(n, [], more)
    assert count == 6 and arcs == [[0.25, 0.30]]
    assert sections_touching_two(n, [], intervals) == (0, [])


def test_deflation_operator_gradient_and_alignment(rng):
    from supercoil.problems.knot_deflation import aligned, deflation_factor

    q = rng.normal(size=12)
    known = [rng.normal(size=12), rng.normal(size=12)]
    _m, g = deflation_factor(q, known)
    h = 1e-6
    fd = np.array([(np.log(deflation_factor(q + h * e, known)[0])
                    - np.log(deflation_factor(q - h * e, known)[0])) / (2 * h)
                   for e in np.eye(12)])
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-8)
    ring = sc.knot_curve("3_1", 30)
    c, s_ = np.cos(0.7), np.sin(0.7)
    rotation = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
    moved = np.roll(ring, 7, axis=0) @ rotation.T + np.array([0.3, -1.0, 2.0])
    np.testing.assert_allclose(aligned(moved.ravel(), ring.ravel()), ring.ravel(), atol=1e-12)


def test_command_equals_the_verb(runs):
    root, status, result = runs
    assert status == 0
    by_cli = json.loads((root / "cli" / "diagram.json").read_text())
    assert _numbers(by_cli) == _numbers(result.summary)
    for name in ("link_writhe.png", "energy.png", "configurations.png"):
        assert (root / "cli" / name).stat().st_size > 0
    stored = sc.load(root / "cli")
    for branch in result.branches:
        np.testing.assert_allclose(stored.branches[branch.name].states, branch.states,
                                   atol=1e-12)


@pytest.mark.parametrize("bad", [
    ["--knot", "9_1"],
    ["--excess-link", "5:2"],
    ["--excess-link", "two"],
    ["--nodes", "3"],
    ["--twist-ratio", "0"],
    ["--max-points", "1"],
    ["--start", "9"],
])
def test_bad_input_exits_2_before_writing(tmp_path, bad, capsys):
    args = dict(zip(ARGS[2::2], ARGS[3::2]))
    for option, value in zip(bad[::2], bad[1::2]):
        args[option] = value
    out = tmp_path / "out"
    flat = ["diagram", "knot", *[w for kv in args.items() for w in kv if w != "-q"], "-q",
            "--out", str(out)]
    assert cli(flat) == 2
    assert "error:" in capsys.readouterr().err
    assert not out.exists()
