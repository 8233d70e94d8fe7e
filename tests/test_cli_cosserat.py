"""``--model cosserat`` on ``ring``, ``diagram ring`` and ``tweezers``, and ``model`` in
study files: the command line against the API on small cases (the same numbers), and
bad combinations refused with exit 2 before any work or write."""

from __future__ import annotations

import json

import pytest

import supercoil as sc
from supercoil.cli.main import app
from supercoil.io.study import StudyError, parse_study


def test_ring_with_the_cosserat_model_matches_the_api(runner, tmp_path):
    path = tmp_path / "ring.json"
    result = runner.invoke(app, ["ring", "--twist-ratio", "0.8", "--excess-link", "2.6",
                                 "--nodes", "24", "--model", "cosserat",
                                 "--stretch-stiffness", "1e4", "--shear-stiffness", "2e4",
                                 "--json", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    data = json.loads(path.read_text())
    state = sc.equilibrium(sc.Ring(sc.CosseratRod(0.8, 1e4, 2e4, nodes=24), 2.6))
    assert data["model"] == "cosserat"
    assert data["stretch_stiffness"] == 1e4 and data["shear_stiffness"] == 2e4
    for key in ("energy", "twist", "writhe", "max_stretch_strain", "max_shear_strain"):
        assert data[key] == pytest.approx(state.record[key], rel=1e-12, abs=1e-14)
    assert data["unstable_count"] == state.unstable_count == 2


def test_kirchhoff_ring_json_states_its_model(runner, tmp_path):
    path = tmp_path / "ring.json"
    result = runner.invoke(app, ["ring", "--twist-ratio", "0.8", "--excess-link", "1",
                                 "--nodes", "16", "--json", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    data = json.loads(path.read_text())
    # the inextensible, unshearable rod: exactly no stretch and no shear
    assert (data["model"], data["max_stretch_strain"], data["max_shear_strain"]) == \
        ("kirchhoff", 0.0, 0.0)


@pytest.mark.parametrize("command, needle", [
    (["ring", "--twist-ratio", "0.8", "--excess-link", "1", "--stretch-stiffness", "10"],
     "--stretch-stiffness needs --model cosserat"),
    (["ring", "--twist-ratio", "0.8", "--excess-link", "1", "--model", "elastica"],
     "--model 'elastica'"),
    (["ring", "--twist-ratio", "0.8", "--excess-link", "1", "--model", "cosserat",
      "--length-over-diameter", "40", "--knot", "3_1"],
     "--knot is not available with --model cosserat"),
    (["diagram", "ring", "--twist-ratio", "0.8", "--length-over-diameter", "40",
      "--shear-stiffness", "5", "--out", "OUT"], "--shear-stiffness needs --model cosserat"),
])
def test_bad_combinations_exit_2_before_any_work(runner, tmp_path, command, needle):
    out = tmp_path / "out"
    command = [str(out) if word == "OUT" else word for word in command]
    result = runner.invoke(app, command)
    assert result.exit_code == 2, result.output
    assert needle in result.output
    assert not out.exists()


def test_tweezers_with_the_cosserat_model_matches_the_api(runner, tmp_path):
    out = tmp_path / "tw"
    result = runner.invoke(app, ["tweezers", "--twist-ratio", "0.8", "--tension", "5",
                                 "--turns", "0:2.2", "--nodes", "14", "--max-points", "14",
                                 "--model", "cosserat", "--stretch-stiffness", "500",
                                 "--out", str(out)])
    assert result.exit_code in (0, 1), result.output  # 1: the buckled branch's point limit
    data = json.loads((out / "branch.json").read_text())
    assert data["model"] == "cosserat"
    run = sc.tweezers(sc.Tweezers(sc.CosseratRod(0.8, 500.0, nodes=14), tension=5.0),
                      (0.0, 2.2), max_points=14)
    (onset,) = [p for p in data["special_points"] if p["kind"] == "bifurcation"]
    (api,) = run.branches["straight"].points_of_kind("bifurcation")
    assert onset["turns"] == pytest.approx(api.parameter, rel=1e-10)
    # the extension includes the stretch: 1 + F L / EA on the straight rod
    first = next(p for p in data["points"] if p["branch"] == "straight")
    assert first["extension"] == pytest.approx(1 + 5.0 / 500.0, rel=1e-12)


def test_study_files_take_the_model():
    text = ('[rod]\ntwist_ratio = 0.8\nnodes = 20\nmodel = "cosserat"\n'
            'stretch_stiffness = 1e4\n[problem]\nkind = "ring"\nexcess_link = 1.0\n')
    rod = parse_study(text).rod()
    assert isinstance(rod, sc.CosseratRod) and rod.stretch_stiffness == 1e4
    assert isinstance(parse_study(text.replace('model = "cosserat"\nstretch_stiffness = 1e4\n',
                                               "")).rod(), sc.Rod)
    # the Cosserat ring takes self-contact; its section is the tube's
    tube = parse_study(text.replace("nodes = 20", "nodes = 20\nlength_over_diameter = 40"))
    assert tube.rod().slenderness == 40.0
    with pytest.raises(StudyError, match='needs model = "cosserat"'):
        parse_study(text.replace('model = "cosserat"', 'model = "kirchhoff"'))
    with pytest.raises(StudyError, match="model"):
        parse_study(text.replace('model = "cosserat"', 'model = "rubber"'))


def test_diagram_ring_resumes_only_with_the_same_rod(runner, tmp_path):
    out = tmp_path / "d"
    command = ["diagram", "ring", "--twist-ratio", "0.6667", "--length-over-diameter", "20",
               "--nodes", "24", "--modes", "2", "--max-excess-link", "4",
               "--contact-max-points", "6", "--quiet", "--out", str(out)]
    cosserat = ["--model", "cosserat", "--stretch-stiffness", "1e5", "--shear-stiffness",
                "1e5"]
    first = runner.invoke(app, command + cosserat)
    assert first.exit_code == 1, first.output  # alpha_contact stopped at its point limit
    stored = sc.load(out)
    assert stored.settings["rod"]["model"] == "cosserat"
    assert stored.branches["alpha_contact"].frames  # the sections' rotations, stored
    kirchhoff = runner.invoke(app, command + ["--resume"])
    assert kirchhoff.exit_code == 2 and "rod" in kirchhoff.output, kirchhoff.output
    again = runner.invoke(app, command + cosserat + ["--resume"])
    assert again.exit_code != 2, again.output
