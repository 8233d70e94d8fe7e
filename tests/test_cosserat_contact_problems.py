"""The Cosserat rod's problems with self-contact: the ring, its diagram, tweezers.

Oracles: the Kirchhoff limit of the ring diagram's first contact (the contact onset
on alpha tends to the Kirchhoff rod's as EA and GA grow, at first order in their
inverses: a tenfold stiffness cuts the shift tenfold; the limit is the Kirchhoff
rod's to the two discretisations' O(h^2) difference); the gap is never negative at
an accepted point of a barrier branch; Lk = Tw + Wr (the Cosserat ring's twist from
its frames, the writhe from the double sum) and, in tweezers, turns = Tw + Wr
(Fuller's closure) at every point; the contact treatments agree on the ring's state;
the stability recomputed from a state equals the solve's.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import supercoil as sc
from supercoil.cli.main import app

C = 2 / 3  # the alpha branch of Coleman & Swigon 2000's Figure 1
LOD = 122.0
N = 40


def _diagram(rod, contact_points: int = 2):
    return sc.ring_diagram(rod, sc.Barrier(LOD), max_excess_link=4.0, modes=(2,),
                           contact_max_points=contact_points)


def _onset(diagram) -> float:
    (onset,) = [p for p in diagram.branches["alpha"].special_points
                if p.kind == "contact_onset"]
    assert onset.located
    return onset.parameter


@pytest.fixture(scope="module")
def stiff_diagram():
    """The Cosserat diagram at EA = GA = 1e5, alpha followed 40 points into contact."""
    return _diagram(sc.CosseratRod(C, 1e5, 1e5, nodes=N), contact_points=40)


def test_first_contact_tends_to_the_kirchhoff_limit_at_first_order(stiff_diagram):
    kirchhoff = _onset(_diagram(sc.Rod(C, nodes=N)))
    both = [_onset(_diagram(sc.CosseratRod(C, 1e4, 1e4, nodes=N))), _onset(stiff_diagram),
            _onset(_diagram(sc.CosseratRod(C, 1e6, 1e6, nodes=N)))]
    # f(S) = f_inf + c / S + O(1/S^2): the differences over decades of S fall tenfold
    # (measured 9.15: the O(1/S^2) term at S = 1e4)
    d1, d2 = both[0] - both[1], both[1] - both[2]
    assert d1 / d2 == pytest.approx(10.0, rel=0.15)
    # the extension alone (GA = 1e6 held): first order in 1/EA too (measured 10.4)
    stretch = [_onset(_diagram(sc.CosseratRod(C, s, 1e6, nodes=N))) for s in (1e4, 1e5)]
    assert (stretch[0] - stretch[1]) / (stretch[1] - both[2]) == pytest.approx(10.0, rel=0.15)
    # the limit (Richardson in 1/S) is the Kirchhoff rod's up to the difference of the two
    # discretisations, O(h^2): 0.0057 at N = 40 and 0.0093 at N = 32 (ratio 1.6, (40/32)^2
    # = 1.56), about 0.5 % here
    limit = both[2] - d2 / 9
    assert limit == pytest.approx(kirchhoff, rel=0.01)


def test_alpha_goes_on_with_contact_keeping_the_gap_and_the_link(stiff_diagram):
    contact = stiff_diagram.branches["alpha_contact"]
    records = contact.records
    assert len(contact) == 40 and contact.parent == "alpha"
    # the barrier: no accepted point touches, let alone penetrates
    assert np.all(records["min_gap_over_diameter"] > 1.0)
    assert np.max(records["link_error"]) < 1e-9
    first = next(p for p in contact.special_points if p.kind == "contact_onset")
    assert np.all(records["n_contact_points"][first.index + 1:]
                  + records["n_contact_intervals"][first.index + 1:] >= 1)
    # the rod shears and stretches where the contact pushes
    assert np.all(records["max_stretch_strain"] > 0) and np.all(records["max_shear_strain"] > 0)
    payload = stiff_diagram.computed.payload()
    assert payload["model"] == "cosserat"
    last = [p for p in payload["points"] if p["branch"] == "alpha_contact"][-1]
    assert len(last["contact_points"]) + len(last["contact_intervals"]) >= 1
    assert contact.states.shape[1] == 3 * N  # the centrelines, as the outputs read them


@pytest.fixture(scope="module")
def rings():
    """The Cosserat ring at dLk = 3 with self-contact, per treatment."""
    rod = sc.CosseratRod(C, 1e4, 1e4, nodes=32)
    return {c.treatment: sc.equilibrium(sc.Ring(rod, 3.0, c))
            for c in (sc.Barrier(60.0), sc.AugmentedLagrangian(60.0), sc.Penalty(60.0))}


def test_ring_with_contact_under_every_treatment(rings):
    for treatment, state in rings.items():
        assert state.status is sc.EquilibriumStatus.STABLE, (treatment, state.message)
        assert state.link_error < 1e-9
        assert state.contacts["n_contact_points"] + state.contacts["n_contact_intervals"] >= 1
        assert state.record["model"] == "cosserat"
        assert state.record["contact_treatment"] == treatment
        tolerance = state.tolerances["penetration_over_diameter"]
        assert state.record["max_penetration_over_diameter"] <= tolerance
    # one state: the treatments differ by their gap at contact (the barrier's stays
    # positive, within its activation of 1 % of D; the others penetrate within tolerance)
    writhes = [state.writhe for state in rings.values()]
    assert max(writhes) - min(writhes) < 2e-3
    assert rings["barrier"].contacts["min_gap_over_diameter"] > 1.0
    # the stability from the state alone (the barrier's energy is the solve's)
    again = sc.stability(rings["barrier"], n_modes=2)
    assert again.unstable_count == 0
    np.testing.assert_allclose(again.eigenvalues[:2],
                               rings["barrier"].stability.eigenvalues[:2], rtol=1e-8)


def test_ring_with_contact_on_the_command_line(runner, tmp_path, rings):
    path = tmp_path / "ring.json"
    result = runner.invoke(app, ["ring", "--twist-ratio", repr(C), "--excess-link", "3",
                                 "--length-over-diameter", "60", "--nodes", "32", "--model",
                                 "cosserat", "--stretch-stiffness", "1e4",
                                 "--shear-stiffness", "1e4", "--json", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    data = json.loads(path.read_text())
    data = data.get("summary", data)
    assert data["model"] == "cosserat" and data["contact_treatment"] == "barrier"
    assert data["writhe"] == pytest.approx(rings["barrier"].writhe, rel=1e-10)
    for key in ("n_contact_points", "n_contact_intervals", "max_stretch_strain",
                "max_shear_strain", "min_gap_over_diameter"):
        assert key in data


def test_tweezers_with_contact_reach_the_plectoneme():
    rod = sc.CosseratRod(0.8, 1e4, 1e4, nodes=40)
    run = sc.tweezers(sc.Tweezers(rod, tension=20.0, contact=sc.Barrier(25.0)), (0.0, 3.0))
    assert run.status is sc.RunStatus.COMPLETE, run.message
    contact = run.branches["buckled_contact"]
    assert contact.parameter_values[-1] == pytest.approx(3.0)
    records = contact.records
    assert np.all(records["min_gap_over_diameter"] > 1.0)
    # Fuller's closure with the clamps' frames: turns = Tw + Wr at every point
    assert np.max(records["closure_error"]) < 1e-8
    assert records["n_contact_points"][-1] + records["n_contact_intervals"][-1] >= 1
    # the plectoneme pulls the end in; the rod stretches under the contact forces
    assert records["extension"][-1] < 0.5 * run.branches["straight"].records["extension"][0]
    assert np.max(records["max_stretch_strain"]) > 20.0 / 1e4
    assert run.computed.model["model"] == "cosserat"
