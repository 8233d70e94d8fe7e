"""A rod clamped at both ends, pulled and turned: the magnetic-tweezers experiment.

:func:`tweezers_branches` computes, for a rod of twist ratio ``C/A`` and tube
diameter ``D = L / (L/D)`` clamped on the ``z`` axis at both ends
(:class:`~supercoil.rod.open.ClampedRodEnergy`) and turned by ``turns``:

**Load control** (dead load ``F L^2/A``, the turned end slides along the axis):

1. the straight twisted rod in ``turns`` (branch ``straight``), its buckling
   located as a ``bifurcation`` (the unstable count jumps by 2: the rotation
   about the axis makes the critical eigenvalue double) and compared with the
   exact clamped condition (:mod:`supercoil.problems.greenhill`);
2. the buckled branch switched from it along the critical mode (branch
   ``buckled``), followed without contact until the closest approach of
   non-neighbouring points reaches ``D`` (a ``contact_onset``, located as a
   sign change of ``d_min/D - 1``; the branch is cut just after it);
3. from the last point of ``buckled`` that the barrier does not reach yet,
   the branch with self-contact (barrier treatment, ``buckled_contact``)
   through the plectoneme's growth up to the last requested turn.

**Displacement control** (end-to-end distance ``z/L < 1`` held): an
inextensible rod cannot be straight at ``z < L``, so there is no straight
branch: the branch starts from the clamped planar Euler buckle at
``turns = 0`` (tangent angle ``a sin(2 pi s / L)`` with ``a`` chosen for the
end distance, then Newton) and is followed in turns without, then with,
contact as above (branch ``clamped``, ``clamped_contact``).

The rotation about the axis is an exact symmetry of every state; the rod
pins the azimuth of one node (:meth:`ClampedRodEnergy.repin`). Along a
branch a continuation run ends at the point before one where the pinned node
no longer sees the rotation well (:func:`pin_stop`, checked at every point),
or after ``segment_points`` points; the pin is re-picked there when needed and
a new run goes on from the last point in the direction the branch was going;
the runs are merged into one :class:`~supercoil.continuation.Branch`. At an
equilibrium the pin carries no reaction (the energy is invariant under the
rotation, and the pinned coordinate moves under it), so every stored state
is an equilibrium of the unpinned problem and the count does not depend on
the pin.

Per point the branches' ``records`` hold (DESIGN.md keys): ``turns``,
``extension`` (end-to-end distance along the axis over L), ``torque`` (axial
moment at the turned end, ``M L / A = 2 pi (C/A) Tw`` for the reduced twist),
``twist`` (excess twist from the reference frames, turns), ``writhe`` (the
double sum of the rod closed by straight tails along the axis),
``closure_error`` = ``|Tw + Wr - turns|`` (Fuller's closure; above 1/2 the
rod has wrapped around a tail, or, without self-contact, passed through itself:
``closure_failed``), ``energy`` (elastic only),
``load_potential`` (``-F z``, zero under displacement control),
``tension`` (the axial force: the dead load, or the reaction at the end
under displacement control), ``n_contact_points``, ``n_contact_intervals``
and ``min_gap_over_diameter``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from supercoil import checks
from supercoil.contact.problem import ContactOptions, ContactProblem, validate_contact_choice
from supercoil.contact.report import COUNT_KEYS, contact_summary
from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    SpecialPoint,
    continuation,
    switch_branch,
)
from supercoil.continuation.resume import resume_branch
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ring_diagram import (
    PREDICTORS,
    branch_tolerances,
    check_steps,
    classify_contact_events,
    contact_count_event,
    onset_event,
    stop_after_onset,
    truncate_after,
)
from supercoil.problems.segments import either, follow, merge_branches, set_pin  # noqa: F401
from supercoil.rod.closed import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.topology import writhe

# Smallest arclength step on a contact branch (see ring_diagram.CONTACT_MIN_STEP).
CONTACT_MIN_STEP = 1e-12
# The contact branch's corrector trust region, in steps (ContinuationOptions.
# max_corrector_distance): where the branch turns back at the contact onset (80 degrees
# within 3e-5 of arclength at N = 100, L/D = 33, F L^2/A = 75) steps that cross the
# corner converged 2-5 steps away from the predictor in 5-9 Newton iterations, then were
# refused by the turn test; stopped at the first iterate beyond one step, the same points
# came with 461 corrector iterations instead of 501 (docs/benchmarks.md, "Session 10").
CONTACT_CORRECTOR_DISTANCE = 1.0
SWITCH_AMPLITUDE = 2e-2  # first point of the buckled branch from the bifurcation (arclength)
# tried in turn when the switch finds no point (the subcritical branch turns back sharply
# under a large tension: measured at F L^2/A = 900, N = 120, 2e-2 diverged)
SWITCH_AMPLITUDES = (SWITCH_AMPLITUDE, 5e-3, 1e-3)
PIN_QUALITY = 0.5  # re-pick the azimuth pin below this (ClampedRodEnergy.pin_quality)
TAIL_WRAP = 0.5  # |Tw + Wr - turns| above this: the closure failed (a tail or a self-crossing)


@dataclass(frozen=True)
class TweezersOptions:
    """What :func:`tweezers_branches` computes; validated on construction.

    ``twist_ratio`` C/A; ``length_over_diameter`` L/D (> pi), or None for a
    rod without self-contact (the contact-free branch is then followed to the
    last turn); exactly one of ``tension`` (F L^2/A >= 0, load control) and
    ``end_distance`` (z/L in (0, 1), displacement control); ``turns`` the
    interval ``(start, stop)`` of turns (``stop > start >= 0``; the straight
    branch starts at ``start``); ``n_nodes`` N. ``free_max_step``: largest
    arclength step without contact (units of L); ``contact_max_step``: with
    contact (units of D); ``max_points`` bounds each branch;
    ``segment_points`` the most points per continuation run: the azimuth pin is checked
    at every point (:func:`pin_stop`) and a run ends where it must be picked again, so
    runs need no other bound (2000, the default ``max_points``; with 30, before the
    per-point check, the benchmark's contact branch took 4 runs and 887 bordered
    factorisations against 1 run and 852, and its pin never changed).
    ``contact_predictor``: the predictor of the contact branch
    (``ContinuationOptions.predictor``). ``"quadratic"`` adds the curvature
    of the branch from the last two tangents: the barrier's stiffness makes
    the corrector's first residual large (5-80) even for short steps, and
    with the tangent predictor the steps stayed at a tenth of
    ``contact_max_step`` (289 points from 0 to 5 turns at N = 100, L/D = 33,
    F L^2/A = 75; 93 with ``"quadratic"``, the same events and end state;
    docs/benchmarks.md, "Session 6").
    Tolerances as in :class:`~supercoil.problems.ring_diagram.DiagramOptions`.
    ``contact_curve``: ``"spline"`` (default) or ``"polygon"``
    (``ContactOptions.curve``); ``contact_formulation``: ``"integral"``
    (default) or ``"pairs"`` (``ContactOptions.formulation``). The default,
    the double integral over the B-spline, counts a contact once wherever it
    lies relative to the nodes: the pair sum on the polygon made a sawtooth
    of fold pairs along the plectoneme (35 folds from 0 to 5 turns at N =
    100 against 3; docs/benchmarks.md, "Integral contact").
    """

    twist_ratio: float
    length_over_diameter: float | None
    tension: float | None = None
    end_distance: float | None = None
    turns: tuple[float, float] = (0.0, 5.0)
    n_nodes: int = 100
    free_max_step: float = 0.1
    contact_max_step: float = 0.5
    max_points: int = 2000
    segment_points: int = 2000
    contact_predictor: str = "quadratic"
    event_tolerance: float = 1e-8
    contact_event_tolerance: float = 1e-6
    contact_tolerance: float = 1e-8
    contact_curve: str = "spline"
    contact_formulation: str = "integral"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "twist_ratio", checks.number("twist_ratio", self.twist_ratio, 0.0,
                                                checks.MAX_MAGNITUDE, low_open=True,
                                                meaning="C/A"))
        set_(self, "length_over_diameter", checks.optional_number(
            "length_over_diameter", self.length_over_diameter, math.pi, checks.MAX_MAGNITUDE,
            low_open=True, meaning="L/D; a thicker tube cannot bend"))
        if (self.tension is None) == (self.end_distance is None):
            raise checks.refuse("tension", "and end_distance: give exactly one of tension "
                                "(F L^2/A, load control) and end_distance (z/L, displacement "
                                "control)")
        set_(self, "tension", checks.optional_number(
            "tension", self.tension, 0.0, checks.MAX_MAGNITUDE, meaning="F L^2/A"))
        set_(self, "end_distance", checks.optional_number(
            "end_distance", self.end_distance, 0.0, 1.0, low_open=True, high_open=True,
            meaning="z/L of an inextensible rod of length L"))
        set_(self, "turns", check_turns(self.turns))
        set_(self, "n_nodes", checks.integer("n_nodes", self.n_nodes, checks.MIN_CLAMPED_NODES,
                                             checks.MAX_NODES,
                                             meaning="nodes of the clamped rod"))
        check_steps(self)
        for name in ("max_points", "segment_points"):
            checks.integer(name, getattr(self, name), 2, checks.MAX_POINTS,
                           meaning="points of a branch")
        checks.choice("contact_predictor", self.contact_predictor, PREDICTORS)
        validate_contact_choice(self.contact_curve, self.contact_formulation)

    @property
    def load_control(self) -> bool:
        return self.tension is not None

    @property
    def diameter(self) -> float | None:
        return None if self.length_over_diameter is None else 1.0 / self.length_over_diameter

    @property
    def tolerances(self) -> dict:
        return branch_tolerances(self)


def check_turns(turns) -> tuple[float, float]:
    """``(start, stop)`` turns with ``0 <= start < stop <= 1000``, or an InputError."""
    valid = (f"(start, stop) turns with 0 <= start < stop <= "
             f"{checks.MAX_TURNS:g}")
    try:
        start, stop = turns
        start = checks.number("turns", start, 0.0, checks.MAX_TURNS)
        stop = checks.number("turns", stop, 0.0, checks.MAX_TURNS)
    except (TypeError, ValueError):
        raise checks.refuse("turns", f"must be {valid}, got {turns!r}") from None
    if not start < stop:
        raise checks.refuse("turns", f"must be {valid}, got {turns!r}")
    return start, stop


@dataclass(frozen=True)
class TweezersResult:
    """Computed branches (in order), the problems to re-evaluate their states, notes."""

    options: TweezersOptions
    branches: tuple[Branch, ...]
    contact_branches: frozenset[str]
    rod_problem: ClampedRodEnergy
    contact_problem: ContactProblem | None
    seconds: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    # per branch: (first point index, pinned DOFs) at each choice of the azimuth pin
    pins: dict = field(default_factory=dict)
    # contact-free branches cut at their first contact: complete whatever the run that
    # went on beyond the contact (penetrating) ended with
    cut_at_contact: frozenset[str] = frozenset()

    def branch_ok(self, branch: Branch) -> bool:
        """The branch is complete: it reached its bound (or closed a loop), or it is a
        contact-free branch handed over at its first contact to the contact branch. A
        branch stopped by the point limit, a step failure or an interrupt is not."""
        return branch.status.complete or branch.name in self.cut_at_contact

    def pin_branch(self, name: str, index: int = 0):
        """Set the azimuth pin with which point ``index`` of branch ``name`` was computed.

        Returns the problem to check that branch against (the contact wrapper
        for contact branches). The pinned coordinate keeps the value it had
        at the first point of its run.
        """
        rod = self.rod_problem
        dofs: tuple[int, ...] = ()
        for start, chosen in self.pins.get(name, ((0, ()),)):
            if start <= index:
                dofs = chosen
        clamps = np.setdiff1d(rod.fixed, rod.gauge_dofs)
        rod.gauge_dofs = np.array(dofs, dtype=np.int64)
        rod.fixed = np.array(sorted(set(clamps.tolist()) | set(dofs)), dtype=np.int64)
        problem = self.contact_problem if name in self.contact_branches else rod
        if problem is not rod:
            problem.fixed = rod.fixed
        return problem

    @property
    def ok(self) -> bool:
        return (all(self.branch_ok(b) for b in self.branches)
                and not any(n.startswith(("failed:", "incomplete:")) for n in self.notes))

    def branch(self, name: str) -> Branch:
        for b in self.branches:
            if b.name == name:
                return b
        raise KeyError(name)

    def special_points(self) -> list[SpecialPoint]:
        return [p for b in self.branches for p in b.special_points]

    @property
    def greenhill_turns(self) -> float | None:
        """Exact critical turns of the straight rod (load control), see greenhill.py."""
        if not self.options.load_control:
            return None
        return critical_turns(self.options.twist_ratio, self.options.tension)


# ------------------------------------------------------------------------ problem set-up
def clamped_problem(options: TweezersOptions) -> tuple[ClampedRodEnergy, np.ndarray]:
    """The rod problem at ``turns = start`` and its first state ``(n_nodes * 3,)``.

    Load control: the straight rod. Displacement control: the planar clamped
    Euler buckle at the end distance (module doc), before Newton.
    """
    opts = options
    rod = Rod(opts.n_nodes, twist_stiffness=opts.twist_ratio, closed=False)
    if opts.load_control:
        pts = straight_rod(opts.n_nodes)
        return ClampedRodEnergy(rod, pts, opts.turns[0], tension=opts.tension), pts.ravel()
    pts = clamped_buckle(opts.n_nodes, opts.end_distance)
    problem = ClampedRodEnergy(rod, pts, opts.turns[0], end_distance_control=True)
    return problem, pts.ravel()


def clamped_buckle(n_nodes: int, end_distance: float) -> np.ndarray:
    """Planar clamped buckle ``(n_nodes, 3)`` in the x-z plane with the given end distance.

    Edges of exact length ``h = L/(n - 2)`` at tangent angles
    ``a sin(2 pi s)`` (``s`` the edge midpoints, so the first and last edges
    lie along the axis); ``a`` solves ``sum h cos(theta) = z`` (Brent). The
    shape is symmetric, so the far end lies on the axis.
    """
    from scipy.optimize import brentq

    h = 1.0 / (n_nodes - 2)
    s = (np.arange(n_nodes - 1)) * h  # edge midpoints: edge k spans [(k - 1/2) h, (k + 1/2) h]

    def distance(a):
        return float(np.sum(h * np.cos(a * np.sin(2 * np.pi * s)))) - h - end_distance

    a = brentq(distance, 0.0, 2.4, xtol=1e-15)  # J0(2.4) ~ 0: below any z/L > 0 here
    theta = a * np.sin(2 * np.pi * s)
    steps = h * np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    pts = np.vstack([[0.0, 0.0, -0.5 * h], -0.5 * h * np.array([0, 0, 1.0]) + np.cumsum(
        steps, axis=0)])
    pts[[0, 1, -2, -1], 0] = 0.0  # round-off of the symmetric sum
    return pts


# ----------------------------------------------------------------------------- records
def tweezers_records(problem, rod: ClampedRodEnergy, contact: bool, probe=None):
    """Per-point records (module doc) for ``continuation(records=)``."""

    def records(q: np.ndarray, multipliers: np.ndarray, turns: float) -> dict:
        x = q.reshape(-1, 3)
        wr = writhe(x, closure="axis", self_crossing="nan")
        tw = rod.twist(q)
        error = abs(tw + wr - turns)
        out = {"turns": float(turns), "extension": rod.extension(q),
               "torque": 2 * math.pi * rod.rod.twist_ratio * tw, "twist": tw, "writhe": wr,
               "closure_error": error,
               "closure_failed": bool(not error <= TAIL_WRAP),  # a crossing: NaN, failed
               "energy": rod.elastic_energy(q), "load_potential": rod.load_potential(q),
               "tension": axial_force(rod, multipliers),
               # the azimuth pin the point was computed with (a resumed run keeps it)
               "azimuth_pin": int(rod.gauge_dofs[0]) if rod.gauge_dofs.size == 1 else -1}
        if contact:
            summary = contact_summary(problem, q, multipliers, COUNT_KEYS)
            gap = summary["min_gap_over_diameter"]
            out.update(n_contact_points=summary["n_contact_points"],
                       n_contact_intervals=summary["n_contact_intervals"],
                       min_gap_over_diameter=float("inf") if gap is None else gap)
        else:
            gap = float("inf") if probe is None else probe.min_distance(q) / probe.diameter
            out.update(n_contact_points=0, n_contact_intervals=0,
                       min_gap_over_diameter=float(gap))
        return out

    return records


def axial_force(rod: ClampedRodEnergy, multipliers: np.ndarray) -> float:
    """The axial force at the turned end: the dead load, or the last edge's tension."""
    if not rod.end_distance_control:
        return float(rod.tension)
    mu = np.asarray(multipliers, dtype=float)
    return float(mu[rod.n_constraints - 1]) if mu.size >= rod.n_constraints else float("nan")


