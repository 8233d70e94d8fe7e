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
