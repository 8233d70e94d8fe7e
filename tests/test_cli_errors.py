"""Errors of the ``supercoil`` command: bad input, parse errors and failures all end as
one ``error:`` line on standard error, with exit status 2 (bad input) or 1 (a failure
of the computation), before any work or write. The oracle is that contract
(docs/model.md, "Files and exit statuses") and the bounds the library states.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import (
    assert_one_line,
    assert_one_line_error,
    invoke,
    run,
    run_main,
    tight_trefoil,
    write_curve,
)

from supercoil import __version__

# ------------------------------------------------------------------- bad input


def _bad_files(tmp_path: Path) -> dict[str, Path]:
    files = {
        "malformed": "0 0 0\n1 0\n1 1 0\n",
        "words": "0 0 0\n1 zero 0\n1 1 0\n",
        "nan": "0 0 0\n1 0 0\nnan 1 0\n",
        "two": "0 0 0\n1 0 0\n",
        "empty": "# nothing here\n\n",
        "repeated": "0 0 0\n1 0 0\n1 1 0\n0 0 0\n",
    }
    paths = {}
    for name, text in files.items():
        paths[name] = tmp_path / f"{name}.txt"
        paths[name].write_text(text)
    paths["binary"] = tmp_path / "binary.txt"
    paths["binary"].write_bytes(b"\xff\xfe\x00\x01")
    paths["trefoil"] = write_curve(tmp_path / "trefoil.txt", tight_trefoil(), "trefoil")
    return paths


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["ring", "--twist-ratio", "0", "--excess-link", "1"], ["--twist-ratio", "above 0"]),
        (["ring", "--twist-ratio", "-1", "--excess-link", "1"], ["--twist-ratio"]),
        (["ring", "--twist-ratio", "nan", "--excess-link", "1"], ["--twist-ratio"]),
        (["ring", "--twist-ratio", "inf", "--excess-link", "1"], ["--twist-ratio"]),
        (["ring", "--twist-ratio", "1", "--excess-link", "nan"], ["--excess-link", "finite"]),
        (["ring", "--twist-ratio", "1", "--excess-link", "-inf"], ["--excess-link"]),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1", "--nodes", "7"],
            ["--nodes", "8 to 100000", "got 7"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1", "--nodes", "100001"],
            ["--nodes", "8 to 100000", "got 100001"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1", "--nodes", "1000000000"],
            ["--nodes", "8 to 100000", "got 1000000000"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1e300"],
            ["--excess-link", "from -1e6 to 1e6", "1e+300"],
        ),
        (["ring", "--twist-ratio", "1", "--excess-link", "-2e6"], ["--excess-link", "1e6"]),
        (["ring", "--twist-ratio", "2e6", "--excess-link", "1"], ["--twist-ratio", "up to 1e6"]),
        (["ring", "--twist-ratio", "1e300", "--excess-link", "1"], ["--twist-ratio", "up to 1e6"]),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1", "--json", "{tmp}/no/such/r.json"],
            ["--json", "does not exist"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "1", "--json", "{tmp}"],
            ["--json", "folder"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "0"],
            ["--length-over-diameter", "above pi", "got 0.0"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "-1"],
            ["--length-over-diameter", "above pi", "got -1.0"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "3.0"],
            ["--length-over-diameter", "above pi (3.1416)", "got 3.0"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "nan"],
            ["--length-over-diameter", "finite", "got nan"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "inf"],
            ["--length-over-diameter", "finite", "got inf"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--length-over-diameter", "40",
             "--contact", "springs"],
            ["--contact", "'springs'", "barrier, augmented, penalty, exact"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "3", "--contact", "exact"],
            ["--contact", "needs --length-over-diameter"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--initial", "{tmp}/trefoil.txt"],
            ["--initial", "needs --length-over-diameter"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--length-over-diameter", "40",
             "--initial", "{tmp}/missing.txt"],
            ["--initial", "missing.txt", "no such file", "x y z"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--length-over-diameter", "40",
             "--initial", "{tmp}/malformed.txt"],
            ["--initial", "malformed.txt", "line 2", "3 numbers"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--length-over-diameter", "40",
             "--initial", "{tmp}/two.txt"],
            ["--initial", "two.txt", "at least 3 vertices"],
        ),
        (
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--length-over-diameter", "40",
             "--initial", "{tmp}/repeated.txt"],
            ["--initial", "repeated.txt", "do not repeat the first vertex"],
        ),
        (
            # the trefoil's closest approach of non-neighbours is about 0.21 L/D = 5 diameters
            # after scaling to L = 1 (the tube is far too thick for the knot)
            ["ring", "--twist-ratio", "1", "--excess-link", "0", "--length-over-diameter", "5",
             "--nodes", "40", "--initial", "{tmp}/trefoil.txt"],
            ["--initial", "trefoil.txt", "penetrates itself", "< D", "larger L/D"],
        ),
        (["writhe", "{tmp}/missing.txt"], ["missing.txt", "no such file"]),
        (["writhe", "{tmp}"], ["is a folder"]),
        (["writhe", "{tmp}/malformed.txt"], ["malformed.txt", "line 2", "3 numbers"]),
        (["writhe", "{tmp}/words.txt"], ["words.txt", "line 2"]),
        (["writhe", "{tmp}/nan.txt"], ["nan.txt", "line 3", "finite"]),
        (["writhe", "{tmp}/binary.txt"], ["binary.txt", "UTF-8"]),
        (["writhe", "{tmp}/two.txt"], ["two.txt", "at least 3"]),
        (["writhe", "{tmp}/empty.txt"], ["empty.txt", "no vertices"]),
        (["writhe", "{tmp}/repeated.txt"], ["repeated.txt", "do not repeat"]),
        (
            ["writhe", "{tmp}/two.txt", "--closure", "spiral"],
            ["--closure", "spiral", "closed, none, chord, axis"],
        ),
        (["writhe", "{tmp}/two.txt", "--closure", "axis", "--axis", "0,0,0"], ["--axis", "zero"]),
        (["writhe", "{tmp}/two.txt", "--closure", "axis", "--axis", "1,2"], ["--axis", "three"]),
        (["writhe", "{tmp}/two.txt", "--closure", "axis", "--axis", "a,b,c"], ["--axis"]),
        (["writhe", "{tmp}/two.txt", "--closure", "axis", "--axis", "0,0,inf"], ["--axis"]),
        (
            ["writhe", "{tmp}/two.txt", "--closure", "none", "--axis", "0,0,1"],
            ["--axis", "--closure axis", "'none'"],
        ),
        (["writhe", "{tmp}/two.txt", "--axis", "1,0,0"], ["--axis", "'closed'"]),
        (["writhe", "{tmp}/two.txt", "--closure", "chord", "--axis", "1,0,0"], ["'chord'"]),
        (["demo", "--out", "{tmp}/two.txt"], ["--out", "file"]),
        (
            ["diagram", "ring", "--twist-ratio", "2/3", "--length-over-diameter", "40",
             "--contact-formulation", "sum", "--out", "{tmp}/d"],
            ["--contact-formulation", "pairs, integral"],
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(runner, tmp_path, args, words):
    _bad_files(tmp_path)
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    result = invoke(runner, *args)
    assert_one_line_error(result, *words)
    assert result.stdout == ""


def test_bad_input_through_the_console_script(tmp_path):
    """The real process: stderr is one line, exit status 2, no traceback."""
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "supercoil.cli.main",
            "ring",
            "--twist-ratio",
            "-2",
            "--excess-link",
            "1",
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: --twist-ratio")
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["ring", "--twist-ratio", "1", "--excess-link", "0", "--nodes", "1e9"], ["'--nodes'"]),
        (["ring", "--twist-ratio", "abc", "--excess-link", "0"], ["'--twist-ratio'", "number"]),
        (["ring", "--excess-link", "0"], ["Missing option", "'--twist-ratio'"]),
        (["ring", "--twist-ratio", "1", "--excess-link", "0", "--bogus"], ["--bogus"]),
        (["ring", "--twist-ratio"], ["--twist-ratio", "requires an argument"]),
        (["rng"], ["No such command", "ring"]),
        (["writhe"], ["Missing argument", "FILE"]),
    ],
)
def test_parse_errors_are_one_line_and_exit_2(capsys, args, words):
    """typer/click's own errors: one ``error:`` line naming the command's help, no box."""
    status, out, err = run_main(capsys, *args)
    assert_one_line(status, out, err, 2, *words)
    assert "--help'" in err
    assert out == ""


def test_help_and_version_through_the_entry_point(capsys):
    status, out, err = run_main(capsys, "--help")
    assert status == 0 and "ring" in out and err == ""
    status, out, err = run_main(capsys, "ring", "--help")
    assert status == 0 and "--twist-ratio" in out and err == ""
    status, out, err = run_main(capsys, "--version")
    assert status == 0 and out.strip() == f"supercoil {__version__}" and err == ""
    status, out, _ = run_main(
        capsys, "ring", "--twist-ratio", "1", "--excess-link", "0.5", "--nodes", "16", "--json", "-"
    )
    assert status == 0 and json.loads(out)["converged"] is True


@pytest.mark.parametrize("group, commands", [((), ("ring", "diagram")), (("diagram",), ("ring",))])
def test_a_group_without_its_command_prints_its_help_and_exits_2(capsys, group, commands):
    status, out, err = run_main(capsys, *group)
    assert status == 2 and err == ""
    assert "Usage" in out and all(command in out for command in commands)


def test_unexpected_exception_is_one_line_internal_error(capsys, monkeypatch):
    """A bug ends as one line with exit status 1; SUPERCOIL_DEBUG=1 re-raises it."""
    from supercoil.problems import ring as ring_module

    def broken(*args, **kwargs):
        raise OverflowError("math range\nerror")

    monkeypatch.setattr(ring_module, "solve_ring", broken)
    monkeypatch.delenv("SUPERCOIL_DEBUG", raising=False)
    args = ("ring", "--twist-ratio", "1", "--excess-link", "0.5", "--nodes", "16")
    status, out, err = run_main(capsys, *args)
    assert_one_line(status, out, err, 1)
    assert err.strip() == ("error: internal error: OverflowError: math range error (please report)")
    monkeypatch.setenv("SUPERCOIL_DEBUG", "1")
    with pytest.raises(OverflowError):
        run([*args])


def test_runtime_warnings_stay_off_stderr(capsys, monkeypatch):
    """numpy's overflow warnings from rejected trial steps do not reach stderr (one line
    per error is the contract); SUPERCOIL_DEBUG=1 shows them."""
    from supercoil.problems import ring as ring_module

    real = ring_module.solve_ring

    def noisy(*args, **kwargs):
        np.float64(1e308) * 10  # RuntimeWarning: overflow encountered
        return real(*args, **kwargs)

    monkeypatch.setattr(ring_module, "solve_ring", noisy)
    monkeypatch.delenv("SUPERCOIL_DEBUG", raising=False)
    args = ("ring", "--twist-ratio", "1", "--excess-link", "0.5", "--nodes", "16", "--json", "-")
    status, out, err = run_main(capsys, *args)
    assert status == 0 and err == "" and json.loads(out)["converged"] is True
    monkeypatch.setenv("SUPERCOIL_DEBUG", "1")
    with pytest.warns(RuntimeWarning, match="overflow"):
        status, _, _ = run_main(capsys, *args)
    assert status == 0


@pytest.mark.parametrize(
    ("message", "expected"),
    [
        (
            "converged; warning: under-resolved, N < 20; warning: second",
            "warning: under-resolved, N < 20; second",
        ),
        ("Warning: twist per edge 0.9 rad\nraise N", "warning: twist per edge 0.9 rad raise N"),
        ("converged", None),
        ("no warnings here", None),
    ],
)
def test_ring_message_warning_goes_to_stderr(runner, monkeypatch, message, expected):
    """A result message with the word warning becomes a ``warning:`` line; status unchanged."""
    from supercoil.problems import ring as ring_module

    real = ring_module.solve_ring

    def warned(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), message=message)

    monkeypatch.setattr(ring_module, "solve_ring", warned)
    result = invoke(runner, "ring", "--twist-ratio", "1", "--excess-link", "0.5", "--nodes", "16")
    assert result.exit_code == 0
    if expected is None:
        assert result.stderr == ""
    else:
        assert result.stderr.splitlines() == [expected]


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--nodes", "1000000000"], ["--nodes", "8 to 100000"]),
        (["--nodes", "1e9"], ["'--nodes'"]),
        (["--excess-link", "1e300"], ["--excess-link", "1e6"]),
    ],
)
def test_bounds_through_the_console_script(args, words):
    """The real process refuses huge inputs at once: one line, exit 2, no traceback."""
    base = ["ring", "--twist-ratio", "1", "--excess-link", "0", "--nodes", "16"]
    result = subprocess.run(
        [sys.executable, "-m", "supercoil.cli.main", *base, *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert_one_line(result.returncode, result.stdout, result.stderr, 2, *words)