def _rotated_mode(mode: np.ndarray) -> tuple[np.ndarray, int]:
    """The critical mode turned about the axis so the node it moves most moves along +x,
    and that node.

    The first such node within a relative ``1e-6`` of the largest move: the clamped
    rod's modes are symmetric about its middle, so two nodes tie exactly and round-off
    picks either (nodes 49 and 50 of 100); see :func:`_pin_node`."""
    v = mode.reshape(-1, 3).copy()
    r = np.linalg.norm(v[:, :2], axis=1)
    k = int(np.flatnonzero(r >= (1.0 - 1e-6) * r.max())[0])
    a = -math.atan2(v[k, 1], v[k, 0])
    c, s = math.cos(a), math.sin(a)
    x, y = v[:, 0].copy(), v[:, 1].copy()
    v[:, 0], v[:, 1] = c * x - s * y, s * x + c * y
    return v.ravel(), k


def _pin_node(rod: ClampedRodEnergy, node: int) -> None:
    """Pin the azimuth of the straight rod's buckling at ``node``: its ``y`` coordinate,
    along which the mode of :func:`_rotated_mode` does not move it.

    What ``rod.repin(q* + 1e-3 mode)`` picks when ``node`` is the one farthest from the
    axis; with two nodes tied (the mode's symmetry about the rod's middle) the rotation's
    round-off decided, and a pin on the other node, which the mode moves across it,
    drops that component of the switch's direction: the switch then left the straight
    rod for another branch (measured at N = 100, F L^2/A = 75: its first point at 2.59
    turns, beyond the second bifurcation, instead of the subcritical branch at 2.20).
    """
    clamps = np.setdiff1d(rod.fixed, rod.gauge_dofs)
    rod.gauge_dofs = np.array([3 * node + 1], dtype=np.int64)
    rod.fixed = np.array(sorted(set(clamps.tolist()) | {3 * node + 1}), dtype=np.int64)


