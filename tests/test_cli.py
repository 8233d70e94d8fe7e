"""Tests of the ``supercoil`` command as a whole, ``writhe``, ``demo`` and the JSON
envelope. Every test has an oracle.

Oracles used here:

- exact values: a planar curve has writhe 0; a mirror image flips the sign of
  the writhe; Michell's points (A/C) sqrt(m^2 - 1) on the demo's circle;
- the command line's contract (docs/model.md, "Files and exit statuses"): JSON keys,
  envelope, exit statuses (0, 1, 2), help that fits 100 columns, output folders never
  overwritten;
- round trips: numpy values written by ``write_json`` read back equal.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import typing

import numpy as np
import pytest
import typer
from cli_helpers import (
    ENVELOPE,
    assert_one_line_error,
    invoke,
    json_out,
    trefoil,
    write_curve,
)
from typer.testing import CliRunner

from supercoil import __version__
from supercoil.cli import demo as demo_module
from supercoil.cli import diagram_output
from supercoil.cli.main import BLAS_THREAD_VARIABLES, COMMANDS, app
from supercoil.io.results import envelope, write_json

# ---------------------------------------------------------------- help, version


def test_help_through_a_fresh_process():
    """``supercoil --help`` works in a new process (it imports the options' modules, whose
    constants and defaults the help states)."""
    result = subprocess.run([sys.executable, "-m", "supercoil.cli.main", "--help"],
                            check=False, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and "ring" in result.stdout and result.stderr == ""


# the BLAS threads a command runs with, seen from inside it (numpy loaded before, as by
# the console script)
BLAS_THREADS_PROGRAM = """
import threadpoolctl
import supercoil.cli.main as main
seen = []
def app(**kwargs):
    seen.append(max(d["num_threads"] for d in threadpoolctl.threadpool_info()
                    if d["user_api"] == "blas"))
    return 0
