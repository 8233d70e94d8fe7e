"""The computed ring diagram (:class:`RingDiagram`): its branches, points and payload.

:meth:`RingDiagram.points` gives one record per branch point: the branch's
records (:mod:`~supercoil.problems.ring_diagram.records`), its stability, the
contact lists recomputed from the stored states, the centreline's symmetry,
and ``condition_e``, the sign of ``d(dLk)/d(Wr)`` along the branch (Coleman &
Swigon's condition E, necessary for stability: :func:`link_writhe_slope_sign`)
beside ``unstable_count`` and ``determinant_sign`` (the test of Chamekh,
Mani-Aouadi & Moakher 2014); docs/model.md ("Stability", "Contacts in the
output", "Special points and branches") for the keys.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import PLACE_KEYS, contact_summary
from supercoil.continuation import Branch
from supercoil.continuation.branch import jsonable
from supercoil.geometry.symmetry import curve_symmetry
from supercoil.problems.branch_set import BranchSet
from supercoil.problems.model_keys import KIRCHHOFF, model_keys
from supercoil.problems.ring import michell_excess_link
from supercoil.problems.ring_diagram.options import DiagramOptions
from supercoil.problems.ring_diagram.secondary import SYMMETRY_TOLERANCE


@dataclass(frozen=True)
class RingDiagram(BranchSet):
    """The computed diagram: branches (circle, primary, contact), their problems' settings."""

    options: DiagramOptions
    branches: tuple[Branch, ...]
    contact_branches: frozenset[str]  # names of the branches computed with self-contact
    seconds: dict[str, float] = field(default_factory=dict)  # wall time per branch
    notes: tuple[str, ...] = ()
    contact_problem: ContactProblem | None = None  # for contact lists of stored states
    generations: dict[str, int] = field(default_factory=dict)  # secondary (2), tertiary (3)
    # contact branches: (first point index, the six rigid pins) at each choice of pins
    pins: dict[str, tuple[tuple[int, tuple[int, ...]], ...]] = field(default_factory=dict)
    model: dict = field(default_factory=lambda: dict(KIRCHHOFF))  # the rod model's keys

    def pin_branch(self, name: str, index: int, segment: bool = False,
                   problem: ContactProblem | None = None) -> None:
        """Set the rigid pins of ``problem`` (default: the diagram's contact problem; a
        ContactProblem on a ring) to those point ``index`` of branch ``name`` was computed
        with (``segment``: those of the step from ``index`` to ``index + 1``; a run's
        first point is its predecessor's last, computed with the older pins), e.g. as
        ``consistency_check(..., pin=lambda i, s: diagram.pin_branch(name, i, s, cp))``.
        Branches without recorded pins leave the problem as it is."""
        target = self.contact_problem if problem is None else problem
        choices = self.pins.get(name)
        if not choices or target is None:
            return
        dofs = choices[0][1]
        for start, chosen in choices:
            if start < index or start == index and (segment or start == 0):
                dofs = chosen
        rod = target.base
        rod.fixed = rod.gauge_dofs = np.array(dofs, dtype=np.int64)
        target.fixed = rod.fixed

    def generation(self, branch: Branch) -> int:
        """0 the circle, 1 a primary branch (with or without contact), 2 secondary, 3
        tertiary (:mod:`supercoil.problems.ring_diagram.secondary`)."""
        return generation_of(branch.name, branch.parent, self.generations)

    @staticmethod
    def branch_ok(branch: Branch) -> bool:
        """The branch is complete: it reached its bound, closed a loop, or was handed over
        as designed (a contact-free branch cut at its first contact, status ``STOPPED``).
        A branch stopped by its point limit, a step failure or an interrupt is not."""
        return branch.status.complete

    @property
    def ok(self) -> bool:
        """Every branch is complete (:meth:`branch_ok`), and no step failed (notes starting
        ``failed:``)."""
        return (all(self.branch_ok(b) for b in self.branches)
                and not any(n.startswith("failed:") for n in self.notes))

    def points(self) -> list[dict]:
        """One record per branch point (module doc), contact lists included."""
        out = []
        cp = self.contact_problem
        tolerance = SYMMETRY_TOLERANCE * self.options.diameter
        for b in self.branches:
            contact = b.name in self.contact_branches
            condition_e = link_writhe_slope_sign(b)
            for i in range(len(b)):
                rec = {k: jsonable(v[i]) for k, v in b.records.items()}
                symmetry = curve_symmetry(b.states[i].reshape(-1, 3), tolerance)
                entry = {"branch": b.name, "index": i, **rec,
                         "unstable_count": int(b.unstable_count[i]),
                         "zero_modes": int(b.zero_modes[i]),
                         "determinant_sign": int(b.determinant_sign[i]),
                         "condition_e": int(condition_e[i]),
                         "stable": bool(b.stable[i]),
                         "symmetry": symmetry.group,
                         "symmetry_residual_over_diameter":
                             symmetry.residual / self.options.diameter}
                if contact and cp is not None:
                    summary = contact_summary(cp, b.states[i], b.multipliers[i], PLACE_KEYS)
                    entry["contact_points"] = summary["contact_points"]
                    entry["contact_intervals"] = summary["contact_intervals"]
                else:
                    entry["contact_points"], entry["contact_intervals"] = [], []
                out.append(entry)
        return out

    def payload(self) -> dict:
        """The ``diagram.json`` payload (without the envelope of :mod:`supercoil.io.results`)."""
        opts = self.options
        branches = []
        for b in self.branches:
            branches.append({
                "name": b.name, "parent": b.parent,
                "origin": None if b.origin is None else b.origin.entry("excess_link"),
                "contact": b.name in self.contact_branches,
                "generation": self.generation(b),
                "parameter": b.parameter, "n_points": len(b), "status": b.status.name,
                "ok": self.branch_ok(b), "message": b.message,
                "seconds": round(self.seconds.get(b.name, float("nan")), 3),
                "file": "result.h5"})
        return {
            "description": "bifurcation diagram of a twisted ring with self-contact: the "
            "circle, its bifurcations, the primary branches without contact up to first "
            "contact, then with self-contact",
            **model_keys(self.model, self.branches),
            "twist_ratio": opts.twist_ratio,
            "length_over_diameter": opts.length_over_diameter,
            "diameter": opts.diameter,
            "n_nodes": opts.n_nodes,
            "contact_curve": opts.contact_curve,
            "contact_formulation": opts.contact_formulation,
            "sliding_gauge": opts.gauge,
            "contact_predictor": opts.contact_predictor,
            "rigid_pins": {name: [{"from_point": i, "dofs": list(d)} for i, d in choices]
                           for name, choices in self.pins.items()},
            "modes": list(opts.modes),
            "max_excess_link": opts.max_excess_link,
            "michell_excess_link": {str(m): float(michell_excess_link(opts.twist_ratio, m))
                                    for m in opts.modes},
            "branches": branches,
            "special_points": [p.entry("excess_link") for p in self.special_points()],
            "points": self.points(),
            "notes": list(self.notes),
            "ok": self.ok,
        }


