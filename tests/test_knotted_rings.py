"""Knotted rings: built, tightened, relaxed with contact; the tight trefoil.

Oracles:

- the ideal (tight) trefoil: ropelength L/D = 16.37 and writhe 3.41 (Pieranski
  1998; Baranska, Pieranski & Rawdon 2005; Carlen, Laurie, Maddocks & Smutny
  2005: 16.372); the discrete tight limit falls towards it from above as about
  1/N^2 (16.73 at N = 40, 16.54 at 60, 16.47 at 80, 16.42 at 120), so the
  Richardson extrapolation of N = 40 and 60 is within 0.05 of it; a tube's
  radius of curvature stays at least D/2;
- Lk = Tw + Wr on a relaxed knotted ring, twist from the material frames and
  writhe from the double sum, computed independently;
- the knot type (both polynomials and the name) is the built knot's at the end
  of every run, every step of which the guard checked.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import supercoil as sc
from supercoil.cli.main import app
from supercoil.problems.knot_ring import knot_start, parse_knot, tight_knot
from supercoil.problems.knot_tighten import min_radius_of_curvature
from supercoil.problems.ring import richardson
from supercoil.topology.knots import identify

IDEAL_TREFOIL_ROPELENGTH = 16.372  # Baranska, Pieranski & Rawdon 2005; Carlen et al. 2005
IDEAL_TREFOIL_WRITHE = 3.41  # Katritch et al. 1996; Pieranski 1998


def test_tight_trefoil_ropelength_and_writhe_converge_to_the_ideal_knot():
    coarse, fine = tight_knot("3_1", 40), tight_knot("3_1", 60)
    for t in (coarse, fine):
        assert t.status == "tight"
        assert identify(t.points).name == "3_1"
        assert t.problem.knot_guard.reference.name == "3_1"
        assert 0 < t.min_gap_over_diameter < 1e-3
        assert min_radius_of_curvature(t.points) * t.length_over_diameter >= 0.5
    # from above, and closer with more nodes
    assert IDEAL_TREFOIL_ROPELENGTH < fine.length_over_diameter < coarse.length_over_diameter
    extrapolated = richardson(coarse.length_over_diameter, fine.length_over_diameter,
                              order=2.0, ratio=1.5)
    assert extrapolated == pytest.approx(IDEAL_TREFOIL_ROPELENGTH, abs=0.05)
    assert fine.writhe == pytest.approx(IDEAL_TREFOIL_WRITHE, abs=0.02)


def test_knotted_ring_keeps_its_type_and_link():
    tight, note = knot_start("3_1", 60, 25.0)  # the built trefoil overlaps below L/D 29
    assert "tightened" in note and identify(tight).name == "3_1"
    state = sc.equilibrium(sc.Ring(sc.Rod(1.0, 60), 3.0, contact=sc.Barrier(25.0),
                                   knot="3_1"))
    record = state.record
    assert state.converged
    assert record["knot_type"] == "3_1" and record["chirality"] == 1
    assert record["link_error"] < 1e-9  # Tw (frames) + Wr (double sum) = dLk
    assert record["twist"] + record["writhe"] == pytest.approx(3.0, abs=1e-9)
    assert record["min_gap_over_diameter"] > 1.0  # min distance over D: no overlap


def test_the_mirror_trefoil_at_the_opposite_excess_link_is_the_mirror_image():
    """An isotropic rod's energy is unchanged by a reflection, which reverses dLk, Tw, Wr
    and the knot's chirality: the left-handed trefoil at dLk = -3 is the mirror image of
    the right-handed one at +3 (the same energy and contacts, the opposite writhe), and
    its record's chirality is that of its own points (-1)."""
    states = [sc.equilibrium(sc.Ring(sc.Rod(1.4, 48), dlk, contact=sc.Barrier(40.0),
                                     knot=knot)) for knot, dlk in (("3_1", 3.0),
                                                                   ("3_1*", -3.0))]
    right, left = (s.record for s in states)
    assert right["chirality"] == 1 and left["chirality"] == -1
    assert identify(np.asarray(states[1].points)).chirality == -1
    assert left["energy"] == pytest.approx(right["energy"], rel=1e-9)
    assert left["writhe"] == pytest.approx(-right["writhe"], abs=1e-9)
    assert left["n_contact_intervals"] == right["n_contact_intervals"]


