"""What the figures and the viewer read from a result: one small adapter.

Plotting never computes: this module only reads. :func:`load_result` turns a
result on disk into a :class:`ResultData` (branches of per-point numbers, the
special points, a lazy loader of the centrelines). It reads

* a result file of :func:`supercoil.load` (``result.h5``, written by every
  command that computes), or the output folder holding one (preferred to the
  JSON beside it: it holds every state, and the points of a run that was
  stopped). :func:`_from_loaded` is the one place that knows that API;
* the JSON summary beside it (``diagram.json`` of ``supercoil diagram ring``
  and ``demo``, ``branch.json`` of ``supercoil tweezers``, points keyed by
  ``turns``), whose ``branches[].file`` names the result file holding the
  states.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from supercoil.errors import InputError
from supercoil.plotting.dna import DNAScales


class ResultError(InputError):
    """A result that cannot be read; the message is one line naming the file."""


@dataclass(frozen=True)
class BranchData:
    """One branch: ``points`` are the per-point numbers (the keys of docs/model.md,
    "Contacts in the output" and "Special points and branches": ``excess_link``,
    ``writhe``, ``twist``, ``energy``, ``unstable_count``, ``contact_points``, ...), in
    branch order."""

    name: str
    parent: str | None
    contact: bool
    points: tuple[Mapping, ...]
    _states: Callable[[], np.ndarray | None] | None = field(default=None, repr=False)
    generation: int = 1  # ring diagram: 0 circle, 1 primary, 2 secondary, 3 tertiary

    def states(self) -> np.ndarray | None:
        """Centrelines, shape ``(len(points), n_nodes, 3)``, or None when not stored
        (read once, then kept)."""
        if self._states is None:
            return None
        cache = self.__dict__.setdefault("_cache", {})
        if "states" not in cache:
            states = self._states()
            cache["states"] = (None if states is None else
                               np.asarray(states, float).reshape(len(states), -1, 3))
        return cache["states"]

    @property
    def has_states(self) -> bool:
        return self.states() is not None

    def values(self, key: str) -> np.ndarray:
        """The number ``key`` at every point, shape ``(len(points),)`` (NaN where missing)."""
        return np.array([_number(p.get(key)) for p in self.points], float)


@dataclass(frozen=True)
class ResultData:
    """A result as the figures and the viewer see it.

    ``kind``: ``"ring"`` (closed rod, parameter ``excess_link``) or
    ``"tweezers"`` (open rod, parameter ``turns``); ``parameter`` names the
    continuation parameter; ``diameter`` is D/L (None without contact);
    ``closed`` says whether the centreline closes on itself.
    """

    path: Path
    kind: str
    title: str
    parameter: str
    diameter: float | None
    closed: bool
    units: str
    branches: tuple[BranchData, ...]
    special_points: tuple[Mapping, ...]
    parameters: Mapping = field(default_factory=dict)
    dna: DNAScales | None = None  # a tweezers result in DNA units: its scales

    def branch(self, name: str) -> BranchData:
        for b in self.branches:
            if b.name == name:
                return b
        raise KeyError(name)


def _number(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def load_result(path: str | Path) -> ResultData:
    """Read a result (see the module docstring); :class:`ResultError` when it cannot."""
    path = Path(path)
    if not path.exists():
        raise ResultError(f"{path}: no such file or folder; give a result folder (with "
                          "diagram.json) or a result file")
    if path.is_dir():
        # a result file holds every state; supercoil run writes it beside diagram.json
        stores = sorted(p for p in path.iterdir() if p.suffix in _STORE_SUFFIXES)
        if len(stores) == 1:
            return _from_store(stores[0])
        for name in ("diagram.json", "branch.json"):
            if (path / name).is_file():
                return _from_json(path / name)
        raise ResultError(f"{path}: folder has no result.h5, diagram.json or branch.json; "
                          "give the --out folder of 'supercoil run', 'supercoil diagram "
                          "ring' or 'supercoil tweezers'")
    if path.suffix in _STORE_SUFFIXES:
        return _from_store(path)
    if path.suffix == ".json":
        return _from_json(path)
    raise ResultError(f"{path}: unknown result type {path.suffix or '(no suffix)'!r}; give a "
                      "result folder, its diagram.json or branch.json, or a "
                      f"{'/'.join(_STORE_SUFFIXES)} result file")


_STORE_SUFFIXES = (".h5", ".hdf5", ".nc")


def _from_store(path: Path) -> ResultData:
    """A result file of :func:`supercoil.load`."""
    from supercoil import load

    try:
        result = load(path)
    except (OSError, ValueError, KeyError, ImportError) as exc:
        raise ResultError(f"{path}: cannot read the result file ({_one_line(exc)})") from None
    return _from_loaded(path, result)


def _from_loaded(path: Path, result) -> ResultData:
    """Adapt a :class:`supercoil.io.store.Result` (docs/results.md): the finished run's
    summary when there is one (it holds the contact lists), else the per-point
    records of every branch stored so far (an interrupted run)."""
    try:
        names = list(result.branch_names)
        contact_names = set(getattr(result, "contact_branches", ()))
        summary = getattr(result, "summary", None)

        def states(name: str, keep: int) -> Callable[[], np.ndarray | None]:
            return lambda: np.array([result.centreline(name, i) for i in range(keep)])

        if isinstance(summary, dict) and isinstance(summary.get("points"), list) \
                and summary["points"]:
            data = {**dict(getattr(result, "attributes", {}) or {}), **summary}
            data.setdefault("units", getattr(result, "units", "nondimensional"))
            return _from_payload(path, data, states)
        points, entries, specials = [], [], []
        for name in names:
            branch = result.branch(name)
            points += [dict(p, branch=p.get("branch", name)) for p in result.points(name)]
            entries.append({"name": name, "parent": branch.parent,
                            "contact": name in contact_names})
            for sp in branch.special_points:
                entry = {"kind": sp.kind, "branch": sp.branch, branch.parameter: sp.parameter}
                entry.update({k: _number(np.asarray(v).ravel()[0]) for k, v in
                              sp.records.items() if np.asarray(v).size == 1})
                specials.append(entry)
        data = {**dict(getattr(result, "attributes", {}) or {}), "points": points,
                "branches": entries, "special_points": specials,
                "units": getattr(result, "units", "nondimensional")}
    except (OSError, ValueError, KeyError, AttributeError, TypeError) as exc:
        raise ResultError(f"{path}: cannot read the result file ({_one_line(exc)})") from None
    return _from_payload(path, data, states)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _read_json(path: Path) -> dict:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ResultError(f"{path}: cannot read ({_one_line(exc)})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ResultError(f"{path}: not valid JSON (line {exc.lineno}: {exc.msg}); give a "
                          "result written by supercoil") from None
    if not isinstance(data, dict):
        raise ResultError(f"{path}: a JSON result is an object with 'points', got "
                          f"{type(data).__name__}")
    return data


StatesFor = Callable[[str, int], Callable[[], np.ndarray | None]]


def _from_json(path: Path) -> ResultData:
    return _from_payload(path, _read_json(path), None)


def _from_payload(path: Path, data: dict, states: StatesFor | None) -> ResultData:
    """``states(name, keep)``: loader of a branch's first ``keep`` states (None: the
    ``branches[].file`` archives beside ``path``)."""
    points = data.get("points")
    if not isinstance(points, list) or not points or not all(isinstance(p, dict)
                                                             for p in points):
        raise ResultError(f"{path}: no 'points' list of objects; give a result written by "
                          "'supercoil diagram ring' or 'supercoil tweezers'")
    if "excess_link" in points[0]:
        kind, parameter, required = "ring", "excess_link", ("excess_link", "writhe")
    elif "turns" in points[0]:
        kind, parameter, required = "tweezers", "turns", ("turns",)
    else:
        raise ResultError(f"{path}: points carry neither 'excess_link' (ring) nor 'turns' "
                          "(tweezers); not a result this command draws")
    default = str(data.get("branch", data.get("name", kind)))
    for i, p in enumerate(points):
        missing = [k for k in required if k not in p]
        if missing:
            raise ResultError(f"{path}: point {i} lacks {', '.join(missing)}")
    points = [p if "branch" in p else dict(p, branch=default) for p in points]
    entries = data.get("branches")
    if not isinstance(entries, list) or not all(isinstance(b, dict) and "name" in b
                                                for b in entries):
        entries = [{"name": n, "contact": kind == "tweezers"}
                   for n in dict.fromkeys(p["branch"] for p in points)]
    folder = path.parent
    opened: dict = {}  # result files read by the loaders, each once
    branches = []
    for entry in entries:
        name = str(entry["name"])
        rows = [p for p in points if p["branch"] == name]
        contact = bool(entry.get("contact", False))
        keep = len(rows)
        if kind == "ring" and not contact and entry.get("parent") is not None and rows:
            # 'supercoil diagram ring' stops a contact-free branch at the first
            # step past the contact onset: that last state overlaps itself
            keep -= 1
        rows = rows[:keep]
        file = entry.get("file")
        if states is not None:
            loader = states(name, keep)
        elif isinstance(file, str) and Path(file).suffix in _STORE_SUFFIXES:
            loader = _stored_states(folder / file, name, keep, opened)
        elif rows and all("centreline" in p for p in rows):
            loader = _inline_states(rows)
        else:
            loader = None
        generation = entry.get("generation")
        if not isinstance(generation, int):
            generation = 0 if entry.get("parent") is None else 1
        branches.append(BranchData(name, entry.get("parent"), contact, tuple(rows), loader,
                                   generation))
    ld = _number(data.get("length_over_diameter"))
    diameter = _number(data.get("diameter", 1.0 / ld if ld > 0 else math.nan))
    if kind == "ring":
        title = "twisted ring"
        labels = (("twist_ratio", "C/A", ".4g"), ("length_over_diameter", "L/D", ".4g"),
                  ("n_nodes", "N", "d"))
        if isinstance(data.get("base_pairs"), int | float):
            title = f"DNA ring of {_number(data['base_pairs']):g} bp"
            if isinstance(data.get("salt_mM"), int | float):
                title += f" in {_number(data['salt_mM']):g} mM salt"
    else:
        title = "rod in magnetic tweezers"
        labels = (("force", "F L²/A", ".4g"), ("twist_ratio", "C/A", ".4g"),
                  ("length_over_diameter", "L/D", ".4g"), ("n_nodes", "N", "d"))
    parts = [f"{label} = {_number(data[k]):{spec}}" if spec != "d" else f"{label} = {data[k]}"
             for k, label, spec in labels
             if k in data and data[k] is not None and math.isfinite(_number(data[k]))]
    if parts:
        title += ", " + ", ".join(parts)
    dna = DNAScales.of(data) if kind == "tweezers" else None
    if dna is not None:
        title = dna.title(data.get("n_nodes"))
    x = "writhe" if kind == "ring" else "extension"
    specials = tuple(s for s in data.get("special_points", []) if isinstance(s, dict)
                     and parameter in s and x in s)
    return ResultData(path=path, kind=kind, title=title, parameter=parameter,
                      diameter=diameter if math.isfinite(diameter) and diameter > 0 else None,
                      closed=kind == "ring", units=str(data.get("units", "nondimensional")),
                      branches=tuple(branches), special_points=specials,
                      parameters={k: data[k] for k in ("twist_ratio", "length_over_diameter",
                                                       "n_nodes", "force") if k in data},
                      dna=dna)


def _inline_states(rows: Sequence[Mapping]) -> Callable[[], np.ndarray]:
    def load() -> np.ndarray:
        return np.array([np.asarray(p["centreline"], float).ravel() for p in rows])
    return load


def _stored_states(file: Path, name: str, keep: int,
                   opened: dict) -> Callable[[], np.ndarray | None]:
    """Loader of the first ``keep`` centrelines of branch ``name`` in the result file
    ``file`` (None when the file or the branch is not there); ``opened`` keeps the
    files read."""
    def load() -> np.ndarray | None:
        if not file.is_file():
            return None
        from supercoil import load as load_result_file

        if file not in opened:
            try:
                opened[file] = load_result_file(file)
            except ValueError as exc:
                raise ResultError(f"{file}: cannot read the result file ({_one_line(exc)})") \
                    from None
        result = opened[file]
        if name not in result.branches or len(result.branches[name]) < keep:
            return None
        return np.array([result.centreline(name, i) for i in range(keep)])
    return load


def stable_mask(points: Sequence[Mapping]) -> np.ndarray:
    """``stable`` per point, else ``unstable_count == 0 and zero_modes == 0``."""
    out = []
    for p in points:
        if "stable" in p:
            out.append(bool(p["stable"]))
        else:
            out.append(p.get("unstable_count", -1) == 0 and p.get("zero_modes", 0) == 0)
    return np.array(out, bool)
