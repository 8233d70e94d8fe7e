"""Every command has its function in ``supercoil``, and the two give the same numbers.

Oracles: for a small case per command, the command's output (its files, its JSON)
equals the function's result; the table of docs/api.md has a row for every command
``supercoil --help`` lists; the points a verb reports through ``on_point`` are
exactly the points its result file holds, and a run stopped in ``on_point`` and
resumed ends where the uninterrupted run ends.
"""

from __future__ import annotations

import json
import re
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
import typer

import supercoil as sc
from supercoil.cli.main import app
from supercoil.cli.main import run as cli

ROOT = Path(__file__).resolve().parent.parent
ROD, LOD = sc.Rod(0.6667, nodes=24), 20.0
DIAGRAM_OPTIONS = {"modes": (2,), "max_excess_link": 4.0, "contact_max_points": 40}
DIAGRAM = ["diagram", "ring", "--twist-ratio", "0.6667", "--length-over-diameter", "20",
           "--nodes", "24", "--modes", "2", "--max-excess-link", "4",
           "--contact-max-points", "40", "--quiet"]
TWEEZERS = sc.Tweezers(sc.Rod(4 / 3, nodes=24), tension=20.0, contact=sc.Barrier(LOD))
TWEEZERS_ARGS = ["tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "20",
                 "--nodes", "24", "--tension", "20", "--turns", "0:1.6", "--quiet"]
RING_STUDY = {"rod": {"twist_ratio": 1.5, "nodes": 24},
              "problem": {"kind": "ring", "excess_link": 0.5},
              "outputs": {"figures": False, "json": True}}


def commands(group=None, prefix=()) -> list[str]:
    """Every command of ``supercoil`` (groups' commands as ``"diagram ring"``)."""
    group = group or typer.main.get_command(app)
    out = []
    for name, command in group.commands.items():
        if getattr(command, "commands", None):
            out += commands(command, (*prefix, name))
        else:
            out.append(" ".join((*prefix, name)))
    return out


def test_every_command_has_a_row_in_the_api_table():
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| `supercoil ([a-z ]+)` \| (.+) \|$", text, re.MULTILINE))
    assert sorted(rows) == sorted(commands())
    for command, function in rows.items():
        names = re.findall(r"\bsc\.([a-zA-Z_]+)\(", function)
        assert names, command
        assert all(name in sc.__all__ for name in names), (command, names)


def assert_same_branches(a, b, atol=0.0):
    assert list(a.branches) == list(b.branches)
    for name, x in a.branches.items():
        y = b.branches[name]
        assert len(x) == len(y), name
        np.testing.assert_allclose(x.states, y.states, atol=atol, rtol=0, err_msg=name)
        np.testing.assert_allclose(x.parameter_values, y.parameter_values, atol=atol, rtol=0)
        assert [(p.kind, p.index) for p in x.special_points] == \
            [(p.kind, p.index) for p in y.special_points], name


def numbers(summary: dict) -> dict:
    """A JSON summary as written, without what depends on the machine and the clock (the
    provenance, the branches' seconds)."""
    from supercoil.io.results import to_jsonable

    data = json.loads(json.dumps(to_jsonable(summary)))
    data.pop("provenance")
    for branch in data.get("branches", ()):
        branch.pop("seconds")
    return data


@pytest.fixture(scope="module")
def diagram_runs(tmp_path_factory):
    """The command's folder, the verb's folder and what the verb reported."""
    root = tmp_path_factory.mktemp("diagram")
    assert cli([*DIAGRAM, "--out", str(root / "cli")]) in (0, 1)
    seen = []
    diagram = sc.ring_diagram(ROD, sc.Barrier(LOD), out=root / "api", **DIAGRAM_OPTIONS,
                              on_point=lambda b: seen.append((b.name, b.states[-1].copy())))
    return root, diagram, seen


def test_diagram_ring_equals_ring_diagram(diagram_runs):
    root, diagram, _ = diagram_runs
    by_cli, by_api = sc.load(root / "cli"), sc.load(root / "api")
    assert_same_branches(by_cli, by_api)
    assert by_cli.status == by_api.status == ("complete" if diagram.ok else "incomplete")
    for name in ("diagram.json",):
        a = json.loads((root / "cli" / name).read_text())
        b = json.loads((root / "api" / name).read_text())
        assert numbers(a) == numbers(b) == numbers(diagram.summary)
    assert by_cli.attributes == by_api.attributes


