"""Study files: a TOML file that describes a whole study (``supercoil run STUDY.toml``).

A study has six tables (``[study]`` and ``[continuation]`` optional)::

    [study]          name, description
    [units]          preset = "nondimensional" (default) or "dna"; with "dna":
                     base_pairs, salt_mM or diameter_nm, temperature_K,
                     twist_persistence_nm
    [rod]            twist_ratio (C/A), length_over_diameter (L/D), nodes
                     (under "dna" C/A and L/D follow from the preset: not given);
                     model = "kirchhoff" (default) or "cosserat", with
                     stretch_stiffness (EA L^2/A) and shear_stiffness (GA L^2/A)
    [problem]        kind = "ring_diagram", "ring" or "tweezers", and its keys (below)
    [continuation]   ring_diagram and tweezers: the step, length and tolerance options
                     of DiagramOptions / TweezersOptions (free_max_step, ...); for
                     ring_diagram also gauge, branch_depth, secondary_max_points,
                     secondary_max_branches, contact_formulation, contact_curve,
                     contact_predictor
    [outputs]        figures (PNG, default true), json (the JSON summary, true)

``[problem]`` keys: ``ring_diagram``: ``modes`` (list of Michell modes >= 2),
``max_excess_link`` (turns; "dna": ``max_superhelical_density``), ``contact``
(barrier or penalty). ``ring``: ``excess_link`` ("dna":
``superhelical_density``), ``contact`` (a treatment; needs L/D).
``tweezers``: ``tension`` (F L^2/A, load control) or ``end_distance`` (z/L,
displacement control) ("dna": ``force_pN``), ``turns`` = [start, stop] (default
[0, 5]; "dna": or ``superhelical_density`` = [start, stop], σ = turns · 10.5 / N_bp,
not both); without ``[rod] length_over_diameter`` the rod has no self-contact. Under
"dna" a tweezers study's ``[rod] nodes`` defaults to n0 = ceil(L/D) + 2, the fewest
whose segments are no longer than D (:func:`~supercoil.units.tweezers.resolving_nodes`);
otherwise to 100.

Every key is checked: an unknown or misspelled key, a key of another problem
kind or a wrong type here; a value out of range by the options and problems
the study constructs (:class:`~supercoil.problems.ring_diagram.DiagramOptions`,
:class:`~supercoil.problems.tweezers.TweezersOptions`, the ring's solver,
:class:`~supercoil.units.dna.DNAPreset`), so that a study and the command line
accept the same values. Either is a :class:`StudyError` (an
:class:`~supercoil.errors.InputError`) whose message is one line naming the
file, the table and key, what is wrong, what is valid, and the closest valid
key (``difflib``).

:func:`load_study` returns a frozen :class:`Study`; its ``settings`` are the
validated tables with every default filled in and, under the DNA preset, the
derived nondimensional numbers (``rod.twist_ratio``,
``rod.length_over_diameter``, ``problem.max_excess_link``); they are what a
result file stores and what ``--resume`` compares.
"""

from __future__ import annotations

import copy
import difflib
import tomllib
from collections.abc import Callable, Iterable, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from supercoil import checks
from supercoil.errors import InputError
from supercoil.io.study_model import MODELS, model_problem

PROBLEM_KINDS = ("ring_diagram", "ring", "tweezers")
DEFAULT_TURNS = (0.0, 5.0)  # a tweezers study's turns when neither they nor sigma are given
UNITS_PRESETS = ("nondimensional", "dna")


class StudyError(InputError):
    """A study file that cannot be run; one line naming the file, the key and the problem."""


# -- value checks: (type test, what is valid) ----------------------------------------------
def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _type_name(v) -> str:
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
class _Key:
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

