"""The bifurcation diagram of a ring with self-contact (seed 001, Figures 1-4).

:func:`ring_diagram` computes, for a ring of twist ratio ``C/A`` and tube
diameter ``D = L / (L/D)``:

1. the circle in ``dLk`` (branch ``circle``) and its Michell bifurcation
   points (:mod:`supercoil.problems.ring_branches`);
2. for each requested mode ``m`` the primary branch switched from the
   circle's bifurcation of mode ``m`` (``alpha``, ``beta``, ...) and followed
   **without contact**. A :class:`~supercoil.continuation.UserEvent` watches
   the closest approach of non-neighbouring centreline points,
   ``d_min / D - 1`` (``ContactProblem.min_distance``: segments closer than
   the neighbour exclusion ``pi D / 2`` along the rod are not compared); its
   sign change is located by Brent's method and is the special point
   ``contact_onset`` (label ``min_gap``). The contact-free branch is then cut
   after the first point beyond the onset (that last point penetrates; it is
   kept so that the onset lies between two points of the branch). The
   continuation itself cannot stop at an event, so the contact-free run goes
   on to its bounds and the rest is discarded (the cost of a few points);
3. from the last point before the onset (a state without contact, gap > 0)
   the branch is continued **with self-contact** (branch ``alpha_contact``,
   parent ``alpha``, origin the ``contact_onset`` point) in the direction the
   contact-free branch was going, within ``0 <= dLk <= max_excess_link``
   (folds are passed, so a branch that turns is followed back up or down).
   Steps are a fraction of ``D`` in the arclength metric (the RMS node
   displacement, plus ``D`` times the change of ``dLk``: a step of ``D/2``
   changes ``dLk`` by at most 1/2), so that no strand can cross another
   within a step; the
   corrector's steps are guarded by continuous collision detection
   (``ContactProblem.step_bound``) as well.

Contact events along a contact branch: the number of contact points and of
contact intervals (:func:`supercoil.contact.report.contact_summary`) are
integers, so a change between two branch points is a jump of the indicators
``n - k + 1/2`` (``k = 1 .. MAX_LEVEL``), one named scalar of a single
:class:`UserEvent` each; the jump is bracketed by Brent's method (bisection
safeguarded) on the branch between the two points, re-corrected at every
trial, to ``contact_event_tolerance`` in arclength. The kind is then read
from the counts at the two neighbouring points (both indicators of one
transition, e.g. a point opening into an interval, land on the same state
and are merged into one special point):

* the number of intervals rises: ``contact_interval_onset``;
* otherwise the number of contacts (points + intervals) rises: a
  ``contact_split`` when every contact after it lies within
  ``SPLIT_DISTANCE`` (in s/L, on both strands) of a contact before it (a
  point that became two nearby points), else a ``contact_onset``;
* otherwise (a count falls): ``contact_release``.

With the barrier treatment a contact carries a force once its gap is below
``barrier_activation * D`` (1 % of D), so the ``contact_onset`` of a contact
branch sits where the gap reaches that value, a little before the geometric
onset of the contact-free branch (``d_min = D``). The grouping into points
and intervals is done on the discrete rod (``contact_summary``): a contact
that slides along a segment can make a count flicker at coarse resolution.

Per point the branches' ``records`` hold ``excess_link``, ``writhe`` (double
sum), ``twist`` (material frames), ``energy`` (elastic only), ``link_error``
= ``|Tw + Wr - dLk|``, ``n_contact_points``, ``n_contact_intervals`` and
``min_gap_over_diameter``, and on contact branches ``sliding_residual``
(below); the contact lists with positions are recomputed from the stored
states by :meth:`RingDiagram.points`, which adds ``condition_e``, the sign of
``d(dLk)/d(Wr)`` along the branch (seed 001's condition E, necessary for
stability: :func:`link_writhe_slope_sign`) beside ``unstable_count`` and
seed 000's ``determinant_sign``.

Material sliding on contact branches. Sliding the material along the
centreline is an exact symmetry of the continuous homogeneous ring, with or
without contact, and DESIGN.md removes it from the unstable count. The
polygon breaks it: a segment-segment contact force is normal to the two
segments, not to the tangents at their nodes, so it pushes the material
along the rod (with a force of order ``F h kappa (2 t - 1)``, ``t`` the
contact's position on its segment), a potential of period ``h`` that locks
contacts to the mesh. Measured at C/A = 2/3, L/D = 122, N = 100 on alpha
after contact, with the sliding free: the lowest eigenvalue of the
constrained Hessian is negative (-0.003 just after the onset, -50 at
``dLk = 1.36``, M metric) with the force along that mode. Released there, the
continuation cannot pass the onset (where the contact force, hence the
sliding stiffness, starts from zero, and the branch runs along the sliding
orbit instead: it stalled at ``dLk = 1.0755``), and a Newton solve from a
pinned state did not converge. So contact branches are followed with the
sliding pinned (``ContinuationOptions.near_symmetry_gauge``, the default
``contact_gauge=True``): their states are equilibria of the discrete energy
with the material's position along the rod held, which is what the
continuous rod's symmetry allows. The force the pin holds is reported as
``sliding_residual`` (max ``|grad E + J^T mu|`` without the pin). It is an
artefact of the polygon contact, yet it does not clearly fall under mesh
refinement once the contact force is large (measured, C/A = 2/3: at L/D =
122, ``dLk`` about 1.32, 0.029 at N = 60 and 0.014 at N = 120; at L/D = 40
it falls from 0.032 (N = 48) to about 0.006 (N = 96) at ``dLk`` 1.35, but is
0.43 and 0.55 at ``dLk`` 1.9). A contact formulation that keeps the
sliding symmetry (distances between smooth interpolants of the nodes, not
between segments) is the fix. ``contact_curve="spline"``
(B-spline pieces) removes the chords' sag ripple but a sum over piece pairs
still counts a contact a varying number of times across piece junctions:
measured in docs/benchmarks.md ("Spline contact"). The default, the double
integral on the spline (``contact_formulation="integral"``), keeps the sliding
force below about 3e-3 on alpha up to ``dLk`` 6 (N = 200), against up to 27 with
the pair sum. On a state with a two-fold axis that is a symmetry of the mesh (through
a node or an edge midpoint) the force vanishes: the sliding mode is odd under the
axis and the gradient even. The primary branches are switched off the circle with
an axis through node 0 (:func:`on_mesh_direction`) and followed with rigid pins that
this axis maps onto themselves (:func:`~supercoil.rod.closed.rigid_pins`), so they
keep it to round-off and their states are equilibria without the gauge
(tests/test_ring_diagram.py); states without such an axis (tertiary branches) still
need it.

Rigid pins on contact branches. The ring removes its rigid motions by fixing
six DOFs (``ClosedRodEnergy.fixed``, chosen on the circle). As alpha folds into
a plectoneme those pins lose their grip (``pin_quality``, the determinant of
their response to rotations against the best choice, fell to 0.1): the pinned
Hessian keeps a nearly null rotation whose eigenvalue the gauge's small force
pushes through zero, and the branch folded back and forth there (measured:
L/D = 122, N = 200, from ``dLk`` 3.40). Contact branches therefore run in
segments of ``CONTACT_SEGMENT_POINTS`` points (:mod:`supercoil.problems.segments`):
the pins are picked at the branch's start and re-picked at a segment boundary
where their quality fell below ``PIN_QUALITY``, and within a run a point where
their determinant fell below a quarter of its value at the run's start is refused
and the pins picked there (``segments.follow(grip=...)``: a fixed set can pass
through a shape where it removes no rotation); the pinned coordinates keep
their values there. :attr:`RingDiagram.pins` records them
(:meth:`RingDiagram.pin_branch` sets them for checking a point), a resumed
branch replays them, and the ring's own pins are restored afterwards.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from supercoil import checks
from supercoil.contact.options import DEFAULT_TREATMENT, ContactOptions, validate_contact_choice
from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import COUNT_KEYS, PLACE_KEYS, contact_summary
from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    ContinuationStatus,
    SpecialPoint,
    UserEvent,
    continuation,
    switch_branch,
)
from supercoil.continuation.branch import jsonable
from supercoil.continuation.resume import resume_branch
from supercoil.geometry.symmetry import axis_invariant_combination, curve_symmetry
from supercoil.problems.ring import michell_excess_link
from supercoil.problems.ring_branches import PRIMARY_NAMES, circle_branch, ring_records
from supercoil.problems.ring_contact import validate_diameter
from supercoil.problems.ring_secondary import (
    SYMMETRY_TOLERANCE,
    generation_of,
    secondary_branches,
)
from supercoil.problems.segments import follow, grip_stop, set_pin
from supercoil.solvers.problem import free_dofs

MAX_LEVEL = 8  # contact-count indicators n - k + 1/2 for k = 1 .. MAX_LEVEL
SPLIT_DISTANCE = 0.1  # s/L, see the module docstring
# Smallest arclength step of a contact branch. Where a contact forms, the branch
# turns within a gap range of about barrier_activation * D * K_rod / kappa
# (the barrier stiffness grows from zero like 6 kappa (g_hat - g) / g_hat):
# about 1e-8 L at N = 60, L/D = 122, so steps far below D are needed there.
CONTACT_MIN_STEP = 1e-12
# Contact branches run in segments of this many points; between them the rigid pins are
# re-picked where their quality (ClosedRodEnergy.pin_quality) fell below PIN_QUALITY.
CONTACT_SEGMENT_POINTS = 40
PIN_QUALITY = 0.5
SWITCH_AMPLITUDE = 2e-3  # first point of a primary branch from its bifurcation (arclength)
SWITCH_AMPLITUDES = (SWITCH_AMPLITUDE, 5e-3, 1.5e-2)  # tried in turn, see _switch_off_circle
SWITCH_TRIAL_POINTS = 4
# energy treatments whose equilibria are plain stationary points of E + sum psi
CONTINUATION_TREATMENTS = ("barrier", "penalty")
PREDICTORS = ("tangent", "secant", "quadratic")
MAX_MODE = 12  # highest Michell mode whose primary branch is followed
MAX_SECONDARY_BRANCHES = 1000
CONTACT_KINDS = ("contact_onset", "contact_release", "contact_split", "contact_interval_onset")


@dataclass(frozen=True)
class DiagramOptions:
    """What :func:`ring_diagram` computes; validated on construction.

    ``twist_ratio`` C/A; ``length_over_diameter`` L/D (> pi); ``n_nodes`` N;
    ``modes`` the circle's bifurcation modes (integers >= 2) whose primary
    branches are followed; ``max_excess_link`` the upper bound of ``dLk``
    (the circle is followed at least 10 % beyond its highest requested
    Michell point); ``contact`` the treatment of self-contact.
    ``free_max_step`` / ``contact_max_step``: largest arclength steps of the
    contact-free branches (units of L) and of the contact branches (units of
    D); ``free_max_points`` / ``contact_max_points`` bound their lengths.
    ``event_tolerance``: arclength accuracy of the contact-free branches'
    events (the geometric contact onset included);
    ``contact_event_tolerance`` that of the contact branches' events.
    ``contact_tolerance``: corrector tolerance (max |KKT residual|) on the
    contact branches; the barrier's stiffness (``A / h^3`` growing like
    ``1 / gap``) puts the residual's round-off floor near 1e-7 at N = 60,
    L/D = 122, so the contact-free default 1e-10 cannot be reached there.
    ``contact_gauge``: pin the material sliding on contact branches
    (``ContinuationOptions.near_symmetry_gauge``; module docstring, "Material
    sliding"). Without it the branch does not pass the contact onset.
    ``branch_depth``: 1 computes the primary branches only, 2 adds the
    secondary branches switched from their bifurcation points, 3 the tertiary
    ones too (:mod:`supercoil.problems.ring_secondary`), each half-branch at
    most ``secondary_max_points`` points and ``secondary_max_branches``
    half-branches in all.
    ``contact_curve``: ``"polygon"``, ``"spline"`` or ``"quintic"``, the curve whose
    self-distance is the contact distance (``ContactOptions.curve``; the
    contact onset of the contact-free branches is measured on it too).
    ``contact_formulation``: ``"pairs"`` or ``"integral"``
    (``ContactOptions.formulation``). ``contact_predictor``: the predictor of the
    contact branches (``ContinuationOptions.predictor``).

    Defaults: the double-integral contact on the cubic B-spline, the integral
    phase condition as the sliding gauge, the quadratic predictor. Measured at
    C/A = 2/3, L/D = 122, N = 200 (docs/benchmarks.md, "Ring diagram, session 6"):
    alpha reaches dLk 6 with the three folds of seed 001's Figure 1 only; the
    pair sum on the polygon reaches it through artefact folds (and its beta
    branch leaves D_3 under refinement), the node gauge failed to restart a run
    at dLk 3.50.
    """

    twist_ratio: float
    length_over_diameter: float
    n_nodes: int = 100
    modes: tuple[int, ...] = (2, 3)
    max_excess_link: float = 6.0
    contact: str = DEFAULT_TREATMENT
    free_max_step: float = 0.1
    free_max_points: int = 80
    contact_max_step: float = 0.5
    contact_max_points: int = 150
    event_tolerance: float = 1e-8
    contact_event_tolerance: float = 1e-6
    contact_tolerance: float = 1e-8
    contact_gauge: bool = True
    gauge: str = "integral"
    branch_depth: int = 1
    secondary_max_points: int = 40
    secondary_max_branches: int = 12
    contact_curve: str = "spline"
    contact_formulation: str = "integral"
    contact_predictor: str = "quadratic"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "twist_ratio", checks.number("twist_ratio", self.twist_ratio, 0.0,
                                                checks.MAX_MAGNITUDE, low_open=True,
                                                meaning="C/A"))
        validate_diameter(self.length_over_diameter)
        set_(self, "length_over_diameter", float(self.length_over_diameter))
        set_(self, "n_nodes", checks.integer("n_nodes", self.n_nodes, checks.MIN_NODES,
                                             checks.MAX_NODES, meaning="nodes of the ring"))
        set_(self, "modes", checks.distinct_integers("modes", self.modes, 2, MAX_MODE,
                                                     meaning="Michell modes"))
        set_(self, "max_excess_link", checks.number(
            "max_excess_link", self.max_excess_link, 0.0, checks.MAX_MAGNITUDE,
            low_open=True, meaning="largest dLk in turns"))
        if self.contact not in CONTINUATION_TREATMENTS:
            raise checks.refuse("contact", f"must be one of {', '.join(CONTINUATION_TREATMENTS)}"
                                f", got {self.contact!r} (the exact and augmented treatments "
                                "need their active-set or multiplier loops, which the "
                                "continuation does not run)")
        check_steps(self)
        for name in ("free_max_points", "contact_max_points", "secondary_max_points"):
            checks.integer(name, getattr(self, name), 2, checks.MAX_POINTS,
                           meaning="points of a branch")
        checks.integer("secondary_max_branches", self.secondary_max_branches, 0,
                       MAX_SECONDARY_BRANCHES, meaning="secondary and tertiary half-branches")
        checks.choice("contact_predictor", self.contact_predictor, PREDICTORS)
        checks.choice("gauge", self.gauge, ("node", "integral"))
        checks.flag("contact_gauge", self.contact_gauge)
        checks.integer("branch_depth", self.branch_depth, 1, 3,
                       meaning="1 primary, 2 and secondary, 3 and tertiary branches")
        validate_contact_choice(self.contact_curve, self.contact_formulation)

    @property
    def diameter(self) -> float:
        """Tube diameter D in units of L."""
        return 1.0 / self.length_over_diameter

    @property
    def tolerances(self) -> dict:
        return branch_tolerances(self)

    def contact_options(self, diameter: float) -> ContactOptions:
        """The :class:`ContactOptions` of the contact branches, tube ``diameter`` (a length)."""
        return ContactOptions(diameter=diameter, treatment=self.contact, curve=self.contact_curve,
                              formulation=self.contact_formulation)


def check_steps(options) -> None:
    """The steps and tolerances shared by :class:`DiagramOptions` and the tweezers' options:
    positive numbers, steps at most 1e3 (units of L or D), tolerances below 1."""
    for name in ("free_max_step", "contact_max_step"):
        checks.number(name, getattr(options, name), 0.0, 1e3, low_open=True,
                      meaning="largest arclength step")
    for name in ("event_tolerance", "contact_event_tolerance", "contact_tolerance"):
        checks.number(name, getattr(options, name), 0.0, 1.0, low_open=True, high_open=True)


def branch_tolerances(options) -> dict:
    """The provenance ``tolerances`` of options with ``event_tolerance``,
    ``contact_event_tolerance`` and ``contact_tolerance`` (ring diagram, tweezers)."""
    return {"corrector_residual": ContinuationOptions.tolerance,
            "zero_modes": ContinuationOptions.zero_tolerance,
            "event_arclength": options.event_tolerance,
            "contact_event_arclength": options.contact_event_tolerance,
            "contact_corrector_residual": options.contact_tolerance}


@dataclass(frozen=True)
class RingDiagram:
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
        tertiary (:mod:`supercoil.problems.ring_secondary`)."""
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

    def branch(self, name: str) -> Branch:
        for b in self.branches:
            if b.name == name:
                return b
        raise KeyError(name)

    def special_points(self) -> list[SpecialPoint]:
        return [p for b in self.branches for p in b.special_points]

    def points(self) -> list[dict]:
        """One record per branch point (DESIGN.md keys), contact lists included."""
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
    """Seed 001's condition E per point: the sign of ``d(dLk)/d(Wr)`` along the branch, (k,).

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


# ----------------------------------------------------------------- records and events
def _contact_records(problem: ContactProblem, base_records, free: bool):
    """Per-point records: the ring's plus the contact counts and the closest approach."""

    def records(q, multipliers, excess_link):
        out = dict(base_records(q, multipliers, excess_link))
        if free:
            d_min = problem.min_distance(q)
            out.update(n_contact_points=0, n_contact_intervals=0,
                       min_gap_over_diameter=float(d_min / problem.diameter))
        else:
            summary = contact_summary(problem, q, multipliers, COUNT_KEYS)
            gap = summary["min_gap_over_diameter"]
            out.update(n_contact_points=summary["n_contact_points"],
                       n_contact_intervals=summary["n_contact_intervals"],
                       min_gap_over_diameter=float("inf") if gap is None else gap,
                       sliding_residual=kkt_residual(problem, q, multipliers))
        return out

    return records


def kkt_residual(problem, q: np.ndarray, multipliers: np.ndarray) -> float:
    """``max |grad E + J^T mu|, |c|`` on the free DOFs, without any continuation gauge.

    On a contact branch followed with the material sliding pinned this is the
    sliding force that the pin holds (module docstring, "Material sliding").
    """
    free = free_dofs(problem)
    g = problem.gradient(q)
    if problem.n_constraints:
        g = g + problem.constraint_jacobian(q).T @ multipliers
        c = np.abs(problem.constraints(q))
    else:
        c = np.zeros(0)
    return float(max(np.max(np.abs(g[free]), initial=0.0), np.max(c, initial=0.0)))


def onset_event(problem: ContactProblem) -> UserEvent:
    """``d_min / D - 1`` (closest approach of non-neighbouring points): contact onset."""

    def gap(q, multipliers, excess_link):
        d_min = problem.min_distance(q)
        return {"min_gap": float(min(d_min / problem.diameter - 1.0, 1e3))}

    return UserEvent("contact_onset", gap)


def contact_count_event(problem: ContactProblem) -> UserEvent:
    """Indicators ``n - k + 1/2`` of the contact point and interval counts (module doc)."""

    def levels(q, multipliers, excess_link):
        summary = contact_summary(problem, q, multipliers, COUNT_KEYS)
        out = {}
        for k in range(1, MAX_LEVEL + 1):
            out[f"points>={k}"] = summary["n_contact_points"] - k + 0.5
            out[f"intervals>={k}"] = summary["n_contact_intervals"] - k + 0.5
        return out

    return UserEvent("contact_change", levels)


def _positions(problem: ContactProblem, q, multipliers) -> np.ndarray:
    """(k, 2) positions (s1, s2) of the contacts (interval midpoints) at a state."""
    summary = contact_summary(problem, q, multipliers, PLACE_KEYS)
    rows = [(p["s1"], p["s2"]) for p in summary["contact_points"]]
    for iv in summary["contact_intervals"]:
        rows.append((_mid(iv["s1_start"], iv["s1_end"]), _mid(iv["s2_start"], iv["s2_end"])))
    return np.array(rows, dtype=float).reshape(-1, 2)


def _mid(a: float, b: float) -> float:
    return (0.5 * (a + b + (1.0 if b < a else 0.0))) % 1.0


def _near(after: np.ndarray, before: np.ndarray, distance: float) -> bool:
    if len(before) == 0 or len(after) == 0:
        return False
    for a in after:
        d = np.abs(before - a)
        d = np.minimum(d, 1.0 - d)  # periodic in s/L
        d_swapped = np.abs(before[:, ::-1] - a)
        d_swapped = np.minimum(d_swapped, 1.0 - d_swapped)
        if min(np.max(d, axis=1).min(), np.max(d_swapped, axis=1).min()) > distance:
            return False
    return True


def classify_contact_events(branch: Branch, problem: ContactProblem) -> Branch:
    """The branch with its ``contact_change`` points given their kinds (module doc), merged."""
    out: list[SpecialPoint] = []
    if "n_contact_points" not in branch.records:  # no point computed (a failed start)
        return branch
    n_points = branch.records["n_contact_points"]
    n_intervals = branch.records["n_contact_intervals"]
    for p in branch.special_points:
        if p.kind != "contact_change":
            out.append(p)
            continue
        i = p.index
        previous = out[-1] if out else None
        if (previous is not None and previous.kind in CONTACT_KINDS and previous.index == i
                and abs(previous.arclength - p.arclength) <= 4 * p.tolerance + 1e-12):
            continue  # the other indicator of the same transition
        dp = int(n_points[i + 1] - n_points[i])
        di = int(n_intervals[i + 1] - n_intervals[i])
        total_before = int(n_points[i] + n_intervals[i])
        if di > 0:
            kind = "contact_interval_onset"
        elif dp + di > 0:
            before = _positions(problem, branch.states[i], branch.multipliers[i])
            after = _positions(problem, branch.states[i + 1], branch.multipliers[i + 1])
            split = total_before >= 1 and _near(after, before, SPLIT_DISTANCE)
            kind = "contact_split" if split else "contact_onset"
        else:
            kind = "contact_release"
        label = (f"{p.label}: points {int(n_points[i])}->{int(n_points[i + 1])}, intervals "
                 f"{int(n_intervals[i])}->{int(n_intervals[i + 1])}")
        out.append(dataclasses.replace(p, kind=kind, label=label))
    return dataclasses.replace(branch, special_points=tuple(_mark_contact_bifurcations(
        out, problem)))


def _mark_contact_bifurcations(points: list[SpecialPoint], problem: ContactProblem | None
                               ) -> list[SpecialPoint]:
    """Label bifurcation points that lie within the barrier's reach of a contact event.

    DESIGN.md: a change of the unstable count at a contact event is not a
    bifurcation of the rod with hard contact. The barrier smooths the event
    over a layer of about ``barrier_activation * D``, where a count change is a
    bifurcation of the smoothed problem (a simple eigenvalue crossing zero
    without a fold always is), and it can be one of the rod too (seed 001's B_1:
    beta's three contact points appear and the C_2 branches start). So the kind
    stays ``bifurcation`` and the label says ``at <contact event>``, for the
    reader to weigh; distance measured in arclength.
    """
    if problem is None or problem.treatment != "barrier":
        return points
    reach = problem.options.barrier_activation * problem.diameter
    contact = [p for p in points if p.kind in CONTACT_KINDS]
    out = []
    for p in points:
        near = [c for c in contact if abs(c.arclength - p.arclength) <= reach]
        if p.kind == "bifurcation" and near:
            nearest = min(near, key=lambda c: abs(c.arclength - p.arclength))
            p = dataclasses.replace(p, label=f"bifurcation at {nearest.kind} (within the "
                                    f"barrier's reach)")
        out.append(p)
    return out


def truncate_after(branch: Branch, point: SpecialPoint, message: str) -> Branch:
    """The branch up to the first point beyond ``point`` (later special points dropped),
    with status ``STOPPED`` and ``message``: how the run went on past it (a failure
    there, e.g. Newton diverging where the contact-free rod passes through itself, is
    past the point kept and does not make the branch incomplete; the message says it)."""
    k = point.index + 2
    keep = tuple(p for p in branch.special_points
                 if p.index < point.index or (p.index == point.index
                                              and p.arclength <= point.arclength))
    arrays = {name: getattr(branch, name)[:k] for name in (
        "parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
        "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")}
    return dataclasses.replace(branch, special_points=keep,
                               records={n: v[:k] for n, v in branch.records.items()},
                               status=ContinuationStatus.STOPPED, message=message, **arrays)


# ------------------------------------------------------------------------- the diagram
def ring_diagram(options: DiagramOptions,
                 progress: Callable[[str], None] | None = None, *,
                 on_point: Callable[[Branch], None] | None = None,
                 on_branch: Callable[[Branch, bool], None] | None = None,
                 resume: Mapping[str, tuple[Branch, bool]] | None = None) -> RingDiagram:
    """Compute the diagram (module docstring); numerical failures end up in branch statuses.

    ``on_point(partial_branch)`` is called after each accepted point of the
    primary and contact branches (not of the switch's short trial runs), and
    ``on_branch(branch, contact)`` once per branch when it is final (the
    circle with its records, a primary branch cut after its contact onset, a
    contact branch with its events classified): e.g. to save them as they
    come (``supercoil run``). ``resume`` maps branch names to ``(branch,
    complete)`` of an interrupted run with the same options: complete primary
    and contact branches are taken as they are, incomplete ones continued
    from their last point (:func:`~supercoil.continuation.resume.resume_branch`);
    the circle is computed again (its problem is needed; about a second).
    """
    opts = options
    stored = dict(resume or {})
    final = on_branch or (lambda branch, contact: None)
    say = progress or (lambda message: None)
    seconds: dict[str, float] = {}
    notes: list[str] = []
    top = max(michell_excess_link(opts.twist_ratio, m) for m in opts.modes)
    circle_top = max(opts.max_excess_link, 1.1 * top)
    say(f"circle up to dLk = {circle_top:.4g}")
    start = time.perf_counter()
    circle, problem = circle_branch(opts.twist_ratio, opts.n_nodes, circle_top)
    seconds["circle"] = time.perf_counter() - start
    D = opts.diameter * problem.rod.length
    contact_options = opts.contact_options(D)
    # the onset is measured on the contact's own curve (and samples, for the integral)
    probe = ContactProblem(problem, dataclasses.replace(contact_options, treatment="barrier"))
    cp = ContactProblem(problem, contact_options)
    if problem.rod.edge_length > D:
        notes.append(f"segments ({problem.rod.edge_length:.3g} L) are longer than the tube "
                     f"diameter ({D:.3g} L): contact lines are under-resolved; use --nodes >= "
                     f"{int(np.ceil(problem.rod.length / D))}")
    asymmetric = [m for m in opts.modes if opts.n_nodes % m]
    if asymmetric:
        notes.append(f"N = {opts.n_nodes} is not a multiple of "
                     f"{', '.join(map(str, asymmetric))}: the mesh lacks the D_m symmetry of "
                     f"those primary branches, so their symmetry-breaking bifurcations (seed "
                     f"001's P on beta) unfold into folds; use --nodes a multiple of "
                     f"{math.lcm(*opts.modes)}")
    circle_records = _contact_records(probe, ring_records(problem), free=True)
    circle = _with_records(circle, problem, circle_records)
    final(circle, False)
    branches: list[Branch] = [circle]
    contact_names: set[str] = set()
    pins: dict[str, tuple[tuple[int, tuple[int, ...]], ...]] = {}
    bifurcations = {p.count_after: p for p in circle.points_of_kind("bifurcation")}
    for mode in opts.modes:
        name = PRIMARY_NAMES.get(mode, f"mode{mode}")
        point = bifurcations.get(2 * (mode - 1))
        if point is None or point.count_before != 2 * (mode - 2):
            notes.append(f"the circle branch has no bifurcation point of mode {mode}: "
                         f"{name} not computed")
            continue
        say(f"{name}: switched from the circle at dLk = {point.parameter:.4g}, no contact")
        start = time.perf_counter()
        free_opts = ContinuationOptions(
            initial_step=SWITCH_AMPLITUDE, max_step=opts.free_max_step,
            max_points=opts.free_max_points, parameter_bounds=(0.0, circle_top),
            event_tolerance=opts.event_tolerance, gauge=opts.gauge,
            rephase=opts.gauge == "integral", factor_refinement=True)
        old, complete = stored.get(name, (None, False))
        if complete:
            free = old
        elif old is not None and len(old):
            watched, stop = stop_after_onset(on_point)
            free = resume_branch(problem, old, free_opts, on_point=watched,
                                 records=_contact_records(probe, ring_records(problem), True),
                                 events=(onset_event(probe),), stop=stop,
                                 admissible=probe.admissible)
        else:
            free = _switch_off_circle(problem, circle, point, free_opts, name, probe, notes,
                                      on_point)
        onsets = [p for p in free.points_of_kind("contact_onset")
                  if p.index + 1 < len(free)]
        seconds[name] = time.perf_counter() - start
        if not onsets:
            notes.append(f"{name}: no contact found without contact ({free.message})")
            final(free, False)
            branches.append(free)
            continue
        onset = onsets[0]
        if not complete:
            free = truncate_after(free, onset, f"stopped at the first contact (dLk = "
                                  f"{onset.parameter:.6g}); the contact-free run: "
                                  f"{free.message}")
        final(free, False)
        branches.append(free)
        contact_name = f"{name}_contact"
        say(f"{contact_name}: from dLk = {onset.parameter:.4g}, with self-contact "
            f"({opts.contact})")
        start = time.perf_counter()
        # Start from the last contact-free point the contact terms do not yet
        # act on (closest approach above the treatment's reach, e.g. the
        # barrier's 1 % of D): it is an equilibrium of the contact problem too,
        # so the continuation's start correction has nothing to do. Points
        # inside the reach are off that problem's equilibria (the branch turns
        # sharply there) and the start correction diverged from them.
        reach = 1.0 + (cp.options.barrier_activation if cp.treatment == "barrier" else 0.0)
        gaps = free.records["min_gap_over_diameter"]
        k = onset.index
        while k > 0 and gaps[k] <= reach:
            k -= 1
        direction = 1 if free.tangents[k, -1] >= 0 else -1
        cp.excess_link = float(free.parameter_values[k])
        cp.accept(free.states[k])
        contact_opts = ContinuationOptions(
            initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
            max_step=opts.contact_max_step * D, max_points=opts.contact_max_points,
            parameter_bounds=(0.0, opts.max_excess_link), direction=direction,
            parameter_weight=D, tolerance=opts.contact_tolerance,
            near_symmetry_gauge=opts.contact_gauge, gauge=opts.gauge, regauge=True,
            rephase=opts.gauge == "integral", predictor=opts.contact_predictor,
            factor_refinement=True, event_tolerance=opts.contact_event_tolerance)
        if not 0.0 <= cp.excess_link <= opts.max_excess_link:
            notes.append(f"{contact_name}: contact at dLk = {cp.excess_link:.4g} is outside "
                         f"[0, {opts.max_excess_link:g}]: not computed")
            continue
        old, complete = stored.get(contact_name, (None, False))
        if complete:
            contact = old
            with _pins_restored(cp):
                pins[contact_name] = tuple(replayed_pins(cp, old.states))
        else:
            contact, pins[contact_name] = _contact_branch(cp, free.states[k], old,
                                                          contact_opts, contact_name, on_point)
            contact = classify_contact_events(contact, cp)
        sliding = contact.records.get("sliding_residual", np.zeros(0))
        # on a branch with a two-fold axis on the mesh the force vanishes by symmetry (module
        # doc, "Material sliding"): no note while it is at the corrector's own level (the
        # residual without the gauge measured 6e-9 to 1.5e-8 there, tolerance 1e-8)
        if (len(contact) and opts.contact_gauge
                and np.max(sliding) > 10 * opts.contact_tolerance):
            notes.append(f"{contact_name}: the material sliding is held fixed (a gauge); the "
                         f"sliding force it holds, max |KKT residual| without the gauge, is at "
                         f"most {float(np.max(sliding)):.2e} (at dLk = "
                         f"{float(contact.parameter_values[int(np.argmax(sliding))]):.4g}): "
                         f"an artefact of the {opts.contact_curve} contact (see the docs of "
                         "ring_diagram)")
        contact = dataclasses.replace(contact, parent=name, origin=onset)
        final(contact, True)
        seconds[contact_name] = time.perf_counter() - start
        branches.append(contact)
        contact_names.add(contact_name)
    diagram = RingDiagram(opts, tuple(branches), frozenset(contact_names), seconds,
                          tuple(notes), cp, pins=pins)
    if opts.branch_depth >= 2:
        diagram = secondary_branches(diagram, opts.branch_depth,
                                     max_points=opts.secondary_max_points,
                                     max_branches=opts.secondary_max_branches, progress=say,
                                     on_point=on_point, on_branch=final)
    return diagram


@contextlib.contextmanager
def _pins_restored(cp: ContactProblem):
    """Restore the ring's rigid pins (on the rod and its contact wrapper) on exit."""
    rod = cp.base
    saved = (rod.fixed, rod.gauge_dofs, cp.fixed)
    try:
        yield
    finally:
        rod.fixed, rod.gauge_dofs, cp.fixed = saved


def replayed_pins(cp: ContactProblem, states: np.ndarray
                  ) -> list[tuple[int, tuple[int, ...]]]:
    """The rigid pins of a contact branch computed by :func:`_contact_branch` without
    interruption, from its states: picked at its first point, then re-picked at every
    run boundary (every ``CONTACT_SEGMENT_POINTS - 1`` points) where their quality had
    fallen below ``PIN_QUALITY``. Leaves ``cp`` pinned as at the last state."""
    rod = cp.base
    set_pin(cp, rod, states[0])
    pins = [(0, tuple(int(d) for d in rod.fixed))]
    for b in range(CONTACT_SEGMENT_POINTS - 1, len(states) - 1, CONTACT_SEGMENT_POINTS - 1):
        if rod.pin_quality(states[b]) < PIN_QUALITY:
            set_pin(cp, rod, states[b])
            pins.append((b, tuple(int(d) for d in rod.fixed)))
    return pins


def _contact_branch(cp: ContactProblem, q_start: np.ndarray, old: Branch | None,
                    options: ContinuationOptions, name: str, on_point=None
                    ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]]:
    """A contact branch from ``q_start`` (or ``old``, an interrupted one, continued) in runs
    of ``CONTACT_SEGMENT_POINTS``, the rigid pins re-picked between runs (module doc,
    "Rigid pins"), and its pins (:attr:`RingDiagram.pins`); the ring's construction pins
    are restored afterwards."""
    rod = cp.base
    records = _contact_records(cp, ring_records(cp.base), free=False)
    events = (contact_count_event(cp),)
    first_opts = dataclasses.replace(options, max_points=min(CONTACT_SEGMENT_POINTS,
                                                             options.max_points))
    with _pins_restored(cp):
        if old is not None and len(old):
            # the pins the interrupted run had; a resumed run's later boundaries
            # are counted from the point it resumed at
            earlier = replayed_pins(cp, old.states)
            first = (resume_branch(cp, old, first_opts, on_point=on_point, records=records,
                                   events=events)
                     if len(old) < CONTACT_SEGMENT_POINTS else old)
        else:
            set_pin(cp, rod, q_start)
            earlier = [(0, tuple(int(d) for d in rod.fixed))]
            first = continuation(cp, q_start, parameter="excess_link", options=first_opts,
                                 name=name, records=records, events=events,
                                 on_point=on_point, stop=grip_stop(rod.pin_grip, q_start))
        branch, later = follow(cp, rod, first, options, name, records, events,
                               max_points=options.max_points,
                               segment_points=CONTACT_SEGMENT_POINTS, on_point=on_point,
                               quality=PIN_QUALITY, grip=rod.pin_grip)
    # follow reports the rod's gauge_dofs, which are all six pins for a ring
    return branch, tuple(earlier) + tuple((i, d) for i, d in later if i > 0)