def test_a_diagram_stopped_by_its_point_limit_names_the_branch(tmp_path):
    """A contact branch cut by its point limit: the command's and the verb's result
    files say which branch stopped early (the branch is ok, not complete)."""
    short = [*DIAGRAM, "--contact-max-points", "3"]
    assert cli([*short, "--out", str(tmp_path / "cli")]) == 1
    options = {**DIAGRAM_OPTIONS, "contact_max_points": 3}
    diagram = sc.ring_diagram(ROD, sc.Barrier(LOD), out=tmp_path / "api", **options)
    stopped = [n for n, b in diagram.branches.items() if not b.status.complete]
    assert stopped == ["alpha_contact"] and not diagram.ok
    for result in (sc.load(tmp_path / "cli"), sc.load(tmp_path / "api")):
        assert result.message == "branch(es) alpha_contact stopped early"


def test_a_diagram_stopped_at_its_point_limit_resumes_with_a_higher_one(tmp_path,
                                                                        diagram_runs):
    """``resume`` may raise a point limit: the contact branch stopped at 3 points is
    continued to the uninterrupted run's (40 points allowed), through the verb and the
    command, and the file records the new limit."""
    root, _, _ = diagram_runs
    short = {**DIAGRAM_OPTIONS, "contact_max_points": 3}
    sc.ring_diagram(ROD, sc.Barrier(LOD), out=tmp_path / "api", **short)
    assert cli([*DIAGRAM, "--contact-max-points", "3", "--out", str(tmp_path / "cli")]) == 1
    sc.ring_diagram(ROD, sc.Barrier(LOD), out=tmp_path / "api", resume=True, **DIAGRAM_OPTIONS)
    full = sc.load(root / "api")
    status = cli([*DIAGRAM, "--out", str(tmp_path / "cli"), "--resume"])
    assert status == (0 if full.status == "complete" else 1)
    for way in ("api", "cli"):
        resumed = sc.load(tmp_path / way)
        assert resumed.settings["options"]["contact_max_points"] == 40
        assert resumed.status == full.status
        assert_same_branches(resumed, full, atol=1e-8)


def test_load_reads_a_summary_as_the_result_beside_it(diagram_runs, tmp_path):
    root, _, _ = diagram_runs
    assert_same_branches(sc.load(root / "cli" / "diagram.json"), sc.load(root / "cli"))
    (tmp_path / "diagram.json").write_text("{}")
    with pytest.raises(sc.InputError, match="no result.h5"):
        sc.load(tmp_path / "diagram.json")


def test_on_point_sees_the_points_stored(diagram_runs):
    """Each branch continued with contact is final as computed: its stored states are
    exactly the reported ones, in order."""
    root, _, seen = diagram_runs
    reported = defaultdict(list)
    for name, q in seen:
        reported[name].append(q)
    stored = sc.load(root / "api")
    contact = [n for n in stored.branches if n.endswith("_contact")]
    assert contact
    for name in contact:
        np.testing.assert_array_equal(np.array(reported[name]), stored.branches[name].states)


def test_a_run_stopped_in_on_point_keeps_what_was_reported_and_resumes(tmp_path,
                                                                      diagram_runs):
    root, _, _ = diagram_runs
    seen = defaultdict(list)

    def stop_at_ten(branch):
        seen[branch.name].append(branch.states[-1].copy())
        if len(seen["alpha_contact"]) == 10:
            raise KeyboardInterrupt

    out = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):
        sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, on_point=stop_at_ten,
                        **DIAGRAM_OPTIONS)
    cut = sc.load(out)
    assert cut.status == "interrupted" and "alpha_contact (10 points)" in cut.message
    assert "alpha_contact" not in cut.complete_branches
    np.testing.assert_array_equal(cut.branches["alpha_contact"].states,
                                  np.array(seen["alpha_contact"]))
    with pytest.raises(sc.InputError, match="other options"):
        sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, resume=True,
                        **{**DIAGRAM_OPTIONS, "contact_max_points": 39})
    resumed = sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, resume=True, **DIAGRAM_OPTIONS)
    full = sc.load(root / "api")
    assert_same_branches(sc.load(out), full, atol=1e-8)
    assert resumed.status.name.lower() == full.status


def test_tweezers_command_equals_tweezers(tmp_path):
    assert cli([*TWEEZERS_ARGS, "--out", str(tmp_path / "cli")]) in (0, 1)
    result = sc.tweezers(TWEEZERS, (0.0, 1.6), out=tmp_path / "api")
    assert_same_branches(sc.load(tmp_path / "cli"), sc.load(tmp_path / "api"))
    a = json.loads((tmp_path / "cli" / "branch.json").read_text())
    b = json.loads((tmp_path / "api" / "branch.json").read_text())
    assert numbers(a) == numbers(b) == numbers(result.summary)