# Types only: the ranges are checked by the options and problems the study constructs
# (DiagramOptions, TweezersOptions, the ring's solver, DNAPreset), which name the input;
# their messages are given here with the study's table and key.
_SCHEMA: dict[str, dict[str, _Key]] = {
    "study": {
        "name": _Key("a string", lambda v: isinstance(v, str), ""),
        "description": _Key("a string", lambda v: isinstance(v, str), ""),
    },
    "units": {
        "preset": _Key(f"one of {', '.join(UNITS_PRESETS)}", _choice(UNITS_PRESETS),
                       "nondimensional"),
        "base_pairs": _Key("a whole number of base pairs", _is_int, presets=("dna",)),
        "salt_mM": _Key("a monovalent salt concentration in mM (a number)", _real,
                        presets=("dna",), convert=float),
        "diameter_nm": _Key("a tube diameter in nm (a number)", _real,
                            presets=("dna",), convert=float),
        "temperature_K": _Key("a temperature in kelvin (a number)", _real,
                              298.0, presets=("dna",), convert=float),
        "twist_persistence_nm": _Key("a twist persistence length in nm (a number)",
                                     _real, 95.0, presets=("dna",), convert=float),
    },
    "rod": {
        "twist_ratio": _Key("C/A, a number", _real, presets=("nondimensional",),
                            convert=float),
        "length_over_diameter": _Key("L/D, a number", _real, presets=("nondimensional",),
                                     convert=float),
        # tweezers: 100, or n0 under "dna" (filled in by _complete_tweezers)
        "nodes": _Key("an integer", _is_int, {"ring_diagram": 100, "ring": 100}),
        "model": _Key('"kirchhoff" or "cosserat"', _choice(MODELS)),
        "stretch_stiffness": _Key("EA L^2/A, a number", _real, convert=float),
        "shear_stiffness": _Key("GA L^2/A, a number", _real, convert=float),
    },
    "problem": {
        "kind": _Key(f"one of {', '.join(PROBLEM_KINDS)}", _choice(PROBLEM_KINDS)),
        "modes": _Key("a list of Michell modes (integers), like [2, 3]", _integers,
                      [2, 3], kinds=("ring_diagram",), convert=lambda v: sorted(v)),
        "max_excess_link": _Key("a number of turns", _real, 6.0, kinds=("ring_diagram",),
                                presets=("nondimensional",), convert=float),
        "max_superhelical_density": _Key("a positive superhelical density up to 1 (e.g. "
                                         "0.06)", lambda v: _real(v) and 0 < v <= 1, 0.06,
                                         kinds=("ring_diagram",), presets=("dna",),
                                         convert=float),
        "excess_link": _Key("a number of turns", _real, kinds=("ring",),
                            presets=("nondimensional",), convert=float),
        "superhelical_density": _Key("a superhelical density (ring: a number, e.g. -0.06; "
                                     "tweezers: a list [start, stop], e.g. [0, 0.06])",
                                     lambda v: _real(v) or _numbers(v),
                                     kinds=("ring", "tweezers"), presets=("dna",),
                                     convert=lambda v: float(v) if _real(v)
                                     else [float(x) for x in v]),
        "contact": _Key("a contact treatment", lambda v: isinstance(v, str), None,
                        kinds=("ring_diagram", "ring")),
        "tension": _Key("a force F L^2/A (load control)", _real, kinds=("tweezers",),
                        presets=("nondimensional",), convert=float),
        "end_distance": _Key("z/L (displacement control)", _real, kinds=("tweezers",),
                             presets=("nondimensional",), convert=float),
        "force_pN": _Key("a pulling force in pN (a number)", _real,
                         kinds=("tweezers",), presets=("dna",), convert=float),
        # [0, 5] unless given ("dna": or superhelical_density given), by _complete_tweezers
        "turns": _Key(_TURNS, _numbers, kinds=("tweezers",),
                      convert=lambda v: [float(x) for x in v]),
    },
    "continuation": {
        "free_max_step": _Key("a number (an arclength step, units of L)", _real,
                              {"ring_diagram": 0.1, "tweezers": 0.1},
                              kinds=("ring_diagram", "tweezers"), convert=float),
        "free_max_points": _Key(_INTEGER, _is_int, 80, kinds=("ring_diagram",)),
        "contact_max_step": _Key("a number (an arclength step, units of D)", _real, 0.5,
                                 kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_max_points": _Key(_INTEGER, _is_int, 150, kinds=("ring_diagram",)),
        "max_points": _Key("an integer (points per branch)", _is_int, 400,
                           kinds=("tweezers",)),
        "segment_points": _Key("an integer (the most points per continuation run; the "
                               "azimuth pin is checked at every point)", _is_int, 2000,
                               kinds=("tweezers",)),
        "event_tolerance": _Key("a number (an arclength tolerance)", _real, 1e-8,
                                kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_event_tolerance": _Key("a number (an arclength tolerance)", _real, 1e-6,
                                        kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_tolerance": _Key("a number (a residual tolerance)", _real, 1e-8,
                                  kinds=("ring_diagram", "tweezers"), convert=float),
        "contact_gauge": _Key("true or false", lambda v: isinstance(v, bool), True,
                              kinds=("ring_diagram",)),
        "gauge": _Key('"node" or "integral"', _choice(("node", "integral")), "integral",
                      kinds=("ring_diagram",)),
        "branch_depth": _Key("1 (primary branches), 2 (and secondary) or 3 (and tertiary)",
                             _is_int, 1, kinds=("ring_diagram",)),
        "secondary_max_points": _Key("an integer (points per secondary half-branch)",
                                     _is_int, 40, kinds=("ring_diagram",)),
        "secondary_max_branches": _Key("an integer (secondary and tertiary half-branches "
                                       "in all)", _is_int, 12, kinds=("ring_diagram",)),
        "contact_formulation": _Key('"integral" or "pairs"', _choice(("integral", "pairs")),
                                    "integral", kinds=("ring_diagram",)),
        "contact_curve": _Key('"spline", "polygon" or "quintic"',
                              _choice(("spline", "polygon", "quintic")), "spline",
                              kinds=("ring_diagram",)),
        "contact_predictor": _Key('"quadratic", "tangent" or "secant"',
                                  _choice(("quadratic", "tangent", "secant")), "quadratic",
                                  kinds=("ring_diagram",)),
    },
    "outputs": {
        "figures": _Key("true or false", lambda v: isinstance(v, bool), True),
        "json": _Key("true or false", lambda v: isinstance(v, bool), True),
    },
}
# the names the options and problems give the study's keys -> "[table] key"
_KEY_NAMES = {
    "twist_ratio": "[rod] twist_ratio", "length_over_diameter": "[rod] length_over_diameter",
    "n_nodes": "[rod] nodes", "treatment": "[problem] contact",
    "superhelical_density": "[problem] superhelical_density",
    "force_pN": "[problem] force_pN",
    **{key: f"[problem] {key}" for key in ("modes", "max_excess_link", "contact",
                                           "excess_link", "tension", "end_distance",
                                           "turns")},
    **{key: f"[units] {key}" for key in ("base_pairs", "salt_mM", "diameter_nm",
                                         "temperature_K", "twist_persistence_nm")},
    **{key: f"[continuation] {key}" for key in _SCHEMA["continuation"]},
}
REQUIRED_TABLES = ("rod", "problem")
# the settings that do not change the computed numbers (ignored by --resume's comparison)
PRESENTATION = ("study", "outputs")


def _closest(word: str, valid: Iterable[str]) -> str:
    match = difflib.get_close_matches(word, list(valid), n=1, cutoff=0.6)
    return f" (did you mean {match[0]!r}?)" if match else ""


@dataclass(frozen=True)
class Study:
    """A validated study (see the module docstring). ``settings`` is plain data."""

    source: str
    text: str
    settings: dict

    @property
    def kind(self) -> str:
        return self.settings["problem"]["kind"]

    @property
    def units(self) -> str:
        return self.settings["units"]["preset"]

    @property
    def name(self) -> str:
        return self.settings["study"]["name"] or Path(self.source).stem

    def computed_settings(self) -> dict:
        """The settings that determine the numbers (what ``--resume`` compares)."""
        return {k: v for k, v in self.settings.items() if k not in PRESENTATION}

    def dna_preset(self):
        """The :class:`~supercoil.units.dna.DNAPreset` of a "dna" study, else None."""
        if self.units != "dna":
            return None
        from supercoil.io.study_dna import dna_preset

        return dna_preset(self.settings["units"], self.settings["problem"])

    def tweezers_options(self):
        """:class:`~supercoil.problems.tweezers.TweezersOptions` of a tweezers study."""
        from supercoil.problems.tweezers import TweezersOptions

        s = self.settings
        c = s["continuation"]
        return TweezersOptions(
            twist_ratio=s["rod"]["twist_ratio"],
            length_over_diameter=s["rod"].get("length_over_diameter"),
            tension=s["problem"].get("tension"), end_distance=s["problem"].get("end_distance"),
            turns=tuple(s["problem"]["turns"]), n_nodes=s["rod"]["nodes"],
            free_max_step=c["free_max_step"], contact_max_step=c["contact_max_step"],
            max_points=c["max_points"], segment_points=c["segment_points"],
            event_tolerance=c["event_tolerance"],
            contact_event_tolerance=c["contact_event_tolerance"],
            contact_tolerance=c["contact_tolerance"])

    def rod(self):
        """The study's :class:`supercoil.Rod` or :class:`supercoil.CosseratRod` (the
        Cosserat rod's section of the rod's L/D, or under the DNA preset its stretch
        modulus and the double helix's diameter)."""
        from supercoil.api.model import make_rod

        rod = self.settings["rod"]
        return make_rod(rod.get("model", "kirchhoff"), rod["twist_ratio"], rod["nodes"],
                        rod.get("stretch_stiffness"), rod.get("shear_stiffness"),
                        slenderness=rod.get("length_over_diameter"), preset=self.dna_preset())

    def diagram_options(self):
        """:class:`~supercoil.problems.ring_diagram.DiagramOptions` of a ring_diagram study."""
        from supercoil.problems.ring_diagram import DiagramOptions

        s = self.settings
        return DiagramOptions(
            twist_ratio=s["rod"]["twist_ratio"],
            length_over_diameter=s["rod"]["length_over_diameter"],
            n_nodes=s["rod"]["nodes"], modes=tuple(s["problem"]["modes"]),
            max_excess_link=s["problem"]["max_excess_link"], contact=s["problem"]["contact"],
            **s["continuation"])


def _parse_override(text: str) -> tuple[str, str, Any]:
    if "=" not in text or "." not in text.split("=", 1)[0]:
        raise StudyError(f"--set {text!r}: give TABLE.KEY=VALUE, like rod.nodes=48")
    lhs, rhs = text.split("=", 1)
    table, key = (w.strip() for w in lhs.split(".", 1))
    try:
        value = tomllib.loads(f"v = {rhs.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = rhs.strip()  # a bare word: a string (e.g. problem.contact=penalty)
    return table, key, value


def load_study(path: str | Path, overrides: Iterable[str] = ()) -> Study:
    """Read and validate the study file at ``path``; ``overrides`` are
    ``TABLE.KEY=VALUE`` strings (TOML values) applied before validation."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise StudyError(f"{path}: no such study file") from None
    except IsADirectoryError:
        raise StudyError(f"{path}: is a folder; give a study file (.toml)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"{path}: cannot read the study file ({exc})") from None
    return parse_study(text, str(path), overrides)


def parse_study(text: str, source: str = "<study>", overrides: Iterable[str] = ()) -> Study:
    """Validate the TOML ``text`` of a study (``source`` names it in messages)."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source}: not valid TOML ({exc})") from None
    raw = copy.deepcopy(raw)
    for item in overrides:
        table, key, value = _parse_override(item)
        if table not in _SCHEMA:
            raise StudyError(f"--set {item!r}: unknown table [{table}]{_closest(table, _SCHEMA)};"
                             f" valid tables: {', '.join(_SCHEMA)}")
        raw.setdefault(table, {})[key] = value
    return Study(source, text, _validate(raw, source))


def _validate(raw: dict, source: str) -> dict:
    for table, body in raw.items():
        if table not in _SCHEMA:
            raise StudyError(f"{source}: unknown table [{table}]{_closest(table, _SCHEMA)}; "
                             f"valid tables: {', '.join(f'[{t}]' for t in _SCHEMA)}")
        if not isinstance(body, dict):
            raise StudyError(f"{source}: {table} must be a table ([{table}]), got "
                             f"{_type_name(body)}")
    for table in REQUIRED_TABLES:
        if table not in raw:
            raise StudyError(f"{source}: missing table [{table}]; a study needs "
                             f"{', '.join(f'[{t}]' for t in REQUIRED_TABLES)}")
    kind = raw["problem"].get("kind")
    if kind is None:
        raise StudyError(f"{source}: [problem] kind is missing; give one of "
                         f"{', '.join(PROBLEM_KINDS)}")
    if not _SCHEMA["problem"]["kind"].check(kind):
        hint = _closest(kind, PROBLEM_KINDS) if isinstance(kind, str) else ""
        raise StudyError(f"{source}: [problem] kind = {kind!r} is not a problem kind{hint}; "
                         f"valid: {', '.join(PROBLEM_KINDS)}")
    preset = raw.get("units", {}).get("preset", "nondimensional")
    if not _SCHEMA["units"]["preset"].check(preset):
        hint = _closest(preset, UNITS_PRESETS) if isinstance(preset, str) else ""
        raise StudyError(f"{source}: [units] preset = {preset!r}{hint}; valid: "
                         f"{', '.join(UNITS_PRESETS)}")
    settings: dict[str, dict] = {}
    for table, schema in _SCHEMA.items():
        body = raw.get(table, {})
        valid = [k for k, spec in schema.items() if kind in spec.kinds and preset in spec.presets]
        out = {}
        for key, value in body.items():
            if key not in schema:
                raise StudyError(f"{source}: unknown key [{table}] {key}{_closest(key, valid)}; "
                                 f"valid keys: {', '.join(valid) or 'none'}")
            spec = schema[key]
            if kind not in spec.kinds:
                raise StudyError(f"{source}: [{table}] {key} does not apply to a {kind} "
                                 f"problem (it belongs to {', '.join(spec.kinds)}); valid "
                                 f"keys: {', '.join(valid) or 'none'}")
            if preset not in spec.presets:
                other = ("the DNA preset derives it" if preset == "dna"
                         else "it needs [units] preset = \"dna\"")
                raise StudyError(f"{source}: [{table}] {key} cannot be given with units preset "
                                 f"{preset!r} ({other}); valid keys: {', '.join(valid)}")
            if not spec.check(value):
                raise StudyError(f"{source}: [{table}] {key} must be {spec.valid}, got "
                                 f"{value!r} ({_type_name(value)})")
            out[key] = spec.convert(value)
        for key in valid:
            default = schema[key].default
            if isinstance(default, dict):
                default = default.get(kind)
            if key not in out and default is not None:
                out[key] = copy.deepcopy(default)
        settings[table] = out
    _complete(settings, kind, preset, source)
    return settings


def _complete(s: dict, kind: str, preset: str, source: str) -> None:
    """Cross-key checks and derived values (DNA preset, contact treatment)."""
    rod, problem = s["rod"], s["problem"]
    problem_with_model = model_problem(s, kind, preset)
    if problem_with_model is not None:
        raise StudyError(f"{source}: {problem_with_model}")
    if preset == "dna":
        from supercoil.io.study_dna import complete_dna

        with _refused(source):
            complete_dna(s, kind, DEFAULT_TURNS)
    else:
        if "twist_ratio" not in rod:
            raise StudyError(f"{source}: [rod] twist_ratio is missing; give C/A, e.g. "
                             "twist_ratio = 0.6667, or use [units] preset = \"dna\"")
        if kind == "ring_diagram" and "length_over_diameter" not in rod:
            raise StudyError(f"{source}: [rod] length_over_diameter is missing; a ring diagram "
                             "with self-contact needs L/D, e.g. length_over_diameter = 40")
        if kind == "ring" and "excess_link" not in problem:
            raise StudyError(f"{source}: [problem] excess_link is missing; give the excess "
                             "link in turns, e.g. excess_link = 2.5")
    if kind == "tweezers":
        _complete_tweezers(s, preset, source)
        return
    contact = problem.get("contact")
    if contact is None:
        problem["contact"] = "barrier" if "length_over_diameter" in rod else None
    elif "length_over_diameter" not in rod:
        raise StudyError(f"{source}: [problem] contact needs [rod] length_over_diameter (the "
                         "tube diameter D = L/(L/D))")
    if problem["contact"] is None:
        del problem["contact"]
    with _refused(source):
        if kind == "ring_diagram":
            Study(source, "", s).diagram_options()
        else:
            _check_ring(rod, problem)


def _check_ring(rod: Mapping, problem: Mapping) -> None:
    """The checks of :func:`~supercoil.problems.ring.solve_ring` and
    :func:`~supercoil.problems.ring_contact.solve_supercoiled_ring` (InputError)."""
    from supercoil.problems.ring import check_ring_inputs

    check_ring_inputs(rod["twist_ratio"], problem["excess_link"], rod["nodes"])
    if "length_over_diameter" in rod:
        from supercoil.contact.options import TREATMENTS
        from supercoil.problems.ring_contact import validate_diameter

        validate_diameter(rod["length_over_diameter"])
        checks.choice("contact", problem["contact"], TREATMENTS, meaning="contact treatment")


@contextmanager
def _refused(source: str):
    """An InputError of the options and problems as a StudyError naming the file and key."""
    try:
        yield
    except InputError as exc:
        raise StudyError(f"{source}: {exc.renamed(_KEY_NAMES)}") from None


def _complete_tweezers(s: dict, preset: str, source: str) -> None:
    problem = s["problem"]
    problem.setdefault("turns", list(DEFAULT_TURNS))
    s["rod"].setdefault("nodes", 100)
    if preset != "dna" and ("tension" in problem) == ("end_distance" in problem):
        raise StudyError(f"{source}: [problem] give exactly one of tension (F L^2/A, load "
                         "control) and end_distance (z/L, displacement control)")
    with _refused(source):
        Study(source, "", s).tweezers_options()
