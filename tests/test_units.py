"""Tests of the DNA units preset (supercoil.units.dna). Every test has an oracle.

Oracles used here:

- hand-computed values: 3500 bp -> L = 3500 * 0.34 = 1190 nm, L/P_b = 1190/50 = 23.8,
  C/A = 95/50 = 1.9, Lk0 = 3500/10.5 = 333.33 turns, sigma = -0.06 -> dLk = -20.0,
  energy unit A/L = 50 nm kT / 1190 nm = 0.0420 kT, 1 pN -> F L^2/A = 1190^2/(50 * 4.11);
- round trips: every converter followed by its inverse returns its input;
- the salt table: the tabulated points come back exactly, the geometric mean of two
  neighbouring concentrations gives the arithmetic mean of their diameters (linear in
  log c), and the diameter decreases monotonically with the concentration;
- validation: bad input is an InputError (a ValueError) naming the field and its range.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math

import pytest

from supercoil.errors import InputError
from supercoil.units import (
    ATHERMAL_CAVEAT,
    DEFAULT_SALT_MM,
    EFFECTIVE_DIAMETER_TABLE,
    KT_REFERENCE_PN_NM,
    SALT_RANGE_MM,
    DNAPreset,
    effective_diameter_nm,
    ring_summary_in_dna_units,
)

PLASMID = DNAPreset(base_pairs=3500, superhelical_density=-0.06)


# ----------------------------------------------------------- hand-computed values


def test_plasmid_maps_to_the_hand_computed_model():
    p = PLASMID
    assert p.length_nm == pytest.approx(1190.0, rel=1e-15)
    assert p.length_over_persistence == pytest.approx(23.8, rel=1e-15)
    assert p.twist_ratio == pytest.approx(1.9, rel=1e-15)
    assert p.relaxed_link == pytest.approx(1000.0 / 3.0, rel=1e-15)
    assert p.excess_link == pytest.approx(-20.0, rel=1e-14)
    assert p.kT_pN_nm == 4.11
    assert p.bending_stiffness_pN_nm2 == pytest.approx(50 * 4.11, rel=1e-15)
    assert p.twist_stiffness_pN_nm2 == pytest.approx(95 * 4.11, rel=1e-15)
    # one unit of E L/A is A/L = P_b kT / L = 50/1190 kT
    assert p.energy_scale_kT == pytest.approx(50.0 / 1190.0, rel=1e-15)
    assert p.energy_to_kT(1.0) == pytest.approx(0.042016806722689, rel=1e-12)
    # 1 pN in units of A/L^2
    assert p.force_from_pN(1.0) == pytest.approx(1190.0**2 / (50 * 4.11), rel=1e-15)
    assert p.force_from_pN(1.0) == pytest.approx(6890.99757, rel=1e-9)
    assert p.torque_scale_pN_nm == pytest.approx(50 * 4.11 / 1190.0, rel=1e-15)
    # default salt 150 mM, between the 100 and 200 mM points, linear in log c
    assert p.salt_mM == DEFAULT_SALT_MM == 150.0
    expected = 5.0 + math.log(1.5) / math.log(2.0) * (3.8 - 5.0)
    assert p.effective_diameter_nm == pytest.approx(expected, rel=1e-15)
    assert p.length_over_diameter == pytest.approx(1190.0 / expected, rel=1e-15)
    assert p.ring_parameters() == {
        "twist_ratio": p.twist_ratio,
        "excess_link": p.excess_link,
        "length_over_diameter": p.length_over_diameter,
    }


def test_twisted_circle_energy_in_kT():
    """The relaxed circle's bending energy 2 pi^2 A/L is 2 pi^2 P_b/L kT at 298 K."""
    p = DNAPreset(base_pairs=3500)
    assert p.energy_to_kT(2 * math.pi**2) == pytest.approx(2 * math.pi**2 * 50 / 1190,
                                                           rel=1e-14)


def test_options_change_the_ratios():
    p = DNAPreset(base_pairs=1050, superhelical_density=0.05, twist_persistence_nm=100.0,
                  diameter_nm=10.0)
    assert p.twist_ratio == pytest.approx(2.0, rel=1e-15)
    assert p.relaxed_link == pytest.approx(100.0, rel=1e-15)
    assert p.excess_link == pytest.approx(5.0, rel=1e-15)
    assert p.salt_mM is None
    assert p.effective_diameter_nm == 10.0
    assert p.length_over_diameter == pytest.approx(1050 * 0.34 / 10.0, rel=1e-15)


def test_temperature_scales_kT_only():
    """A and C stay those of 298 K; kT = 4.11 T/298, so only values in kT change."""
    cold, warm = DNAPreset(base_pairs=2000, superhelical_density=-0.05), DNAPreset(
        base_pairs=2000, superhelical_density=-0.05, temperature_K=310.0)
    assert warm.kT_pN_nm == pytest.approx(KT_REFERENCE_PN_NM * 310.0 / 298.0, rel=1e-15)
    assert warm.ring_parameters() == cold.ring_parameters()
    assert warm.bending_stiffness_pN_nm2 == cold.bending_stiffness_pN_nm2
    assert warm.force_scale_pN == cold.force_scale_pN
    assert warm.torque_scale_pN_nm == cold.torque_scale_pN_nm
    assert warm.energy_to_kT(7.0) == pytest.approx(cold.energy_to_kT(7.0) * 298.0 / 310.0,
                                                   rel=1e-15)


