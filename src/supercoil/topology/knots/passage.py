"""Whether a closed rod without contact passed a strand through another: its step guard.

Nothing in the energy of a closed rod without self-contact keeps a strand from
passing through another, and such a passage changes what the computation is
about: the linking number (the double-sum writhe jumps by 2 while the writhe the
energy carries, :meth:`~supercoil.rod.closed.ClosedRodEnergy.writhe_local`, is
continuous, so the state is no longer at the excess link asked for) and possibly
the knot type (a crossing of a diagram changed). :class:`StrandPassageGuard`
refuses such a state; Newton's line search and the continuation's step control
then retry the step shorter, and stop with the refusal as their status when no
step is short enough (the branch has reached a state where the rod touches itself).

Both invariants are checked, the link because the knot type alone does not see
every passage (a figure-eight unknot whose crossing changes stays an unknot),
the knot type because two passages of opposite signs in one step keep the link.

Cost: a state within half the closest approach of non-neighbouring edges
(:func:`~supercoil.topology.crossings.closest_approach`) of the last verified
state cannot have passed an edge through another, and is admitted without any
invariant; otherwise the double-sum writhe and :func:`~.knot_type.identify`
(each O(N^2) with small constants: together about 2 ms at N = 200).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from supercoil.errors import InputError
from supercoil.topology.crossings import closest_approach
from supercoil.topology.knots.guard import KnotGuard
from supercoil.topology.writhe import writhe


class StrandPassageGuard:
    """Whether the states of a closed polygon kept its linking number and knot type.

    ``points`` ``(n, 3)``: the curve whose knot type every state must keep (computed
    at the first check, so that a problem costs nothing until it is solved).
    ``refusal`` says why the last refused state was refused; ``knot_guard`` is the
    :class:`KnotGuard` holding the reference knot type (None if the reference
    curve's strands meet: its knot type is not defined, and only the link is kept).
    """

    def __init__(self, points: np.ndarray):
        self._reference_points: np.ndarray | None = np.array(points, dtype=float)
        self.knot_guard = KnotGuard()
        self.refusal: str | None = None
        self._verified: tuple[np.ndarray, float] | None = None

    @property
    def invariant_evaluations(self) -> int:
        """How many full knot invariants were computed (the reference included)."""
        return self.knot_guard.invariant_evaluations

    def admissible(self, q: np.ndarray, carried_writhe: Callable[[np.ndarray], float]) -> bool:
        """Whether the polygon ``q`` (flat or ``(n, 3)``) has the reference's knot type and
        a double-sum writhe within half a turn of ``carried_writhe(q)`` (the writhe the
        energy carries continuously along the computation)."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        if self._verified is not None:
            x_v, d_v = self._verified
            if x_v.shape == x.shape and 2.0 * np.max(np.linalg.norm(x - x_v, axis=1)) < d_v:
                return True
        if self._reference_points is not None:
            try:
                self.knot_guard.keep(self._reference_points)
            except InputError:  # a reference curve whose strands meet: the link only
                pass
            self._reference_points = None
        try:
            wr = writhe(x)
        except InputError as exc:
            self.refusal = f"the rod touches itself ({exc})"
            return False
        jump = wr - carried_writhe(q)  # the link's change: Lk - dLk
        if abs(jump) >= 0.5:
            self.refusal = (f"the linking number would change by {jump:+.0f} (a strand "
                            "through another)")
            return False
        if not self.knot_guard.admissible(x):
            self.refusal = self.knot_guard.refusal
            return False
        self._verified = (x.copy(), closest_approach(x))
        return True