def test_built_knot_is_tightened_only_when_it_overlaps():
    free, note = knot_start("3_1", 60, 40.0)
    assert "free of overlap" in note and identify(free).name == "3_1"
    mirrored, _ = knot_start("5_2*", 60, 200.0)
    assert identify(mirrored).name == "5_2" and identify(mirrored).chirality == -1


def test_knot_names():
    assert parse_knot("T(2,5)") == ("T(2,5)", (2, 5))
    assert parse_knot((3, 2)) == ("T(3,2)", (3, 2))
    assert parse_knot("4_1*") == ("4_1*", None)
    with pytest.raises(sc.InputError, match="knot"):
        parse_knot("9_1")
    with pytest.raises(sc.InputError, match="contact"):
        sc.Ring(sc.Rod(1.0, 60), 0.0, knot="3_1")


def test_ring_cli_torus_knot_json_and_export(runner, tmp_path):
    out = tmp_path / "ring"
    result = runner.invoke(app, ["ring", "--twist-ratio", "1", "--excess-link", "3",
                                 "--nodes", "60", "--length-over-diameter", "25",
                                 "--torus-knot", "2,3", "--json", "-", "--out", str(out)],
                           catch_exceptions=False)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["knot_type"] == "3_1" and data["chirality"] == 1
    assert data["initial_curve"] == "knot T(2,3)"
    assert data["link_error"] < 1e-9
    # the coordinates are in the result file: exported, they are the same trefoil
    xyz = tmp_path / "ring.xyz"
    exported = runner.invoke(app, ["export", str(out), "--out", str(xyz)],
                             catch_exceptions=False)
    assert exported.exit_code == 0, exported.output
    points = np.loadtxt(xyz, skiprows=2, usecols=(1, 2, 3))
    assert points.shape == (60, 3)
    assert identify(points).name == "3_1"
    assert float(sc.writhe(points)) == pytest.approx(data["writhe"], abs=1e-6)


@pytest.mark.parametrize("args", [
    ["--knot", "9_1", "--length-over-diameter", "40"],
    ["--knot", "3_1"],
    ["--knot", "3_1", "--torus-knot", "2,3", "--length-over-diameter", "40"],
    ["--torus-knot", "2,4", "--length-over-diameter", "40"],
])
def test_ring_cli_refuses_bad_knots(runner, args):
    result = runner.invoke(app, ["ring", "--twist-ratio", "1", "--excess-link", "0", *args])
    assert result.exit_code == 2
    assert "error:" in result.output and "knot" in result.output


def test_tighten_cli_refuses_bad_input(runner):
    assert runner.invoke(app, ["tighten"]).exit_code == 2
    assert runner.invoke(app, ["tighten", "--knot", "3_1", "--nodes", "3"]).exit_code == 2
    assert runner.invoke(app, ["tighten", "--knot", "11_1"]).exit_code == 2


def test_tighten_json_has_the_coordinates(runner, tmp_path):
    target = tmp_path / "tight.json"
    result = runner.invoke(app, ["tighten", "--knot", "3_1", "--nodes", "24", "--json",
                                 str(target)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    data = json.loads(target.read_text())
    points = np.array(data["points"])
    assert points.shape == (24, 3)
    assert identify(points).name == data["knot_type"] == "3_1"
    assert IDEAL_TREFOIL_ROPELENGTH < data["length_over_diameter"] < 18.0
    assert data["writhe"] == pytest.approx(float(sc.writhe(points)), abs=1e-12)


def test_knotted_branch_in_excess_link_keeps_link_and_knot_type():
    from supercoil.problems.knot_branch import knotted_branch

    followed = knotted_branch("3_1", 1.4, 40.0, (3.0, 4.5), n_nodes=60, max_points=25)
    branch = followed.branch
    assert branch.status.name == "PARAMETER_BOUND"
    assert branch.parameter_values[-1] == pytest.approx(4.5)
    records = branch.records
    assert len(branch) >= 5
    # Lk = Tw + Wr at every point: twist from the material frames, writhe from the double sum
    assert np.max(records["link_error"]) < 1e-9
    # the knot type of every state, computed anew, is the start's
    assert followed.knot.name == "3_1"
    assert set(records["knot_determinant"].tolist()) == {3}
    assert set(records["knot_alexander_degree"].tolist()) == {2}
    for q in branch.states[:: max(1, len(branch) // 4)]:
        assert identify(q.reshape(-1, 3)) == followed.knot
    assert np.all(records["min_gap_over_diameter"] > 0)