# -------------------------------------------------------------------- round trips


@pytest.mark.parametrize("value", [-3.5, -1e-3, 0.0, 0.25, 1.0, 42.0, 1e6])
@pytest.mark.parametrize("preset", [
    PLASMID,
    DNAPreset(base_pairs=200, superhelical_density=0.1, salt_mM=10.0, temperature_K=277.0),
    DNAPreset(base_pairs=48502, diameter_nm=2.0, twist_persistence_nm=110.0),
])
def test_converters_round_trip(preset, value):
    pairs = [
        (preset.length_to_nm, preset.length_from_nm),
        (preset.energy_to_kT, preset.energy_from_kT),
        (preset.force_to_pN, preset.force_from_pN),
        (preset.torque_to_pN_nm, preset.torque_from_pN_nm),
    ]
    for forward, backward in pairs:
        assert backward(forward(value)) == pytest.approx(value, rel=1e-14, abs=1e-300)
        assert forward(backward(value)) == pytest.approx(value, rel=1e-14, abs=1e-300)
    dlk = preset.superhelical_density * preset.relaxed_link
    assert preset.superhelical_density_of(dlk) == pytest.approx(
        preset.superhelical_density, rel=1e-14, abs=1e-300)


def test_scales_are_the_units_of_the_model():
    """F L^2/A, M L/A and f L^3/A: the physical value of one model unit, by dimensions."""
    p = PLASMID
    a, length = p.bending_stiffness_pN_nm2, p.length_nm
    assert p.force_to_pN(1.0) == pytest.approx(a / length**2, rel=1e-15)
    assert p.torque_to_pN_nm(1.0) == pytest.approx(a / length, rel=1e-15)
    assert p.force_per_length_to_pN_per_nm(1.0) == pytest.approx(a / length**3, rel=1e-15)
    assert p.length_to_nm(0.5) == pytest.approx(595.0, rel=1e-15)


# ---------------------------------------------------------------------- salt table


def test_salt_table_reproduces_its_points_exactly():
    for salt, diameter in EFFECTIVE_DIAMETER_TABLE:
        assert effective_diameter_nm(salt) == diameter
        assert DNAPreset(base_pairs=300, salt_mM=salt).effective_diameter_nm == diameter
    assert SALT_RANGE_MM == (EFFECTIVE_DIAMETER_TABLE[0][0], EFFECTIVE_DIAMETER_TABLE[-1][0])


def test_salt_table_interpolates_linearly_in_log_concentration():
    for (c0, d0), (c1, d1) in itertools.pairwise(EFFECTIVE_DIAMETER_TABLE):
        assert effective_diameter_nm(math.sqrt(c0 * c1)) == pytest.approx((d0 + d1) / 2,
                                                                          rel=1e-14)
        quarter = c0 * (c1 / c0) ** 0.25
        assert effective_diameter_nm(quarter) == pytest.approx(d0 + 0.25 * (d1 - d0),
                                                               rel=1e-14)


def test_salt_table_is_monotonic():
    lo, hi = SALT_RANGE_MM
    grid = [lo * (hi / lo) ** (k / 400) for k in range(401)]
    grid[-1] = hi  # exactly the last point (no round-off past the range)
    values = [effective_diameter_nm(c) for c in grid]
    assert all(b < a for a, b in itertools.pairwise(values))
    assert values[0] == EFFECTIVE_DIAMETER_TABLE[0][1]
    assert values[-1] == EFFECTIVE_DIAMETER_TABLE[-1][1]


@pytest.mark.parametrize("salt", [0.0, 5.0, 9.999, 200.001, 1000.0, -10.0])
def test_salt_outside_the_table_is_refused(salt):
    with pytest.raises(ValueError, match="outside the tabulated range 10-200 mM"):
        effective_diameter_nm(salt)
    with pytest.raises(ValueError, match="outside the tabulated range"):
        DNAPreset(base_pairs=1000, salt_mM=salt)