def pin_stop(rod: ClampedRodEnergy) -> Callable[[np.ndarray], str | None]:
    """A ``continuation`` ``stop`` that refuses a state where the azimuth pin's quality
    (``rod.pin_quality``) is below ``PIN_QUALITY``: the run ends at the point before,
    where :func:`~supercoil.problems.segments.follow` picks the pin again.

    Checked at every point (about 20 us): the pin was re-picked only between runs of
    ``segment_points``, so it could degrade for up to that many points, and the runs
    were kept short (30 points) for it; each new run starts without the step growth and
    the quadratic predictor's history of the last, and recomputes its first point's
    stability (measured on the benchmark's contact branch, which keeps its first pin:
    93 points in 4 runs, against 91 in one).
    """

    def refuse(q: np.ndarray) -> str | None:
        quality = rod.pin_quality(q)
        if quality < PIN_QUALITY:
            return f"the azimuth pin's quality fell to {quality:.2g} (below {PIN_QUALITY:g})"
        return None

    return refuse


def _onset_stop(run: Branch) -> bool:
    return any(p.kind == "contact_onset" and p.index + 1 < len(run) for p in run.special_points)


# ----------------------------------------------------------------------------- branches
STRAIGHT_MAX_STEP = 1.0  # arclength step of the straight branch (see straight_branch)
# relative departure from linearity in turns of the straight rod's Hessian above which
# the pencil is not trusted (measured: 1e-17 of its largest entry at N = 100)
PENCIL_LINEARITY = 1e-10