def test_tweezers_protocol_path_equals_tweezers_path(tmp_path):
    problem = sc.Tweezers(sc.Rod(4 / 3, nodes=16), tension=20.0)
    args = ["tweezers", "--twist-ratio", "4/3", "--nodes", "16", "--tension", "20",
            "--turns", "0:0.6", "--protocol", "up-down", "--step", "0.1", "--quiet"]
    assert cli([*args, "--out", str(tmp_path / "cli")]) in (0, 1)
    path = sc.tweezers_path(problem, (0.0, 0.6), protocol="up-down", step=0.1)
    stored = json.loads((tmp_path / "cli" / "branch.json").read_text())["path"]
    from supercoil.io.results import to_jsonable

    assert json.loads(json.dumps(to_jsonable(list(path.points)))) == stored
    np.testing.assert_array_equal(sc.load(tmp_path / "cli").extras["path"]["states"],
                                  path.states)
    assert len(repr(path).splitlines()) == 1


def test_demo_computes_through_ring_diagram(tmp_path, monkeypatch):
    """The demo's call is the one in the table of docs/api.md."""
    from supercoil.api import verbs
    from supercoil.cli import demo

    calls = []

    def stop(rod, contact, **kwargs):
        calls.append((rod, contact, kwargs))
        raise KeyboardInterrupt

    monkeypatch.setattr(verbs, "ring_diagram", stop)
    assert cli(["demo", "--out", str(tmp_path / "d"), "--quiet"]) == 1
    (rod, contact, kwargs), = calls
    assert rod == sc.Rod(2 / 3, nodes=132) and contact == sc.Barrier(122)
    assert kwargs["modes"] == (2, 3) and kwargs["max_excess_link"] == 3
    assert kwargs["contact_max_points"] == 300
    assert (rod.nodes, contact.length_over_diameter) == (demo.N_NODES,
                                                         demo.LENGTH_OVER_DIAMETER)


def test_ring_command_equals_equilibrium(tmp_path):
    assert cli(["ring", "--twist-ratio", "1.5", "--excess-link", "0.5", "--nodes", "24",
                "--json", str(tmp_path / "ring.json"), "--out", str(tmp_path / "cli"),
                "--quiet"]) == 0
    state = sc.equilibrium(sc.Ring(sc.Rod(1.5, nodes=24), 0.5))
    data = json.loads((tmp_path / "ring.json").read_text())
    assert data["energy"] == state.energy and data["writhe"] == state.writhe
    assert data["unstable_count"] == state.unstable_count
    sc.save(state, tmp_path / "api.h5")
    assert_same_branches(sc.load(tmp_path / "cli"), sc.load(tmp_path / "api.h5"))


def test_a_ring_with_contact_is_plotted_and_viewed_as_any_result(tmp_path):
    """The folder of ``ring --out`` with self-contact (whose solve reports the route it
    took, circle or contact) is drawn and viewed; its one point is of the stored
    branch ``ring``."""
    out = tmp_path / "cli"
    assert cli(["ring", "--twist-ratio", "1.5", "--excess-link", "0.5", "--nodes", "24",
                "--length-over-diameter", "20", "--out", str(out), "--quiet"]) == 0
    points = json.loads((out / "ring.json").read_text())["points"]
    assert [p["branch"] for p in points] == list(sc.load(out).branches) == ["ring"]
    for given in (out, out / "result.h5", out / "ring.json"):
        assert cli(["plot", str(given), "--kind", "diagram", "--format", "svg", "--out",
                    str(tmp_path / "figures"), "--overwrite", "--quiet"]) == 0
        assert cli(["view", str(given), "--out", str(tmp_path / f"{given.name}.html"),
                    "--quiet"]) == 0
    assert sc.plot(sc.load(out), "diagram", out=tmp_path, formats=("svg",))