def link_writhe_slope_sign(branch: Branch) -> np.ndarray:
    """Coleman & Swigon's condition E per point: the sign of ``d(dLk)/d(Wr)`` along the
    branch, (k,).

    ``d(dLk)/ds`` is the tangent's exact parameter component; ``d(Wr)/ds`` is the
    second-order finite difference of the recorded writhe over the points'
    arclength (``np.gradient``). 0 where the writhe does not change (the
    circle: Wr = 0) or the branch has fewer than two points.
    """
    k = len(branch)
    if k < 2 or "writhe" not in branch.records:
        return np.zeros(k, dtype=np.int64)
    s = np.asarray(branch.arclength, dtype=float)
    writhe = np.asarray(branch.records["writhe"], dtype=float)
    if np.any(np.diff(s) <= 0):
        return np.zeros(k, dtype=np.int64)
    d_writhe = np.gradient(writhe, s)
    d_link = branch.tangents[:, -1]
    scale = max(float(np.max(np.abs(d_writhe))), 1e-300)
    sign = np.sign(d_link) * np.sign(d_writhe)
    sign[np.abs(d_writhe) <= 1e-9 * max(scale, 1.0)] = 0
    return sign.astype(np.int64)


def generation_of(name: str, parent: str | None, known: dict[str, int]) -> int:
    """0 for the circle, 1 for a primary branch (with or without contact), else ``known``."""
    if name in known:
        return known[name]
    return 0 if parent is None else 1
