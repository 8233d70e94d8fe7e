"""The Cosserat rod in tweezers under displacement control: the straight rod's exact
reaction, and the load- and displacement-controlled branches through the same states."""

import json

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

import supercoil as sc
from supercoil.cli.main import app
from supercoil.cosserat.clamped import ClampedCosseratEnergy, planar_buckle
from supercoil.cosserat.rod import CosseratRod


@pytest.mark.parametrize("end_distance, turns", [(0.97, 0.0), (1.05, 0.6)])
def test_straight_rod_at_an_end_distance_has_tension_ea_times_the_strain(end_distance, turns):
    # uniform strains Gamma = (0, 0, z/L - 1) balance every node: the end's reaction is
    # EA (z/L - 1) exactly, twisted or not
    rod = CosseratRod(10, length=2.0, bending_stiffness=1.5, twist_stiffness=0.8,
                      shear_stiffness=40.0, stretch_stiffness=25.0)
    strain = end_distance - 1.0
    x, R = ClampedCosseratEnergy.straight(rod, turns, rod.stretch_stiffness * strain)
    problem = ClampedCosseratEnergy(rod, turns, end_distance_control=True, positions=x,
                                    rotations=R)
    q = problem.initial_state()
    free = np.setdiff1d(np.arange(problem.n_dofs), problem.fixed)
    assert np.max(np.abs(problem.gradient(q)[free])) < 1e-12
    assert problem.end_force(q) == pytest.approx(rod.stretch_stiffness * strain, rel=1e-12)
    assert problem.extension(q) == pytest.approx(end_distance, rel=1e-14)


def test_planar_buckle_meets_the_clamps_at_the_end_distance():
    rod = CosseratRod(15, length=2.0)
    x, R = planar_buckle(rod, 0.7, turns=0.3)
    assert x[-1, 2] == pytest.approx(0.7 * rod.length, rel=1e-12)
    assert np.allclose(x[-1, :2], 0.0) and np.allclose(x[:, 1], 0.0)
    # unstretched, unsheared: the sections' d3 along the elements at first order
    shear, _ = rod.strains(x, R)
    assert np.max(np.abs(shear)) < 0.05
    ClampedCosseratEnergy(rod, 0.3, end_distance_control=True, positions=x, rotations=R)


def test_load_and_displacement_control_meet_at_the_same_states():
    # a point of the buckled branch at F L^2/A = 5 has some end distance z; the branch
    # held at that z passes through the same state at the same turns: tension 5 and the
    # same torque, writhe and energy (cubic interpolation between its points)
    rod = sc.CosseratRod(0.8, 500.0, nodes=16)
    load = sc.tweezers(sc.Tweezers(rod, tension=5.0), (0.0, 2.5), max_points=45)
    buckled = load.branches["buckled"]
    k = 40
    turns, z = buckled.parameter_values[k], float(buckled.records["extension"][k])
    held = sc.tweezers(sc.Tweezers(rod, end_distance=z), (0.0, 1.6), max_points=120)
    assert held.status is sc.RunStatus.COMPLETE, held.message
    clamped = held.branches["clamped"]
    records = clamped.records
    assert np.max(np.abs(records["extension"] - z)) < 1e-12
    assert np.all(records["load_potential"] == 0.0)
    j = int(np.searchsorted(clamped.parameter_values, turns))
    near = slice(j - 2, j + 2)

    def at(key):
        return float(CubicSpline(clamped.parameter_values[near], records[key][near])(turns))

    assert at("tension") == pytest.approx(5.0, rel=2e-4)
    for key in ("torque", "energy"):
        assert at(key) == pytest.approx(buckled.records[key][k], rel=1e-6)
    assert at("writhe") == pytest.approx(buckled.records["writhe"][k], abs=1e-5)


