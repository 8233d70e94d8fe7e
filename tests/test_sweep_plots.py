"""The figures of a sweep: ``supercoil plot DIR`` and ``supercoil.plot(DIR)``.

A tiny tweezers sweep (two forces, 16 nodes) is run in this process. Oracles: every
figure is written and its axes are labelled; the hat curves have one labelled line
per swept force and draw each branch's stored numbers; the buckling torque is the
dataset's, one point per force; on the curve map, at end rotations before the
buckling and the first stable point of another branch of each force, the stable state is the
straight rod, whose extension is exactly 1 (an inextensible rod); the command line and the Python call write the same
files.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_sweep import TWEEZERS_STUDY

from supercoil.io.study import parse_study
from supercoil.sweeps.dataset import build_dataset, load_sweep, write_dataset
from supercoil.sweeps.grid import parse_sweep_study

FORCES = (10.0, 20.0)
TWEEZERS = TWEEZERS_STUDY + f'[sweep]\n"problem.tension" = [{FORCES[1]}, {FORCES[0]}]\n'


@pytest.fixture(scope="module")
def sweep_folder(tmp_path_factory):
    """The folder of a two-force tweezers sweep (its tasks run here, one after the
    other, as a worker runs them), and its results by task key."""
    from supercoil import load
    from supercoil.api.study_run import run_study
    from supercoil.sweeps.summary import summarize

    folder = tmp_path_factory.mktemp("sweep")
    sweep = parse_sweep_study(TWEEZERS, "t.toml")
    outcomes, results = {}, {}
    for task in sweep.tasks:
        out = folder / "tasks" / task.key
        out.mkdir(parents=True)
        assert run_study(parse_study(task.text, "t.toml"), out)["status"] == "complete"
        results[task.key] = load(out / "result.h5")
        outcomes[task.key] = {"status": "complete", "message": "",
                              "values": summarize(results[task.key])}
    write_dataset(build_dataset(sweep, outcomes), folder / "sweep.nc")
    return folder, results


def _labelled(ax) -> None:
    assert ax.get_xlabel() and ax.get_ylabel()


def test_sweep_kinds(sweep_folder):
    from supercoil.plotting.sweep import sweep_kinds

    folder, _ = sweep_folder
    assert sweep_kinds(load_sweep(folder)) == ("hat-curves", "curve-map", "map",
                                               "buckling-torque")


def test_hat_curves_one_labelled_line_per_force(sweep_folder):
    from supercoil.plotting.sweep import hat_curves_figure

    folder, results = sweep_folder
    dataset = load_sweep(folder)
    (ax,) = hat_curves_figure(dataset, folder).axes
    _labelled(ax)
    labels = [line.get_label() for line in ax.lines if not line.get_label().startswith("_")]
    assert len(labels) == len(FORCES)
    assert sorted(labels) == sorted(f"tension = {f:g}" for f in FORCES)
    thin = [line for line in ax.lines if line.get_linewidth() < 2]
    branches = [b for key in dataset["task"].values for b in results[key].branches.values()
                if len(b)]
    assert len(thin) == len(branches)
    for line, branch in zip(thin, branches, strict=True):
        np.testing.assert_array_equal(line.get_ydata(), branch.records["extension"])


def test_buckling_torque_against_force(sweep_folder):
    from supercoil.plotting.sweep import buckling_torque_figure

    folder, _ = sweep_folder
    dataset = load_sweep(folder)
    (ax, ) = buckling_torque_figure(dataset).axes
    _labelled(ax)
    (line,) = ax.lines
    np.testing.assert_array_equal(line.get_xdata(), sorted(FORCES))
    by_force = dict(zip(dataset["problem.tension"].values, dataset["buckling_torque"].values,
                        strict=True))
    np.testing.assert_array_equal(line.get_ydata(), [by_force[f] for f in sorted(FORCES)])
    assert np.all(np.isfinite(line.get_ydata()))


def test_curve_map_straight_rod_before_any_other_stable_state(sweep_folder):
    from supercoil.plotting.sweep import CURVE_MAP_COLUMNS, curve_map_figure

    folder, results = sweep_folder
    dataset = load_sweep(folder)
    fig = curve_map_figure(dataset, folder)
    ax = fig.axes[0]
    _labelled(ax)
    mesh = ax.collections[0]
    cells = np.ma.masked_invalid(mesh.get_array()).reshape(len(FORCES), CURVE_MAP_COLUMNS)
    ys = mesh.get_coordinates()[:, 0, 1]  # the cells' lower edges, one row per force
    xs = mesh.get_coordinates()[0, :, 0]
    centres = (xs[1:] + xs[:-1]) / 2
    rows = np.sort(dataset["problem.tension"].values)
    assert np.all(np.diff(ys) > 0) and len(ys) == len(rows) + 1
    for k, force in enumerate(rows):
        cell = dataset.sel({"problem.tension": force})
        buckling = float(cell["buckling_turns"])
        others = [b for b in results[str(cell["task"].values)].branches.values()
                  if b.name != "straight" and len(b)]
        first = min(np.min(np.asarray(b.parameter_values)[np.asarray(b.unstable_count) == 0],
                           initial=np.inf) for b in others)
        # the straight rod (extension 1, exactly) is the only stable state before
        # another branch's first stable point and before it buckles
        before = centres < min(first, buckling)
        assert before.sum() > 10
        np.testing.assert_array_equal(cells[k][before], 1.0)
        assert cells[k].count() > before.sum()  # the other states are drawn too
        assert np.all(cells[k].compressed() <= 1.0)


def test_command_and_python_write_every_sweep_figure(sweep_folder, tmp_path):
    import matplotlib.image

    import supercoil
    from supercoil.cli.main import run as cli

    folder, _ = sweep_folder
    names = ["buckling_torque.png", "curve_map.png", "hat_curves.png",
             "map_end_extension.png"]
    assert cli(["plot", str(folder), "--out", str(tmp_path / "cli"), "--format", "png",
                "-q"]) == 0
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == names
    written = supercoil.plot(folder, out=tmp_path / "py")  # the folder is created
    assert sorted(p.name for p in written) == names
    for name in names:
        image = matplotlib.image.imread(tmp_path / "py" / name)
        assert image.shape[0] > 100 and image.std() > 0  # drawn, not blank
    one = supercoil.plot(folder / "sweep.nc", kind="map", out=tmp_path / "py",
                         variable="buckling_turns")
    assert [p.name for p in one] == ["map_buckling_turns.png"]


@pytest.mark.parametrize(("args", "message"), [
    (["--kind", "diagram"], "give one of hat-curves, curve-map, map, buckling-torque"),
    (["--kind", "map", "--variable", "status"], "not a number of this sweep"),
])
def test_bad_sweep_plot_options_are_refused(sweep_folder, tmp_path, capsys, args, message):
    from supercoil.cli.main import run as cli

    folder, _ = sweep_folder
    assert cli(["plot", str(folder), "--out", str(tmp_path / "f"), *args]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "f").exists()
