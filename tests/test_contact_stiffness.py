"""The tweezers' barrier stiffness: the rule ``max(A/h^3, F/(pi g_hat))`` and its factor.

Oracles: the crossing law of the integral barrier, exact for straight lines: two
strands crossing at the angle ``theta`` at the gap ``u g_hat`` are pushed apart by
``P = pi kappa g_hat (1 - u)^4 log(1/u) (1 + u g_hat/D) / sin(theta)`` (the energy
``2 pi / sin(theta) int psi(d - D) d dd / (2 D g_hat)`` differentiated in the distance),
checked against the kernel's energy by central differences; with the load rule's
stiffness a right-angle crossing carrying the load sits at the root of
``(1 - u)^4 log(1/u) (1 + u g_hat/D) = 1``. The problem's stiffness is the rule's times
the factor exactly; a stiffer barrier holds the strands at a larger gap, inside its
reach (1 % of D); and the mechanics of a hard-core tube does not depend on it beyond
the gap's change, so extension, torque and writhe at the last turn agree to within
that change over D.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import supercoil as sc
from supercoil.cli.main import run
from supercoil.contact.integral import integral_terms
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.sample_weights import polygon_weights
from supercoil.problems.tweezers import TweezersOptions, clamped_problem

REACH = 0.01  # the barrier acts on gaps below 1 % of D


def crossing_energy(theta: float, distance: float, stiffness: float, diameter: float,
                    g_hat: float, samples: int = 32) -> float:
    """The integral barrier's energy of two straight strands (9 nodes, 0.5 D apart)
    crossing at ``theta`` with their axes ``distance`` apart, ``samples`` a segment."""
    n = 9
    s = (np.arange(n) - (n - 1) / 2) * 0.5 * diameter
    a = np.stack([s, np.zeros(n), np.zeros(n)], 1)
    b = np.stack([s * np.cos(theta) + 0.11 * diameter, s * np.sin(theta),
                  np.full(n, -distance)], 1)
    seg = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    stencil = np.concatenate([seg, seg + n])
    pairs = np.array([[i, n - 1 + j] for i in range(n - 1) for j in range(n - 1)])
    return integral_terms(np.concatenate([a, b]), stencil,
                          polygon_weights(len(stencil), samples),
                          pairs, diameter, "barrier", stiffness, g_hat, 0.5 * diameter,
                          order=0)[0].sum()


def _crossing_force(theta, u, stiffness, diameter, g_hat):
    distance, step = diameter + u * g_hat, 1e-7 * g_hat
    return -(crossing_energy(theta, distance + step, stiffness, diameter, g_hat)
             - crossing_energy(theta, distance - step, stiffness, diameter, g_hat)) / (2 * step)


@pytest.mark.parametrize("theta", [np.pi / 2, 0.6])
@pytest.mark.parametrize("u", [0.05, 0.149, 0.3])
def test_the_crossing_law_of_the_integral_barrier(theta, u):
    diameter, g_hat, kappa = 0.02, 2e-4, 3.0
    law = (np.pi * kappa * g_hat * (1 - u) ** 4 * np.log(1 / u) * (1 + u * g_hat / diameter)
           / np.sin(theta))
    assert _crossing_force(theta, u, kappa, diameter, g_hat) == pytest.approx(law, rel=1e-4)


def test_under_the_load_rule_a_crossing_carrying_the_load_sits_at_its_root():
    diameter, load = 0.02, 5000.0
    options = ContactOptions(diameter=diameter, formulation="integral", force_scale=load)
    g_hat = options.barrier_activation * diameter
    kappa = options.default_stiffness(1.0, 0.02)
    assert kappa == pytest.approx(load / (np.pi * g_hat), rel=1e-12)  # above A/h^3 = 125000
    root = brentq(lambda u: (1 - u) ** 4 * np.log(1 / u) * (1 + u * g_hat / diameter) - 1,
                  1e-3, 0.9, xtol=1e-14)
    assert root == pytest.approx(0.149, abs=1e-3)
    assert _crossing_force(np.pi / 2, root, kappa, diameter, g_hat) == pytest.approx(
        load, rel=1e-4)


def test_the_rule_and_the_factor():
    kwargs = {"twist_ratio": 1.5, "length_over_diameter": 30, "n_nodes": 40}
    rod, _ = clamped_problem(TweezersOptions(tension=100.0, **kwargs))
    h = rod.rod.edge_length
    g_hat = REACH / 30

    def stiffness(**more):
        return ContactProblem(rod, TweezersOptions(**kwargs, **more).contact_options()
                              ).stiffness
    # A = 1: the bending rule's A/h^3; the load rule's max(A/h^3, F/(pi g_hat))
    assert stiffness(tension=100.0, contact_stiffness="bending") == pytest.approx(
        1.0 / h**3, rel=1e-12)
    assert stiffness(tension=1.0) == pytest.approx(1.0 / h**3, rel=1e-12)
    assert stiffness(tension=100.0) == pytest.approx(100.0 / (np.pi * g_hat), rel=1e-12)
    assert 100.0 / (np.pi * g_hat) > 1.0 / h**3
    assert stiffness(tension=100.0, contact_stiffness_scale=30.0) == pytest.approx(
        30.0 * stiffness(tension=100.0), rel=1e-12)
    # under displacement control the load is unknown: A/h^3
    assert stiffness(end_distance=0.9) == pytest.approx(1.0 / h**3, rel=1e-12)
    with pytest.raises(sc.InputError, match="contact_stiffness_scale"):
        TweezersOptions(tension=100.0, contact_stiffness_scale=0.0, **kwargs)
    with pytest.raises(sc.InputError, match="contact_stiffness"):
        TweezersOptions(tension=100.0, contact_stiffness="soft", **kwargs)


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


def test_the_command_line_takes_the_rule_and_the_scale(tmp_path):
    out = tmp_path / "run"
    status = run(["tweezers", "--twist-ratio", "1.5", "--tension", "100",
                  "--length-over-diameter", "30", "--nodes", "24", "--turns", "0:1",
                  "--contact-stiffness-scale", "30", "--out", str(out), "--quiet"])
    assert status == 0
    settings = sc.load(out).settings
    assert settings["contact_stiffness_scale"] == 30.0
    assert settings["contact_stiffness"] == "load"
    assert run(["tweezers", "--twist-ratio", "1.5", "--tension", "100",
                "--length-over-diameter", "30", "--turns", "0:1",
                "--contact-stiffness-scale", "0", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
    assert run(["tweezers", "--twist-ratio", "1.5", "--tension", "100",
                "--length-over-diameter", "30", "--turns", "0:1",
                "--contact-stiffness", "soft", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
