"""The Cosserat rod behind the public API: rings, their diagram and tweezers.

Oracles: the section's stiffnesses from elasticity; the Kirchhoff limit of the
Michell and Greenhill thresholds found by the continuation, first order in 1/EA,
1/GA with the coefficient of the continuous circle's second variation; the exact
extension T L / EA of the straight rod; Lk = Tw + Wr along the diagram's branches;
the stability recomputed from the state against the solve's; the DNA preset's
stretch stiffness from its constants.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import supercoil as sc
from supercoil.cosserat import circle
from supercoil.cosserat.ring import michell_threshold
from supercoil.problems.cosserat_ring import cosserat_circle_branch, gap_curve
from supercoil.problems.greenhill import critical_turns
from supercoil.units.dna import DNAPreset


def test_default_stiffnesses_are_those_of_a_solid_circular_section():
    # E = 1, diameter d: A = E pi d^4 / 64, EA = E pi d^2 / 4, G = E / (2 (1 + nu)) and
    # Cowper's (1966) k = 6 (1 + nu) / (7 + 6 nu), GA = k G pi d^2 / 4 (L = 1)
    for slenderness, nu in ((100.0, 0.3), (20.0, 0.5), (40.0, 0.0)):
        d = 1.0 / slenderness
        A = math.pi * d**4 / 64
        EA = math.pi * d**2 / 4
        GA = 6 * (1 + nu) / (7 + 6 * nu) * math.pi * d**2 / (8 * (1 + nu))
        rod = sc.CosseratRod(0.8, slenderness=slenderness, poisson_ratio=nu)
        assert rod.stretch_stiffness == pytest.approx(EA / A, rel=1e-13)
        assert rod.shear_stiffness == pytest.approx(GA / A, rel=1e-13)
    given = sc.CosseratRod(0.8, 123.0, 456.0)
    assert (given.stretch_stiffness, given.shear_stiffness) == (123.0, 456.0)


def test_invalid_cosserat_problems_are_refused():
    with pytest.raises(sc.InputError, match="stretch_stiffness"):
        sc.CosseratRod(0.8, -1.0)
    with pytest.raises(sc.InputError, match="poisson_ratio"):
        sc.CosseratRod(0.8, poisson_ratio=0.7)
    rod = sc.CosseratRod(0.8, nodes=20)
    with pytest.raises(sc.InputError, match="knot"):
        sc.equilibrium(sc.Ring(rod, 1.0, contact=sc.Penalty(30.0), knot="3_1"))
    with pytest.raises(sc.InputError, match="branch_depth: the Cosserat ring's secondary "
                       "branches are followed with self-contact"):
        sc.ring_diagram(rod, branch_depth=2)
    with pytest.raises(sc.InputError, match="resume=True continues the result in out"):
        sc.tweezers(sc.Tweezers(rod, tension=1.0), resume=True)


def test_ring_equilibrium_and_its_recomputed_stability():
    C, n = 0.8, 24
    rod = sc.CosseratRod(C, 1e4, 1e4, nodes=n)
    below = sc.equilibrium(sc.Ring(rod, 1.0))
    above = sc.equilibrium(sc.Ring(rod, 2.6))
    assert below.status is sc.EquilibriumStatus.STABLE
    assert above.status is sc.EquilibriumStatus.UNSTABLE and above.unstable_count == 2
    for state in (below, above):
        assert state.link_error < 1e-10 and abs(state.writhe) < 1e-10
        assert state.record["model"] == "cosserat"
        again = sc.stability(state, n_modes=4)
        assert again.unstable_count == state.stability.unstable_count
        assert np.allclose(again.eigenvalues[:2], state.stability.eigenvalues[:2], rtol=1e-8)
        assert again.modes.shape[1:] == (n, 3)
    # the circle's strains are the continuous circle's (Gamma_3 stretch, |Gamma_1,2|
    # shear), to O(h^2)
    exact = circle.circle_state(C, 1.0, 1e4, 1e4)
    assert below.record["max_stretch_strain"] == pytest.approx(abs(exact.shear[2]), rel=0.05)
    assert below.record["max_shear_strain"] == pytest.approx(
        np.linalg.norm(exact.shear[:2]), rel=0.05)


def _circle_threshold(stiffness: float, n: int = 24) -> float:
    curve = gap_curve(n, 0.02)
    branch, _ = cosserat_circle_branch(0.8, n, 2.4, stiffness, stiffness, curve, link=2)
    (point,) = [p for p in branch.points_of_kind("bifurcation") if p.count_after == 2]
    return point.parameter


def test_michell_threshold_tends_to_the_kirchhoff_limit_at_first_order():
    # continuous circle (supercoil.cosserat.circle): dLk_2 = michell (1 + (C - 3A/2)
    # kappa^2 / GA - A kappa^2 / (2 EA)), so with GA = EA = S the shift is
    # michell (C - 2) kappa^2 / S: first order, ten times smaller per decade of S
    C, kappa2 = 0.8, (2 * np.pi) ** 2
    values = [_circle_threshold(s) for s in (1e4, 1e5, 1e6)]
    d1, d2 = values[0] - values[1], values[1] - values[2]
    assert d1 / d2 == pytest.approx(10.0, rel=0.01)
    limit = values[2] - d2 / 9  # Richardson in 1/S
    slope = (values[1] - limit) * 1e5
    assert slope == pytest.approx(limit * (C - 2) * kappa2, rel=0.02)
    # the limit is the discrete Kirchhoff-limit threshold (bisection on the count at
    # GA = EA = 1e8), Michell's to the discretisation's O(h^2)
    assert limit == pytest.approx(michell_threshold(C, 24, 2, 1e8, 1e8), rel=1e-5)
    assert limit == pytest.approx(np.sqrt(3) / C, rel=0.01)


def test_greenhill_onset_tends_to_the_kirchhoff_limit_and_tension_extends_by_t_over_ea():
    C, T, n = 0.8, 10.0, 16
    onsets = []
    for stiffness in (1e3, 1e4, 1e5):
        rod = sc.CosseratRod(C, stiffness, stiffness, nodes=n)
        run = sc.tweezers(sc.Tweezers(rod, tension=T), (0.0, 2.4), max_points=14)
        straight = run.branches["straight"]
        # the straight rod extends by exactly T L / EA, twisted or not
        assert np.allclose(straight.records["extension"], 1 + T / stiffness, rtol=0, atol=1e-12)
        assert np.max(straight.records["closure_error"]) < 1e-10
        (onset,) = [p for p in straight.points_of_kind("bifurcation") if p.count_before == 0]
        onsets.append(onset.parameter)
    d1, d2 = onsets[0] - onsets[1], onsets[1] - onsets[2]
    assert d1 / d2 == pytest.approx(10.0, rel=0.1)
    limit = onsets[2] - d2 / 9
    assert limit == pytest.approx(critical_turns(C, T), rel=0.01)
    buckled = run.branches["buckled"]
    assert len(buckled) >= 5 and np.all(buckled.unstable_count == 1)
    assert np.max(buckled.records["closure_error"]) < 1e-8
    assert run.computed.model["model"] == "cosserat"


def test_ring_diagram_keeps_the_link_along_its_primary_branch():
    rod = sc.CosseratRod(0.8, 1e4, 1e4, nodes=24, slenderness=30.0)
    diagram = sc.ring_diagram(rod, modes=(2,), max_excess_link=2.5, free_max_points=80)
    alpha = diagram.branches["alpha"]
    assert len(alpha) >= 10
    assert np.max(alpha.records["link_error"]) < 1e-8
    assert np.all(np.diff(np.abs(alpha.records["writhe"])) > 0)
    assert alpha.states.shape[1] == 3 * 24  # the centreline, as the outputs read it
    payload = diagram.computed.payload()
    assert payload["model"] == "cosserat" and payload["max_stretch_strain"] > 0
    (onset,) = [p for p in alpha.special_points if p.kind == "contact_onset"]
    # the onset: the closest approach of non-neighbouring points is the section's D
    assert onset.records["min_gap_over_diameter"] == pytest.approx(1.0, abs=1e-6)


def test_dna_preset_sets_the_measured_stretch_modulus():
    preset = DNAPreset(base_pairs=300)
    length = 300 * 0.34
    assert preset.stretch_stiffness == pytest.approx(1100.0 * length**2 / (50.0 * 4.11),
                                                     rel=1e-13)
    from supercoil.api.model import make_rod

    rod = make_rod("cosserat", preset.twist_ratio, 40, None, None, preset=preset)
    assert rod.stretch_stiffness == preset.stretch_stiffness
    assert rod.slenderness == pytest.approx(length / 2.0)
