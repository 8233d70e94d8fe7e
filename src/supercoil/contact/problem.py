"""Self-contact of a rod as a constrained-energy problem.

:class:`ContactProblem` wraps a rod energy (closed or clamped) and adds the
condition that two points of the centreline farther apart along the rod than
the neighbour exclusion stay at least the tube diameter ``D`` apart. The
centreline is a polygon, so the condition is imposed on every pair of its
segments, with the exact segment–segment distance ``d`` (smooth per distance
type, :mod:`supercoil.contact.distance`) or the distance of the B-spline
pieces of those segments (below, "Contact curve"), and the gap ``g = d - D``:

* ``penalty``, ``augmented``, ``barrier``: ``E + sum_pairs psi(g)``
  (:mod:`supercoil.contact.potentials`);
* ``exact``: ``g >= 0`` as inequality constraints; the active ones join the
  rod's equality constraints, and their multipliers are minus the contact
  forces (:mod:`supercoil.contact.solve` runs the active-set loop). Inactive
  pairs that penetrate during the search meet the penalty, which vanishes at
  a solution (no inactive pair penetrates there).

Contact curve (``ContactOptions.curve``). ``"polygon"`` measures ``d``
between the segments. ``"spline"`` measures it between the pieces of the
uniform cubic B-spline whose control points are the nodes
(:mod:`supercoil.contact.spline_distance`; piece ``i`` belongs to segment
``i`` and depends on nodes ``i-1 .. i+2``, ghost end nodes by reflection on
open rods), so a pair's distance has 24 DOFs instead of 12. A chord sags
inside the curve by up to ``h^2 kappa / 8`` and not at all at the nodes, so
the polygon's contact energy ripples with period ``h`` as the material slides
along a contact; the B-spline's distance does not depend on the sampling
phase up to ``O(h^4)`` (its shift ``(h^2/6) x''`` is the same at every phase).
Reported positions ``s1, s2`` are the spline parameters mapped to arc length
like the segments' parameters. The broad phase runs on the segments with the
cutoff widened by twice the largest sag bound (a piece lies within
``max |second difference| / 6`` of its chord), so it misses no pair.

Two guards stay on the polygon whatever the curve, and they are still the
right guards: the rod's topology *is* the polygon's. Its linking number is
``Tw + Wr`` with the writhe of the polygon (the energy carries it through
the reference twist, and :meth:`ContactProblem.admissible` compares it with
the polygon's double sum), and the knot type is the polygon's. A strand can
only change those by passing a segment through another, which the polygon
collision detection of :meth:`ContactProblem.step_bound` forbids (no segment
pair may approach below ``min(0.9 d0, max(0.1 d0, D/2))``). Near contact the
spline and the polygon differ by at most twice the sag bound, about
``h^2 kappa / 3``, far below ``D/2`` on any resolved rod, so this guard does
not limit the steps of a spline contact. The barrier additionally needs its
own gap to stay positive: with the spline, a second conservative advancement
on the spline pieces (``first_time_of_approach_pieces``) keeps every spline
gap above a tenth of its value.

The wrapper speaks the :class:`~supercoil.solvers.problem.ConstrainedEnergy`
protocol, so Newton, the inertia count and the eigenvalues see the contact
terms through the Hessian (energy treatments) or through the active
constraints (exact treatment): a direction that would open a contact carrying
a positive force is excluded from the tangent space. It also offers
``step_bound(q, dq)``: continuous collision detection along the straight step,
which Newton uses to shorten a step before any two segments could pass
through each other.

Neighbour exclusion: two points closer than ``pi D / 2`` along the rod are not
a contact. A tube of diameter ``D`` cannot bend more tightly than radius
``D/2`` without overlapping itself locally, and on a curve whose radius of
curvature is at least ``D/2`` two points ``s`` apart along it are at a chord
distance of at least ``D sin(s/D)``, which first reaches ``D`` at ``s = pi D/2``
(a half turn of radius ``D/2``): closer pairs are neighbours within one tube,
farther pairs are genuine contacts (the global radius of curvature of
Gonzalez & Maddocks 1999 formalises this).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil import checks
from supercoil.contact import potentials
from supercoil.contact.broadphase import candidate_pairs, verlet_displacement
from supercoil.contact.ccd import (
    first_time_of_approach,
    first_time_of_approach_pieces,
    largest_displacement,
)
from supercoil.contact.distance import (
    segment_distance,
    segment_distance_derivatives,
    segment_pairs_within,
)
from supercoil.contact.integral import (
    closest_samples_within,
    default_samples,
    first_time_of_approach_samples,
    integral_terms,
    polygon_weights,
    quintic_samples,
    sample_state,
    spline_weights,
)
from supercoil.contact.spline_distance import (
    bspline_pieces,
    local_minimum_pairs,
    piece_distance,
    piece_distance_derivatives,
    sag_bound,
)
from supercoil.solvers.csr_sum import block_csr, csr_add_blocks
from supercoil.solvers.problem import HessianParts
from supercoil.topology import writhe

TREATMENTS = ("barrier", "augmented", "penalty", "exact")
# the curve whose self-distance is the contact distance (quintic: integral formulation only)
CURVES = ("polygon", "spline", "quintic")
FORMULATIONS = ("pairs", "integral")  # how the potential is summed, see ContactOptions
LINK_CHECK_MAX_NODES = 2000  # see ContactProblem.admissible
_PAIR_MEMO = 8  # pair states remembered, see ContactProblem.pair_state
# Verlet list of ContactProblem._candidates: broad phase reach beyond the asked
# cutoff (edge lengths, at most D), and the largest cutoff (in units of D) served
# from it. A wider reach keeps the list longer but holds more pairs: the pairs
# within D + m of a line contact grow like N^2 at fixed m / L (measured on the
# tweezers at N = 400: 4002 pairs for m = D, 285 for m = 2 h).
_VERLET_MARGIN = 2.0
_VERLET_CUTOFF = 2.0
DEFAULT_TREATMENT = "barrier"


def validate_contact_choice(curve: str, formulation: str) -> None:
    """The drivers' check of ``contact_curve`` and ``contact_formulation`` (their key names
    in the messages); raises :class:`~supercoil.errors.InputError`."""
    checks.choice("contact_curve", curve, CURVES)
    checks.choice("contact_formulation", formulation, FORMULATIONS)
    if curve == "quintic" and formulation != "integral":
        raise checks.refuse("contact_curve", f"'quintic' needs contact_formulation "
                            f"'integral', got {formulation!r}; valid: spline or polygon with "
                            "pairs, any curve with integral")


@dataclass(frozen=True)
class ContactOptions:
    """How self-contact is imposed; validated on construction.

    ``diameter`` D (in units of L). ``exclusion``: arc length below which two
    points are neighbours, default ``pi D / 2``. ``stiffness``: ``k`` of the
    penalty and augmented Lagrangian, ``kappa`` of the barrier; default
    ``stiffness_scale * A / h^3``, the stiffness with which one node of the
    discrete rod resists a transverse displacement in bending, so that the
    contact neither dominates the conditioning nor is soft next to the rod.
    ``penetration_tolerance``: largest accepted penetration over D (augmented,
    exact). ``penalty_tolerance``: the same for the penalty, which needs a
    penetration ``F / k`` to carry a force ``F`` (with the default ``k`` a few
    per cent of D for DNA-like L/D at N = 100, falling like ``h^3``): the solve
    raises ``k`` until the penetration is within it
    (:func:`~supercoil.contact.solve.solve_contact`); states beyond it (the
    stiffness at its bound) are flagged, not returned silently. ``barrier_activation``: the
    barrier acts on gaps below ``barrier_activation * D``. ``curve``: the
    centreline whose self-distance is the contact distance, ``"polygon"``
    (segment pairs), ``"spline"`` (the uniform cubic B-spline of the nodes;
    see the module docstring) or ``"quintic"`` (the quintic B-spline,
    integral formulation only: :func:`~supercoil.contact.integral.quintic_samples`).
    ``count_local_minima`` (spline only, experimental): sum the potential only
    over pairs whose closest points are a local minimum of the distance between
    the whole curves, dropping the *shadows* of a contact seen by the
    neighbouring pairs through their shared piece ends
    (``spline_distance.local_minimum_pairs``). The plain sum counts a point
    contact once inside a piece pair and up to four times at a piece junction,
    a ripple of period h of its own; dropping the shadows removes it, but the
    energy then jumps where a local minimum is born inside the barrier's reach
    (line contacts). Measured in docs/benchmarks.md ("Spline contact"): it
    helps point contacts (the ring), it stalls line contacts (tweezers).
    ``formulation``: ``"pairs"`` sums the potential of the closest distance of
    every segment (piece) pair; ``"integral"`` integrates it over both strands
    (:mod:`supercoil.contact.integral`), so that a contact counts once wherever
    it lies relative to the nodes (barrier and penalty only).
    ``samples_per_segment``: quadrature points per segment of the integral,
    default :func:`~supercoil.contact.integral.default_samples`.
    """

    diameter: float
    treatment: str = DEFAULT_TREATMENT
    exclusion: float | None = None
    stiffness: float | None = None
    stiffness_scale: float = 1.0
    penetration_tolerance: float = 1e-4
    penalty_tolerance: float = 1e-3
    barrier_activation: float = 1e-2
    max_outer_iterations: int = 50
    force_tolerance: float = 1e-8
    curve: str = "polygon"
    count_local_minima: bool = False
    formulation: str = "pairs"
    samples_per_segment: int | None = None

    def __post_init__(self) -> None:
        checks.number("diameter", self.diameter, 0.0, low_open=True, meaning="tube diameter D")
        checks.choice("treatment", self.treatment, TREATMENTS, meaning="contact treatment")
        checks.optional_number("exclusion", self.exclusion, 0.0,
                               meaning="arc length of neighbours")
        checks.optional_number("stiffness", self.stiffness, 0.0, low_open=True,
                               meaning="contact stiffness")
        checks.number("stiffness_scale", self.stiffness_scale, 0.0, low_open=True)
        for name in ("penetration_tolerance", "penalty_tolerance", "barrier_activation"):
            checks.number(name, getattr(self, name), 0.0, 1.0, low_open=True,
                          meaning="over D")
        checks.number("force_tolerance", self.force_tolerance, 0.0, low_open=True)
        checks.integer("max_outer_iterations", self.max_outer_iterations, 1, 100_000)
        checks.flag("count_local_minima", self.count_local_minima)
        checks.choice("formulation", self.formulation, FORMULATIONS,
                      meaning="a sum over segment pairs or a double integral over the strands")
        checks.choice("curve", self.curve, CURVES,
                      meaning="the polygon's segments, the cubic or the quintic B-spline")
        if self.count_local_minima and self.curve != "spline":
            raise checks.refuse("count_local_minima", "needs curve='spline'")
        if self.formulation == "integral" and self.treatment not in ("barrier", "penalty"):
            raise checks.refuse("formulation", f"'integral' takes the barrier or the penalty "
                                f"treatment, not {self.treatment!r}")
        if self.formulation == "integral" and self.count_local_minima:
            raise checks.refuse("count_local_minima", "belongs to the pairs formulation")
        if self.samples_per_segment is not None:
            checks.integer("samples_per_segment", self.samples_per_segment, 1, 1000)
        if self.curve == "quintic" and self.formulation != "integral":
            raise checks.refuse("curve", "'quintic' needs formulation='integral' (its "
                                "distance is only sampled)")

    @property
    def tolerance(self) -> float:
        """Largest accepted penetration over D for this treatment."""
        return self.penalty_tolerance if self.treatment == "penalty" else self.penetration_tolerance

    @property
    def exclusion_length(self) -> float:
        return 0.5 * np.pi * self.diameter if self.exclusion is None else float(self.exclusion)


@dataclass(frozen=True)
class PairState:
    """Segment pairs near contact at one configuration (arrays over pairs)."""

    pairs: np.ndarray  # (m, 2) segment indices, i < j
    distance: np.ndarray  # (m,)
    s: np.ndarray  # (m,) closest parameter on segment i
    t: np.ndarray  # (m,) closest parameter on segment j


class ContactProblem:
    """A rod energy plus impenetrability; see the module docstring.

    ``base`` is a :class:`~supercoil.rod.closed.RodEnergy` (closed or clamped).
    Unknown attributes are looked up on ``base`` (twist, writhe_local, ...).
    """

    def __init__(self, base, options: ContactOptions):
        self.base = base
        self.options = options
        rod = base.rod
        self.diameter = float(options.diameter)
        self.closed = bool(rod.closed)
        h = rod.edge_length
        self.edge_length = h
        self.default_stiffness = (options.stiffness if options.stiffness is not None
                                  else options.stiffness_scale * rod.bending_stiffness / h**3)
        self.stiffness = self.default_stiffness  # the augmented Lagrangian may raise it
        self.segments = np.asarray(base.edge_nodes, dtype=np.int64)
        k = np.arange(len(self.segments), dtype=float)
        offset = 0.0 if self.closed else -0.5  # open rods: ends at mid-edges
        self.s_start = (k + offset) * h
        self.s_end = (k + offset + 1.0) * h
        self.period = rod.length if self.closed else None
        self.exclusion = options.exclusion_length
        self.spline = options.curve == "spline"
        self.pieces = bspline_pieces(self.segments, self.closed) if self.spline else None
        self.integral = options.formulation == "integral"
        if self.integral:
            self.samples = (options.samples_per_segment if options.samples_per_segment
                            else default_samples(h, self.diameter,
                                                 options.barrier_activation * self.diameter))
            if options.curve == "quintic":
                self.sample_stencil, self.sample_weights = quintic_samples(
                    self.segments, self.closed, self.samples)
            elif self.spline:
                self.sample_stencil = np.ascontiguousarray(self.pieces.stencil)
                self.sample_weights = spline_weights(self.pieces.coefficients, self.samples)
            else:
                self.sample_stencil = np.ascontiguousarray(self.segments)
                self.sample_weights = polygon_weights(len(self.segments), self.samples)
        self.n_dofs = base.n_dofs
        self.fixed = base.fixed
        self.mass = base.mass
        # augmented Lagrangian multipliers (contact forces) per segment pair
        self.pair_multipliers: dict[tuple[int, int], float] = {}
        # exact treatment: active pairs, constraints g_p = d_p - D = 0
        self.active = np.zeros((0, 2), dtype=np.int64)
        self._slide_pin: tuple[int, np.ndarray, np.ndarray] | None = None
        # see stability_view()
        self.stability_mode = False

    def __getattr__(self, name):  # forward rod-specific queries to the wrapped energy
        if name == "base":
            raise AttributeError(name)
        return getattr(self.base, name)

    def __setattr__(self, name, value):
        # Load parameters live on the rod (``excess_link``, ``turns``,
        # ``tension``): a continuation that sets them on this wrapper must
        # reach the rod (the remembered pair states depend on q only).
        own = self.__dict__
        if "base" in own and name not in own and name not in type(self).__dict__ \
                and hasattr(own["base"], name):
            setattr(own["base"], name, value)
            return
        object.__setattr__(self, name, value)

    # ----------------------------------------------------------- geometry
    @property
    def treatment(self) -> str:
        return self.options.treatment

    @property
    def n_equalities(self) -> int:
        """Constraints before the contact ones: the rod's, plus the sliding gauge if set."""
        return self.base.n_constraints + (self._slide_pin is not None)

    @property
    def n_constraints(self) -> int:
        return self.n_equalities + len(self.active)

    def pin_sliding(self, q: np.ndarray) -> None:
        """Remove the material-sliding near-symmetry of a closed homogeneous rod.

        Off the circle, sliding the material along the centreline leaves the
        continuum energy unchanged; the discretisation breaks the symmetry
        only weakly (a ripple of period one edge), so the mode is nearly null:
        unremoved, it lets Newton wander along the rod and lets the
        augmented-Lagrangian multipliers (attached to segment pairs) drag the
        state along it (DESIGN.md, traps). The gauge is the linear constraint
        ``t_k . (x_k - x_k(q)) = 0`` on one node ``k`` (tangential motion of
        that node), whose multiplier is the ripple's reaction. With contact the
        ripple is not small (a
        reaction of 4 % of the contact forces measured at N = 100), so the
        gauge only steers the augmented-Lagrangian outer iterations; every
        returned state is an equilibrium without it.
        """
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        n = len(x)
        fixed_nodes = set((np.asarray(self.base.fixed) // 3).tolist())
        k = next(i for i in range(n // 4, n // 4 + n) if i % n not in fixed_nodes) % n
        t = x[(k + 1) % n] - x[(k - 1) % n]
        self._slide_pin = (k, t / np.linalg.norm(t), x[k].copy())
        self.invalidate()

    def release_sliding(self) -> None:
        """Remove the sliding gauge (see :meth:`pin_sliding`)."""
        self._slide_pin = None
        self.invalidate()

    @property
    def gauge_dofs(self):
        return getattr(self.base, "gauge_dofs", np.zeros(0, dtype=np.int64))

    def _endpoints(self, q: np.ndarray):
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        return x[self.segments[:, 0]], x[self.segments[:, 1]]

    def pair_distances(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, s, t)`` ``(m,)`` of pairs ``(m, 2)`` on the contact curve (exact minima)."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if self.spline:
            return piece_distance(np.asarray(q, dtype=float).reshape(-1, 3), self.pieces, pairs)
        a, b = self._endpoints(q)
        i, j = pairs[:, 0], pairs[:, 1]
        return segment_distance(a[i], b[i], a[j], b[j])

    def pair_state(self, q: np.ndarray, cutoff: float, polygon: bool = False,
                   shadows: bool = False) -> PairState:
        """Pairs (beyond the exclusion) whose distance is at most ``cutoff``.

        The distance is that of the contact curve (``options.curve``), or of the
        polygon's segments when ``polygon``. The broad phase runs on the
        segments; for the spline its cutoff is widened by twice the largest
        distance of a piece from its chord (``spline_distance.sag_bound``).

        A pure function of its arguments (the segments, pieces, arc lengths and
        exclusion are fixed at construction), remembered for the last
        ``_PAIR_MEMO`` arguments: one continuation point asks for the same
        state about fifty times (residual, finite-difference parameter
        derivative, Hessian, records, stability), and setting a load
        parameter does not change it. Callers must not modify the arrays.
        """
        key = (np.ascontiguousarray(q, dtype=np.float64).tobytes(), float(cutoff),
               float(self.exclusion), bool(polygon), bool(shadows))
        memo = self.__dict__.setdefault("_pair_memo", {})
        found = memo.get(key)
        if found is None:
            found = self._compute_pair_state(q, cutoff, polygon, shadows)
            if len(memo) >= _PAIR_MEMO:
                del memo[next(iter(memo))]
            memo[key] = found
        return found

    def _candidates(self, q: np.ndarray, cutoff: float) -> np.ndarray:
        """Segment pairs among which every pair within ``cutoff`` at ``q`` is.

        A Verlet neighbour list: the broad phase is run at ``cutoff + m``,
        ``m = min(D, _VERLET_MARGIN h)``, and its pairs kept with the state
        ``x_ref``; while no node has moved by ``delta`` with ``cutoff + 2
        delta`` beyond that reach, they still hold every pair within
        ``cutoff`` (a segment distance changes by at most twice the largest
        node displacement), and the exact distances computed on them give the
        same pairs as a new broad phase. Cutoffs above ``_VERLET_CUTOFF D``
        (a step bound's reach, a closest-approach search) are not widened: the
        broad phase runs at the cutoff asked, unless one of the two lists (the
        Verlet list, or the last such wide result, kept the same way) already
        covers it by the same test. A step bound asks for two cutoffs at one
        state (the sample points' reach, then the segments'); the wider first,
        so that the second is served from it.
        """
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        for slot in ("_verlet", "_verlet_wide"):
            reference = self.__dict__.get(slot)
            if reference is None:
                continue
            x_ref, reach, exclusion, pairs = reference
            if x_ref.shape != x.shape or exclusion != self.exclusion or cutoff > reach:
                continue
            scale, moved = verlet_displacement(x, x_ref)
            slack = 1e-9 * max(1.0, scale, reach)
            if cutoff + 2.0 * moved + slack <= reach:
                return pairs
        a, b = self._endpoints(q)
        if cutoff > _VERLET_CUTOFF * self.diameter:
            pairs = candidate_pairs(a, b, self.s_start, self.s_end, cutoff, self.exclusion,
                                    period=self.period)
            self.__dict__["_verlet_wide"] = (x.copy(), float(cutoff), self.exclusion, pairs)
            return pairs
        reach = cutoff + min(self.diameter, _VERLET_MARGIN * self.edge_length)
        pairs = candidate_pairs(a, b, self.s_start, self.s_end, reach, self.exclusion,
                                period=self.period)
        self.__dict__["_verlet"] = (x.copy(), reach, self.exclusion, pairs)
        return pairs

    def _samples(self, q: np.ndarray):
        """``(sample points (k, samples, 3), largest distance of a sample point from its
        segment's chord)`` at ``q``; see :meth:`_sample_geometry`."""
        return self._sample_geometry(q)[:2]

    def _sample_geometry(self, q: np.ndarray):
        """:func:`~supercoil.contact.integral.sample_state` at ``q``: the sample points,
        their largest distance from their segment's chord, and the bounding spheres of
        each segment's samples; the last state's are remembered (a residual and the
        step bound from the same iterate ask for them)."""
        key = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        cached = self.__dict__.get("_sample_memo")
        if cached is not None and cached[0] == key:
            return cached[1]
        geometry = sample_state(np.asarray(q, dtype=float).reshape(-1, 3), self.sample_stencil,
                                self.sample_weights, self.segments)
        self.__dict__["_sample_memo"] = (key, geometry)
        return geometry

    def _sample_pair_state(self, q: np.ndarray, cutoff: float) -> PairState:
        """Pairs whose closest *sample points* are within ``cutoff`` (integral formulation:
        the energy sees the curve only there). The broad phase runs on the segments, its
        cutoff widened by twice the samples' largest distance from their chords."""
        points, deviation, centre, radius = self._sample_geometry(q)
        reach = cutoff + 2.0 * deviation
        cand = self._candidates(q, reach)
        if len(cand) == 0:
            empty = np.zeros(0)
            return PairState(np.zeros((0, 2), dtype=np.int64), empty, empty, empty)
        return PairState(*closest_samples_within(points, centre, radius, cand, cutoff))

    def _compute_pair_state(self, q: np.ndarray, cutoff: float, polygon: bool,
                            shadows: bool) -> PairState:
        if self.integral and not polygon:
            return self._sample_pair_state(np.asarray(q, dtype=float), cutoff)
        spline = self.spline and not polygon
        reach = cutoff
        if spline:
            reach += 2.0 * float(np.max(sag_bound(np.asarray(q, dtype=float).reshape(-1, 3),
                                                  self.pieces)))
        cand = self._candidates(q, reach)
        if len(cand) == 0:
            empty = np.zeros(0)
            return PairState(np.zeros((0, 2), dtype=np.int64), empty, empty, empty)
        if not spline:
            # the segment distances of the candidates, filtered, in one compiled pass
            return PairState(*segment_pairs_within(np.asarray(q, dtype=float).reshape(-1, 3),
                                                   self.segments, cand, cutoff))
        d, s, t = self.pair_distances(q, cand)
        keep = d <= cutoff
        if spline and self.options.count_local_minima and not shadows and keep.any():
            keep[keep] = local_minimum_pairs(np.asarray(q, dtype=float).reshape(-1, 3),
                                             self.pieces, cand[keep],
                                             s[keep], t[keep])
        return PairState(cand[keep], d[keep], s[keep], t[keep])

    def min_distance(self, q: np.ndarray, polygon: bool = False) -> float:
        """Smallest distance over non-neighbour pairs (``inf`` if none), on the contact
        curve or, with ``polygon``, between the segments.

        A remembered pair state at ``q`` (any cutoff) that holds a pair already knows
        it: every pair beyond that state's cutoff is farther than the pairs within,
        so their smallest distance is the smallest of all, the value the search
        below finds (the same per-pair distances). The records of an accepted point
        ask here right after the corrector's residual at it: along the ring's
        diagram (N = 200) about 180 of the 2 D searches (sample states over some 700
        candidate pairs each) are answered so; the guard's searches between the
        segments (``admissible``) mostly find no remembered state.
        """
        remembered = self._remembered_min_distance(q, polygon)
        if remembered is not None:
            return remembered
        cutoff = 2.0 * self.diameter
        a, b = self._endpoints(q)
        span = float(np.max(np.ptp(np.concatenate([a, b]), axis=0)))
        while True:
            st = self.pair_state(q, cutoff, polygon)
            if len(st.pairs):
                return float(st.distance.min())
            if cutoff > 2 * span + self.diameter:
                return float("inf")
            cutoff *= 4.0

    def _remembered_min_distance(self, q: np.ndarray, polygon: bool) -> float | None:
        """Smallest distance of a remembered non-empty pair state at ``q`` (see
        :meth:`min_distance`), or None. Not with ``count_local_minima``: its states
        hold the local minima only."""
        memo = self.__dict__.get("_pair_memo")
        if not memo or (self.options.count_local_minima and not polygon):
            return None
        key = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        for (state, _cutoff, exclusion, on_polygon, _shadows), st in memo.items():
            if on_polygon == bool(polygon) and exclusion == float(self.exclusion) \
                    and len(st.pairs) and state == key:
                return float(st.distance.min())
        return None

    def _cutoff(self) -> float:
        """Distance below which a pair contributes to the energy or may become active."""
        D = self.diameter
        if self.treatment == "penalty":
            return D
        if self.treatment == "barrier":
            return D * (1.0 + self.options.barrier_activation)
        if self.treatment == "augmented":
            lam_max = max(self.pair_multipliers.values(), default=0.0)
            return D + lam_max / self.stiffness
        return D

    def _state(self, q: np.ndarray) -> PairState:
        return self.pair_state(q, self._cutoff())

    def invalidate(self) -> None:
        """Forget the remembered pair states (they are keyed by state and cutoff, so
        this only frees them; the multipliers and active set change the cutoff)."""
        self.__dict__.pop("_pair_memo", None)

    def _multipliers_of(self, pairs: np.ndarray) -> np.ndarray:
        get = self.pair_multipliers.get
        return np.array([get((int(i), int(j)), 0.0) for i, j in pairs], dtype=float)

    def _psi(self, gap: np.ndarray, pairs: np.ndarray):
        opts = self.options
        if self.treatment == "penalty":
            return potentials.penalty(gap, self.stiffness)
        if self.treatment == "augmented":
            return potentials.augmented(gap, self._multipliers_of(pairs), self.stiffness)
        if self.treatment == "barrier":
            return potentials.barrier(gap, self.stiffness, opts.barrier_activation * self.diameter)
        # exact: the active pairs are constraints; any other pair that
        # penetrates meets the penalty (a guard while the active set is being
        # found: it vanishes at a solution, where no inactive pair penetrates)
        value, first, second = potentials.penalty(gap, self.stiffness)
        if len(self.active):
            active = {(int(i), int(j)) for i, j in self.active}
            inactive = np.array([(int(i), int(j)) not in active for i, j in pairs], dtype=bool)
            value, first, second = value * inactive, first * inactive, second * inactive
        return value, first, second

    def _pair_nodes(self, pairs: np.ndarray) -> np.ndarray:
        """``(m, 4)`` node indices (p0, p1, q0, q1) of segment pairs."""
        return np.concatenate([self.segments[pairs[:, 0]], self.segments[pairs[:, 1]]], axis=1)

    def _pair_derivatives(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, gradient, Hessian, dofs)`` of the pairs' distances; the last call is
        cached (gradient and Hessian at one state ask for the same pairs)."""
        key = (np.asarray(q, dtype=float).tobytes(), np.asarray(pairs).tobytes())
        cached = self.__dict__.get("_derivative_cache")
        if cached is not None and cached[0] == key:
            return cached[1]
        value = self._compute_pair_derivatives(q, pairs)
        self.__dict__["_derivative_cache"] = (key, value)
        return value

    def _compute_pair_derivatives(self, q: np.ndarray, pairs: np.ndarray):
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        if self.spline:
            d, _s, _t, grad, hess, _kind, nodes = piece_distance_derivatives(x, self.pieces,
                                                                            pairs)
            dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(pairs), 24)
            return d, grad, hess, dofs
        nodes = self._pair_nodes(pairs)
        d, grad, hess, _kind = segment_distance_derivatives(
            x[nodes[:, 0]], x[nodes[:, 1]], x[nodes[:, 2]], x[nodes[:, 3]])
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(pairs), 12)
        return d, grad, hess, dofs

    def _integral(self, q: np.ndarray, order: int):
        """:func:`~supercoil.contact.integral.integral_terms` of the pairs within reach
        at ``q``; the last call is remembered, and serves lower orders too."""
        st = self._state(q)
        key = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        cached = self.__dict__.get("_integral_cache")
        if cached is not None and cached[0] == key and cached[1] >= order \
                and cached[2] == self.stiffness:
            return st, cached[3]
        opts = self.options
        # the sample points of the pair state's search (remembered for this q), not
        # formed again per pair in the kernel
        terms = integral_terms(np.asarray(q, dtype=float).reshape(-1, 3), self.sample_stencil,
                               self.sample_weights, st.pairs, self.diameter, self.treatment,
                               self.stiffness, opts.barrier_activation * self.diameter,
                               self.edge_length, order, points=self._samples(q)[0])
        self.__dict__["_integral_cache"] = (key, order, self.stiffness, terms)
        return st, terms

    # ------------------------------------------------------------ energy
    def contact_energy(self, q: np.ndarray) -> float:
        if self.integral:
            return float(np.sum(self._integral(q, 0)[1][0]))
        st = self._state(q)
        if len(st.pairs) == 0:
            return 0.0
        value, _, _ = self._psi(st.distance - self.diameter, st.pairs)
        return float(np.sum(value))

    def energy(self, q: np.ndarray) -> float:
        return self.base.energy(q) + self.contact_energy(q)

    def gradient(self, q: np.ndarray) -> np.ndarray:
        g = self.base.gradient(q)
        if self.integral:
            _st, (_e, grad, _h, _f, _p, dofs) = self._integral(q, 1)
            np.add.at(g, dofs.ravel(), grad[: len(dofs)].ravel())
            return g
        st = self._state(q)
        if len(st.pairs):
            d, grad, _hess, dofs = self._pair_derivatives(q, st.pairs)
            _, first, _ = self._psi(d - self.diameter, st.pairs)
            np.add.at(g, dofs.ravel(), (first[:, None] * grad).ravel())
        return g

    def contact_hessian(self, q: np.ndarray) -> sp.csr_matrix:
        if self.integral:
            # the pair blocks in one compiled pass (scipy's COO path took 0.6 ms at
            # N = 200; the same pattern, duplicates summed in another order)
            dofs, local = self._integral_blocks(q)
            return block_csr(dofs, local, self.n_dofs)
        return self._pairs_contact_hessian(q)

    def _integral_blocks(self, q: np.ndarray):
        """``(dofs, blocks)`` of the integral formulation's contact Hessian at ``q``."""
        # a sample pair touching without force (penalty) weighs nothing here: the
        # one-sided closing stiffness of the pairs formulation is not added
        _st, (_e, _g, local, _f, _p, dofs) = self._integral(q, 2)
        return dofs, local

    def _pairs_contact_hessian(self, q: np.ndarray) -> sp.csr_matrix:
        one_sided = self.stability_mode and self.treatment in ("penalty", "augmented")
        D = self.diameter
        if one_sided:
            st = self.pair_state(q, max(self._cutoff(), D * (1 + self.options.tolerance)))
        else:
            st = self._state(q)
        n = self.n_dofs
        if len(st.pairs) == 0:
            return sp.csr_matrix((n, n))
        d, grad, hess, dofs = self._pair_derivatives(q, st.pairs)
        _, first, second = self._psi(d - D, st.pairs)
        if one_sided:
            # A pair touching without force sits on the kink of psi (C^1 only):
            # closing it costs k g^2/2, opening it nothing. Admissible second-order
            # directions cannot penetrate it, so its closing stiffness counts.
            touching = (second == 0) & (d - D <= self.options.tolerance * D)
            second = np.where(touching, self.stiffness, second)
        local = (second[:, None, None] * grad[:, :, None] * grad[:, None, :]
                 + first[:, None, None] * hess)
        w = dofs.shape[1]
        rows = np.repeat(dofs, w, axis=1).ravel()
        cols = np.tile(dofs, (1, w)).ravel()
        return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))

    def hessian(self, q: np.ndarray) -> HessianParts:
        """The rod's Hessian plus :meth:`contact_hessian`. The integral formulation's pair
        blocks are merged into the rod's matrix directly (:func:`csr_add_blocks`, the
        entries of ``csr_add(rod, contact_hessian)`` bit for bit, without the
        intermediate matrix)."""
        parts = self.base.hessian(q)
        if self.integral:
            dofs, local = self._integral_blocks(q)
            return HessianParts(csr_add_blocks(parts.sparse, dofs, local), parts.vectors,
                                parts.coefficients)
        return parts.plus_sparse(self.contact_hessian(q))

    def lagrangian_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> HessianParts:
        """``hessian(q)`` plus ``constraint_hessian(q, multipliers)`` (the sum of
        :func:`~supercoil.solvers.newton.lagrangian_hessian`), bit for bit. The integral
        formulation's pair blocks and the constraint curvature are merged into the rod's
        matrix in one compiled pass (:func:`csr_add_blocks` with ``then``) instead of a
        merge for the blocks and another for the curvature (``plus_sparse``)."""
        if not self.integral:
            parts = self.hessian(q)
            if self.n_constraints:
                parts = parts.plus_sparse(self.constraint_hessian(q, multipliers))
            return parts
        parts = self.base.hessian(q)
        dofs, local = self._integral_blocks(q)
        curvature = self.constraint_hessian(q, multipliers) if self.n_constraints else None
        return HessianParts(csr_add_blocks(parts.sparse, dofs, local, curvature), parts.vectors,
                            parts.coefficients)

    def stability_view(self) -> ContactProblem:
        """This problem as the stability analysis must see it (shares the state).

        Penalty and augmented Lagrangian energies are only C¹ where a pair just
        touches without force; the view adds the closing stiffness of such
        pairs so that the unstable count does not include directions that
        would push through a touching pair (DESIGN.md: zero-force contacts).
        """
        view = copy.copy(self)
        view.stability_mode = True
        return view

    # ------------------------------------------------------- constraints
    def constraints(self, q: np.ndarray) -> np.ndarray:
        c = self.base.constraints(q)
        if self._slide_pin is not None:
            k, t, xk = self._slide_pin
            x = np.asarray(q, dtype=float).reshape(-1, 3)
            c = np.concatenate([c, [float(t @ (x[k] - xk))]])
        if len(self.active) == 0:
            return c
        d, _, _ = self.pair_distances(q, self.active)
        return np.concatenate([c, d - self.diameter])

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        J = self.base.constraint_jacobian(q)
        if self._slide_pin is not None:
            k, t, _ = self._slide_pin
            row = sp.csr_matrix((t, (np.zeros(3, dtype=np.int64), 3 * k + np.arange(3))),
                                shape=(1, self.n_dofs))
            J = sp.vstack([J, row]).tocsr()
        if len(self.active) == 0:
            return J
        _d, grad, _hess, dofs = self._pair_derivatives(q, self.active)
        m = len(self.active)
        rows = np.repeat(np.arange(m), dofs.shape[1])
        Jc = sp.csr_matrix((grad.ravel(), (rows, dofs.ravel())), shape=(m, self.n_dofs))
        return sp.vstack([J, Jc]).tocsr()

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix:
        m0 = self.n_equalities  # the sliding gauge is linear: no Hessian
        lam = np.asarray(multipliers, dtype=float)
        H = self.base.constraint_hessian(q, lam[: self.base.n_constraints])
        if len(self.active) == 0:
            return H
        _d, _grad, hess, dofs = self._pair_derivatives(q, self.active)
        local = lam[m0:, None, None] * hess
        w = dofs.shape[1]
        rows = np.repeat(dofs, w, axis=1).ravel()
        cols = np.tile(dofs, (1, w)).ravel()
        n = self.n_dofs
        return (H + sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))).tocsr()

    def accept(self, q: np.ndarray) -> None:
        self.base.accept(q)

    def parameter_derivative(self, q: np.ndarray, multipliers: np.ndarray,
                             parameter: str) -> np.ndarray | None:
        """The rod's ``parameter_derivative`` (None if it has none for ``parameter``),
        zero on the contact constraints: the contact terms depend on ``q`` alone."""
        derivative = getattr(self.base, "parameter_derivative", None)
        m0 = self.base.n_constraints
        full = None if derivative is None else derivative(
            q, np.asarray(multipliers, dtype=float)[:m0], parameter)
        if full is None:
            return None
        return np.concatenate([np.asarray(full, dtype=float),
                               np.zeros(self.n_constraints - m0)])

    # ---------------------------------------------------- step guard (CCD)
    def admissible(self, q: np.ndarray) -> bool:
        """Whether the closed rod kept its linking number at ``q`` (Newton's per-step guard).

        The writhe the energy carries continuously (from the reference twist)
        must equal the double-sum writhe: a strand that passed through another
        changes the latter by 2, so half a turn separates the two cases far
        beyond round-off. The double sum costs O(N^2) (0.1 s at N = 5000): it
        runs up to ``LINK_CHECK_MAX_NODES`` nodes, and only when ``q`` is not
        within half the closest approach of the last verified state (then no
        pair can have crossed); beyond that size the collision detection of
        :meth:`step_bound` is the guard. Open rods: always True.
        """
        if not self.closed or self.n_dofs // 3 > LINK_CHECK_MAX_NODES:
            return True
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        verified = self.__dict__.get("_verified")
        if verified is not None:
            # No pair's distance can fall by more than twice the largest node
            # displacement: within that of a verified state nothing crossed.
            x_v, d_v = verified
            if x_v.shape == x.shape and 2.0 * np.max(np.linalg.norm(x - x_v, axis=1)) < d_v:
                return True
        ok = abs(self.base.writhe_local(q) - writhe(x)) < 0.5
        if ok:
            self.__dict__["_verified"] = (x.copy(), self.min_distance(q, polygon=True))
        return ok

    def step_size_ratio(self, q: np.ndarray, dq: np.ndarray) -> float:
        """Largest node displacement of ``dq`` over the trust radius (one edge length)."""
        dx = np.asarray(dq, dtype=float).reshape(-1, 3)
        return float(np.max(np.linalg.norm(dx, axis=1))) / self.edge_length if dx.size else 0.0

    def step_bound(self, q: np.ndarray, dq: np.ndarray) -> float:
        """Largest fraction of the step ``dq`` free of collisions (continuous detection).

        No pair's centreline distance may fall below ``min(0.9 d0, max(0.1 d0, D/2))``
        during the step (``d0`` its distance at ``q``), so segments never pass
        through each other; for the barrier, no gap may fall below a tenth of
        its value (Li et al. 2020, sec. 4.3), so the state stays free of contact.
        """
        x0 = np.asarray(q, dtype=float).reshape(-1, 3)
        dx = np.asarray(dq, dtype=float).reshape(-1, 3)
        largest = largest_displacement(dx) if dx.size else 0.0
        if largest == 0.0:
            return 1.0
        # Trust region: no node moves more than one edge length per step. The
        # stiff contact terms and the near-null mode of a closed rod (sliding
        # the material along itself) otherwise give Newton steps far outside
        # the region where the quadratic model holds.
        cap = min(1.0, self.edge_length / largest)
        # pairs that may come within reach: relative motion at most twice the
        # largest node displacement; the barrier's threshold sits above D, so
        # a margin (2.5 rather than 2) keeps every pair that could reach it
        step = cap * largest
        reach = self.diameter + 2.5 * step
        D = self.diameter
        polygon_barrier = self.treatment == "barrier" and not self.spline and not self.integral
        samples = None
        if self.integral and self.treatment == "barrier":
            # asked first: its broad phase (the widest cutoff) serves the segments' below
            samples = self.pair_state(q, reach)
        if polygon_barrier:
            st = self.pair_state(q, reach, polygon=True)
        else:
            # the threshold min(0.9 d0, max(0.1 d0, D/2)) is at most max(0.1 d0, D/2): a
            # pair farther than D/2 + 2.5 s (s the step's largest node displacement)
            # cannot reach it (its distance falls by at most 2 s, and 0.9 d0 > 2 s
            # there), and the conservative advancement drops such a pair before its
            # first move (its bound gap / speed exceeds 1) without touching the
            # others: the pairs within the former reach D + 2.5 s give the same time
            st = self.pair_state(q, 0.5 * D + 2.5 * step, polygon=True)
        t_hit = 1.0
        if len(st.pairs):
            d0 = st.distance
            if polygon_barrier:
                threshold = D + 0.1 * np.maximum(d0 - D, 0.0)
            else:
                threshold = np.minimum(0.9 * d0, np.maximum(0.1 * d0, 0.5 * D))
            t_hit, _k = first_time_of_approach(x0, cap * dx, self._pair_nodes(st.pairs),
                                               threshold)
        if samples is not None:
            # the barrier's gaps are those of the sample points: none may fall below
            # a tenth of the smallest one now (sliding brings other sample pairs
            # into line, and their gaps may fall to that of the contact)
            st = samples
            if len(st.pairs):
                gap = float(np.min(st.distance)) - D  # the closest sample points'
                t_samples = first_time_of_approach_samples(
                    x0, cap * dx, self.sample_stencil, self.sample_weights, st.pairs,
                    D + 0.1 * max(gap, 0.0), points0=self._samples(q)[0])
                t_hit = min(t_hit, t_samples)
        elif self.spline and self.treatment == "barrier":
            # the barrier's gap is the spline's: keep it above a tenth of its value
            st = self.pair_state(q, reach, shadows=True)
            if len(st.pairs):
                nodes = self.pieces.stencil[st.pairs].reshape(-1, 8)
                pieces = (self.pieces.control[st.pairs], self.pieces.coefficients[st.pairs])
                t_spline, _k = first_time_of_approach_pieces(
                    x0[nodes], cap * dx[nodes], pieces, D + 0.1 * np.maximum(st.distance - D, 0.0))
                t_hit = min(t_hit, t_spline)
        return cap * float(t_hit)

    # ------------------------------------------------------------ forces
    def pair_forces(self, q: np.ndarray, multipliers: np.ndarray | None = None):
        """``(PairState, force)`` of the pairs that carry a contact force at ``q``.

        Energy treatments: ``force = -psi'(g)``; exact: minus the multipliers
        of the active constraints (``multipliers`` is the full vector).
        """
        if self.treatment == "exact":
            m0 = self.n_equalities
            lam = np.zeros(len(self.active)) if multipliers is None else \
                np.asarray(multipliers, dtype=float)[m0:]
            if len(self.active) == 0:
                return self.pair_state(q, 0.0), np.zeros(0)
            d, s, t = self.pair_distances(q, self.active)
            return PairState(self.active.copy(), d, s, t), -lam
        if self.integral:
            # per pair: the integrated force and its force-weighted sample positions
            st, (_e, _g, _h, force, param, _dofs) = self._integral(q, 1)
            keep = force > 0
            return (PairState(st.pairs[keep], st.distance[keep], param[keep, 0],
                              param[keep, 1]), force[keep])
        st = self.pair_state(q, self._cutoff())
        if len(st.pairs) == 0:
            return st, np.zeros(0)
        _, first, _ = self._psi(st.distance - self.diameter, st.pairs)
        force = -first
        keep = force > 0
        return PairState(st.pairs[keep], st.distance[keep], st.s[keep], st.t[keep]), force[keep]

    def arclength(self, segment: np.ndarray, param: np.ndarray) -> np.ndarray:
        """Arc-length fraction ``s/L`` of the point ``param`` along ``segment``."""
        L = self.base.rod.length
        s = self.s_start[segment] + param * (self.s_end[segment] - self.s_start[segment])
        s = np.clip(s, 0.0, L) if not self.closed else np.mod(s, L)
        return s / L