def straight_branch(options: TweezersOptions, problem: ClampedRodEnergy, q0: np.ndarray,
                    records, on_point=None) -> Branch:
    """The straight rod in turns (load control), with its bifurcations located.

    The straight twisted rod is the same state at every ``turns``: its points
    only bracket the count changes. Steps up to one turn (``STRAIGHT_MAX_STEP``)
    halve the points against a quarter turn (N = 100, 0-5 turns: 12 points
    instead of 24, the five bifurcations within 3e-9 turns of those found with
    quarter turns). The points are followed without bifurcation detection and
    the count changes are located all at once by :func:`straight_bifurcations`
    (the Hessian is linear in turns there); where that does not certify them,
    the branch is computed again with the continuation's own localisation
    (bisection on the count, then Brent's method on the eigenvalue nearest zero).
    """
    opts = options
    cont = ContinuationOptions(initial_step=0.05, max_step=STRAIGHT_MAX_STEP,
                               parameter_bounds=opts.turns, max_points=opts.max_points,
                               event_tolerance=opts.event_tolerance, detect_bifurcations=False)
    branch = continuation(problem, q0, parameter="turns", options=cont, name="straight",
                          records=records, on_point=on_point)
    specials = straight_bifurcations(problem, branch, cont, records)
    if specials is not None:
        return dataclasses.replace(branch, special_points=specials)
    problem.turns = opts.turns[0]
    problem.accept(q0)
    return continuation(problem, q0, parameter="turns", options=dataclasses.replace(
        cont, detect_bifurcations=True), name="straight", records=records, on_point=on_point)