def _switch_off_circle(problem, circle: Branch, point: SpecialPoint,
                       options: ContinuationOptions, name: str, probe: ContactProblem,
                       notes: list[str], on_point=None) -> Branch:
    """The primary branch from ``point``, checked to leave the circle.

    Measured: the switch can fall back onto the circle (writhe ~1e-6 and the
    circle's count along the "new" branch; C/A = 0.6667, N = 40). A short
    trial run (``SWITCH_TRIAL_POINTS`` points) must show the writhe growing
    away from zero; otherwise the other side of the critical mode and larger
    amplitudes are tried, in that order. The last attempt is returned anyway.

    The run refuses a state past a strand passage (``probe.admissible``: the
    double-sum writhe off the carried one by 2) and retries the step shorter:
    the onset event measures an unsigned distance, positive on both sides of
    a step that carries the rod through itself (measured: alpha at N = 200
    with steps of 0.2 L ran to dLk = 0 without an onset, and at 0.1 L the
    demo's N = 132 kept a point with Tw + Wr off dLk by 2 after the onset).
    The run stops (``STOPPED``) at the first point past the located onset: the
    branch is cut there anyway (:func:`truncate_after`), and beyond it alpha
    creeps towards its figure-eight in ever shorter steps (measured: 30 points
    at N = 200, every longer step refused as a strand passage).
    """
    records = _contact_records(probe, ring_records(problem), free=True)
    direction = on_mesh_direction(problem, point)
    attempts = [(a, side) for a in SWITCH_AMPLITUDES for side in (1, -1)]
    for number, (amplitude, side) in enumerate(attempts):
        trial_opts = dataclasses.replace(options, max_points=SWITCH_TRIAL_POINTS,
                                         initial_step=amplitude)
        trial = switch_branch(problem, circle, point, trial_opts, side=side,
                              amplitude=amplitude, name=name, records=records,
                              direction=direction)
        wr = np.abs(trial.records.get("writhe", np.zeros(0)))
        leaves = wr.size >= 2 and wr[-1] > 1e-4 and wr[-1] > 2 * wr[0]
        if leaves or number == len(attempts) - 1:
            if number:
                notes.append(f"{name}: switched with amplitude {amplitude:g}, side {side:+d} "
                             f"({number} earlier attempt(s) fell back onto the circle)")
            if not leaves:
                notes.append(f"failed: {name}: every switching attempt fell back onto the "
                             "circle")
            opts = dataclasses.replace(options, initial_step=amplitude)
            watched, stop = stop_after_onset(on_point)
            return switch_branch(problem, circle, point, opts, side=side, amplitude=amplitude,
                                 name=name, records=records, events=(onset_event(probe),),
                                 on_point=watched, direction=direction, stop=stop,
                                 admissible=probe.admissible)
    raise AssertionError("unreachable")