def test_end_distance_on_the_command_line(runner, tmp_path):
    # at z/L = 0.95 the compressed straight rod is stable (EA L^2/A = 500: its compression
    # 25 is below the clamped Euler load); the reaction is EA (z/L - 1) at every turn
    out = tmp_path / "tw"
    result = runner.invoke(app, ["tweezers", "--twist-ratio", "0.8", "--end-distance", "0.95",
                                 "--turns", "0:1", "--nodes", "12", "--model", "cosserat",
                                 "--stretch-stiffness", "500", "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = json.loads((out / "branch.json").read_text())
    assert data["model"] == "cosserat"
    points = [p for p in data["points"] if p["branch"] == "clamped"]
    assert points[-1]["turns"] == pytest.approx(1.0)
    for point in points:
        assert point["tension"] == pytest.approx(500.0 * (0.95 - 1.0), rel=1e-9)
        assert point["extension"] == pytest.approx(0.95, rel=1e-12)


def test_quasistatic_path_jumps_where_the_straight_rod_buckles():
    # the experiment's path minimises at every step: the straight rod (extension
    # 1 + F L / EA exactly) until the first step at or past the buckling that the
    # continuation locates, where it jumps to the plectoneme; on the way down it keeps
    # the plectoneme below that (hysteresis) and jumps back to the straight rod
    rod = sc.CosseratRod(0.8, 1e4, 1e4, nodes=24)
    step = 0.1
    problem = sc.Tweezers(rod, tension=5.0, contact=sc.Barrier(20.0))
    path = sc.tweezers_path(problem, (0.0, 2.2), protocol="up-down", step=step)
    assert path.ok, path.message
    free = sc.tweezers(sc.Tweezers(rod, tension=5.0), (0.0, 2.2), max_points=20)
    (buckling,) = free.branches["straight"].points_of_kind("bifurcation")
    up, back = path.jumps[0], path.jumps[-1]
    assert up["direction"] == 1 and up["count_left"] > 0
    assert buckling.parameter <= up["turns"] < buckling.parameter + step
    assert back["direction"] == -1 and back["turns"] < buckling.parameter - step
    # reached by minimisation from the plectoneme (residual 1e-9, soft bending modes)
    assert back["extension_after"] == pytest.approx(1 + 5.0 / 1e4, rel=1e-6)
    for point in path.points:
        assert point["unstable_count"] == 0
        assert point["closure_error"] < 1e-8  # Fuller's closure, turns = Tw + Wr
        assert point["min_gap_over_diameter"] > 1.0
        if point["turns"] < buckling.parameter and point["direction"] == 1:
            assert point["extension"] == pytest.approx(1 + 5.0 / 1e4, rel=1e-9)
    assert path.states.shape == (len(path.points), 3 * 24)  # the centrelines


def test_protocol_on_the_command_line_matches_the_api(runner, tmp_path):
    out = tmp_path / "tw"
    result = runner.invoke(app, ["tweezers", "--twist-ratio", "0.8", "--tension", "5",
                                 "--turns", "0:1", "--nodes", "12", "--model", "cosserat",
                                 "--stretch-stiffness", "500", "--protocol", "up-down",
                                 "--step", "0.25", "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = json.loads((out / "branch.json").read_text())
    path = sc.tweezers_path(sc.Tweezers(sc.CosseratRod(0.8, 500.0, nodes=12), tension=5.0),
                            (0.0, 1.0), protocol="up-down", step=0.25)
    assert [p["turns"] for p in data["path"]] == pytest.approx(
        [p["turns"] for p in path.points], abs=1e-15)
    for point in data["path"]:  # below the buckling: the straight rod, stretched
        assert point["extension"] == pytest.approx(1 + 5.0 / 500.0, rel=1e-9)
        assert point["stable"]


def test_force_ramp_stretches_the_straight_rod_by_f_l_over_ea():
    # at 1 turn the straight rod is stable for every force of the ramp (it buckles
    # above 1.7 turns unloaded): each step's extension is 1 + F L / EA
    rod = sc.CosseratRod(0.8, 500.0, nodes=12)
    path = sc.tweezers_path(sc.Tweezers(rod, tension=5.0), (0.0, 1.0), protocol="force-ramp",
                            step=0.5, force_range=(0.0, 20.0), force_step=5.0)
    assert path.ok, path.message
    ramp = [p for p in path.points if p["ramp"] == "tension"]
    assert sorted({p["tension"] for p in ramp}) == pytest.approx([0, 5, 10, 15, 20])
    for point in path.points:
        assert point["extension"] == pytest.approx(1 + point["tension"] / 500.0, rel=1e-9)
        assert point["stable"]


def test_study_file_with_an_end_distance(tmp_path):
    from supercoil.api.study_run import run_study
    from supercoil.io.study import parse_study

    study = parse_study('[rod]\ntwist_ratio = 0.8\nnodes = 12\nmodel = "cosserat"\n'
                        'stretch_stiffness = 500\n[problem]\nkind = "tweezers"\n'
                        'end_distance = 0.95\nturns = [0, 0.5]\n')
    outcome = run_study(study, tmp_path)
    assert outcome["status"] == "complete", outcome["message"]
    points = [p for p in sc.load(tmp_path / "result.h5").points() if p["branch"] == "clamped"]
    assert points and all(p["tension"] == pytest.approx(500.0 * (0.95 - 1.0), rel=1e-9)
                          for p in points)


def test_rod_stretched_beyond_its_length_carries_tension_ea_times_the_strain():
    # held at z/L = 1.02 the straight rod's strains are Gamma = (0, 0, 0.02) at every turn
    # (the linear law decouples stretch from twist): the reaction is EA (z/L - 1) exactly
    # along the straight branch, and the extension is z/L
    rod = sc.CosseratRod(0.8, 500.0, nodes=12)
    held = sc.tweezers(sc.Tweezers(rod, end_distance=1.02), (0.0, 0.5), max_points=40)
    straight = held.branches["straight"]
    assert len(straight) > 2 and straight.parameter_values[-1] == pytest.approx(0.5)
    records = straight.records
    assert np.allclose(records["tension"], 500.0 * 0.02, rtol=1e-9, atol=0.0)
    assert np.allclose(records["extension"], 1.02, rtol=1e-13, atol=0.0)
    assert np.allclose(records["max_stretch_strain"], 0.02, rtol=1e-9, atol=0.0)
    assert np.all(records["load_potential"] == 0.0)


@pytest.mark.parametrize("end_distance", [1.0, 1.3])
def test_an_inextensible_rod_is_not_stretched(end_distance):
    with pytest.raises(sc.InputError, match="inextensible"):
        sc.Tweezers(sc.Rod(0.8, nodes=12), end_distance=end_distance)
    sc.Tweezers(sc.CosseratRod(0.8, 500.0, nodes=12), end_distance=end_distance)
    with pytest.raises(sc.InputError, match="end_distance"):
        sc.Tweezers(sc.CosseratRod(0.8, 500.0, nodes=12), end_distance=2.5)


def test_stretched_end_distance_on_the_command_line(runner, tmp_path):
    args = ["tweezers", "--twist-ratio", "0.8", "--end-distance", "1.05", "--turns", "0:0.3",
            "--nodes", "12"]
    refused = runner.invoke(app, args + ["--out", str(tmp_path / "k")])
    assert refused.exit_code == 2 and "inextensible" in refused.output
    assert not (tmp_path / "k").exists()
    out = tmp_path / "c"
    result = runner.invoke(app, args + ["--model", "cosserat", "--stretch-stiffness", "400",
                                        "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = json.loads((out / "branch.json").read_text())
    tensions = [p["tension"] for p in data["points"] if p["branch"] == "straight"]
    assert tensions and np.allclose(tensions, 400.0 * 0.05, rtol=1e-9)