def straight_bifurcations(problem: ClampedRodEnergy, branch: Branch,
                          options: ContinuationOptions, records=None
                          ) -> tuple[SpecialPoint, ...] | None:
    """The count changes of the straight branch from one symmetric-definite eigenproblem;
    None where they are not certified (the caller then locates them by continuation).

    Every point of ``branch`` is the one state ``(q, mu)`` (checked), so the Hessian
    of the Lagrangian on the free DOFs is a function of ``turns`` alone, and it is
    linear there, ``H(t) = H_0 + (t - t_0) B``: the twist energy is ``(C/2L)(2 pi Tw)^2``
    with ``Tw = turns + f(q)`` and ``grad f = 0`` on the straight rod (by its symmetry
    under the half turn about the axis), so its Hessian is ``(C/L)(2 pi)^2 Tw hess f``.
    Linearity is checked at a third point (departure at most ``PENCIL_LINEARITY``
    of the largest entry). With ``Z`` an orthonormal basis of the constraints' kernel
    (``J Z = 0``, the same ``J`` at every point) and ``A = Z^T H_0 Z`` positive definite
    (the count is 0 at the first point), Sylvester's law of inertia gives the count at
    ``t > t_0`` as the number of eigenvalues ``theta > 1 / (t - t_0)`` of the definite
    pencil ``(-Z^T B Z) v = theta A v``: the constrained Hessian is singular exactly at
    ``t_0 + 1 / theta``, the axisymmetric rod's pairs giving double roots. These roots
    are the bifurcations (roots within ``event_tolerance`` of each other one event, its
    count jump their number).

    Certified by inertia counts: the pencil's count must equal the branch's stored
    count at every point, and the continuation's
    :func:`~supercoil.continuation.stability.inertia` halfway between consecutive
    roots (and between the first root and ``t_0``, the last and the branch's end) must
    give the counts the pencil predicts there, so every count change lies between two
    such checks and at the pencil's root, a backward-stable eigenvalue. (A first
    version checked the inertia ``event_tolerance`` from each root: at N = 1000 the
    constrained eigenvalues there are 1e-17 of the Hessian's largest, below what an
    inertia resolves, so it never certified and the branch was located again by
    continuation, 118 s against 88 s; the review of session 9 measured it.) For
    ``t < t_0`` (turns decreasing) the count is the number of ``theta (t - t_0) > 1``,
    the same rule. Each special point is then filled as the continuation's
    localisation fills it (its stability, ``point_stability``, with the critical modes
    that the branch switch follows; its records), at the state of the branch, except
    its ``unstable_count``: the count of the eigenvalues below zero there, i.e. the
    count before (certified; the pair is at zero). ``point_stability`` at a point this
    close to singular counts from an inertia that round-off decides and undercounts
    (measured: 0, 2, 2, 5, 8 at the continuation's five points, whose counts before
    are 0, 2, 4, 6, 8).

    Measured (N = 100, C/A = 4/3, F L^2/A = 75, 0-5 turns): the five bifurcations agree
    with the continuation's bisection-then-Brent localisation to 1e-9 turns (its
    tolerance 1e-8); the straight branch took 75 inertia counts and 48 eigenproblems
    with that localisation, 23 and 17 with this one (12 points, 6 certifying counts
    halfway between the roots and the ends, 5 special points; 27 with the first
    version's two counts beside each root) plus the 192 x 192 definite eigenproblem:
    0.54-0.69 s against 0.18 s of CPU (docs/benchmarks.md, "Session 9").
    """
    from scipy.linalg import LinAlgError, eigh, null_space

    from supercoil.continuation.stability import count_gauge, inertia, point_stability
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.solvers.errors import InertiaError, SingularMatrixError

    n_points = len(branch)
    if n_points < 2 or branch.unstable_count[0] != 0 or branch.zero_modes[0] != 0:
        return None
    q, mu = branch.states[0], branch.multipliers[0]
    if not (np.array_equal(branch.states, np.broadcast_to(q, branch.states.shape))
            and np.array_equal(branch.multipliers,
                               np.broadcast_to(mu, branch.multipliers.shape))):
        return None
    turns = branch.parameter_values
    t0 = float(turns[0])
    system = ExtendedSystem(problem, "turns", q, None, q, options.parameter_weight,
                            options.finite_difference_step)

    def x_at(t: float) -> np.ndarray:
        return system.pack(q, mu, t)

    last = float(turns[-1])
    if last == t0:
        return None
    sense = 1.0 if last > t0 else -1.0  # the direction of travel in turns
    try:
        if count_gauge(system, x_at(t0)).size:
            return None
        h0 = system.hessian(x_at(t0)).dense()
        slope = (system.hessian(x_at(last)).dense() - h0) / (last - t0)
        middle = 0.5 * (t0 + last)  # not a stored point: a two-point branch has none
        departure = np.abs(system.hessian(x_at(middle)).dense() - (h0 + (middle - t0) * slope))
        if departure.max() > PENCIL_LINEARITY * np.abs(h0).max():
            return None
        J = system.jacobian(x_at(t0))
        Z = null_space(J.toarray()) if J.shape[0] else np.eye(system.n)
        theta = eigh(-(Z.T @ slope @ Z), Z.T @ h0 @ Z, eigvals_only=True)
    except LinAlgError:
        return None

    def pencil_count(t: float) -> int:
        return int(np.sum(theta * (t - t0) > 1.0))

    counts = np.array([0] + [pencil_count(t) for t in turns[1:]])
    if not np.array_equal(counts, branch.unstable_count) or np.any(branch.zero_modes):
        return None
    ahead = theta[theta * sense > 0]
    roots = t0 + 1.0 / ahead[np.argsort(-np.abs(ahead))]  # nearest t0 first
    roots = roots[sense * (roots - last) <= 0]
    delta = options.event_tolerance / options.parameter_weight  # in turns
    clusters: list[list[float]] = []
    for root in roots:
        if clusters and abs(root - clusters[-1][-1]) <= delta:
            clusters[-1].append(float(root))
        else:
            clusters.append([float(root)])
    centres = [float(np.mean(c)) for c in clusters]
    # the count halfway between consecutive roots (and the ends) must be the pencil's
    stops = [t0, *centres, last]
    for k in range(len(stops) - 1):
        if abs(stops[k + 1] - stops[k]) <= 4 * delta:
            return None
        check = 0.5 * (stops[k] + stops[k + 1])
        try:
            if inertia(system, x_at(check), options.zero_tolerance)[0] != pencil_count(check):
                return None
        except (SingularMatrixError, InertiaError):
            return None
    order = turns if sense > 0 else -turns  # increasing, for the segment of a root
    specials = []
    before = 0
    try:
        for cluster, at in zip(clusters, centres, strict=True):
            after = before + len(cluster)
            index = int(np.searchsorted(order, sense * at)) - 1
            x = x_at(at)
            stab = point_stability(system, x, options.zero_tolerance, options.n_modes)
            values, modes = stab.critical_modes(len(cluster))
            u = (at - turns[index]) / (turns[index + 1] - turns[index])
            arclength = float(branch.arclength[index]
                              + u * (branch.arclength[index + 1] - branch.arclength[index]))
            tangent = np.zeros(branch.tangents.shape[1])
            tangent[-1] = 1.0  # the branch's secant: the state does not move
            system.set_parameter(at)
            specials.append(SpecialPoint(
                kind="bifurcation", label="bifurcation", branch=branch.name, index=index,
                parameter=at, arclength=arclength, q=q.copy(), multipliers=mu.copy(),
                tangent=tangent, unstable_count=before, count_before=before,
                count_after=after, critical_eigenvalues=values, critical_modes=modes,
                located=True, tolerance=options.event_tolerance,
                records=dict(records(q, mu, at)) if records is not None else {}))
            before = after
    finally:
        system.set_parameter(last)
    return tuple(specials)


