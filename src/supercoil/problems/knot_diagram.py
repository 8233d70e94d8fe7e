"""The knotted ring's diagram in its excess link (Coleman & Swigon 2000, Figure 5).

A knotted ring has no circle to start from: :func:`compute_knot_diagram`
relaxes the knot with self-contact at ``start`` (by default the middle of the
range ``dLk_min:dLk_max``) and follows that equilibrium both ways, up to
``dLk_max`` (branch ``knot_up``) and down to ``dLk_min`` (``knot_down``), as
:func:`~supercoil.problems.knot_branch.follow_knot` does: pseudo-arclength
continuation with the barrier contact, folds passed, every state vetted by the
knot guard. The continuation's special points are kept: folds, bifurcations
(a change of the unstable count between two points, located where the
determinant changes sign; one within the barrier's reach of a contact event
is labelled so) and the contact events (``contact_onset``,
``contact_release``, ``contact_interval_onset``, ``contact_split``).

Per point the keys of the ring diagram
(:meth:`~supercoil.problems.ring_diagram.RingDiagram.points`) plus
``knot_type`` and ``chirality`` (of the state itself,
:func:`~supercoil.topology.knots.identify`), ``lowest_energy``,
``n_sections_touching_two`` and ``sections_touching_two``
(:mod:`~supercoil.problems.knot_diagram_points`); the payload adds
``by_excess_link``, the states found on a grid of ``dLk`` (how many, how many
stable, the lowest).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from supercoil import checks
from supercoil.contact.report import PLACE_KEYS, contact_summary
from supercoil.continuation import Branch
from supercoil.continuation.branch import jsonable
from supercoil.geometry.symmetry import curve_symmetry
from supercoil.problems.knot_branch import follow_knot, relaxed_knot
from supercoil.problems.knot_diagram_points import (
    lowest_energy,
    sections_touching_two,
    states_by_excess_link,
)
from supercoil.problems.knot_ring import parse_knot
from supercoil.problems.model_keys import KIRCHHOFF, model_keys
from supercoil.problems.ring_diagram.result import link_writhe_slope_sign
from supercoil.problems.ring_diagram.secondary import SYMMETRY_TOLERANCE
from supercoil.topology.knots import identify

TABLE_STEP = 0.1  # dLk between the rows of by_excess_link (at most MAX_ROWS rows)
MAX_ROWS = 1001
BRANCH_NAMES = ("knot_up", "knot_down")


@dataclasses.dataclass(frozen=True)
class KnotDiagramOptions:
    """The inputs of the knotted-ring diagram; validated on construction (InputError)."""

    knot: str
    twist_ratio: float
    length_over_diameter: float
    excess_link: tuple[float, float]
    n_nodes: int = 60
    max_points: int = 150  # per half (knot_up, knot_down)
    start: float | None = None  # dLk of the relaxed knot; None: the middle of the range
    tolerance: float = 1e-8

    def __post_init__(self):
        parse_knot(self.knot)
        checks.number("twist_ratio", self.twist_ratio, 0.0, checks.MAX_MAGNITUDE,
                      low_open=True, meaning="C/A")
        checks.number("length_over_diameter", self.length_over_diameter, np.pi,
                      checks.MAX_MAGNITUDE, low_open=True, meaning="L/D")
        span = self.excess_link
        if not isinstance(span, (tuple, list)) or len(span) != 2:
            raise checks.refuse("excess_link", f"must be a pair (dLk_min, dLk_max), got "
                                f"{span!r}")
        low, high = (checks.number("excess_link", v, -checks.MAX_MAGNITUDE,
                                   checks.MAX_MAGNITUDE, meaning="turns") for v in span)
        if not low < high:
            raise checks.refuse("excess_link", f"must be an interval dLk_min < dLk_max, got "
                                f"{low:g}:{high:g}")
        object.__setattr__(self, "excess_link", (low, high))
        checks.integer("n_nodes", self.n_nodes, checks.MIN_NODES, checks.MAX_NODES,
                       meaning="nodes of the ring")
        checks.integer("max_points", self.max_points, 2, checks.MAX_POINTS,
                       meaning="points of each half-branch")
        if self.start is not None:
            checks.number("start", self.start, low, high, meaning="dLk of the relaxed knot")
        checks.number("tolerance", self.tolerance, 0.0, 1e-2, low_open=True)

    @property
    def start_excess_link(self) -> float:
        low, high = self.excess_link
        return 0.5 * (low + high) if self.start is None else float(self.start)

    @property
    def diameter(self) -> float:
        return 1.0 / self.length_over_diameter

    @property
    def tolerances(self) -> dict:
        return {"newton": self.tolerance}


@dataclasses.dataclass(frozen=True)
class KnotDiagram:
    """The computed diagram: its two halves, the knot they keep, their problem."""

    options: KnotDiagramOptions
    branches: tuple[Branch, ...]
    knot: object  # the KnotType of the relaxed start
    problem: object  # the ContactProblem (for the contact lists of stored states)
    seconds: dict
    start_message: str

    @property
    def ok(self) -> bool:
        return all(b.status.complete for b in self.branches)

    def points(self) -> list[dict]:
        """One record per point (module doc)."""
        cp, opts = self.problem, self.options
        tolerance = SYMMETRY_TOLERANCE * opts.diameter
        lowest = lowest_energy([(np.asarray(b.parameter_values, float),
                                 np.asarray(b.records["energy"], float), b.stable)
                                for b in self.branches])
        out = []
        for b, flags in zip(self.branches, lowest):
            condition_e = link_writhe_slope_sign(b)
            for i in range(len(b)):
                q = b.states[i]
                knot = identify(q.reshape(-1, 3))
                symmetry = curve_symmetry(q.reshape(-1, 3), tolerance)
                places = contact_summary(cp, q, b.multipliers[i], PLACE_KEYS)
                n_two, arcs = sections_touching_two(opts.n_nodes, places["contact_points"],
                                             places["contact_intervals"])
                out.append({
                    "branch": b.name, "index": i,
                    **{k: jsonable(v[i]) for k, v in b.records.items()},
                    "unstable_count": int(b.unstable_count[i]),
                    "zero_modes": int(b.zero_modes[i]),
                    "determinant_sign": int(b.determinant_sign[i]),
                    "condition_e": int(condition_e[i]), "stable": bool(b.stable[i]),
                    "symmetry": symmetry.group,
                    "symmetry_residual_over_diameter": symmetry.residual / opts.diameter,
                    "contact_points": places["contact_points"],
                    "contact_intervals": places["contact_intervals"],
                    "knot_type": knot.name, "chirality": int(knot.chirality),
                    "lowest_energy": bool(flags[i]),
                    "n_sections_touching_two": n_two,
                    "sections_touching_two": arcs})
        return out

    def payload(self) -> dict:
        """The ``diagram.json`` payload (without the JSON envelope)."""
        opts = self.options
        low, high = opts.excess_link
        n_rows = min(MAX_ROWS, max(2, round((high - low) / TABLE_STEP) + 1))
        table = states_by_excess_link(
            [(np.asarray(b.parameter_values, float), np.asarray(b.records["energy"], float),
              b.stable) for b in self.branches], np.round(np.linspace(low, high, n_rows), 10),
            [b.name for b in self.branches])
        return {
            "description": "diagram of a knotted ring with self-contact in its excess link: "
            "the relaxed knot followed both ways from start_excess_link",
            **model_keys(KIRCHHOFF, self.branches),
            "knot": opts.knot, "knot_type": self.knot.name,
            "chirality": int(self.knot.chirality),
            "twist_ratio": opts.twist_ratio,
            "length_over_diameter": opts.length_over_diameter,
            "diameter": opts.diameter, "n_nodes": opts.n_nodes,
            "excess_link": list(opts.excess_link),
            "start_excess_link": opts.start_excess_link,
            "start_message": self.start_message,
            "branches": [{
                "name": b.name, "parent": None, "origin": None, "contact": True,
                "generation": 1, "parameter": b.parameter, "n_points": len(b),
                "status": b.status.name, "ok": b.status.complete, "message": b.message,
                "seconds": round(self.seconds.get(b.name, float("nan")), 3),
                "file": "result.h5"} for b in self.branches],
            "special_points": [p.entry("excess_link") for b in self.branches
                               for p in b.special_points],
            "points": self.points(),
            "by_excess_link": table,
            "notes": [],
            "ok": self.ok,
        }


def compute_knot_diagram(options: KnotDiagramOptions, progress=None,
                         on_point=None) -> KnotDiagram:
    """The diagram of ``options`` (module doc). ``progress(message)`` as each half starts,
    ``on_point(branch)`` after every accepted point."""
    opts = options
    start = opts.start_excess_link
    low, high = opts.excess_link
    if progress is not None:
        progress(f"relaxing {opts.knot} at dLk = {start:g}")
    cp, q0, knot, message = relaxed_knot(opts.knot, opts.twist_ratio,
                                         opts.length_over_diameter, start, opts.n_nodes,
                                         opts.tolerance)
    rod = cp.base
    pins = (rod.fixed, rod.gauge_dofs, cp.fixed)
    branches, seconds = [], {}
    for name, stop in zip(BRANCH_NAMES, (high, low)):
        if stop == start:
            continue
        if progress is not None:
            progress(f"{name}: dLk {start:g} -> {stop:g}")
        rod.fixed, rod.gauge_dofs, cp.fixed = pins
        began = time.perf_counter()
        branch = follow_knot(cp, q0.copy(), start, stop, opts.max_points, opts.tolerance,
                             name, on_point=on_point)
        seconds[name] = time.perf_counter() - began
        branches.append(branch)
    rod.fixed, rod.gauge_dofs, cp.fixed = pins
    return KnotDiagram(opts, tuple(branches), knot, cp, seconds, message)
