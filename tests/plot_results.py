"""Small result folders for the figure and viewer tests, made without computing.

:func:`write_ring_result` writes what ``supercoil diagram ring`` writes
(``result.h5`` through :func:`supercoil.io.store.save`, ``diagram.json`` beside it) for
two made-up branches: a circle (planar, stable below ΔLk = 2) and a
"contact" branch of non-planar rings with contact points and intervals. The
numbers are invented: plotting must show them as they are, whatever they are.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from supercoil.continuation import Branch
from supercoil.continuation.options import ContinuationStatus
from supercoil.io.store import save

N_NODES = 24
DIAMETER = 0.025


def ring_state(t: float, n: int = N_NODES) -> np.ndarray:
    """A closed curve of length about 1: the circle at t = 0, bent out of plane as t grows."""
    s = 2 * np.pi * np.arange(n) / n
    x = np.stack([np.cos(s), (1 - 0.6 * t) * np.sin(s), 0.8 * t * np.sin(2 * s)], axis=1)
    perimeter = np.sum(np.linalg.norm(np.roll(x, -1, 0) - x, axis=1))
    return x / perimeter


def _branch(name: str, parent: str | None, values: np.ndarray, states: np.ndarray,
            unstable: np.ndarray, writhe: np.ndarray) -> Branch:
    k, n = states.shape
    return Branch(name=name, parent=parent, origin=None, parameter="excess_link",
                  parameter_values=values, states=states, multipliers=np.zeros((k, 1)),
                  unstable_count=unstable, zero_modes=np.zeros(k, int),
                  determinant_sign=np.where(unstable % 2, -1, 1),
                  nearest_eigenvalue=np.ones(k), tangents=np.zeros((k, n + 2)),
                  arclength=values.copy(), special_points=(),
                  status=ContinuationStatus.PARAMETER_BOUND, message="made up",
                  records={"excess_link": values, "writhe": writhe})


def write_ring_result(folder: Path, *, shift: float = 0.0) -> Path:
    """The result folder; ``shift`` moves the last contact state (to change a picture)."""
    folder.mkdir(parents=True, exist_ok=True)
    circle_dlk = np.linspace(0.0, 3.0, 7)
    circle_states = np.array([ring_state(0.0).ravel() for _ in circle_dlk])
    circle_unstable = np.where(circle_dlk < 2.0, 0, 2)
    contact_t = np.linspace(0.2, 1.0, 9)
    contact_states = np.array([ring_state(t).ravel() for t in contact_t])
    contact_states[-1] += shift
    contact_dlk = 1.0 + 2.0 * contact_t
    contact_unstable = np.array([1, 1, 0, 0, 0, 0, 1, 0, 0])
    branches = [_branch("circle", None, circle_dlk, circle_states, circle_unstable,
                        np.zeros_like(circle_dlk)),
                _branch("loop_contact", "circle", contact_dlk, contact_states,
                        contact_unstable, 0.8 * contact_t)]
    points = []
    for i, dlk in enumerate(circle_dlk):
        points.append({"branch": "circle", "index": i, "excess_link": float(dlk),
                       "writhe": 0.0, "twist": float(dlk), "energy": 20.0 + dlk ** 2,
                       "link_error": 0.0, "n_contact_points": 0, "n_contact_intervals": 0,
                       "min_gap_over_diameter": 12.0, "unstable_count": int(circle_unstable[i]),
                       "zero_modes": 0, "determinant_sign": 1,
                       "stable": bool(circle_unstable[i] == 0), "contact_points": [],
                       "contact_intervals": []})
    for i, (t, dlk) in enumerate(zip(contact_t, contact_dlk, strict=True)):
        contacts = [{"s1": 0.25, "s2": 0.75, "force": 10.0 * t}] if i < 5 else []
        intervals = ([{"s1_start": 0.2, "s1_end": 0.3, "s2_start": 0.7, "s2_end": 0.8,
                       "force_per_length": 100.0 * t}] if i >= 5 else [])
        points.append({"branch": "loop_contact", "index": i, "excess_link": float(dlk),
                       "writhe": float(0.8 * t), "twist": float(dlk - 0.8 * t),
                       "energy": 30.0 + t, "link_error": 0.0,
                       "n_contact_points": len(contacts), "n_contact_intervals": len(intervals),
                       "min_gap_over_diameter": 1.0 + 1e-3 * i,
                       "unstable_count": int(contact_unstable[i]), "zero_modes": 0,
                       "determinant_sign": 1, "stable": bool(contact_unstable[i] == 0),
                       "contact_points": contacts, "contact_intervals": intervals})
    payload = {
        "schema_version": "1.0", "units": "nondimensional", "twist_ratio": 0.6667,
        "length_over_diameter": 1 / DIAMETER, "diameter": DIAMETER, "n_nodes": N_NODES,
        "branches": [
            {"name": "circle", "parent": None, "origin": None, "contact": False,
             "file": "result.h5"},
            {"name": "loop_contact", "parent": "circle", "origin": None, "contact": True,
             "file": "result.h5"}],
        "special_points": [
            {"kind": "bifurcation", "branch": "circle", "excess_link": 2.0, "writhe": 0.0},
            {"kind": "fold", "branch": "loop_contact", "excess_link": 2.2,
             "writhe": 0.48}],
        "points": points, "notes": [], "ok": True, "conventions": {}, "provenance": {}}
    save(folder / "result.h5", branches, problem="ring_diagram", summary=payload,
         attributes={"twist_ratio": 0.6667, "length_over_diameter": 1 / DIAMETER,
                     "diameter": DIAMETER, "n_nodes": N_NODES, "closed": True},
         overwrite=True)
    (folder / "diagram.json").write_text(json.dumps(payload), encoding="utf-8")
    return folder


def open_rod_state(t: float, n: int = N_NODES) -> np.ndarray:
    """Nodes of an open rod from (0, 0, 0) along +z, bowed sideways by t."""
    z = np.linspace(0.0, 1.0 - 0.3 * t, n)
    return np.stack([0.2 * t * np.sin(np.pi * z), 0.1 * t * np.sin(2 * np.pi * z), z], axis=1)


def write_tweezers_result(folder: Path, *, with_states: bool = False) -> Path:
    """``branch.json`` with ``points`` keyed by ``turns`` (a hat curve); with
    ``with_states`` as ``supercoil tweezers`` writes it (branch names, branch files)."""
    folder.mkdir(parents=True, exist_ok=True)
    turns = np.linspace(-6.0, 6.0, 13)
    extension = np.where(np.abs(turns) < 2.0, 0.98, 0.98 - 0.1 * (np.abs(turns) - 2.0))
    unstable = np.where(np.abs(turns) < 5, 0, 1)
    points = [{"turns": float(n), "extension": float(z), "torque": float(0.1 * n),
               "writhe": float(0.5 * n), "twist": float(0.5 * n), "energy": float(n * n),
               "unstable_count": int(u), "zero_modes": 0}
              for n, z, u in zip(turns, extension, unstable, strict=True)]
    payload = {"schema_version": "1.0", "units": "nondimensional", "force": 10.0,
               "twist_ratio": 1.5, "points": points,
               "special_points": [{"kind": "bifurcation", "turns": 2.0, "extension": 0.98}]}
    if with_states:
        states = np.array([open_rod_state(abs(n) / 6.0).ravel() for n in turns])
        branch = _branch("plectoneme", None, turns, states, unstable, 0.5 * turns)
        for p in points:
            p["branch"] = "plectoneme"
        payload.update(n_nodes=N_NODES, diameter=DIAMETER, branches=[
            {"name": "plectoneme", "parent": None, "contact": True, "file": "result.h5"}])
        save(folder / "result.h5", [branch], problem="tweezers", summary=payload,
             attributes={"n_nodes": N_NODES, "diameter": DIAMETER, "closed": False},
             overwrite=True)
    (folder / "branch.json").write_text(json.dumps(payload), encoding="utf-8")
    return folder
