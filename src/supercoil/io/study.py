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
"dna" a tweezers study's ``[rod] nodes`` defaults to the fewest whose segments are no
longer than D (n0 = ceil(L/D) + 2) and at most a third of the loop's core sqrt(A/F)
(:func:`~supercoil.units.tweezers.default_nodes`); otherwise to 100.

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
from collections.abc import Iterable, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from supercoil import checks
from supercoil.errors import InputError
from supercoil.io.study_model import model_problem
from supercoil.io.study_schema import (
    KEY_NAMES,
    PRESENTATION,
    PROBLEM_KINDS,
    REQUIRED_TABLES,
    SCHEMA,
    UNITS_PRESETS,
    type_name,
)

DEFAULT_TURNS = (0.0, 5.0)  # a tweezers study's turns when neither they nor sigma are given


class StudyError(InputError):
    """A study file that cannot be run; one line naming the file, the key and the problem."""


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
            segment_points=c["segment_points"],
            event_tolerance=c["event_tolerance"],
            contact_event_tolerance=c["contact_event_tolerance"],
            contact_tolerance=c["contact_tolerance"],
            **self._dna_numerics({"max_points": c["max_points"]}))

    def _dna_numerics(self, given: dict) -> dict:
        """``given`` with a DNA study's defaults (:func:`~supercoil.units.tweezers.dna_numerics`:
        the contact curve; the study's ``max_points`` is always given), alone otherwise
        (the options' defaults)."""
        if self.units != "dna":
            return dict(given)
        from supercoil.units.tweezers import dna_numerics

        return dna_numerics(given)

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
    return parse_study(read_study_text(path), str(path), overrides)


def read_study_text(path: str | Path) -> str:
    """The text of the study file at ``path``; a :class:`StudyError` naming the path
    when there is no such file, it is a folder, or it cannot be read as UTF-8."""
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise StudyError(f"{path}: no such study file") from None
    except IsADirectoryError:
        raise StudyError(f"{path}: is a folder; give a study file (.toml)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"{path}: cannot read the study file ({exc})") from None


def parse_study(text: str, source: str = "<study>", overrides: Iterable[str] = ()) -> Study:
    """Validate the TOML ``text`` of a study (``source`` names it in messages)."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source}: not valid TOML ({exc})") from None
    raw = copy.deepcopy(raw)
    for item in overrides:
        table, key, value = _parse_override(item)
        if table not in SCHEMA:
            raise StudyError(f"--set {item!r}: unknown table [{table}]{_closest(table, SCHEMA)};"
                             f" valid tables: {', '.join(SCHEMA)}")
        raw.setdefault(table, {})[key] = value
    return Study(source, text, _validate(raw, source))


def _validate(raw: dict, source: str) -> dict:
    for table, body in raw.items():
        if table not in SCHEMA:
            raise StudyError(f"{source}: unknown table [{table}]{_closest(table, SCHEMA)}; "
                             f"valid tables: {', '.join(f'[{t}]' for t in SCHEMA)}")
        if not isinstance(body, dict):
            raise StudyError(f"{source}: {table} must be a table ([{table}]), got "
                             f"{type_name(body)}")
    for table in REQUIRED_TABLES:
        if table not in raw:
            raise StudyError(f"{source}: missing table [{table}]; a study needs "
                             f"{', '.join(f'[{t}]' for t in REQUIRED_TABLES)}")
    kind = raw["problem"].get("kind")
    if kind is None:
        raise StudyError(f"{source}: [problem] kind is missing; give one of "
                         f"{', '.join(PROBLEM_KINDS)}")
    if not SCHEMA["problem"]["kind"].check(kind):
        hint = _closest(kind, PROBLEM_KINDS) if isinstance(kind, str) else ""
        raise StudyError(f"{source}: [problem] kind = {kind!r} is not a problem kind{hint}; "
                         f"valid: {', '.join(PROBLEM_KINDS)}")
    preset = raw.get("units", {}).get("preset", "nondimensional")
    if not SCHEMA["units"]["preset"].check(preset):
        hint = _closest(preset, UNITS_PRESETS) if isinstance(preset, str) else ""
        raise StudyError(f"{source}: [units] preset = {preset!r}{hint}; valid: "
                         f"{', '.join(UNITS_PRESETS)}")
    settings: dict[str, dict] = {}
    for table, schema in SCHEMA.items():
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
                                 f"{value!r} ({type_name(value)})")
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
    problem_with_model = model_problem(s, kind)
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
        raise StudyError(f"{source}: {exc.renamed(KEY_NAMES)}") from None


def _complete_tweezers(s: dict, preset: str, source: str) -> None:
    problem = s["problem"]
    problem.setdefault("turns", list(DEFAULT_TURNS))
    s["rod"].setdefault("nodes", 100)
    if preset != "dna" and ("tension" in problem) == ("end_distance" in problem):
        raise StudyError(f"{source}: [problem] give exactly one of tension (F L^2/A, load "
                         "control) and end_distance (z/L, displacement control)")
    with _refused(source):
        Study(source, "", s).tweezers_options()
