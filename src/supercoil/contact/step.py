"""Newton's step guards: how far a step may go, and whether its end kept the link.

:func:`step_bound` runs continuous collision detection (:mod:`supercoil.contact.ccd`)
along the straight step ``q + t dq`` and returns the largest free fraction of it.
The guard stays on the polygon whatever the contact curve, and it is the right
guard: the rod's topology *is* the polygon's. Its linking number is ``Tw + Wr``
with the writhe of the polygon, and the knot type is the polygon's; a strand can
only change those by passing a segment through another, which this guard forbids
(no segment pair may approach below ``min(0.9 d0, max(0.1 d0, D/2))``). Near
contact the spline and the polygon differ by at most twice the sag bound, about
``h^2 kappa / 3``, far below ``D/2`` on any resolved rod, so the guard does not
limit the steps of a spline contact. The barrier additionally needs its own gap
to stay positive: a second conservative advancement on its curve (the spline
pieces, or the integral formulation's sample points) keeps every gap above a
tenth of its value (Li et al. 2020, sec. 4.3). :class:`LinkGuard` checks the
linking number of a closed rod after the step.
"""

from __future__ import annotations

import numpy as np

from supercoil.contact.ccd import (
    first_time_of_approach,
    first_time_of_approach_pieces,
    largest_displacement,
)
from supercoil.contact.curve import ContactCurve
from supercoil.contact.sample_ccd import first_time_of_approach_samples
from supercoil.topology import writhe

LINK_CHECK_MAX_NODES = 2000  # see LinkGuard


def step_bound(curve: ContactCurve, q: np.ndarray, dq: np.ndarray, barrier: bool) -> float:
    """Largest fraction of the step ``dq`` free of collisions (continuous detection).

    No pair's centreline distance may fall below ``min(0.9 d0, max(0.1 d0, D/2))``
    during the step (``d0`` its distance at ``q``), so segments never pass
    through each other; for the barrier (``barrier``), no gap may fall below a
    tenth of its value, so the state stays free of contact. No node moves more
    than one edge length (a trust region).
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
    cap = min(1.0, curve.edge_length / largest)
    # pairs that may come within reach: relative motion at most twice the
    # largest node displacement; the barrier's threshold sits above D, so
    # a margin (2.5 rather than 2) keeps every pair that could reach it
    step = cap * largest
    reach = curve.diameter + 2.5 * step
    D = curve.diameter
    polygon_barrier = barrier and not curve.spline and not curve.integral
    samples = None
    if curve.integral and barrier:
        # asked first: its broad phase (the widest cutoff) serves the segments' below
        samples = curve.pair_state(q, reach)
    if polygon_barrier:
        st = curve.pair_state(q, reach, polygon=True)
    else:
        # the threshold min(0.9 d0, max(0.1 d0, D/2)) is at most max(0.1 d0, D/2): a
        # pair farther than D/2 + 2.5 s (s the step's largest node displacement)
        # cannot reach it (its distance falls by at most 2 s, and 0.9 d0 > 2 s
        # there), and the conservative advancement drops such a pair before its
        # first move (its bound gap / speed exceeds 1) without touching the
        # others: the pairs within the former reach D + 2.5 s give the same time
        st = curve.pair_state(q, 0.5 * D + 2.5 * step, polygon=True)
    t_hit = 1.0
    if len(st.pairs):
        d0 = st.distance
        if polygon_barrier:
            threshold = D + 0.1 * np.maximum(d0 - D, 0.0)
        else:
            threshold = np.minimum(0.9 * d0, np.maximum(0.1 * d0, 0.5 * D))
        t_hit, _k = first_time_of_approach(x0, cap * dx, curve.pair_nodes(st.pairs), threshold)
    if samples is not None:
        # the barrier's gaps are those of the sample points: none may fall below
        # a tenth of the smallest one now (sliding brings other sample pairs
        # into line, and their gaps may fall to that of the contact)
        st = samples
        if len(st.pairs):
            gap = float(np.min(st.distance)) - D  # the closest sample points'
            t_samples = first_time_of_approach_samples(
                x0, cap * dx, curve.sample_stencil, curve.sample_weights, st.pairs,
                D + 0.1 * max(gap, 0.0), points0=curve.sample_points(q))
            t_hit = min(t_hit, t_samples)
    elif curve.spline and barrier:
        # the barrier's gap is the spline's: keep it above a tenth of its value
        st = curve.pair_state(q, reach, shadows=True)
        if len(st.pairs):
            nodes = curve.pieces.stencil[st.pairs].reshape(-1, 8)
            pieces = (curve.pieces.control[st.pairs], curve.pieces.coefficients[st.pairs])
            t_spline, _k = first_time_of_approach_pieces(
                x0[nodes], cap * dx[nodes], pieces, D + 0.1 * np.maximum(st.distance - D, 0.0))
            t_hit = min(t_hit, t_spline)
    return cap * float(t_hit)


class LinkGuard:
    """Whether a closed rod kept its linking number at a state.

    The writhe the energy carries continuously (from the reference twist,
    ``writhe_local``) must equal the double-sum writhe: a strand that passed
    through another changes the latter by 2, so half a turn separates the two
    cases far beyond round-off. The double sum costs O(N^2) (0.1 s at N = 5000):
    it runs up to ``LINK_CHECK_MAX_NODES`` nodes, and only when ``q`` is not within
    half the closest approach of the last verified state (then no pair can have
    crossed); beyond that size the collision detection of :func:`step_bound` is
    the guard.
    """

    def __init__(self):
        self._verified: tuple[np.ndarray, float] | None = None

    def admissible(self, curve: ContactCurve, points: np.ndarray, carried_writhe) -> bool:
        """Whether the centreline ``points`` kept the link; ``carried_writhe()`` is the
        writhe the energy carries there (asked only when the double sum runs)."""
        x = np.asarray(points, dtype=float).reshape(-1, 3)
        if len(x) > LINK_CHECK_MAX_NODES:
            return True
        if self._verified is not None:
            # No pair's distance can fall by more than twice the largest node
            # displacement: within that of a verified state nothing crossed.
            x_v, d_v = self._verified
            if x_v.shape == x.shape and 2.0 * np.max(np.linalg.norm(x - x_v, axis=1)) < d_v:
                return True
        ok = abs(carried_writhe() - writhe(x)) < 0.5
        if ok:
            self._verified = (x.copy(), curve.min_distance(x.ravel(), polygon=True))
        return ok
