"""The numbered scripts in examples/ run (at small size) and pin one number each."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import supercoil as sc
from supercoil.problems.greenhill import critical_turns
from supercoil.units.tweezers import tweezers_parameters

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def example(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_numbered_script_is_tested():
    scripts = sorted(p.stem for p in EXAMPLES.glob("[0-9][0-9]_*.py"))
    assert scripts == ["01_ring_diagram", "02_dna_plasmid", "03_tweezers_hat_curve",
                       "04_own_energy", "05_cosserat_roll_up", "06_cosserat_twisted_rod"]


def test_ring_diagram_script_finds_michells_point(tmp_path):
    figure = tmp_path / "diagram.png"
    dlk = example("01_ring_diagram").main(nodes=24, max_excess_link=2.8,
                                          contact_max_points=5, figure=str(figure))
    assert dlk == pytest.approx(np.sqrt(3) * 1.5, rel=2e-2)  # O(h^2) at N = 24
    assert figure.stat().st_size > 10_000


def test_dna_plasmid_script_keeps_lk_equal_tw_plus_wr():
    assert example("02_dna_plasmid").main(base_pairs=500, sigma=-0.06, nodes=80) < 1e-8


def test_tweezers_script_buckles_at_greenhills_threshold():
    turns = example("03_tweezers_hat_curve").main(base_pairs=600, force_pN=0.5, nodes=48,
                                                  turns=2.2)
    numbers = tweezers_parameters(sc.DNAPreset(base_pairs=600, salt_mM=150), 0.5)
    exact = critical_turns(numbers["twist_ratio"], numbers["tension"])
    assert turns == pytest.approx(exact, rel=1e-2)


def test_own_energy_script_locates_the_pitchfork_at_zero():
    assert abs(example("04_own_energy").main()) < 1e-8


def test_cosserat_roll_up_script_closes_the_circle(tmp_path):
    # Simo & Vu-Quoc 1986: exact for any GA and EA, the discrete rod too (to round-off)
    figure = tmp_path / "roll_up.png"
    gap = example("05_cosserat_roll_up").main(elements=12, stretch_stiffness=50.0,
                                              shear_stiffness=20.0, figure=str(figure))
    assert gap < 1e-9
    assert figure.stat().st_size > 5_000


def test_cosserat_twisted_rod_script_buckles_at_greenhills_threshold():
    # Kirchhoff limit (EA = GA = 1e4 A/L^2: a shift of order 1e-3) at N = 16 (O(h^2))
    turns = example("06_cosserat_twisted_rod").main(nodes=16, max_points=12)
    assert turns == pytest.approx(critical_turns(0.8, 5.0), rel=1e-2)
