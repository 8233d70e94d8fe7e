"""The schema of a study file: its tables, their keys, the type each key takes, its
default, and the problem kinds and units presets it belongs to
(:mod:`supercoil.io.study` reads and validates a study against it).

Types only: the ranges are checked by the options and problems the study constructs
(:class:`~supercoil.problems.ring_diagram.DiagramOptions`,
:class:`~supercoil.problems.tweezers.TweezersOptions`, the ring's solver,
:class:`~supercoil.units.dna.DNAPreset`), which name the input; :data:`KEY_NAMES` turns
their names into the study's table and key.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from supercoil.io.study_model import MODELS

__all__ = ["KEY_NAMES", "PRESENTATION", "PROBLEM_KINDS", "REQUIRED_TABLES", "SCHEMA",
           "UNITS_PRESETS", "StudyKey", "type_name"]

PROBLEM_KINDS = ("ring_diagram", "ring", "tweezers")
UNITS_PRESETS = ("nondimensional", "dna")


# -- value checks: (type test, what is valid) ----------------------------------------------
def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def type_name(v) -> str:
    """What a TOML value is, in words (``"an integer"``, ``"a list"``, ...)."""
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, int):
        return "an integer"
    if isinstance(v, float):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


@dataclass(frozen=True)
class StudyKey:
    """One key of a study table: its type test, its default and where it applies."""

    valid: str  # what is valid, in words
    check: Callable[[Any], bool]
    default: Any = None  # or {kind: default} where the kinds differ
    kinds: tuple[str, ...] = PROBLEM_KINDS  # problem kinds the key belongs to
    presets: tuple[str, ...] = UNITS_PRESETS  # units presets the key belongs to
    convert: Callable[[Any], Any] = lambda v: v


def _real(v) -> bool:
    return _is_number(v)


def _choice(options: tuple[str, ...]):
    return lambda v: isinstance(v, str) and v in options


def _integers(v) -> bool:
    return isinstance(v, list) and all(_is_int(m) for m in v)


def _numbers(v) -> bool:
    return isinstance(v, list) and all(_is_number(x) for x in v)


_NUMBER, _INTEGER = "a number", "an integer"
_TURNS = "a list [start, stop] of numbers of turns"

SCHEMA: dict[str, dict[str, StudyKey]] = {
    "study": {
        "name": StudyKey("a string", lambda v: isinstance(v, str), ""),
        "description": StudyKey("a string", lambda v: isinstance(v, str), ""),
    },
    "units": {
        "preset": StudyKey(f"one of {', '.join(UNITS_PRESETS)}", _choice(UNITS_PRESETS),
                       "nondimensional"),
        "base_pairs": StudyKey("a whole number of base pairs", _is_int, presets=("dna",)),
        "salt_mM": StudyKey("a monovalent salt concentration in mM (a number)", _real,
                        presets=("dna",), convert=float),
        "diameter_nm": StudyKey("a tube diameter in nm (a number)", _real,
                            presets=("dna",), convert=float),
        "temperature_K": StudyKey("a temperature in kelvin (a number)", _real,
                              298.0, presets=("dna",), convert=float),
        "twist_persistence_nm": StudyKey("a twist persistence length in nm (a number)",
                                     _real, 95.0, presets=("dna",), convert=float),
    },
    "rod": {
        "twist_ratio": StudyKey("C/A, a number", _real, presets=("nondimensional",),
                            convert=float),
        "length_over_diameter": StudyKey("L/D, a number", _real, presets=("nondimensional",),
                                     convert=float),
        # tweezers: 100, or n0 under "dna" (filled in by _complete_tweezers)
        "nodes": StudyKey("an integer", _is_int, {"ring_diagram": 100, "ring": 100}),
        "model": StudyKey('"kirchhoff" or "cosserat"', _choice(MODELS)),
        "stretch_stiffness": StudyKey("EA L^2/A, a number", _real, convert=float),
        "shear_stiffness": StudyKey("GA L^2/A, a number", _real, convert=float),
    },
    "problem": {
        "kind": StudyKey(f"one of {', '.join(PROBLEM_KINDS)}", _choice(PROBLEM_KINDS)),
        "modes": StudyKey("a list of Michell modes (integers), like [2, 3]", _integers,
                      [2, 3], kinds=("ring_diagram",), convert=lambda v: sorted(v)),
        "max_excess_link": StudyKey("a number of turns", _real, 6.0, kinds=("ring_diagram",),
                                presets=("nondimensional",), convert=float),
        "max_superhelical_density": StudyKey("a positive superhelical density up to 1 (e.g. "
                                         "0.06)", lambda v: _real(v) and 0 < v <= 1, 0.06,
                                         kinds=("ring_diagram",), presets=("dna",),
                                         convert=float),
        "excess_link": StudyKey("a number of turns", _real, kinds=("ring",),
                            presets=("nondimensional",), convert=float),
        "superhelical_density": StudyKey("a superhelical density (ring: a number, e.g. -0.06; "
                                     "tweezers: a list [start, stop], e.g. [0, 0.06])",
                                     lambda v: _real(v) or _numbers(v),
                                     kinds=("ring", "tweezers"), presets=("dna",),
                                     convert=lambda v: float(v) if _real(v)
                                     else [float(x) for x in v]),
        "contact": StudyKey("a contact treatment", lambda v: isinstance(v, str), None,
                        kinds=("ring_diagram", "ring")),
        "tension": StudyKey("a force F L^2/A (load control)", _real, kinds=("tweezers",),
                        presets=("nondimensional",), convert=float),
        "end_distance": StudyKey("z/L (displacement control)", _real, kinds=("tweezers",),
                             presets=("nondimensional",), convert=float),
        "force_pN": StudyKey("a pulling force in pN (a number)", _real,
                         kinds=("tweezers",), presets=("dna",), convert=float),
        # [0, 5] unless given ("dna": or superhelical_density given), by _complete_tweezers
        "turns": StudyKey(_TURNS, _numbers, kinds=("tweezers",),
                      convert=lambda v: [float(x) for x in v]),
    },
    "continuation": {
        "free_max_step": StudyKey("a number (an arclength step, units of L)", _real,
                              {"ring_diagram": 0.1, "tweezers": 0.1},
                              kinds=("ring_diagram", "tweezers"), convert=float),
        "free_max_points": StudyKey(_INTEGER, _is_int, 80, kinds=("ring_diagram",)),
        "contact_max_step": StudyKey("a number (an arclength step, units of D)", _real, 0.5,
                                 kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_max_points": StudyKey(_INTEGER, _is_int, 150, kinds=("ring_diagram",)),
        "max_points": StudyKey("an integer (points per branch)", _is_int, 400,
                           kinds=("tweezers",)),
        "segment_points": StudyKey("an integer (the most points per continuation run; the "
                               "azimuth pin is checked at every point)", _is_int, 2000,
                               kinds=("tweezers",)),
        "event_tolerance": StudyKey("a number (an arclength tolerance)", _real, 1e-8,
                                kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_event_tolerance": StudyKey("a number (an arclength tolerance)", _real, 1e-6,
                                        kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_tolerance": StudyKey("a number (a residual tolerance)", _real, 1e-8,
                                  kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_gauge": StudyKey("true or false", lambda v: isinstance(v, bool), True,
                              kinds=("ring_diagram",)),
        "gauge": StudyKey('"node" or "integral"', _choice(("node", "integral")), "integral",
                      kinds=("ring_diagram",)),
        "branch_depth": StudyKey("1 (primary branches), 2 (and secondary) or 3 (and tertiary)",
                             _is_int, 1, kinds=("ring_diagram",)),
        "secondary_max_points": StudyKey("an integer (points per secondary half-branch)",
                                     _is_int, 40, kinds=("ring_diagram",)),
        "secondary_max_branches": StudyKey("an integer (secondary and tertiary half-branches "
                                       "in all)", _is_int, 12, kinds=("ring_diagram",)),
        "contact_formulation": StudyKey('"integral" or "pairs"', _choice(("integral", "pairs")),
                                    "integral", kinds=("ring_diagram",)),
        "contact_curve": StudyKey('"spline", "polygon" or "quintic"',
                              _choice(("spline", "polygon", "quintic")), "spline",
                              kinds=("ring_diagram",)),
        "contact_predictor": StudyKey('"quadratic", "tangent" or "secant"',
                                  _choice(("quadratic", "tangent", "secant")), "quadratic",
                                  kinds=("ring_diagram",)),
    },
    "outputs": {
        "figures": StudyKey("true or false", lambda v: isinstance(v, bool), True),
        "json": StudyKey("true or false", lambda v: isinstance(v, bool), True),
    },
}
# the names the options and problems give the study's keys -> "[table] key"
KEY_NAMES = {
    "twist_ratio": "[rod] twist_ratio", "length_over_diameter": "[rod] length_over_diameter",
    "n_nodes": "[rod] nodes", "treatment": "[problem] contact",
    "superhelical_density": "[problem] superhelical_density",
    "force_pN": "[problem] force_pN",
    **{key: f"[problem] {key}" for key in ("modes", "max_excess_link", "contact",
                                           "excess_link", "tension", "end_distance",
                                           "turns")},
    **{key: f"[units] {key}" for key in ("base_pairs", "salt_mM", "diameter_nm",
                                         "temperature_K", "twist_persistence_nm")},
    **{key: f"[continuation] {key}" for key in SCHEMA["continuation"]},
}
REQUIRED_TABLES = ("rod", "problem")
# the settings that do not change the computed numbers (ignored by --resume's comparison)
PRESENTATION = ("study", "outputs")