main.app = app
main.run(["--version"])
print(seen[0])
"""


@pytest.mark.parametrize(("variables", "threads"), [({}, "1"), ({"OPENBLAS_NUM_THREADS": "2"}, "2")])
def test_a_command_runs_on_one_blas_thread_unless_the_environment_says(variables, threads):
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    result = subprocess.run([sys.executable, "-c", BLAS_THREADS_PROGRAM],
                            env={**env, **variables}, check=True, capture_output=True,
                            text=True, timeout=300)
    assert result.stdout.strip() == threads


@pytest.mark.parametrize(
    ("command", "words"),
    [
        (
            "writhe",
            ["--closure", "closed", "none", "chord", "axis", "--axis", "--json", "turns", "x y z"],
        ),
        (
            "ring",
            [
                "--twist-ratio",
                "C/A",
                "--excess-link",
                "turns",
                "--nodes",
                "--json",
                "E*L/A",
                "--length-over-diameter",
                "--contact",
                "barrier",
                "augmented",
                "penalty",
                "exact",
                "--initial",
                "scaled",
                "resampled",
                "equally",
                "knot",
            ],
        ),
        ("demo", ["--out", "--overwrite", "--resume", "2/3", "122"]),
    ],
)
def test_help_explains_parameters_and_units(runner, command, words):
    result = invoke(runner, command, "--help")
    assert result.exit_code == 0
    text = " ".join(result.stdout.split())
    for word in words:
        assert word in text, word


def test_version(runner):
    result = invoke(runner, "--version")
    assert result.exit_code == 0
    assert result.stdout.strip() == f"supercoil {__version__}"


def test_python_dash_m_runs_the_command():
    """``python -m supercoil`` is the ``supercoil`` command: its version, and a bad input's
    one-line error under the command's name with exit 2."""
    ok = subprocess.run([sys.executable, "-m", "supercoil", "--version"], check=False,
                        capture_output=True, text=True, timeout=300)
    assert (ok.returncode, ok.stdout.strip()) == (0, f"supercoil {__version__}")
    bad = subprocess.run([sys.executable, "-m", "supercoil", "tweezers", "--turns", "0:1"],
                         check=False, capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines()[-1].startswith("error: Missing option '--out'")
    assert "supercoil tweezers --help" in bad.stderr


# ------------------------------------------------------- one consistent command line

# the commands that write result files or folders (writhe and knot write only the --json
# document, which like standard output is replaced if it exists)
WRITES_FILES = {("demo",), ("ring",), ("diagram", "ring"), ("diagram", "knot"), ("tweezers",),
                ("run",), ("sweep",), ("plot",), ("view",), ("export",)}
# words of a project's development history, which the help must not carry
HISTORY = re.compile(r"\bsessions?\b|\bissues? #?\d|\bseed 0\d\d\b|DESIGN\.md|\.\./shared|"
                     r"benchmarks\.md|\btoday\b|\byet\b|\bmeasured\b|\b20\d\d-\d\d-\d\d\b",
                     re.IGNORECASE)
RANGE = re.compile(r"<=|>=|<|>|\bfrom \S+ to\b|\bin \(|\d+ to \d+")


def _commands(command=None, path=()):
    """``(path, command)`` of every command that runs (groups walked through)."""
    command = typer.main.get_command(app) if command is None else command
    if hasattr(command, "commands"):
        for name, sub in command.commands.items():
            yield from _commands(sub, (*path, name))
    else:
        yield path, command


def _numeric_parameters(callback) -> set[str]:
    """Names of the callback's int and float parameters (optional ones too), read from its
    annotations (the same whatever typer's internals)."""
    out = set()
    for name, hint in typing.get_type_hints(callback, include_extras=True).items():
        if typing.get_origin(hint) is typing.Annotated:
            hint = typing.get_args(hint)[0]
        kinds = typing.get_args(hint) or (hint,)
        if any(k in (int, float) for k in kinds):
            out.add(name)
    return out


def _options(command) -> set[str]:
    return {name for p in command.params if p.param_type_name == "option" for name in p.opts}


def test_commands_are_listed_in_the_order_a_new_user_meets_them(runner):
    text = invoke(runner, "--help").stdout
    listed = [line.split()[1] for line in text.splitlines()
              if len(line.split()) > 2 and line.split()[1] in COMMANDS]
    assert listed == list(COMMANDS)
    assert {path[0] for path, _ in _commands()} == set(COMMANDS)


@pytest.mark.parametrize("path", [(), ("diagram",), *(p for p, _ in _commands())],
                         ids=lambda p: " ".join(p) or "supercoil")
def test_help_fits_100_columns_and_speaks_of_the_tool(path):
    """Every help at COLUMNS=100: no line wider, no word of development history."""
    result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "100"})
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert len(lines) > 3
    assert max(len(line) for line in lines) == 100  # the panels fill the width, no more
    assert HISTORY.findall(result.stdout) == []


@pytest.mark.parametrize(("path", "command"), list(_commands()),
                         ids=lambda p: " ".join(p) if isinstance(p, tuple) else "")
def test_help_shows_every_bracketed_word_it_is_given(path, command):
    """A word in brackets in an option's help (a study file's table, '[sweep]') is shown
    as written, not taken for console markup and dropped."""
    result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "100"})
    shown = " ".join(result.stdout.replace("│", " ").split())
    for p in command.params:
        for word in re.findall(r"\\?(\[[a-z_.]+\])", p.help or ""):
            assert word in shown, (path, p.opts, word)


@pytest.mark.parametrize(("path", "command"), list(_commands()),
                         ids=lambda p: " ".join(p) if isinstance(p, tuple) else "")
def test_every_command_spells_its_options_one_way(path, command):
    """-q/--quiet everywhere; --out, --overwrite on every command that writes files (never
    --force); every numeric option states its range."""
    options = _options(command)
    assert {"-q", "--quiet"} <= options, path
    assert "--force" not in options
    if path in WRITES_FILES:
        assert {"--out", "--overwrite"} <= options, path
    else:
        assert "--out" not in options and options & {"--json"}, path
    numeric = _numeric_parameters(command.callback)
    for p in command.params:
        if p.param_type_name == "option" and p.name in numeric:
            assert RANGE.search(p.help or ""), (path, p.opts, p.help)


# ---------------------------------------------------------------------- writhe