def stop_after_onset(on_point: Callable[[Branch], None] | None = None
                     ) -> tuple[Callable[[Branch], None], Callable[[np.ndarray], str | None]]:
    """``(on_point, stop)`` for a contact-free run: the first passes each partial branch
    on to ``on_point`` and notes a located ``contact_onset``; from then on the second
    refuses the next state (the run ends ``STOPPED`` at the point past the onset)."""
    located = []

    def watched(branch: Branch) -> None:
        if branch.points_of_kind("contact_onset"):
            located.append(True)
        if on_point is not None:
            on_point(branch)

    return watched, lambda q: "the contact onset is located" if located else None


def on_mesh_direction(problem, point: SpecialPoint) -> np.ndarray | None:
    """The combination of a circle bifurcation's two critical modes (``cos m theta``,
    ``sin m theta``: the circle's O(2) makes the eigenvalue double) whose two-fold axis
    passes through node 0 (``c = 0`` of :func:`~supercoil.geometry.symmetry.reversal_axes`),
    a full DOF vector; None for a simple eigenvalue.

    On the discrete ring the map ``x_i -> R x_{c - i}`` is an exact symmetry only for
    an integer ``c`` (an axis through a node or an edge midpoint); the switch picks
    the axis, and the continuation (equivariant, the integral phase row included)
    keeps it: measured at L/D 122, N = 132, beta with the axis at ``c = 0`` kept it to
    1e-11 D up to dLk 6, where the modes' own combination put it at ``c = 22.03``
    (``22 + 0.03``) and the axes drifted to ``0.11`` off the mesh. An axis off the
    mesh is a symmetry of no discrete problem: the secondary branches' C_2 was then
    approximate, and their symmetry-breaking bifurcations (seed 001's S) unfolded into
    smooth turns from C_2 to C_1. With ``m`` dividing ``N`` all ``m`` axes of a D_m
    branch are on the mesh.
    """
    modes = np.asarray(point.critical_modes, dtype=float)
    if modes.ndim != 2 or modes.shape[0] < 2:
        return None
    x = np.asarray(point.q, dtype=float).reshape(-1, 3)
    fields = modes.reshape(modes.shape[0], -1, 3)
    mass = np.asarray(problem.mass, dtype=float).reshape(-1, 3)[:, 0]
    direction = axis_invariant_combination(x, 0.0, fields, mass) @ modes
    # node 0 moves outward: for even m it then sits at a lobe's tip, far from node n/2
    # (the axis's other point), and the rigid pins on that axis keep their grip (with
    # node 0 at alpha's crossing, nodes 0 and n/2 came within 1.7 D)
    if direction.reshape(-1, 3)[0] @ (x[0] - x.mean(axis=0)) < 0:
        direction = -direction
    return direction


def _with_records(branch: Branch, problem, records) -> Branch:
    """The branch with its records recomputed by ``records`` (the problem follows it)."""
    rows = []
    for q, mu, lam in zip(branch.states, branch.multipliers, branch.parameter_values):
        problem.excess_link = float(lam)
        problem.accept(q)
        rows.append(records(q, mu, float(lam)))
    merged = {k: np.array([r[k] for r in rows]) for k in rows[0]} if rows else {}
    return dataclasses.replace(branch, records=merged)


def parse_modes(text: str | Sequence[int]) -> tuple[int, ...]:
    """``"2,3"`` -> ``(2, 3)``; a ValueError naming what is valid otherwise."""
    words = text.replace(",", " ").split() if isinstance(text, str) else list(text)
    try:
        modes = tuple(int(w) for w in words)
    except ValueError:
        raise ValueError(f"modes {text!r}: give integers >= 2 separated by commas, like 2,3"
                         ) from None
    if not modes or any(m < 2 for m in modes) or len(set(modes)) != len(modes):
        raise ValueError(f"modes {text!r}: give distinct integers >= 2 (2 = alpha, 3 = beta), "
                         "like 2,3")
    return tuple(sorted(modes))
