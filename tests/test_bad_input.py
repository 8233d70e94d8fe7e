"""Bad input is refused before any work or any write: one ``error:`` line, exit status 2.

Oracles: the exit status and the single ``error:`` line (the command line's contract);
the file system (a refused input leaves no output folder behind, and the valid rerun is
then accepted); the wall clock and the size of what is read (an endless curve file, a
billion base pairs or a quasi-static path of 1e12 steps end at once); and a property-based
test feeding random options, strings and numbers to every command: the exit status is
0, 1 or 2, never a traceback or an internal error.
"""

from __future__ import annotations

import contextlib
import io
import os
import time
from pathlib import Path

import numpy as np
import pytest
import typer
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from supercoil.cli.main import run

LONG_NAME = "n" * 256

RING_STUDY = """
[rod]
twist_ratio = 1.0
nodes = 16
[problem]
kind = "ring"
excess_link = 0.5
[outputs]
figures = false
"""


def call(*args) -> tuple[int, str, str]:
    """Run the command in this process: (exit status, standard output, standard error)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = run([str(a) for a in args])
    return status, out.getvalue(), err.getvalue()


def refused(status: int, out: str, err: str, *words: str) -> str:
    """Assert one ``error:`` line and exit 2; return the line."""
    lines = err.strip().splitlines()
    assert status == 2, (status, out, err)
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in out + err and "internal error" not in err, err
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("inputs")
    paths = {"folder": root / "folder", "study": root / "ring.toml",
             "curve": root / "curve.txt", "collinear": root / "collinear.txt",
             "eight": root / "eight.txt", "binary": root / "binary.txt"}
    paths["folder"].mkdir()
    paths["study"].write_text(RING_STUDY)
    paths["curve"].write_text("0 0 0\n1 0 0\n1 1 0.2\n0 1 0\n")
    paths["collinear"].write_text("0 0 0\n1 0 0\n2 0 0\n")
    t = 2 * np.pi * np.arange(40) / 40
    eight = np.stack([np.sin(2 * t), np.sin(t), 0 * t], axis=1)
    paths["eight"].write_text("\n".join(" ".join(repr(float(c)) for c in p) for p in eight))
    paths["binary"].write_bytes(bytes(range(256)))
    status, _, err = call("run", paths["study"], "--out", root / "result", "--quiet")
    assert status == 0, err
    paths["result"] = root / "result" / "result.h5"
    return paths


# ----------------------------------------------------------------- the cases, one by one


def test_an_endless_curve_file_is_refused_at_once():
    """/dev/zero is read only up to the curve files' limit (16 MiB), not to memory's end."""
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    start = time.perf_counter()
    refused(*call("writhe", "/dev/zero"), "/dev/zero", "larger than 16 MiB")
    refused(*call("ring", "--twist-ratio", "1", "--excess-link", "1",
                  "--length-over-diameter", "40", "--initial", "/dev/zero"), "--initial")
    assert time.perf_counter() - start < 10


def test_a_256_character_name_is_refused_by_every_command(tmp_path, files):
    long = tmp_path / LONG_NAME
    cases = [
        ("writhe", long),
        ("ring", "--twist-ratio", "1", "--excess-link", "1", "--json", long),
        ("ring", "--twist-ratio", "1", "--excess-link", "1", "--length-over-diameter", "40",
         "--initial", long),
        ("demo", "--out", long),
        ("diagram", "ring", "--twist-ratio", "1", "--length-over-diameter", "40", "--out", long),
        ("tweezers", "--twist-ratio", "1", "--tension", "1", "--turns", "0:1", "--out", long),
        ("run", long),
        ("run", files["study"], "--out", long),
        ("export", long, "--out", tmp_path / "x.vtk"),
        ("export", files["result"], "--out", long),
        ("plot", long),
        ("plot", files["result"], "--out", long),
        ("view", long),
    ]
    for args in cases:
        refused(*call(*args), "255")
    assert list(tmp_path.iterdir()) == []


def test_collinear_initial_curve_is_refused(files):
    refused(*call("ring", "--twist-ratio", "1", "--excess-link", "1", "--length-over-diameter",
                  "40", "--initial", files["collinear"]), "--initial", "one straight line")


def test_a_self_intersecting_curve_has_no_writhe(files):
    """The lemniscate crosses itself at the origin: its writhe is undefined (exit 2)."""
    refused(*call("writhe", files["eight"]), "eight.txt", "intersects itself", "undefined")
    status, out, err = call("writhe", files["curve"])
    assert status == 0 and out.startswith("writhe "), err


def test_a_quasi_static_path_of_a_trillion_steps_is_refused_at_once(tmp_path):
    start = time.perf_counter()
    refused(*call("tweezers", "--twist-ratio", "4/3", "--tension", "20", "--turns", "0:1.6",
                  "--protocol", "up-down", "--step", "1e-12", "--out", tmp_path / "t"),
            "--step", "at most 100000")
    assert time.perf_counter() - start < 10
    assert not (tmp_path / "t").exists()


def test_result_file_that_is_a_folder_is_refused(tmp_path, files):
    out = tmp_path / "d"
    (out / "result.h5").mkdir(parents=True)
    for args in [("diagram", "ring", "--twist-ratio", "1", "--length-over-diameter", "40"),
                 ("tweezers", "--twist-ratio", "1", "--tension", "1", "--turns", "0:1"),
                 ("run", files["study"])]:
        refused(*call(*args, "--out", out, "--overwrite"), "result.h5", "not a file")
    assert sorted(p.name for p in out.iterdir()) == ["result.h5"]


def test_export_of_a_billion_base_pairs_is_refused_at_once(tmp_path, files):
    """--bp is bounded (1e7), and a PDB's bead count is checked before a bead is made."""
    start = time.perf_counter()
    refused(*call("export", files["result"], "--out", tmp_path / "x.pdb", "--bp",
                  "1000000000"), "--bp", "12 to 10000000")
    refused(*call("export", files["result"], "--out", tmp_path / "y.pdb", "--bp",
                  "10000000"), "--format pdb", "five digits")
    assert time.perf_counter() - start < 10
    assert list(tmp_path.iterdir()) == []


