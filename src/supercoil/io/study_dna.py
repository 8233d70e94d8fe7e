"""The DNA preset of a study file (``[units] preset = "dna"``): its molecule and the
nondimensional numbers it derives.

:func:`complete_dna` fills in a validated study's settings (:mod:`supercoil.io.study`)
from the preset: ``[rod] twist_ratio`` and ``length_over_diameter``; a ring diagram's
``max_excess_link`` (σ_max · Lk0), a ring's ``excess_link`` (σ · Lk0); a tweezers study's
``tension`` (from ``force_pN``), ``turns`` (given, or ``superhelical_density`` ·
Lk0) and ``[rod] nodes`` (given, or n0), through
:func:`~supercoil.units.tweezers.dna_tweezers_inputs`, the check the command line
shares. Invalid input is an :class:`~supercoil.errors.InputError` naming the input as
the library does (``superhelical_density``) or, for a missing key, as the study does
(``[problem] force_pN``); the study renames the former and names the file.
"""

from __future__ import annotations

from collections.abc import Mapping

from supercoil.errors import InputError


def dna_preset(units: Mapping, problem: Mapping):
    """The :class:`~supercoil.units.dna.DNAPreset` of the ``[units]`` table (and, for a
    ring, the ``[problem]`` superhelical density)."""
    from supercoil.units.dna import DNAPreset

    sigma = problem.get("superhelical_density", 0.0) if problem["kind"] == "ring" else 0.0
    kwargs = {"base_pairs": units["base_pairs"], "superhelical_density": sigma,
              "salt_mM": units.get("salt_mM") if units.get("diameter_nm") is None else None,
              "diameter_nm": units.get("diameter_nm"),
              "temperature_K": units["temperature_K"],
              "twist_persistence_nm": units["twist_persistence_nm"]}
    return DNAPreset(**kwargs)


def complete_dna(s: dict, kind: str, default_turns: tuple[float, float]) -> None:
    """Check the DNA keys of the settings ``s`` of a ``kind`` study and add the numbers
    they derive (see the module docstring); ``default_turns``: a tweezers study's turns
    when neither they nor the superhelical density are given."""
    rod, problem, units = s["rod"], s["problem"], s["units"]
    if "base_pairs" not in units:
        raise InputError("[units] base_pairs is missing; the DNA preset needs the molecule's "
                         "length in base pairs, e.g. base_pairs = 1000")
    if "salt_mM" in units and "diameter_nm" in units:
        raise InputError("[units] salt_mM and diameter_nm both set the tube diameter; give one "
                         "of them")
    if kind == "ring" and "superhelical_density" not in problem:
        raise InputError("[problem] superhelical_density is missing; a DNA ring needs it, e.g. "
                         "superhelical_density = -0.06")
    if kind == "tweezers" and "force_pN" not in problem:
        raise InputError("[problem] force_pN is missing; DNA tweezers need the pulling force, "
                         "e.g. force_pN = 0.5")
    dna = dna_preset(units, problem)
    if "diameter_nm" not in units:
        units["salt_mM"] = float(dna.salt_mM)  # the default salt when none was given
    units["effective_diameter_nm"] = dna.effective_diameter_nm
    rod["twist_ratio"] = dna.twist_ratio
    rod["length_over_diameter"] = dna.length_over_diameter
    if kind == "ring_diagram":
        problem["max_excess_link"] = problem["max_superhelical_density"] * dna.relaxed_link
    elif kind == "ring":
        problem["excess_link"] = dna.excess_link
    else:
        from supercoil.units.tweezers import dna_tweezers_inputs

        numbers = dna_tweezers_inputs(dna, problem["force_pN"], turns=problem.get("turns"),
                                      superhelical_density=problem.get("superhelical_density"),
                                      n_nodes=rod.get("nodes"), default_turns=default_turns)
        problem["tension"] = numbers["tension"]
        problem["turns"] = list(numbers["turns"])
        rod["nodes"] = numbers["n_nodes"]
