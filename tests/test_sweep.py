"""Sweep studies without a cluster: the grid of a [sweep] table, its errors, the dataset.

Oracles: every task's study equals the study with the same keys given by ``--set``
(another path through the study reader); TOML text read back equals what was
written; a dataset read back equals the one written, and each of its cells holds
its task's own outcome; the tweezers summary obeys torque = 2 pi (C/A) twist.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from supercoil.cli.main import run as cli
from supercoil.errors import InputError
from supercoil.io.study import parse_study
from supercoil.problems.ply import hard_core_ply
from supercoil.sweeps.dataset import build_dataset, load_sweep, write_dataset
from supercoil.sweeps.grid import parse_sweep_study, task_key, toml_text

ROOT = Path(__file__).resolve().parents[1]
RING = """
[rod]
twist_ratio = 0.6667
nodes = 24

[problem]
kind = "ring"
excess_link = 2.5

[outputs]
figures = false
json = false
"""


def sweep_text(table: str) -> str:
    return RING + "\n[sweep]\n" + table


def test_product_of_lists_and_zip_groups():
    sweep = parse_sweep_study(sweep_text(
        '"rod.twist_ratio" = [0.5, 0.6, 0.7]\n'
        '"rod.nodes" = {start = 16, stop = 24, num = 2}\n'
        '"problem.excess_link" = [1.0, 2.0, 3.0]\n'
        'zip = [["rod.twist_ratio", "problem.excess_link"]]\n'), "s.toml")
    assert [d.name for d in sweep.dimensions] == ["rod.twist_ratio+problem.excess_link",
                                                  "rod.nodes"]
    assert sweep.shape == (3, 2) and len(sweep.tasks) == 6
    assert sweep.dimensions[1].values == ((16, 24),)  # integer ends: integer values
    seen = set()
    for task in sweep.tasks:
        i, j = task.index
        assert task.overrides == {"rod.twist_ratio": (0.5, 0.6, 0.7)[i],
                                  "problem.excess_link": (1.0, 2.0, 3.0)[i],
                                  "rod.nodes": (16, 24)[j]}
        # the same study through --set overrides
        expected = parse_study(RING, "s.toml", [f"{k}={v}" for k, v in task.overrides.items()])
        assert task.settings == expected.settings
        assert task.key == task_key(expected.settings) and len(task.key) == 16
        seen.add(task.key)
    assert len(seen) == 6


def test_dotted_keys_unquoted_are_the_same_sweep():
    quoted = parse_sweep_study(sweep_text('"problem.excess_link" = [1.0, 2.0]\n'))
    bare = parse_sweep_study(sweep_text("problem.excess_link = [1.0, 2.0]\n"))
    assert [t.key for t in quoted.tasks] == [t.key for t in bare.tasks]
    assert quoted.dimensions == bare.dimensions


def test_example_sweep_is_valid():
    from supercoil.sweeps.grid import load_sweep_study

    sweep = load_sweep_study(ROOT / "examples" / "sweep_hat_curves.toml")
    assert sweep.kind == "tweezers" and sweep.shape == (4,)
    assert [t.settings["problem"]["tension"] for t in sweep.tasks] == [10.0, 20.0, 30.0, 40.0]


_scalars = st.one_of(st.booleans(), st.integers(-10**12, 10**12),
                     st.floats(allow_nan=False), st.text(max_size=12))
_keys = st.text(min_size=1, max_size=6)
_tables = st.dictionaries(_keys, st.one_of(_scalars, st.lists(_scalars, max_size=3)),
                          max_size=3)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(_keys, _tables, max_size=3))
@example({"0\n": {}})  # a key ending in a newline: "$" of a regex matches before it
@example({"0": {"0\n": False}})
def test_toml_text_reads_back(study):
    assert tomllib.loads(toml_text(study)) == study


BAD_TABLES = {
    "unknown key": ('"rod.twist_ration" = [0.5, 1.0]', "did you mean 'twist_ratio'"),
    "empty list": ('"problem.excess_link" = []', "list of values is empty"),
    "zip of unequal lengths": (('"rod.twist_ratio" = [0.5, 1.0]\n"problem.excess_link" = '
                                '[1, 2, 3]\nzip = [["rod.twist_ratio", "problem.excess_link"]]'),
                               "rod.twist_ratio has 2, problem.excess_link has 3 values"),
    "zip of an unswept key": (('"rod.twist_ratio" = [0.5, 1.0]\n'
                               'zip = [["rod.twist_ratio", "rod.nodes"]]'),
                              "'rod.nodes' is not a swept key"),
    "value out of range": ('"rod.nodes" = [16, 4]', "[rod] nodes (nodes of the ring) must be a whole number from 8"),
    "range without num": ('"rod.twist_ratio" = {start = 0.5, stop = 1.0}', "num missing"),
    "key without a table": ('twist_ratio = [0.5, 1.0]', "TABLE.KEY"),
    "values of two types": ('"problem.excess_link" = [1.0, "two"]', "mix"),
    "a value twice": ('"problem.excess_link" = [1.0, 2.0, 1.0]', "given twice"),
}


@pytest.mark.parametrize("name", list(BAD_TABLES))
def test_bad_sweep_tables_are_refused_before_any_task(name, tmp_path, capsys):
    table, phrase = BAD_TABLES[name]
    study = tmp_path / "s.toml"
    study.write_text(sweep_text(table + "\n"), encoding="utf-8")
    out = tmp_path / "out"
    status = cli(["sweep", str(study), "--out", str(out), "--workers", "1", "-q"])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert err.startswith("error: ") and "\n" not in err and phrase in err, err
    assert "s.toml" in err and not out.exists()  # nothing written, no task run


def test_a_study_without_sweep_table_and_clashing_options(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(RING, encoding="utf-8")
    assert cli(["sweep", str(study), "--out", str(tmp_path / "o")]) == 2
    assert "no [sweep] table" in capsys.readouterr().err
    study.write_text(sweep_text('"problem.excess_link" = [1.0]\n'), encoding="utf-8")
    for args, phrase in ((["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "exclude"),
                         (["--resume", "--overwrite"], "exclude"),
                         (["--workers", "0"], "from 1 to"),
                         (["--resume"], "nothing to resume")):
        assert cli(["sweep", str(study), "--out", str(tmp_path / "o"), *args]) == 2
        assert phrase in capsys.readouterr().err
    (tmp_path / "o").mkdir()
    (tmp_path / "o" / "notes.txt").write_text("mine")
    assert cli(["sweep", str(study), "--out", str(tmp_path / "o")]) == 2
    assert "not empty" in capsys.readouterr().err
    assert not (tmp_path / "o" / "tasks").exists()


def test_parse_errors_are_input_errors():
    with pytest.raises(InputError, match=r"^s\.toml: \[sweep\] 'problem\.excess_link': the "):
        parse_sweep_study(sweep_text('"problem.excess_link" = []\n'), "s.toml")


def test_dataset_cells_hold_their_tasks_and_read_back(tmp_path):
    import xarray as xr

    sweep = parse_sweep_study(sweep_text(
        '"problem.excess_link" = [1.0, 2.0, 3.0]\n"rod.twist_ratio" = [0.5, 1.0]\n'))
    outcomes = {}
    for n, task in enumerate(sweep.tasks[:-1]):  # the last task is not run
        values = {"writhe": 0.1 * n, "ring.status": "PARAMETER_BOUND"}
        if n % 2:
            values["folds"] = float(n)
        outcomes[task.key] = {"status": "complete" if n else "failed", "message": f"m{n}",
                              "values": values}
    ds = build_dataset(sweep, outcomes, {"wall_seconds": 1.0})
    assert ds["writhe"].dims == ("problem.excess_link", "rod.twist_ratio")
    for n, task in enumerate(sweep.tasks):
        cell = ds.sel({"problem.excess_link": task.overrides["problem.excess_link"],
                       "rod.twist_ratio": task.overrides["rod.twist_ratio"]})
        assert str(cell["task"].values) == task.key
        if n == len(sweep.tasks) - 1:
            assert str(cell["status"].values) == "not run"
            assert math.isnan(float(cell["writhe"])) and str(cell["ring.status"].values) == ""
            continue
        assert str(cell["status"].values) == ("complete" if n else "failed")
        assert float(cell["writhe"]) == 0.1 * n
        assert (float(cell["folds"]) == n) if n % 2 else math.isnan(float(cell["folds"]))
    path = write_dataset(ds, tmp_path / "sweep.nc")
    back = load_sweep(tmp_path)
    xr.testing.assert_equal(back, load_sweep(path))
    again = build_dataset(sweep, outcomes, {"wall_seconds": 2.0})  # attributes aside: equal
    write_dataset(again, tmp_path / "again.nc")
    xr.testing.assert_equal(back, load_sweep(tmp_path / "again.nc"))
    np.testing.assert_array_equal(back["writhe"].values, ds["writhe"].values)
    with pytest.raises(InputError, match="no such sweep dataset"):
        load_sweep(tmp_path / "nowhere")


TWEEZERS_STUDY = """
[rod]
twist_ratio = 1.3333333333333333
length_over_diameter = 20
nodes = 16
[problem]
kind = "tweezers"
tension = 20.0
turns = [0.0, 1.6]
[outputs]
figures = false
json = false
"""
TWEEZERS = TWEEZERS_STUDY + '[sweep]\n"problem.tension" = [20.0]\n'


@pytest.fixture(scope="module")
def tweezers_sweep(tmp_path_factory):
    """A one-task tweezers sweep run in this process: (folder, sweep, dataset, result)."""
    from supercoil import load
    from supercoil.api.study_run import run_study
    from supercoil.sweeps.summary import summarize

    folder = tmp_path_factory.mktemp("tweezers")
    sweep = parse_sweep_study(TWEEZERS, "t.toml")
    (task,) = sweep.tasks
    out = folder / "tasks" / task.key
    out.mkdir(parents=True)
    assert run_study(parse_study(task.text, "t.toml"), out)["status"] == "complete"
    result = load(out / "result.h5")
    outcome = {"status": "complete", "message": "", "values": summarize(result)}
    write_dataset(build_dataset(sweep, {task.key: outcome}), folder / "sweep.nc")
    return folder, sweep, load_sweep(folder), result


def _branches(result) -> dict:
    return dict(result.branches)


def test_tweezers_summary(tweezers_sweep):
    _, _, dataset, result = tweezers_sweep
    s = {name: dataset[name].values[0].item() for name in dataset.data_vars}
    branches = _branches(result)
    buckling = [p for p in branches["straight"].special_points if p.kind == "bifurcation"]
    assert s["buckling_turns"] == buckling[0].parameter
    assert s["straight.bifurcation"] == s["buckling_turns"]
    # at the buckling point the rod is still straight: extension = 1
    assert abs(s["buckling_extension"] - 1.0) < 1e-9
    # the reduced twist is uniform: torque = 2 pi (C/A) twist, at the plateau too
    assert s["torque_plateau"] == pytest.approx(
        2 * math.pi * (4 / 3) * s["buckled_contact.end.twist"], rel=1e-9)
    ply = hard_core_ply(1 / 20, 20.0, 4 / 3)
    assert s["ply_torque"] == pytest.approx(ply.torque, rel=1e-12)
    assert s["ply_spanning_turns"] == pytest.approx(ply.spanning_turns, rel=1e-12)
    assert s["folds"] == sum(p.kind == "fold" for b in branches.values()
                             for p in b.special_points)
    assert s["first_contact_turns"] == s["buckled.contact_onset"]
    assert s["buckled_contact.end.turns"] == 1.6
    assert s["buckled_contact.points"] == len(branches["buckled_contact"])


def test_sweep_figures_draw_the_stored_numbers(tweezers_sweep, tmp_path):
    from supercoil.plotting.sweep import hat_curves_figure, map_figure, plot_sweep, sweep_kinds

    folder, _, dataset, result = tweezers_sweep
    assert sweep_kinds(dataset) == ("hat-curves", "curve-map", "map", "buckling-torque")
    fig = hat_curves_figure(dataset, folder)
    thin = [line for line in fig.axes[0].lines if line.get_linewidth() < 2]
    branches = [b for b in _branches(result).values() if len(b)]
    assert len(thin) == len(branches)
    for line, branch in zip(thin, branches, strict=True):
        np.testing.assert_array_equal(line.get_xdata(), branch.parameter_values)
        np.testing.assert_array_equal(line.get_ydata(), branch.records["extension"])
    fig = map_figure(dataset, "torque_plateau")
    (line,) = fig.axes[0].lines
    assert line.get_ydata()[0] == dataset["torque_plateau"].values[0]
    with pytest.raises(ValueError, match="not a number of this sweep"):
        map_figure(dataset, "status")
    written = plot_sweep(folder, "hat-curves", tmp_path, ["png"])
    assert [p.name for p in written] == ["hat_curves.png"] and written[0].stat().st_size > 0


def test_map_of_two_dimensions_colours_each_cell():
    from supercoil.plotting.sweep import map_figure

    sweep = parse_sweep_study(sweep_text(
        '"problem.excess_link" = [1.0, 2.0, 3.0]\n"rod.twist_ratio" = [0.5, 1.0]\n'))
    outcomes = {t.key: {"status": "complete", "message": "",
                        "values": {"writhe": 10 * t.index[0] + t.index[1]}}
                for t in sweep.tasks[1:]}
    dataset = build_dataset(sweep, outcomes)
    fig = map_figure(dataset, "writhe")
    mesh = fig.axes[0].collections[0]
    cells = np.ma.masked_invalid(dataset["writhe"].values)
    np.testing.assert_array_equal(np.ma.getmaskarray(mesh.get_array()).ravel(),
                                  np.ma.getmaskarray(cells).ravel())
    np.testing.assert_array_equal(mesh.get_array().compressed(), cells.compressed())


def test_a_failing_task_is_an_outcome(tmp_path):
    from supercoil.sweeps.driver import run_task, stored_outcome

    outcome = run_task("0" * 16, "[rod]\nnodes = 3\n", "bad.toml", str(tmp_path / "t"))
    assert outcome["status"] == "failed" and outcome["values"] == {}
    assert outcome["message"].startswith("StudyError: bad.toml:") or "bad.toml" in outcome[
        "message"]
    assert stored_outcome(tmp_path / "t", "0" * 16) is None  # nothing to resume


def test_the_command_exits_1_saying_how_many_failed(tmp_path, capsys, monkeypatch):
    from supercoil.sweeps import driver

    study = tmp_path / "s.toml"
    study.write_text(sweep_text('"problem.excess_link" = [1.0, 2.0, 3.0]\n'), encoding="utf-8")

    def fake(sweep, out, **kwargs):
        return driver.SweepOutcome(Path(out) / "sweep.nc", 3, 3, 0, 2, False,
                                   {"complete": 1, "failed": 1, "incomplete": 1})

    monkeypatch.setattr(driver, "run_sweep", fake)
    assert cli(["sweep", str(study), "--out", str(tmp_path / "o"), "-q"]) == 1
    assert "2 of 3 tasks failed or stopped early" in capsys.readouterr().err