# ---------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"base_pairs": 0}, InputError, "base_pairs must be a whole number from 12 to"),
        ({"base_pairs": -5}, InputError, "base_pairs must be a whole number from 12 to"),
        ({"base_pairs": 10**8}, InputError, "from 12 to 10000000, got 100000000"),
        ({"base_pairs": 2.5}, InputError, "whole number"),
        ({"base_pairs": float("nan")}, InputError, "whole number"),
        ({"base_pairs": True}, InputError, "whole number"),
        ({"base_pairs": "100"}, InputError, "whole number"),
        ({"base_pairs": 20}, InputError, r"base_pairs = 20 .* L/D > pi: give base_pairs >= "),
        ({"superhelical_density": float("nan")}, InputError, "superhelical_density"),
        ({"superhelical_density": float("inf")}, InputError, "superhelical_density"),
        ({"superhelical_density": "-0.06"}, InputError, "superhelical_density"),
        ({"superhelical_density": -6.0}, InputError, "from -1 to 1, got -6.0"),
        ({"temperature_K": 0.0}, InputError, "temperature_K must be a number above 0"),
        ({"temperature_K": -273.0}, InputError, "temperature_K must be a number above 0"),
        ({"temperature_K": float("nan")}, InputError, "temperature_K"),
        ({"salt_mM": float("nan")}, InputError, "salt concentration"),
        ({"salt_mM": 100.0, "diameter_nm": 5.0}, InputError, "give one of them"),
        ({"diameter_nm": 0.0}, InputError, "diameter_nm must be a number above 0"),
        ({"diameter_nm": float("inf")}, InputError, "diameter_nm"),
        ({"bending_persistence_nm": 0.0}, InputError, "bending_persistence_nm"),
        ({"twist_persistence_nm": -95.0}, InputError, "twist_persistence_nm"),
        ({"rise_nm_per_bp": 0.0}, InputError, "rise_nm_per_bp"),
        ({"helical_repeat_bp": float("nan")}, InputError, "helical_repeat_bp"),
    ],
)
def test_bad_input_is_refused(kwargs, error, words):
    """Every field is checked, with its valid range (an InputError, a ValueError)."""
    arguments = {"base_pairs": 1000, **kwargs}
    with pytest.raises(error, match=words) as info:
        DNAPreset(**arguments)
    assert isinstance(info.value, ValueError)


def test_whole_float_base_pairs_become_int_and_the_preset_is_immutable():
    p = DNAPreset(base_pairs=3000.0)
    assert p.base_pairs == 3000 and isinstance(p.base_pairs, int)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.base_pairs = 10  # type: ignore[misc]


# ------------------------------------------------------------------- JSON helpers


def test_record_lists_every_constant_and_is_json():
    record = PLASMID.record()
    json.dumps(record, allow_nan=False)
    assert record["name"] == "dna"
    for key, value in [("rise_nm_per_bp", 0.34), ("helical_repeat_bp", 10.5),
                       ("bending_persistence_nm", 50.0), ("twist_persistence_nm", 95.0),
                       ("kT_reference_pN_nm", 4.11), ("reference_temperature_K", 298.0)]:
        assert record[key] == value
    assert record["salt_table_mM_nm"] == [list(point) for point in EFFECTIVE_DIAMETER_TABLE]
    assert "not verified" in record["salt_table_note"]
    assert record["athermal"] == ATHERMAL_CAVEAT
    assert "athermal" in PLASMID.conventions()
    assert "zero temperature" in ATHERMAL_CAVEAT and "buckling torques" in ATHERMAL_CAVEAT


def test_ring_summary_gains_suffixed_keys_and_keeps_the_nondimensional_ones():
    p = DNAPreset(base_pairs=1000, superhelical_density=-0.04, salt_mM=100.0)
    summary = {
        "twist_ratio": p.twist_ratio, "excess_link": p.excess_link, "energy": 150.0,
        "energy_circle_exact": 500.0, "michell_threshold_exact": math.sqrt(3) / 1.9,
        "min_gap_over_diameter": 1.002,
        "contacts": [{"s1": 0.1, "s2": 0.6, "force": 700.0}],
        "contact_points": [{"s1": 0.1, "s2": 0.6, "force": 700.0}],
        "contact_intervals": [{"s1_start": 0.2, "s1_end": 0.3, "s2_start": 0.7,
                               "s2_end": 0.8, "force_per_length": 9000.0}],
    }
    before = json.dumps(summary)
    out = ring_summary_in_dna_units(summary, p)
    assert json.dumps(summary) == before  # input untouched
    for key, value in summary.items():
        if key not in ("contacts", "contact_points", "contact_intervals"):
            assert out[key] == value
    a = 50 * 4.11  # pN nm^2
    assert out["length_nm"] == pytest.approx(340.0, rel=1e-15)
    assert out["diameter_nm"] == 5.0  # the 100 mM point of the table
    assert out["energy_kT"] == pytest.approx(150.0 * a / 340.0 / 4.11, rel=1e-14)
    assert out["energy_circle_exact_kT"] == pytest.approx(500.0 * 50 / 340, rel=1e-14)
    assert out["superhelical_density"] == -0.04
    assert out["michell_threshold_superhelical_density"] == pytest.approx(
        math.sqrt(3) / 1.9 / (1000 / 10.5), rel=1e-14)
    assert out["min_gap_nm"] == pytest.approx(1.002 * 5.0, rel=1e-15)
    for key in ("contacts", "contact_points"):
        (entry,) = out[key]
        assert entry["force"] == 700.0
        assert entry["force_pN"] == pytest.approx(700.0 * a / 340.0**2, rel=1e-14)
    (interval,) = out["contact_intervals"]
    assert interval["force_per_length"] == 9000.0
    assert interval["force_per_length_pN_per_nm"] == pytest.approx(9000.0 * a / 340.0**3,
                                                                   rel=1e-14)
    assert ring_summary_in_dna_units({**summary, "min_gap_over_diameter": None},
                                     p)["min_gap_nm"] is None
