"""The tweezers' barrier stiffness, ``contact_stiffness_scale`` times ``A/h^3``.

Oracles: the contact problem's stiffness is the scale times the default exactly; a
stiffer barrier holds the strands at a larger gap, inside its reach (1 % of D); and
the mechanics of a hard-core tube does not depend on it beyond the gap's change, so
extension, torque and writhe at the last turn agree to within that change over D.
"""

from __future__ import annotations

import pytest

import supercoil as sc
from supercoil.cli.main import run
from supercoil.contact.problem import ContactProblem
from supercoil.problems.tweezers import TweezersOptions, clamped_problem

REACH = 0.01  # the barrier acts on gaps below 1 % of D


def test_the_scale_multiplies_the_default_stiffness():
    options = TweezersOptions(twist_ratio=1.5, length_over_diameter=30, tension=100.0,
                              n_nodes=40)
    scaled = TweezersOptions(twist_ratio=1.5, length_over_diameter=30, tension=100.0,
                             n_nodes=40, contact_stiffness_scale=30.0)
    rod, _ = clamped_problem(options)
    default = ContactProblem(rod, options.contact_options()).stiffness
    h = rod.rod.edge_length
    assert default == pytest.approx(1.0 / h**3, rel=1e-12)  # A = 1
    assert ContactProblem(rod, scaled.contact_options()).stiffness == pytest.approx(
        30.0 * default, rel=1e-12)
    with pytest.raises(sc.InputError, match="contact_stiffness_scale"):
        TweezersOptions(twist_ratio=1.5, length_over_diameter=30, tension=100.0,
                        contact_stiffness_scale=0.0)


@pytest.fixture(scope="module")
def two_stiffnesses():
    problem = sc.Tweezers(sc.Rod(1.5, 40), tension=100.0,
                          contact=sc.Barrier(length_over_diameter=30))
    return {scale: sc.tweezers(problem, (0.0, 3.0), contact_stiffness_scale=scale)
            for scale in (1.0, 30.0)}


def test_a_stiffer_barrier_moves_the_contact_within_its_reach(two_stiffnesses):
    last = {}
    for scale, diagram in two_stiffnesses.items():
        assert diagram.ok, diagram.message
        branch = diagram.branches["buckled_contact"]
        assert branch.parameter_values[-1] == pytest.approx(3.0, abs=1e-12)
        last[scale] = {k: float(branch.records[k][-1]) for k in
                       ("extension", "torque", "writhe", "min_gap_over_diameter")}
    gap = {s: v["min_gap_over_diameter"] - 1.0 for s, v in last.items()}
    assert 0.0 < gap[1.0] < gap[30.0] < REACH
    moved = gap[30.0] - gap[1.0]  # the tube's effective diameter changed by this, over D
    for key in ("extension", "torque", "writhe"):
        assert last[30.0][key] == pytest.approx(last[1.0][key], rel=moved)


def test_the_command_line_takes_the_scale(tmp_path):
    out = tmp_path / "run"
    status = run(["tweezers", "--twist-ratio", "1.5", "--tension", "100",
                  "--length-over-diameter", "30", "--nodes", "24", "--turns", "0:1",
                  "--contact-stiffness-scale", "30", "--out", str(out), "--quiet"])
    assert status == 0
    assert sc.load(out).settings["contact_stiffness_scale"] == 30.0
    assert run(["tweezers", "--twist-ratio", "1.5", "--tension", "100",
                "--length-over-diameter", "30", "--turns", "0:1",
                "--contact-stiffness-scale", "0", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