def test_writhe_of_planar_square_is_zero(runner, tmp_path):
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    path = write_curve(tmp_path / "square.txt", square, "unit square in the plane z = 0")
    data = json_out(invoke(runner, "writhe", path, "--json", "-"))
    assert data["writhe"] == pytest.approx(0.0, abs=1e-14)
    assert data["n_nodes"] == 4
    assert data["closure"] == "closed"
    for key in ENVELOPE:
        assert key in data
    human = invoke(runner, "writhe", path)
    assert human.exit_code == 0
    assert human.stdout.startswith("writhe ")
    assert float(human.stdout.split()[1]) == pytest.approx(0.0, abs=1e-14)


def test_writhe_of_mirror_image_flips_sign(runner, tmp_path):
    knot = trefoil()
    mirror = knot * np.array([1.0, 1.0, -1.0])
    original = json_out(
        invoke(runner, "writhe", write_curve(tmp_path / "k.txt", knot), "--json", "-")
    )["writhe"]
    mirrored = json_out(
        invoke(runner, "writhe", write_curve(tmp_path / "m.txt", mirror), "--json", "-")
    )["writhe"]
    assert abs(original) > 1.0
    assert mirrored == pytest.approx(-original, rel=1e-12)


def test_writhe_open_closures_and_axis(runner, tmp_path):
    """A right-handed helix closed by axial tails has positive writhe; reversing the
    axis is the same as rotating the curve by pi about x, which keeps the writhe of the
    closed curve: Wr(curve, -z) = Wr(rotated curve, +z). (1.95 turns: the chord of a whole
    number of turns would pass through a vertex, where the writhe is undefined.)"""
    t = np.linspace(0, 3.9 * np.pi, 81)
    helix = np.stack([np.cos(t), np.sin(t), 0.3 * t], axis=1)
    rotated = helix * np.array([1.0, -1.0, -1.0])
    path = write_curve(tmp_path / "helix.txt", helix)
    up = json_out(invoke(runner, "writhe", path, "--closure", "axis", "--json", "-"))
    assert up["closure"] == "axis"
    assert up["axis"] == [0.0, 0.0, 1.0]
    assert up["writhe"] > 0
    down = json_out(
        invoke(runner, "writhe", path, "--closure", "axis", "--axis", "0,0,-1", "--json", "-")
    )
    turned = json_out(
        invoke(
            runner,
            "writhe",
            write_curve(tmp_path / "r.txt", rotated),
            "--closure",
            "axis",
            "--json",
            "-",
        )
    )
    assert down["writhe"] == pytest.approx(turned["writhe"], rel=1e-12)
    chord = json_out(invoke(runner, "writhe", path, "--closure", "chord", "--json", "-"))
    closed = json_out(invoke(runner, "writhe", path, "--json", "-"))
    assert chord["writhe"] == closed["writhe"]  # same polygon, the convention is named
    none = json_out(invoke(runner, "writhe", path, "--closure", "none", "--json", "-"))
    assert none["closure"] == "none" and none["n_nodes"] == 81


def test_writhe_json_file_and_human_output(runner, tmp_path):
    path = write_curve(tmp_path / "k.txt", trefoil(60))
    target = tmp_path / "out.json"
    result = invoke(runner, "writhe", path, "--json", target)
    assert result.exit_code == 0
    data = json.loads(target.read_text())
    assert float(result.stdout.split()[1]) == pytest.approx(data["writhe"], rel=1e-14)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.json")]


# ------------------------------------------------------------------------ demo