def test_run_command_equals_run(tmp_path):
    from supercoil.sweeps.grid import toml_text

    study = tmp_path / "ring.toml"
    study.write_text(toml_text(RING_STUDY), encoding="utf-8")
    assert cli(["run", str(study), "--out", str(tmp_path / "cli"), "--quiet"]) == 0
    result = sc.run(RING_STUDY, tmp_path / "api")
    assert result.status == "complete" and result.problem == "ring"
    assert_same_branches(sc.load(tmp_path / "cli"), result)
    a = json.loads((tmp_path / "cli" / "ring.json").read_text())
    b = json.loads((tmp_path / "api" / "ring.json").read_text())
    assert numbers(a) == numbers(b)
    with pytest.raises(sc.InputError, match="not empty"):
        sc.run(RING_STUDY, tmp_path / "api")
    with pytest.raises(sc.InputError, match="exclude each other"):
        sc.run(study, tmp_path / "api", resume=True, overwrite=True)


def test_sweep_command_equals_sweep(tmp_path):
    from supercoil.sweeps.grid import toml_text

    table = {**RING_STUDY, "sweep": {"problem.excess_link": [0.5, 1.0]}}
    study = tmp_path / "s.toml"
    study.write_text(toml_text(table), encoding="utf-8")
    assert cli(["sweep", str(study), "--out", str(tmp_path / "cli"), "--workers", "1",
                "--quiet"]) == 0
    by_api = sc.sweep(table, tmp_path / "api", workers=1)
    by_cli = sc.load(tmp_path / "cli")
    assert sorted(by_api.data_vars) == sorted(by_cli.data_vars)
    for name in by_cli.data_vars:
        if by_cli[name].dtype.kind == "f":
            np.testing.assert_array_equal(by_cli[name].values, by_api[name].values,
                                          err_msg=name)


def test_export_view_and_plot_commands_equal_their_functions(tmp_path, diagram_runs):
    root, diagram, _ = diagram_runs
    folder = root / "api"
    assert cli(["export", str(folder), "--branch", "alpha", "--point", "3", "--out",
                str(tmp_path / "cli.xyz"), "--quiet"]) == 0
    done = sc.export(diagram, tmp_path / "api.xyz", branch="alpha", point=3)
    assert (done.branch, done.point, done.format, done.unit) == ("alpha", 3, "xyz", "L")
    assert len(repr(done).splitlines()) == 1
    a = np.loadtxt(tmp_path / "cli.xyz", skiprows=2, usecols=(1, 2, 3))
    b = np.loadtxt(tmp_path / "api.xyz", skiprows=2, usecols=(1, 2, 3))
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(b, diagram.branches["alpha"].states[3].reshape(-1, 3),
                               atol=1e-12)
    with pytest.raises(sc.InputError, match="did you mean 'alpha'"):
        sc.export(folder, tmp_path / "x.xyz", branch="alpah")
    with pytest.raises(sc.InputError, match="base_pairs N"):
        sc.export(folder, tmp_path / "x.pdb")

    assert cli(["view", str(folder), "--out", str(tmp_path / "cli.html"), "--quiet"]) == 0
    page = sc.view(sc.load(folder), tmp_path / "api.html")
    assert page.read_text() == (tmp_path / "cli.html").read_text()
    with pytest.raises(sc.InputError, match="exists"):
        sc.view(folder, page)

    assert cli(["plot", str(folder), "--kind", "diagram", "--format", "svg", "--out",
                str(tmp_path / "cli"), "--quiet"]) == 0
    written = sc.plot(diagram, "diagram", out=tmp_path, formats=("svg",))
    assert [p.name for p in written] == ["diagram.svg"]


def test_writhe_and_knot_commands_equal_their_functions(tmp_path):
    curve = tmp_path / "trefoil.txt"
    np.savetxt(curve, sc.torus_knot(2, 3, 60))
    assert cli(["writhe", str(curve), "--json", str(tmp_path / "w.json"), "--quiet"]) == 0
    assert cli(["knot", str(curve), "--json", str(tmp_path / "k.json"), "--quiet"]) == 0
    points = sc.read_curve(curve)
    assert json.loads((tmp_path / "w.json").read_text())["writhe"] == sc.writhe(points)
    knot = sc.knot_type(points)
    data = json.loads((tmp_path / "k.json").read_text())
    assert (data["knot_type"], data["chirality"]) == (knot.name, knot.chirality) == ("3_1", 1)


def test_tighten_command_equals_tighten(tmp_path):
    assert cli(["tighten", "--knot", "3_1", "--nodes", "24", "--json",
                str(tmp_path / "t.json"), "--quiet"]) == 0
    data = json.loads((tmp_path / "t.json").read_text())
    tight = sc.tighten("3_1", 24)
    record = json.loads(json.dumps(tight.record()))
    assert {k: data[k] for k in record} == record
    assert len(repr(tight).splitlines()) <= 5