def test_a_refused_input_leaves_nothing_and_the_valid_rerun_is_accepted(tmp_path, files):
    out = tmp_path / "ring"
    for bad in ("problem.excess_link=1e300", "rod.nodes=7", "rod.twist_ratio=-1"):
        refused(*call("run", files["study"], "--out", out, "--set", bad, "--quiet"))
        assert not out.exists()
    for args in [("diagram", "ring", "--twist-ratio", "1", "--length-over-diameter", "2"),
                 ("diagram", "ring", "--twist-ratio", "1", "--length-over-diameter", "40",
                  "--modes", "2,13"),
                 ("tweezers", "--twist-ratio", "1", "--tension", "-1", "--turns", "0:1")]:
        refused(*call(*args, "--out", out))
        assert not out.exists()
    status, _, err = call("run", files["study"], "--out", out, "--quiet")
    assert status == 0, err
    assert (out / "result.h5").is_file()


# ------------------------------------------------------------- random input, every command

NUMBERS = ["0", "1", "-1", "2/3", "4/3", "1/0", "1e300", "-1e300", "nan", "inf", "-inf",
           "1e-12", "3.5", "40", "100000", "1000000000", "0:1", "5:1", "0:1e300", "0:nan",
           "2,3", "2,13", "1,2,3", "0,0,0", "0,0,1", "", " ", "abc", "--", "-", "1e6", "2e6"]
FILES = ["curve", "collinear", "eight", "binary", "folder", "study", "result", "missing",
         "long", "/dev/zero"]
