"""The contact curve of a rod: its segment pairs near contact, their distances and derivatives.

The centreline is a polygon, so the contact condition is imposed on every pair
of its segments farther apart along the rod than the neighbour exclusion, with
the exact segment–segment distance ``d`` (smooth per distance type,
:mod:`supercoil.contact.distance`) or the distance of the B-spline pieces of
those segments.

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
``max |second difference| / 6`` of its chord), so it misses no pair. The
integral formulation sees the curve only at its sample points
(:mod:`supercoil.contact.integral`); its pairs are those of the closest sample
points.

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

from dataclasses import dataclass

import numpy as np

from supercoil.contact.broadphase import candidate_pairs, verlet_displacement
from supercoil.contact.distance import (
    segment_distance,
    segment_distance_derivatives,
    segment_pairs_within,
)
from supercoil.contact.options import ContactOptions
from supercoil.contact.sample_weights import (
    default_samples,
    polygon_weights,
    quintic_samples,
    spline_weights,
)
from supercoil.contact.samples import closest_samples_within, sample_state
from supercoil.contact.spline_distance import (
    local_minimum_pairs,
    piece_distance,
    piece_distance_derivatives,
)
from supercoil.contact.spline_pieces import bspline_pieces, sag_bound

_PAIR_MEMO = 8  # pair states remembered, see ContactCurve.pair_state
# Verlet list of ContactCurve._candidates: broad phase reach beyond the asked
# cutoff (edge lengths, at most D), and the largest cutoff (in units of D) served
# from it. A wider reach keeps the list longer but holds more pairs: the pairs
# within D + m of a line contact grow like N^2 at fixed m / L (on the tweezers at
# N = 400: 4002 pairs for m = D, 285 for m = 2 h).
_VERLET_MARGIN = 2.0
_VERLET_CUTOFF = 2.0


@dataclass(frozen=True)
class PairState:
    """Segment pairs near contact at one configuration (arrays over pairs)."""

    pairs: np.ndarray  # (m, 2) segment indices, i < j
    distance: np.ndarray  # (m,)
    s: np.ndarray  # (m,) closest parameter on segment i
    t: np.ndarray  # (m,) closest parameter on segment j


def _empty_state() -> PairState:
    empty = np.zeros(0)
    return PairState(np.zeros((0, 2), dtype=np.int64), empty, empty, empty)


class ContactCurve:
    """The curve whose self-distance is the contact distance (see the module docstring).

    ``segments`` ``(n_segments, 2)``: the node indices of the rod's edges; ``closed``:
    whether the rod is a ring; ``edge_length`` h and ``length`` L of the rod; ``origin``:
    the arc length of the first segment's start (default 0 for a ring, ``-h/2`` for an
    open rod, whose ends are mid-edges). Every
    query is a pure function of ``q`` (and of the fixed segments, pieces, arc lengths
    and exclusion); the recent answers are remembered.
    """

    def __init__(self, segments: np.ndarray, closed: bool, edge_length: float, length: float,
                 options: ContactOptions, origin: float | None = None):
        h = float(edge_length)
        self.options = options
        self.diameter = float(options.diameter)
        self.closed = bool(closed)
        self.edge_length = h
        self.length = float(length)
        self.segments = np.asarray(segments, dtype=np.int64)
        k = np.arange(len(self.segments), dtype=float)
        offset = (0.0 if self.closed else -0.5) if origin is None else origin / h
        self.s_start = (k + offset) * h
        self.s_end = (k + offset + 1.0) * h
        self.period = self.length if self.closed else None
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
        self._pair_memo: dict = {}
        self._verlet = None
        self._verlet_wide = None
        self._sample_memo = None
        self._derivative_memo = None

    def endpoints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The segments' first and last nodes ``(n_segments, 3)`` each at ``q``."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        return x[self.segments[:, 0]], x[self.segments[:, 1]]

    def pair_distances(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, s, t)`` ``(m,)`` of pairs ``(m, 2)`` on the contact curve (exact minima)."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if self.spline:
            return piece_distance(np.asarray(q, dtype=float).reshape(-1, 3), self.pieces, pairs)
        a, b = self.endpoints(q)
        i, j = pairs[:, 0], pairs[:, 1]
        return segment_distance(a[i], b[i], a[j], b[j])

    def pair_state(self, q: np.ndarray, cutoff: float, polygon: bool = False,
                   shadows: bool = False) -> PairState:
        """Pairs (beyond the exclusion) whose distance is at most ``cutoff``.

        The distance is that of the contact curve (``options.curve``), or of the
        polygon's segments when ``polygon``. The broad phase runs on the
        segments; for the spline its cutoff is widened by twice the largest
        distance of a piece from its chord (``spline_pieces.sag_bound``).
        ``shadows``: keep the pairs that ``count_local_minima`` drops.

        A pure function of its arguments, remembered for the last ``_PAIR_MEMO``
        arguments: one continuation point asks for the same state about fifty
        times (residual, finite-difference parameter derivative, Hessian,
        records, stability), and setting a load parameter does not change it.
        Callers must not modify the arrays.
        """
        key = (np.ascontiguousarray(q, dtype=np.float64).tobytes(), float(cutoff),
               float(self.exclusion), bool(polygon), bool(shadows))
        memo = self._pair_memo
        found = memo.get(key)
        if found is None:
            found = self._compute_pair_state(q, cutoff, polygon, shadows)
            if len(memo) >= _PAIR_MEMO:
                del memo[next(iter(memo))]
            memo[key] = found
        return found

    def forget_pair_states(self) -> None:
        """Forget the remembered pair states (they are keyed by state and cutoff, so
        this only frees them)."""
        self._pair_memo.clear()

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
        for reference in (self._verlet, self._verlet_wide):
            if reference is None:
                continue
            x_ref, reach, exclusion, pairs = reference
            if x_ref.shape != x.shape or exclusion != self.exclusion or cutoff > reach:
                continue
            scale, moved = verlet_displacement(x, x_ref)
            slack = 1e-9 * max(1.0, scale, reach)
            if cutoff + 2.0 * moved + slack <= reach:
                return pairs
        a, b = self.endpoints(q)
        if cutoff > _VERLET_CUTOFF * self.diameter:
            pairs = candidate_pairs(a, b, self.s_start, self.s_end, cutoff, self.exclusion,
                                    period=self.period)
            self._verlet_wide = (x.copy(), float(cutoff), self.exclusion, pairs)
            return pairs
        reach = cutoff + min(self.diameter, _VERLET_MARGIN * self.edge_length)
        pairs = candidate_pairs(a, b, self.s_start, self.s_end, reach, self.exclusion,
                                period=self.period)
        self._verlet = (x.copy(), reach, self.exclusion, pairs)
        return pairs

    def sample_points(self, q: np.ndarray) -> np.ndarray:
        """The integral formulation's sample points ``(n_segments, samples, 3)`` at ``q``."""
        return self.sample_geometry(q)[0]

    def sample_geometry(self, q: np.ndarray):
        """:func:`~supercoil.contact.samples.sample_state` at ``q``: the sample points,
        their largest distance from their segment's chord, and the bounding spheres of
        each segment's samples; the last state's are remembered (a residual and the
        step bound from the same iterate ask for them)."""
        key = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        cached = self._sample_memo
        if cached is not None and cached[0] == key:
            return cached[1]
        geometry = sample_state(np.asarray(q, dtype=float).reshape(-1, 3), self.sample_stencil,
                                self.sample_weights, self.segments)
        self._sample_memo = (key, geometry)
        return geometry

    def _sample_pair_state(self, q: np.ndarray, cutoff: float) -> PairState:
        """Pairs whose closest *sample points* are within ``cutoff`` (integral formulation:
        the energy sees the curve only there). The broad phase runs on the segments, its
        cutoff widened by twice the samples' largest distance from their chords."""
        points, deviation, centre, radius = self.sample_geometry(q)
        cand = self._candidates(q, cutoff + 2.0 * deviation)
        if len(cand) == 0:
            return _empty_state()
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
            return _empty_state()
        if not spline:
            # the segment distances of the candidates, filtered, in one compiled pass
            return PairState(*segment_pairs_within(np.asarray(q, dtype=float).reshape(-1, 3),
                                                   self.segments, cand, cutoff))
        d, s, t = self.pair_distances(q, cand)
        keep = d <= cutoff
        if self.options.count_local_minima and not shadows and keep.any():
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
        remembered = self.remembered_min_distance(q, polygon)
        if remembered is not None:
            return remembered
        cutoff = 2.0 * self.diameter
        a, b = self.endpoints(q)
        span = float(np.max(np.ptp(np.concatenate([a, b]), axis=0)))
        while True:
            st = self.pair_state(q, cutoff, polygon)
            if len(st.pairs):
                return float(st.distance.min())
            if cutoff > 2 * span + self.diameter:
                return float("inf")
            cutoff *= 4.0

    def remembered_min_distance(self, q: np.ndarray, polygon: bool) -> float | None:
        """Smallest distance of a remembered non-empty pair state at ``q`` (see
        :meth:`min_distance`), or None. Not with ``count_local_minima``: its states
        hold the local minima only."""
        memo = self._pair_memo
        if not memo or (self.options.count_local_minima and not polygon):
            return None
        key = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        for (state, _cutoff, exclusion, on_polygon, _shadows), st in memo.items():
            if on_polygon == bool(polygon) and exclusion == float(self.exclusion) \
                    and len(st.pairs) and state == key:
                return float(st.distance.min())
        return None

    def pair_nodes(self, pairs: np.ndarray) -> np.ndarray:
        """``(m, 4)`` node indices (p0, p1, q0, q1) of segment pairs."""
        return np.concatenate([self.segments[pairs[:, 0]], self.segments[pairs[:, 1]]], axis=1)

    def pair_derivatives(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, gradient, Hessian, dofs)`` of the pairs' distances on the contact curve
        (``(m,)``, ``(m, w)``, ``(m, w, w)``, ``(m, w)`` with ``w`` 12 for segments and 24
        for spline pieces); the last call is remembered (gradient and Hessian at one state
        ask for the same pairs)."""
        key = (np.asarray(q, dtype=float).tobytes(), np.asarray(pairs).tobytes())
        cached = self._derivative_memo
        if cached is not None and cached[0] == key:
            return cached[1]
        value = self._compute_pair_derivatives(q, pairs)
        self._derivative_memo = (key, value)
        return value

    def _compute_pair_derivatives(self, q: np.ndarray, pairs: np.ndarray):
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        if self.spline:
            d, _s, _t, grad, hess, _kind, nodes = piece_distance_derivatives(x, self.pieces,
                                                                            pairs)
            dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(pairs), 24)
            return d, grad, hess, dofs
        nodes = self.pair_nodes(pairs)
        d, grad, hess, _kind = segment_distance_derivatives(
            x[nodes[:, 0]], x[nodes[:, 1]], x[nodes[:, 2]], x[nodes[:, 3]])
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(pairs), 12)
        return d, grad, hess, dofs

    def arclength(self, segment: np.ndarray, param: np.ndarray) -> np.ndarray:
        """Arc-length fraction ``s/L`` of the point ``param`` along ``segment``."""
        L = self.length
        s = self.s_start[segment] + param * (self.s_end[segment] - self.s_start[segment])
        s = np.clip(s, 0.0, L) if not self.closed else np.mod(s, L)
        return s / L
