"""Helpers of the command-line tests (test_cli*.py): run a command, read its JSON, write
curve files, and assert the one-line ``error:`` contract."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from supercoil.cli.main import app, run

ENVELOPE = ("schema_version", "units", "conventions", "provenance")
RING_KEYS = (
    "twist_ratio",
    "excess_link",
    "twist",
    "writhe",
    "link_error",
    "energy",
    "energy_circle_exact",
    "unstable_count",
    "zero_modes",
    "negative_eigenvalue_count",
    "determinant_sign",
    "lowest_eigenvalues",
    "stable",
    "converged",
    "status",
    "message",
    "residual",
    "newton_iterations",
    "n_nodes",
    "michell_threshold_exact",
)


def invoke(runner: CliRunner, *args: str):
    return runner.invoke(app, [str(a) for a in args], catch_exceptions=False)


def json_out(result) -> dict:
    assert result.exit_code == 0, result.stderr
    return json.loads(result.stdout)


def write_curve(path: Path, points: np.ndarray, header: str = "") -> Path:
    """Write ``(n, 3)`` points with a comment, a blank line and mixed separators."""
    lines = [f"# {header}", ""]
    for i, (x, y, z) in enumerate(points):
        sep = ", " if i % 2 else "\t"
        lines.append(f"{float(x)!r}{sep}{float(y)!r} {float(z)!r}  # vertex {i}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def trefoil(n: int = 90) -> np.ndarray:
    """A (2, 3) torus knot ``(n, 3)``: non-planar and chiral, |Wr| of order 3."""
    s = 2 * np.pi * np.arange(n) / n
    r = 2 + np.cos(3 * s)
    return np.stack([r * np.cos(2 * s), r * np.sin(2 * s), np.sin(3 * s)], axis=1)


def tight_trefoil(n: int = 120) -> np.ndarray:
    """A trefoil ``(n, 3)`` that is fairly tight at L/D = 40 (writhe about -3.05 there)."""
    t = 2 * np.pi * np.arange(n) / n
    return np.stack(
        [np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], axis=1
    )


def assert_one_line_error(result, *words: str) -> None:
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error:"), lines[0]
    assert "Traceback" not in result.stderr + result.stdout
    for word in words:
        assert word in lines[0], (word, lines[0])


def run_main(capsys, *args) -> tuple[int, str, str]:
    """The console script's entry point in-process: (exit status, stdout, stderr)."""
    status = run([str(a) for a in args])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def assert_one_line(status: int, out: str, err: str, expected: int, *words: str) -> None:
    assert status == expected, (status, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error:"), lines[0]
    for box in ("Traceback", "Usage", "\u256d", "Try '"):
        assert box not in err + out, (box, err)
    for word in words:
        assert word in lines[0], (word, lines[0])
