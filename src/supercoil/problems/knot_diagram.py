"""The knotted ring's diagram in its excess link (Coleman & Swigon 2004, Figure 5).

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

Further branches: at ``deflation`` computed points spread over the range, new
states are sought by deflation of the point's state
(:mod:`~supercoil.problems.knot_deflation`) and by relaxing the built knot
anew at that ``dLk``; a state whose energy or writhe differs from every
computed state there (:func:`states_at`, :func:`is_new_state`) is followed
both ways (``deflated_K_up``/``_down``, ``relaxed_K_up``/``_down``).

Switched branches: with ``branch_depth`` 2 (3), the half-branches that
bifurcate from the located bifurcation points of those branches (and of the
switched ones) are followed too (:mod:`~supercoil.problems.knot_switching`:
``knot_I+``, ``knot_II-``, ..., each with its ``parent`` and ``origin``).
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
from supercoil.problems.ring_diagram.secondary import MAX_DEPTH, SYMMETRY_TOLERANCE
from supercoil.topology.knots import identify

TABLE_STEP = 0.1  # dLk between the rows of by_excess_link (at most MAX_ROWS rows)
MAX_ROWS = 1001
MAX_DEFLATION = 50
# a state found by deflation is new when its energy or its writhe differs from every
# computed branch's state at its dLk by more than these (relative, turns): copies of one
# state slid along the mesh (equilibria with the sliding held) differ by the mesh's ripple,
# measured up to 3e-4 turns of writhe on the trefoil at N = 48
NEW_ENERGY, NEW_WRITHE = 1e-3, 1e-2
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
    deflation: int = 3  # dLk values at which further states are sought by deflation
    tolerance: float = 1e-8
    branch_depth: int = 1  # 1: no switching; 2: switched branches; 3: and from those
    secondary_max_points: int = 60  # points of each switched half-branch
    secondary_max_branches: int = 12  # switched half-branches in all

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
        checks.integer("deflation", self.deflation, 0, MAX_DEFLATION,
                       meaning="dLk values searched by deflation")
        checks.number("tolerance", self.tolerance, 0.0, 1e-2, low_open=True)
        checks.integer("branch_depth", self.branch_depth, 1, MAX_DEPTH,
                       meaning="generations of branches: 1 without switching, 2 switched "
                       "from bifurcation points, 3 switched from those too")
        checks.integer("secondary_max_points", self.secondary_max_points, 2,
                       checks.MAX_POINTS, meaning="points of each switched half-branch")
        checks.integer("secondary_max_branches", self.secondary_max_branches, 0,
                       checks.MAX_POINTS, meaning="switched half-branches in all")

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
    origins: dict = dataclasses.field(default_factory=dict)  # deflated branches' origin
    notes: tuple = ()
    generations: dict = dataclasses.field(default_factory=dict)  # switched branches' (2, 3)
    retraced: frozenset = frozenset()  # switched branches along computed families

    @property
    def ok(self) -> bool:
        return all(b.status.complete for b in self.branches)

    @property
    def contact_branches(self) -> frozenset:
        """The names of the branches with self-contact: all of them."""
        return frozenset(b.name for b in self.branches)

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
                if knot.same_invariants(self.knot):  # guarded along the branch: its name
                    knot = self.knot
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
        counted = [b for b in self.branches if b.name not in self.retraced and len(b)]
        table = states_by_excess_link(
            [(np.asarray(b.parameter_values, float), np.asarray(b.records["energy"], float),
              b.stable) for b in counted], np.round(np.linspace(low, high, n_rows), 10),
            [b.name for b in counted])
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
            "deflation": opts.deflation,
            "branch_depth": opts.branch_depth,
            "branches": [{
                "name": b.name, "parent": b.parent, "origin": self.origins.get(b.name, (
                    None if b.origin is None else b.origin.entry("excess_link"))),
                "contact": True, "generation": self.generations.get(b.name, 1),
                "parameter": b.parameter, "n_points": len(b),
                "status": b.status.name, "ok": b.status.complete, "message": b.message,
                "seconds": round(self.seconds.get(b.name, float("nan")), 3),
                "file": "result.h5"} for b in self.branches],
            "special_points": [p.entry("excess_link") for b in self.branches
                               for p in b.special_points],
            "points": self.points(),
            "by_excess_link": table,
            "notes": list(self.notes),
            "ok": self.ok,
        }


def compute_knot_diagram(options: KnotDiagramOptions, progress=None, on_point=None,
                         on_branch=None, resume=None) -> KnotDiagram:
    """The diagram of ``options`` (module doc). ``progress(message)`` as each half starts,
    ``on_point(branch)`` after every accepted point, ``on_branch(branch, contact)`` when a
    branch is final (``contact`` True: every branch has self-contact). ``resume`` maps
    branch names to ``(branch, complete)`` of an interrupted run with the same options:
    complete branches are taken as they are, incomplete ones continued from their last
    point (:func:`~supercoil.problems.knot_branch.follow_knot`'s ``old``); the start is
    relaxed again and the deflation searches are made again (their branches kept or
    continued the same way)."""
    opts = options
    start = opts.start_excess_link
    low, high = opts.excess_link
    say = progress or (lambda message: None)
    stored = dict(resume or {})
    final = on_branch or (lambda branch, contact: None)
    origins, notes = {}, []
    follow = _follower(opts, stored, say, on_point, final, notes)
    say(f"relaxing {opts.knot} at dLk = {start:g}")
    cp, q0, knot, message = relaxed_knot(opts.knot, opts.twist_ratio,
                                         opts.length_over_diameter, start, opts.n_nodes,
                                         opts.tolerance)
    rod = cp.base
    pins = (rod.fixed, rod.gauge_dofs, cp.fixed)
    branches, seconds = [], {}
    for name, stop in zip(BRANCH_NAMES, (high, low)):
        if stop == start:
            continue
        rod.fixed, rod.gauge_dofs, cp.fixed = pins
        began = time.perf_counter()
        branches.append(follow(cp, q0, start, stop, name))
        seconds[name] = time.perf_counter() - began
    rod.fixed, rod.gauge_dofs, cp.fixed = pins
    if opts.deflation and branches:
        found = _deflated_branches(opts, cp, branches, say, follow, seconds)
        for branch, origin in found:
            branches.append(branch)
            origins[branch.name] = origin
        notes.append(f"deflation and relaxation at {opts.deflation} dLk value(s): "
                     f"{len(found)} further half-branch(es) from new states")
    rod.fixed, rod.gauge_dofs, cp.fixed = pins
    generations, retraced = {}, set()
    if opts.branch_depth >= 2 and branches:
        from supercoil.problems.knot_switching import knot_switched

        switched, more = knot_switched(opts, cp, branches, stored, say, on_point,
                                       lambda branch: final(branch, True), pins)
        for item in switched:
            branches.append(item.branch)
            generations[item.branch.name] = item.generation
            seconds[item.branch.name] = item.seconds
            if item.fell_back:
                retraced.add(item.branch.name)
        notes += more
    return KnotDiagram(opts, tuple(branches), knot, cp, seconds, message, origins,
                       tuple(notes), generations, frozenset(retraced))


def _follower(opts: KnotDiagramOptions, stored: dict, say, on_point, on_branch, notes: list):
    """``follow(cp, q0, start, stop, name)``: the branch ``name`` as stored when complete,
    else followed (an incomplete stored one continued), and handed to ``on_branch``; a
    start at a singular point is made off it (``notes`` and ``say`` get the note)."""

    def follow(cp, q0, start: float, stop: float, name: str) -> Branch:
        old, complete = stored.get(name, (None, False))
        if complete:
            say(f"{name}: kept ({len(old)} points)")
            return old
        say(f"{name}: dLk {start:g} -> {stop:g}" + (
            f", continued from point {len(old) - 1}" if old is not None and len(old) else ""))
        before = len(notes)
        branch = follow_knot(cp, q0.copy(), start, stop, opts.max_points, opts.tolerance,
                             name, on_point=on_point, old=old, notes=notes,
                             singular_bounds=opts.excess_link)
        for note in notes[before:]:
            say(note)
        on_branch(branch, True)
        return branch

    return follow


def states_at(cp, branches, value: float, tolerance: float) -> list[tuple[float, float]]:
    """``(energy, writhe)`` of the states of ``branches`` at ``dLk = value``: on every
    segment that ``value`` falls on, the endpoint nearer in ``dLk`` corrected by Newton
    at ``value`` (:func:`~supercoil.problems.knot_deflation.deflated_newton`, nothing
    deflated); the segment's linear interpolation if Newton fails."""
    from supercoil.problems.knot_deflation import deflated_newton
    from supercoil.problems.ring_branches import ring_records

    cp = cp.at(excess_link=float(value))
    records = ring_records(cp.base)
    out = []
    for b in branches:
        lam = np.asarray(b.parameter_values, float)
        energy = np.asarray(b.records["energy"], float)
        writhe = np.asarray(b.records["writhe"], float)
        for j in range(len(lam) - 1):
            lo, hi = sorted((lam[j], lam[j + 1]))
            if not lo <= value <= hi:
                continue
            near = j if abs(lam[j] - value) <= abs(lam[j + 1] - value) else j + 1
            corrected = deflated_newton(cp, b.states[near], [], tolerance)
            if corrected is not None:
                rec = records(corrected.q, np.zeros(0), value)
                out.append((float(rec["energy"]), float(rec["writhe"])))
            else:
                t = 0.0 if hi == lo else (value - lam[j]) / (lam[j + 1] - lam[j])
                out.append(((1 - t) * energy[j] + t * energy[j + 1],
                            (1 - t) * writhe[j] + t * writhe[j + 1]))
    return out


def is_new_state(known: list[tuple[float, float]], energy: float, writhe: float) -> bool:
    """Whether a state of ``energy`` and ``writhe`` differs from every ``(energy, writhe)``
    of ``known`` (one dLk) by more than :data:`NEW_ENERGY` (relative) or
    :data:`NEW_WRITHE` (turns)."""
    return not any(abs(e - energy) <= NEW_ENERGY * max(1.0, abs(e))
                   and abs(w - writhe) <= NEW_WRITHE for e, w in known)


def _deflated_branches(opts, cp, branches, say, follow, seconds):
    """New states at ``opts.deflation`` computed points spread over the range, by deflation
    of the point's state and by relaxing the built knot there anew (module doc), each
    new one followed both ways (``deflated_K_up``/``_down``, ``relaxed_K_up``/``_down``) by
    ``follow`` (:func:`_follower`)."""
    from supercoil.problems.knot_deflation import deflate_at
    from supercoil.problems.ring_branches import ring_records

    low, high = opts.excess_link
    records = ring_records(cp.base)
    pool = [(b, i) for b in branches for i in range(len(b))]
    out, known, count = [], list(branches), {"deflation": 0, "relaxation": 0}
    for target in np.linspace(low, high, opts.deflation + 2)[1:-1]:
        b, i = min(pool, key=lambda bi: abs(bi[0].parameter_values[bi[1]] - target))
        value = float(b.parameter_values[i])
        say(f"deflation at dLk = {value:.4g} (from {b.name})")
        began = time.perf_counter()
        candidates = [(cp, d.q, "deflation") for d in deflate_at(
            cp, value, [b.states[i]], tolerance=opts.tolerance)]
        cp_new, q_new, _knot, _message = relaxed_knot(
            opts.knot, opts.twist_ratio, opts.length_over_diameter, value, opts.n_nodes,
            opts.tolerance)
        candidates.append((cp_new, q_new, "relaxation"))
        at_value = states_at(cp, known, value, opts.tolerance)
        for problem, q, method in candidates:
            rec = records(q, np.zeros(0), value)
            if not is_new_state(at_value, rec["energy"], rec["writhe"]):
                continue
            at_value.append((rec["energy"], rec["writhe"]))
            count[method] += 1
            stem = f"{'deflated' if method == 'deflation' else 'relaxed'}_{count[method]}"
            for name, stop in ((f"{stem}_up", high), (f"{stem}_down", low)):
                if abs(stop - value) < 1e-12:
                    continue
                branch = follow(problem, q, value, stop, name)
                out.append((branch, {"method": method, "excess_link": value,
                                     "from_branch": b.name, "from_index": i,
                                     "energy": rec["energy"], "writhe": rec["writhe"]}))
                known.append(branch)
                seconds[name] = time.perf_counter() - began
    return out