def straight_force_branch(options: TweezersOptions, turns: float,
                          force_range: tuple[float, float], records=None) -> Branch:
    """The straight rod at fixed ``turns`` followed in the force (``tension``), high to low.

    Continuation in the load parameter ``tension`` (F L^2/A) from ``force_range[1]``
    down to ``force_range[0]``: the straight rod loses stability where the force
    falls below the one at which ``turns`` is critical (located as a
    ``bifurcation``; exact: ``critical_moment(F) = 2 pi (C/A) turns``).
    """
    low, high = (float(v) for v in force_range)
    if not (math.isfinite(low) and math.isfinite(high) and 0 <= low < high):
        raise ValueError(f"force_range must be (low, high) with 0 <= low < high, got "
                         f"{force_range!r}")
    opts = dataclasses.replace(options, tension=high, end_distance=None, turns=(0.0, 1.0))
    problem, q0 = clamped_problem(opts)
    problem.turns = float(turns)
    cont = ContinuationOptions(initial_step=0.05, max_step=max(1.0, 0.05 * (high - low)),
                               parameter_bounds=(low, high), max_points=options.max_points,
                               direction=-1, event_tolerance=options.event_tolerance)
    return continuation(problem, q0, parameter="tension", options=cont,
                        name="straight_in_force", records=records)