OPTIONS = {
    ("writhe",): ["--closure", "--axis", "--json"],
    ("ring",): ["--twist-ratio", "--excess-link", "--nodes", "--length-over-diameter",
                "--contact", "--initial", "--dna", "--bp", "--sigma", "--salt-mM",
                "--diameter-nm", "--temperature-K", "--twist-persistence-nm", "--json",
                "--out", "--overwrite"],
    ("demo",): ["--out", "--overwrite", "--resume", "--quiet"],
    ("diagram", "ring"): ["--twist-ratio", "--length-over-diameter", "--out", "--nodes",
                          "--modes", "--max-excess-link", "--contact",
                          "--contact-max-points", "--branch-depth",
                          "--secondary-max-points", "--secondary-max-branches",
                          "--contact-curve", "--contact-formulation", "--overwrite", "--resume",
                          "--quiet"],
    ("tweezers",): ["--turns", "--out", "--twist-ratio", "--length-over-diameter",
                    "--tension", "--end-distance", "--nodes", "--protocol", "--step",
                    "--force-range", "--force-step", "--max-points", "--contact-curve",
                    "--contact-formulation", "--overwrite", "--dna", "--bp", "--force-pN",
                    "--sigma",
                    "--salt-mM", "--diameter-nm", "--temperature-K", "--resume", "--quiet"],
    ("run",): ["--out", "--resume", "--quiet", "--overwrite", "--json", "--set"],
    ("export",): ["--out", "--branch", "--point", "--format", "--sides", "--bp", "--overwrite"],
    ("plot",): ["--out", "--kind", "--format", "--overwrite"],
    ("view",): ["--out", "--overwrite"],
}
FLAGS = {"--dna", "--overwrite", "--quiet", "--resume"}
WORDS = ["barrier", "penalty", "exact", "augmented", "springs", "closed", "none", "chord",
         "axis", "up", "up-down", "force-ramp", "spline", "polygon", "quintic", "integral",
         "pairs", "png", "svg", "vtk", "pdb", "obj", "xyz", "circle", "ring",
         "rod.nodes=7", "problem.excess_link=1e300", "rod.nodes=many", "x.y=1", "nodes=3"]


def _stop(*_args, **_kwargs):
    """Stands in for the computation: the inputs passed validation (exit 0 here)."""
    raise typer.Exit(0)


@pytest.fixture(scope="module")
def fuzz_world(files, tmp_path_factory):
    """A working folder, the input files by name, and the computations replaced by _stop
    (the property is about validation; each case would otherwise start a computation)."""
    from supercoil.api import study_run
    from supercoil.cli import diagram_output, saving
    from supercoil.plotting import figures, viewer
    from supercoil.problems import ring, ring_contact

    work = tmp_path_factory.mktemp("fuzz")
    names = {key: str(value) for key, value in files.items()}
    names.update(missing=str(work / "missing.txt"), long=str(work / LONG_NAME))
    names["/dev/zero"] = "/dev/zero"

    checked_only = saving.prepare_folder

    def prepared_then_stop(out, **kwargs):
        checked_only(out, **{**kwargs, "create": False})
        raise typer.Exit(0)

    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(work)
        patch.setattr(ring, "twisted_circle_problem", _stop)
        patch.setattr(ring_contact, "twisted_circle_problem", _stop)
        patch.setattr(ring_contact, "Rod", _stop)
        patch.setattr(saving, "prepare_folder", prepared_then_stop)
        patch.setattr(diagram_output, "run_diagram", _stop)
        patch.setattr(study_run, "run_study", _stop)
        patch.setattr(figures, "plot_result", _stop)
        patch.setattr(viewer, "write_viewer", _stop)
        from supercoil.cli import demo

        patch.setattr(demo, "run_demo", _stop)
        yield names


@st.composite
def command_lines(draw, names: dict[str, str]):
    command = draw(st.sampled_from(sorted(OPTIONS)))
    value = st.one_of(st.sampled_from(NUMBERS), st.sampled_from(WORDS),
                      st.sampled_from(FILES).map(lambda k: names.get(k, k)),
                      st.floats(allow_nan=True, allow_infinity=True).map(repr),
                      st.integers(-10**12, 10**12).map(str),
                      st.text(max_size=12))
    args = list(command)
    if command in (("writhe",), ("run",), ("export",), ("plot",), ("view",)):
        args.append(draw(st.one_of(st.sampled_from(FILES).map(lambda k: names.get(k, k)),
                                   value)))
    for option in draw(st.lists(st.sampled_from(OPTIONS[command]), max_size=7)):
        args.append(option)
        if option not in FLAGS:
            args.append(draw(value))
    if draw(st.booleans()) and draw(st.booleans()):
        args.insert(draw(st.integers(0, len(args))), draw(value))  # a stray word
    return args


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture,
                                 HealthCheck.too_slow])
@given(data=st.data())
def test_random_input_never_ends_in_a_traceback(fuzz_world, data):
    args = data.draw(command_lines(fuzz_world))
    status, out, err = call(*args)
    assert status in (0, 1, 2), (args, status, err)
    assert "Traceback" not in out + err, (args, err)
    assert "internal error" not in err, (args, err)
    if status == 2:
        lines = err.strip().splitlines()
        assert lines and lines[-1].startswith("error:"), (args, err)
