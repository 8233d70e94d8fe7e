"""The study files in examples/ run (at small size) and pin one number each."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import supercoil
from supercoil.cli.main import run as cli
from supercoil.problems.greenhill import critical_turns

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def run_example(tmp_path, name, *overrides, stopped=()):
    """Run the example with ``overrides``; ``stopped``: the branches that then stop at
    their point limit (the run is incomplete: exit status 1, the file says which)."""
    out = tmp_path / name
    args = ["run", str(EXAMPLES / f"{name}.toml"), "--out", str(out), "--quiet",
            "--set", "outputs.figures=false"]
    for item in overrides:
        args += ["--set", item]
    assert cli(args) == (1 if stopped else 0)
    result = supercoil.load(out / "result.h5")
    assert result.status == ("incomplete" if stopped else "complete"), result.message
    for branch in stopped:
        assert branch in result.message, result.message
    return out, result


def bifurcations(summary, key):
    return [p[key] for p in summary["special_points"] if p["kind"] == "bifurcation"]


def test_ring_diagram_example(tmp_path):
    out, result = run_example(tmp_path, "ring_diagram", "rod.nodes=24",
                              "continuation.free_max_points=40",
                              "continuation.contact_max_points=5", stopped=["alpha_contact"])
    assert result.branch_names == ("circle", "alpha", "alpha_contact")
    summary = json.loads((out / "diagram.json").read_text())
    assert summary == result.summary
    # Michell: the circle loses stability to m = 2 at dLk = sqrt(3) A/C (O(h^2) at N = 24)
    first = bifurcations(summary, "excess_link")[0]
    assert first == pytest.approx(math.sqrt(3) / 0.6667, rel=1.5e-2)


def test_dna_plasmid_example(tmp_path):
    _out, result = run_example(tmp_path, "dna_plasmid", "rod.nodes=48",
                              "continuation.free_max_points=40",
                              "continuation.contact_max_points=5", stopped=["alpha_contact"])
    summary = result.summary
    assert summary["units"] == "dna" and summary["base_pairs"] == 600
    assert result.attributes["length_nm"] == pytest.approx(600 * 0.34)
    # Michell in superhelical density: sigma = sqrt(3) (P_b / P_t) / (bp / 10.5)
    exact = math.sqrt(3) * 50 / 95 / (600 / 10.5)
    assert summary["michell_superhelical_density"]["2"] == pytest.approx(exact, rel=1e-12)
    first = next(p for p in summary["special_points"] if p["kind"] == "bifurcation")
    assert first["superhelical_density"] == pytest.approx(exact, rel=5e-3)
    assert all("energy_kT" in p and "superhelical_density" in p for p in summary["points"])


def test_tweezers_example(tmp_path):
    # max_points bounds every branch (the contact branch needs 30 points here; a first
    # run of 30 points passed a bound of 12 before)
    out, result = run_example(tmp_path, "tweezers_hat_curve", "rod.nodes=16",
                              "continuation.max_points=40", "problem.turns=[0, 1.5]")
    summary = json.loads((out / "branch.json").read_text())
    assert summary == result.summary and not result.closed
    assert result.branch_names[:2] == ("straight", "buckled")
    # the straight rod buckles at the clamped Greenhill point (O(h^2) at N = 16)
    (turns,) = bifurcations(summary, "turns")
    assert turns == pytest.approx(critical_turns(4 / 3, 20.0), rel=6e-2)