def tweezers_branches(options: TweezersOptions,
                      progress: Callable[[str], None] | None = None, *,
                      on_point: Callable[[Branch], None] | None = None,
                      on_branch: Callable[[Branch, bool], None] | None = None,
                      resume: Mapping[str, tuple[Branch, bool]] | None = None,
                      ) -> TweezersResult:
    """Compute the branches (module docstring); numerical failures end up in statuses.

    ``on_point(branch_so_far)`` is called after every accepted point (of the
    runs that make a branch, merged), ``on_branch(branch, contact)`` once per
    branch when it is final (the contact-free branch cut after its contact
    onset): e.g. to save them as they come (``supercoil run``). ``resume`` maps
    branch names to ``(branch, complete)`` of an interrupted run with the same
    options: complete branches are taken as they are, an incomplete one with at
    least two points is continued from its last point with the azimuth pin its
    points were computed with (the record ``azimuth_pin``) by
    :func:`~supercoil.continuation.resume.resume_branch`, then in segments as usual.
    """
    opts = options
    final = on_branch or (lambda branch, contact: None)
    stored = dict(resume or {})

    def resumed(problem, name, segment_opts, records, events, stop=None):
        """The stored branch ``name`` continued for one segment, or None (none stored)."""
        old, complete = stored.get(name, (None, False))
        if old is None or complete or len(old) < 2:
            return None
        q = old.states[-1]
        problem.turns = float(old.parameter_values[-1])
        problem.accept(q)
        pin = int(old.records["azimuth_pin"][-1]) if "azimuth_pin" in old.records else -1
        if pin >= 0:  # the pin the stored points were computed with: the same gauge
            clamps = np.setdiff1d(rod.fixed, rod.gauge_dofs)
            rod.gauge_dofs = np.array([pin], dtype=np.int64)
            rod.fixed = np.array(sorted(set(clamps.tolist()) | {pin}), dtype=np.int64)
            if problem is not rod:
                problem.fixed = rod.fixed
        else:
            set_pin(problem, rod, q)
        return resume_branch(problem, old, dataclasses.replace(
            segment_opts, max_points=len(old) + segment_opts.max_points - 1),
            records=records, events=events, on_point=on_point, stop=stop)
    say = progress or (lambda message: None)
    seconds: dict[str, float] = {}
    notes: list[str] = []
    rod, q0 = clamped_problem(opts)
    D = opts.diameter
    contact_options = (ContactOptions(diameter=D, curve=opts.contact_curve,
                                      formulation=opts.contact_formulation)
                       if D is not None else None)
    probe = ContactProblem(rod, contact_options) if D is not None else None
    cp = ContactProblem(rod, contact_options) if D is not None else None
    if D is not None and rod.rod.edge_length > D:
        notes.append(f"segments ({rod.rod.edge_length:.3g} L) are longer than the tube "
                     f"diameter ({D:.3g} L): contact lines are under-resolved; use --nodes >= "
                     f"{int(np.ceil(rod.rod.length / D)) + 2}")
    free_records = tweezers_records(rod, rod, False, probe)
    events = (onset_event(probe),) if probe is not None else ()
    free_opts = ContinuationOptions(initial_step=SWITCH_AMPLITUDE, max_step=opts.free_max_step,
                                    parameter_bounds=opts.turns,
                                    max_points=min(opts.segment_points, opts.max_points),
                                    event_tolerance=opts.event_tolerance, chord_steps=True)
    # The contact-free runs end at the first point past a located contact onset (the
    # branch is cut there anyway): the switch's run computed 27 points, 12 beyond the
    # 15 kept (N = 100, L/D = 33, F L^2/A = 75, 0-5 turns).
    free_point, past_onset = (stop_after_onset(on_point) if probe is not None
                              else (on_point, None))
    pinned = pin_stop(rod)
    free_stop = either(past_onset, pinned)
    branches: list[Branch] = []
    start = time.perf_counter()
    if opts.load_control:
        say(f"straight rod in turns at F L^2/A = {opts.tension:g}")
        old, complete = stored.get("straight", (None, False))
        straight = (old if complete else
                    straight_branch(opts, rod, q0, free_records, on_point=on_point))
        seconds["straight"] = time.perf_counter() - start
        final(straight, False)
        branches.append(straight)
        bifurcations = straight.points_of_kind("bifurcation")
        if not bifurcations:
            exact = critical_turns(opts.twist_ratio, opts.tension)
            if straight.status.complete:
                notes.append(f"the straight rod does not buckle below {opts.turns[1]:g} turns "
                             f"(exact threshold {exact:.6g})")
            else:  # no conclusion beyond the last point computed
                notes.append(f"incomplete: straight stopped at "
                             f"{straight.parameter_values[-1]:.6g} turns ({straight.message}), "
                             f"before {opts.turns[1]:g}; no buckling found up to there (exact "
                             f"threshold {exact:.6g})")
            return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                                  tuple(notes))
        point = bifurcations[0]
        free_name = "buckled"
        start = time.perf_counter()
        free_complete = stored.get(free_name, (None, False))[1]
        first = resumed(rod, free_name, free_opts, free_records, events, free_stop)
        if first is not None:
            say(f"{free_name}: continued from point {len(stored[free_name][0]) - 1}")
        direction, node = _rotated_mode(point.critical_modes[0])
        for amplitude in SWITCH_AMPLITUDES if first is None and not free_complete else ():
            if amplitude == SWITCH_AMPLITUDES[0]:
                say(f"{free_name}: switched from the straight rod at {point.parameter:.6g} "
                    "turns")
            rod.turns = point.parameter
            _pin_node(rod, node)
            first = switch_branch(rod, straight, point,
                                  dataclasses.replace(free_opts, initial_step=amplitude),
                                  direction=direction, amplitude=amplitude, name=free_name,
                                  records=free_records, events=events, on_point=free_point,
                                  stop=free_stop)
            if len(first):
                break
        if not free_complete and not len(first):
            notes.append(f"failed: {free_name}: no point found off the straight rod at "
                         f"{point.parameter:.6g} turns ({first.message})")
            branches.append(first)
            return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                                  tuple(notes), {"straight": ((0, ()),)})
    else:
        free_name = "clamped"
        say(f"clamped buckle at z/L = {opts.end_distance:g}, in turns")
        free_complete = stored.get(free_name, (None, False))[1]
        first = resumed(rod, free_name, free_opts, free_records, events, free_stop)
    if not opts.load_control and first is None and not free_complete:
        set_pin(rod, rod, q0)
        res = newton(rod, q0, NewtonOptions(mode="stationary"))
        if not res.converged:
            notes.append(f"failed: the clamped buckle at z/L = {opts.end_distance:g} did not "
                         f"converge ({res.message})")
            return TweezersResult(opts, (), frozenset(), rod, cp, seconds, tuple(notes))
        rod.accept(res.q)
        first = continuation(rod, res.q, res.multipliers, parameter="turns", options=free_opts,
                             name=free_name, records=free_records, events=events,
                             on_point=free_point, stop=free_stop)
    old, free_complete = stored.get(free_name, (None, False))
    if free_complete:
        free, free_pins = old, ((0, tuple(int(d) for d in rod.gauge_dofs)),)
    else:
        free, free_pins = follow(rod, rod, first, free_opts, free_name, free_records, events,
                                 stop=_onset_stop if probe is not None else None,
                                 max_points=opts.max_points,
                                 segment_points=opts.segment_points, on_point=free_point,
                                 quality=PIN_QUALITY, refuse=free_stop)
    onsets = [p for p in free.points_of_kind("contact_onset") if p.index + 1 < len(free)]
    seconds[free_name] = time.perf_counter() - start
    pins = {"straight": ((0, ()),), free_name: free_pins}
    if probe is None or not onsets:
        if not free.status.complete:
            notes.append(f"incomplete: {free_name} stopped at "
                         f"{free.parameter_values[-1]:.6g} turns: {free.message}")
        elif probe is not None:
            notes.append(f"{free_name}: no contact found ({free.message})")
        final(free, False)
        branches.append(free)
        return TweezersResult(opts, tuple(branches), frozenset(), rod, cp, seconds,
                              tuple(notes), pins)
    onset = onsets[0]
    if not free_complete:
        free = truncate_after(free, onset, f"stopped at the first contact "
                              f"({onset.parameter:.6g} turns); the contact-free run: "
                              f"{free.message}")
    final(free, False)
    branches.append(free)
    contact_name = f"{free_name}_contact"
    say(f"{contact_name}: from {onset.parameter:.6g} turns, with self-contact (barrier)")
    start = time.perf_counter()
    reach = 1.0 + cp.options.barrier_activation
    gaps = free.records["min_gap_over_diameter"]
    k = onset.index
    while k > 0 and gaps[k] <= reach:
        k -= 1
    q = free.states[k]
    cp.turns = float(free.parameter_values[k])
    cp.accept(q)
    set_pin(cp, rod, q)
    contact_opts = ContinuationOptions(
        initial_step=0.1 * opts.contact_max_step * D, min_step=CONTACT_MIN_STEP,
        max_step=opts.contact_max_step * D,
        max_points=min(opts.segment_points, opts.max_points),
        parameter_bounds=opts.turns, direction=1 if free.tangents[k, -1] >= 0 else -1,
        parameter_weight=D, tolerance=opts.contact_tolerance,
        event_tolerance=opts.contact_event_tolerance,
        predictor=opts.contact_predictor, max_corrector_distance=CONTACT_CORRECTOR_DISTANCE,
        chord_steps=True)
    contact_records = tweezers_records(cp, rod, True)
    contact_events = (contact_count_event(cp),)
    old, contact_complete = stored.get(contact_name, (None, False))
    if contact_complete:
        contact, contact_pins = old, ((0, tuple(int(d) for d in rod.gauge_dofs)),)
    else:
        first = resumed(cp, contact_name, contact_opts, contact_records, contact_events,
                        pinned)
        if first is not None:
            say(f"{contact_name}: continued from point {len(old) - 1}")
        else:
            first = continuation(cp, q, parameter="turns", options=contact_opts,
                                 name=contact_name, records=contact_records,
                                 events=contact_events, on_point=on_point, stop=pinned)
        contact, contact_pins = follow(cp, rod, first, contact_opts, contact_name,
                                       contact_records, contact_events,
                                       max_points=opts.max_points,
                                       segment_points=opts.segment_points, on_point=on_point,
                                       quality=PIN_QUALITY, refuse=pinned)
        contact = classify_contact_events(contact, cp)
    contact = dataclasses.replace(contact, parent=free_name, origin=onset)
    seconds[contact_name] = time.perf_counter() - start
    final(contact, True)
    branches.append(contact)
    if not contact.ok:
        notes.append(f"failed: {contact_name}: {contact.message}")
    elif contact.parameter_values[-1] < opts.turns[1] - 1e-9:
        notes.append(f"incomplete: {contact_name} ended at {contact.parameter_values[-1]:.6g} "
                     f"turns, before {opts.turns[1]:g}: {contact.message}")
    pins[contact_name] = contact_pins
    return TweezersResult(opts, tuple(branches), frozenset({contact_name}), rod, cp, seconds,
                          tuple(notes), pins, frozenset({free_name}))

