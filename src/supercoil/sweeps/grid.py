"""The ``[sweep]`` table of a study file: the grid of studies a sweep runs.

A sweep study is a study file (:mod:`supercoil.io.study`) with one more table::

    [sweep]
    "problem.tension" = [5.0, 10.0, 20.0]                 # a list of values
    "rod.twist_ratio" = {start = 0.5, stop = 1.5, num = 3}  # numpy.linspace(start, stop, num)
    "problem.turns" ...                                   # any key of the study, TABLE.KEY
    zip = [["rod.twist_ratio", "units.salt_mM"]]          # lists paired element by element

Each swept key overrides the same key of the study. The grid is the product of
the swept lists, except for the keys of one ``zip`` group, whose lists (of equal
lengths) are paired element by element and vary together along one dimension.
Dimensions come in the order of the keys in the table (a zip group where its
first key is); a zip group's dimension is named by its keys joined with ``+``.

Every point of the grid is a complete study, validated here before anything runs
(:func:`load_sweep_study`); its task key is a short SHA-256 of the canonical JSON
of its validated settings, so the key names the inputs of the task and nothing
else (two sweeps that share a point share its key, and its result).

Every problem is an :class:`~supercoil.errors.InputError` whose message names the
file, the ``[sweep]`` entry, what is wrong and what is valid.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from supercoil.errors import InputError

SWEEP_TABLE = "sweep"
ZIP = "zip"
RANGE_KEYS = ("start", "stop", "num")
MAX_VALUES = 100_000  # values of one swept key
MAX_TASKS = 100_000  # points of the grid
KEY_LENGTH = 16  # hexadecimal digits of a task key


@dataclass(frozen=True)
class Dimension:
    """One dimension of the grid: a swept key, or a zip group of keys that vary together.

    ``values[i]`` is the tuple of values of ``keys[i]`` along the dimension (all of
    length ``size``)."""

    name: str
    keys: tuple[str, ...]
    values: tuple[tuple, ...]

    @property
    def size(self) -> int:
        return len(self.values[0])


@dataclass(frozen=True)
class Task:
    """One point of the grid: its position (one index per dimension), the overridden
    keys, its task key and the complete study it runs (TOML text and validated
    settings)."""

    index: tuple[int, ...]
    overrides: dict
    key: str
    text: str
    settings: dict

    def label(self) -> str:
        """``rod.twist_ratio = 0.5, problem.tension = 10``."""
        return ", ".join(f"{k} = {_show(v)}" for k, v in self.overrides.items())


@dataclass(frozen=True)
class SweepStudy:
    """A validated sweep study: the study file, the grid's dimensions and its tasks
    (one per point, in the grid's C order)."""

    source: str
    text: str
    kind: str
    dimensions: tuple[Dimension, ...]
    tasks: tuple[Task, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(d.size for d in self.dimensions)

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for d in self.dimensions for k in d.keys)

    def unique_tasks(self) -> dict[str, Task]:
        """Task key -> the first task of that key (points whose studies are equal share one
        run)."""
        out: dict[str, Task] = {}
        for task in self.tasks:
            out.setdefault(task.key, task)
        return out

    def record(self) -> dict:
        """The sweep's definition as plain data: dimensions, keys and values."""
        return {"kind": self.kind,
                "dimensions": [{"name": d.name, "keys": list(d.keys),
                                "values": [list(v) for v in d.values]}
                               for d in self.dimensions]}


def _show(value) -> str:
    return repr(value) if isinstance(value, str) else f"{value}"


def _kind_of(value) -> str | None:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "string"
    return None


# ----------------------------------------------------------------------------- reading
def load_sweep_study(path: str | Path) -> SweepStudy:
    """Read the sweep study at ``path``, check its ``[sweep]`` table and validate the
    study of every point of its grid (nothing runs)."""
    from supercoil.io.study import read_study_text

    return parse_sweep_study(read_study_text(path), str(path))


def parse_sweep_study(text: str, source: str = "<study>") -> SweepStudy:
    """Validate the TOML ``text`` of a sweep study (``source`` names it in messages)."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML ({exc})") from None
    if SWEEP_TABLE not in raw:
        raise InputError(f"{source}: no [sweep] table; a sweep needs one, mapping study keys "
                         'to values, e.g. [sweep] "problem.tension" = [5, 10, 20] '
                         "(a single study runs with 'supercoil run')")
    table = raw.pop(SWEEP_TABLE)
    if not isinstance(table, dict):
        raise InputError(f"{source}: sweep must be a table ([sweep]), not a value")
    swept = _swept_values(table, source)
    groups = _zip_groups(table.get(ZIP, []), swept, source)
    dimensions = _dimensions(swept, groups)
    size = math.prod(d.size for d in dimensions)
    if size > MAX_TASKS:
        raise InputError(f"{source}: [sweep] makes {size} tasks; at most {MAX_TASKS} "
                         "(split the sweep into several study files)")
    tasks = tuple(_task(raw, dimensions, index, source)
                  for index in itertools.product(*(range(d.size) for d in dimensions)))
    kinds = {t.settings["problem"]["kind"] for t in tasks}
    if len(kinds) > 1:
        raise InputError(f"{source}: [sweep] mixes problem kinds ({', '.join(sorted(kinds))}); "
                         "a sweep runs one kind of problem")
    return SweepStudy(source, text, kinds.pop(), dimensions, tasks)


def _flat_entries(table: dict, source: str) -> dict[str, Any]:
    """``[sweep]``'s entries as dotted key -> value spec (a TOML dotted key,
    ``rod.twist_ratio = [...]`` unquoted, is a nested table: flattened here)."""
    out: dict[str, Any] = {}
    for name, value in table.items():
        if name == ZIP:
            continue
        if isinstance(value, dict) and not any(k in value for k in RANGE_KEYS):
            for key, inner in value.items():
                if isinstance(inner, dict) and not any(k in inner for k in RANGE_KEYS):
                    raise InputError(f"{source}: [sweep] {name}.{key}: a swept key is "
                                     "TABLE.KEY (one dot), like rod.twist_ratio")
                out[f"{name}.{key}"] = inner
        else:
            out[name] = value
    return out


def _swept_values(table: dict, source: str) -> dict[str, tuple]:
    entries = _flat_entries(table, source)
    if not entries:
        raise InputError(f"{source}: [sweep] sweeps no key; give study keys and their values, "
                         'e.g. "problem.tension" = [5, 10, 20]')
    out = {}
    for key, spec in entries.items():
        where = f"{source}: [sweep] {key!r}"
        parts = key.split(".")
        if len(parts) != 2 or not all(parts):
            raise InputError(f"{where}: a swept key is TABLE.KEY (one dot), like "
                             '"rod.twist_ratio" or "problem.tension"')
        if parts[0] == SWEEP_TABLE:
            raise InputError(f"{where}: the [sweep] table itself cannot be swept")
        out[key] = _values(spec, where)
    return out


def _values(spec, where: str) -> tuple:
    if isinstance(spec, dict):
        return _range(spec, where)
    if not isinstance(spec, list):
        raise InputError(f"{where}: give a list of values, like [5, 10, 20], or a range "
                         f"{{start = 0.5, stop = 1.5, num = 3}}; got {spec!r}")
    if not spec:
        raise InputError(f"{where}: the list of values is empty; give at least one value")
    if len(spec) > MAX_VALUES:
        raise InputError(f"{where}: {len(spec)} values; at most {MAX_VALUES}")
    kinds = {_kind_of(v) for v in spec}
    if None in kinds:
        bad = next(v for v in spec if _kind_of(v) is None)
        raise InputError(f"{where}: value {bad!r} is not a number, a string or a boolean; "
                         "swept values are single numbers, strings or booleans")
    if len(kinds) > 1:
        raise InputError(f"{where}: the values mix {' and '.join(sorted(kinds))}s; give "
                         "values of one type")
    if kinds == {"number"} and not all(math.isfinite(v) for v in spec):
        raise InputError(f"{where}: the values must be finite numbers, got {spec!r}")
    seen = set()
    for v in spec:
        if v in seen:
            raise InputError(f"{where}: value {_show(v)} is given twice; give each value once")
        seen.add(v)
    return tuple(spec)


def _range(spec: dict, where: str) -> tuple:
    unknown = [k for k in spec if k not in RANGE_KEYS]
    missing = [k for k in RANGE_KEYS if k not in spec]
    if unknown or missing:
        what = (f"unknown key {unknown[0]!r}" if unknown else
                f"{', '.join(missing)} missing")
        raise InputError(f"{where}: a range is {{start = ..., stop = ..., num = ...}} "
                         f"(numpy.linspace); {what}")
    start, stop, num = spec["start"], spec["stop"], spec["num"]
    for name, v in (("start", start), ("stop", stop)):
        if _kind_of(v) != "number" or not math.isfinite(v):
            raise InputError(f"{where}: {name} must be a finite number, got {v!r}")
    if not isinstance(num, int) or isinstance(num, bool) or not 1 <= num <= MAX_VALUES:
        raise InputError(f"{where}: num must be a whole number of values from 1 to "
                         f"{MAX_VALUES}, got {num!r}")
    if num > 1 and start == stop:
        raise InputError(f"{where}: start = stop = {start} gives {num} equal values; give "
                         "num = 1 or different start and stop")
    values = np.linspace(float(start), float(stop), num)
    if isinstance(start, int) and isinstance(stop, int) and np.all(values == np.round(values)):
        return tuple(int(v) for v in np.round(values))  # an integer key (rod.nodes) stays one
    return tuple(float(v) for v in values)


def _zip_groups(spec, swept: dict, source: str) -> list[tuple[str, ...]]:
    where = f"{source}: [sweep] zip"
    if not isinstance(spec, list) or not all(isinstance(g, list) for g in spec):
        raise InputError(f"{where}: give a list of groups of swept keys, like "
                         '[["rod.twist_ratio", "problem.tension"]]')
    groups, used = [], {}
    for group in spec:
        if len(group) < 2:
            raise InputError(f"{where}: group {group!r} has fewer than two keys; a zip group "
                             "pairs the values of two keys or more")
        for key in group:
            if not isinstance(key, str) or key not in swept:
                raise InputError(f"{where}: {key!r} is not a swept key; swept keys: "
                                 f"{', '.join(swept)}")
            if key in used:
                raise InputError(f"{where}: {key!r} is in two groups; a key belongs to one "
                                 "group at most")
            used[key] = True
        lengths = {key: len(swept[key]) for key in group}
        if len(set(lengths.values())) > 1:
            shown = ", ".join(f"{k} has {n}" for k, n in lengths.items())
            raise InputError(f"{where}: the keys of a group need lists of equal lengths "
                             f"(paired element by element); {shown} values")
        groups.append(tuple(group))
    return groups


def _dimensions(swept: dict, groups: list[tuple[str, ...]]) -> tuple[Dimension, ...]:
    group_of = {k: g for g in groups for k in g}
    out, done = [], set()
    for key in swept:
        group = group_of.get(key, (key,))
        if group in done:
            continue
        done.add(group)
        out.append(Dimension("+".join(group), group, tuple(swept[k] for k in group)))
    return tuple(out)


def _task(raw: dict, dimensions, index: tuple[int, ...], source: str) -> Task:
    from supercoil.io.study import parse_study

    overrides = {k: d.values[j][i] for d, i in zip(dimensions, index, strict=True)
                 for j, k in enumerate(d.keys)}
    study = {t: (dict(b) if isinstance(b, dict) else b) for t, b in raw.items()}
    for key, value in overrides.items():
        table, name = key.split(".")
        body = study.setdefault(table, {})
        if not isinstance(body, dict):
            raise InputError(f"{source}: [sweep] {key!r}: {table} is a value in the study, "
                             "not a table")
        body[name] = value
    text = toml_text(study)
    label = ", ".join(f"{k} = {_show(v)}" for k, v in overrides.items())
    try:
        settings = parse_study(text, f"{source} [sweep] at {label}").settings
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return Task(index, overrides, task_key(settings), text, settings)


# ----------------------------------------------------------------------------- keys
def _plain(value):
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def canonical_json(settings: dict) -> str:
    """The settings as JSON with sorted keys and no spaces (floats in their shortest
    round-trip form), the same for a study's settings and their copy in a result file."""
    return json.dumps(_plain(settings), sort_keys=True, separators=(",", ":"),
                      allow_nan=False, ensure_ascii=True)


def task_key(settings: dict) -> str:
    """The first 16 hexadecimal digits of the SHA-256 of :func:`canonical_json`."""
    return hashlib.sha256(canonical_json(settings).encode("utf-8")).hexdigest()[:KEY_LENGTH]


# ----------------------------------------------------------------------------- TOML
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_string(text: str) -> str:
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007F")


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    if hasattr(value, "isoformat"):  # TOML dates and times
        return value.isoformat()
    raise TypeError(f"no TOML form for {type(value).__name__}")


def toml_text(study: dict) -> str:
    """TOML text of a study's tables (``tomllib.loads`` of it gives ``study`` back)."""
    top = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in study.items()
           if not isinstance(v, dict)]
    lines = top + ([""] if top else [])
    for table, body in study.items():
        if isinstance(body, dict):
            lines.append(f"[{_toml_key(table)}]")
            lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in body.items()]
            lines.append("")
    return "\n".join(lines)