def test_demo_writes_files_and_never_overwrites(runner, tmp_path, monkeypatch):
    """The full demo through the console script, then a refused and a forced rerun.

    Oracles: Michell's points (A/C) sqrt(m^2 - 1) on the circle, Lk = Tw + Wr
    at every point (twist from frames, writhe from the double sum), no
    penetration on the contact branches, alpha's first contact close to the
    figure eight (writhe just below 1) and before it in dLk.
    """
    out = tmp_path / "demo"
    first = subprocess.run(
        [sys.executable, "-m", "supercoil.cli.main", "demo", "--out", out],
        check=False,
        capture_output=True,
        text=True,
        timeout=600,
    )
    data = json.loads((out / "diagram.json").read_text())
    # exit 1 exactly when a branch stopped early, and then the message names them
    stopped = [b["name"] for b in data["branches"] if not b["ok"]]
    assert first.returncode == (1 if stopped else 0), first.stderr
    if stopped:
        assert "incomplete: branch(es) " + ", ".join(stopped) in first.stderr
    assert all(b["ok"] for b in data["branches"] if b["name"] in ("circle", "alpha"))
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(diagram_output.DIAGRAM_FILES)
    assert str(out.resolve()) in first.stdout
    for name in diagram_output.DIAGRAM_FILES[2:]:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    for key in ENVELOPE:
        assert key in data
    assert data["twist_ratio"] == pytest.approx(2 / 3)
    assert data["length_over_diameter"] == 122
    assert data["n_nodes"] == demo_module.N_NODES == data["provenance"]["n_nodes"]
    names = [b["name"] for b in data["branches"]]
    assert names == ["circle", "alpha", "alpha_contact", "beta", "beta_contact"]
    for b in data["branches"]:
        assert (out / b["file"]).is_file()
    circle = sorted(p["excess_link"] for p in data["special_points"]
                    if p["branch"] == "circle" and p["kind"] == "bifurcation")
    for m, value in zip((2, 3), circle):
        assert value == pytest.approx(1.5 * math.sqrt(m * m - 1), rel=2e-3)
    for point in data["points"]:
        assert abs(point["twist"] + point["writhe"] - point["excess_link"]) < 1e-8
        if point["branch"].endswith("_contact"):
            assert point["min_gap_over_diameter"] >= 1 - 1e-9
    onset = next(p for p in data["special_points"]
                 if p["branch"] == "alpha" and p["kind"] == "contact_onset")
    assert 0.8 < onset["writhe"] < 1.0 and onset["excess_link"] < circle[0]
    # Coleman & Swigon 2002: the primary branch of mode m has D_m symmetry (off the circle)
    for name, group in (("alpha", "D2"), ("beta", "D3")):
        groups = {p["symmetry"] for p in data["points"] if p["branch"] == name}
        assert groups <= {group, "O(2)"} and group in groups, (name, groups)

    before = {p: p.read_bytes() for p in out.rglob('*') if p.is_file()}
    second = invoke(runner, "demo", "--out", out)
    assert_one_line_error(second, "--out", "not empty", "--overwrite")
    assert {p: p.read_bytes() for p in out.rglob('*') if p.is_file()} == before

    # --overwrite reuses the folder (the computation itself is stubbed: it ran above).
    calls = []
    monkeypatch.setattr(demo_module, "run_demo",
                        lambda folder, quiet=False, stored=None: calls.append(folder) or True)
    (out / "notes.txt").write_text("mine")
    forced = invoke(runner, "demo", "--out", out, "--overwrite")
    assert forced.exit_code == 0, forced.stderr
    assert calls == [out]
    assert (out / "notes.txt").read_text() == "mine"


def test_demo_default_folder_is_always_new(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    made = [demo_module.prepare_folder(None, overwrite=False)[0] for _ in range(3)]
    assert [p.name for p in made] == ["supercoil-demo", "supercoil-demo-2", "supercoil-demo-3"]
    assert all(p.is_dir() for p in made)


# --------------------------------------------------------------- JSON envelope


def test_envelope_and_write_json_round_trip(tmp_path, capsys):
    payload = {
        "energy": np.float64(1.5),
        "unstable_count": np.int64(2),
        "stable": np.bool_(False),
        "points": np.arange(6.0).reshape(2, 3),
        "residual": float("nan"),
    }
    data = envelope(payload, n_nodes=np.int64(12), tolerances={"zero_modes": 1e-6})
    assert list(data)[:2] == ["schema_version", "units"]
    target = tmp_path / "r.json"
    write_json(data, target)
    back = json.loads(target.read_text())
    assert back["energy"] == 1.5 and back["unstable_count"] == 2 and back["stable"] is False
    assert back["points"] == [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]
    assert back["residual"] is None  # strict JSON has no NaN
    assert back["provenance"]["n_nodes"] == 12
    assert back["provenance"]["tolerances"] == {"zero_modes": 1e-6}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json"]  # no temporary left
    write_json(data, "-")
    assert json.loads(capsys.readouterr().out) == back
    with pytest.raises(ValueError, match="reserved"):
        envelope({"units": "pN"}, n_nodes=3, tolerances={})
    with pytest.raises(OSError):
        write_json(data, tmp_path / "missing" / "r.json")
