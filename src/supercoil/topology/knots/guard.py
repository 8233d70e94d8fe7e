"""Whether a closed rod kept its knot type: the per-step guard of every closed-rod computation.

A closed rod's knot type can only change when a strand passes through another.
Continuous collision detection keeps segments from meeting during a step, and
:class:`KnotGuard` checks the result: the invariants of every state asked about
(:func:`~.knot_type.identify`: the Alexander and Jones polynomials) must equal the
reference's. The name is not compared: it can depend on the view, when a
diagram with many crossings leaves a knot of more crossings with the same
polynomials among the candidates (5_1 and 10_132). A state that differs is refused, and the caller (Newton's line
search, the continuation's step control) retries the step shorter.

Cost: :func:`~.knot_type.identify` takes about 0.1-1.3 ms at 100-400 nodes on
the built knots up to 5 crossings (the projection's all-pairs crossing test and
the polynomials of the simplified diagram), less than one Newton iteration of a
rod with contact. A cheaper test first: no pair of points can come closer by
more than twice the largest node displacement, so a state within half the
closest approach of non-neighbouring segments (``clearance``) of the last
verified state has the same knot type without any invariant computed.
"""

from __future__ import annotations

import logging

import numpy as np

from supercoil.errors import InputError
from supercoil.topology.knots.knot_type import KnotType, identify

log = logging.getLogger(__name__)


class KnotGuard:
    """The knot type of a reference state, and whether later states kept it.

    ``reference``: a :class:`KnotType`, or None until :meth:`keep` or the first
    :meth:`accept` sets it (the first accepted state is then the reference).
    ``refusal``: why the last refused state was refused (None if none was).
    ``invariant_evaluations`` counts the full invariants computed.
    """

    def __init__(self, reference: KnotType | None = None):
        self.reference = reference
        self.refusal: str | None = None
        self.invariant_evaluations = 0
        self._verified: tuple[np.ndarray, float] | None = None

    def keep(self, points: np.ndarray, known: KnotType | None = None) -> KnotType:
        """Make the knot type of the polygon ``points`` ``(n, 3)`` (or a flat vector) the
        reference, and return it. ``known``: the type of a curve deformed into this one
        with no strand through another (a guarded relaxation of a built knot); when the
        invariants agree its name is kept, since a view of the deformed curve may leave
        a second candidate of the same polynomials (5_1 and 10_132)."""
        x = np.asarray(points, dtype=float).reshape(-1, 3)
        found = identify(x)
        self.reference = known if known is not None and known.same_invariants(found) \
            else found
        self.invariant_evaluations += 1
        self._verified = None
        return self.reference

    def accept(self, q: np.ndarray) -> None:
        """An accepted state: the reference if there is none yet."""
        if self.reference is None:
            self.keep(q)

    def admissible(self, q: np.ndarray, clearance=None) -> bool:
        """Whether the polygon ``q`` (flat or ``(n, 3)``) has the reference's knot type
        (True while there is no reference). ``clearance(q)``: the closest approach of
        non-neighbouring segments at ``q``, for the displacement test (module doc)."""
        if self.reference is None:
            return True
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        if self._verified is not None:
            x_v, d_v = self._verified
            if x_v.shape == x.shape and 2.0 * np.max(np.linalg.norm(x - x_v, axis=1)) < d_v:
                return True
        try:
            found = identify(x)
        except InputError as exc:  # strands that meet: no knot type
            self.refusal = f"the knot type is not defined ({exc})"
            return False
        finally:
            self.invariant_evaluations += 1
        if not found.same_invariants(self.reference):
            self.refusal = (f"the knot type would change from {_label(self.reference)} to "
                            f"{_label(found)} (a strand through another)")
            log.debug("knot guard: %s", self.refusal)
            return False
        if clearance is not None:
            self._verified = (x.copy(), float(clearance(q)))
        return True


def _label(knot: KnotType) -> str:
    name = knot.name or f"an unknown knot (Alexander {list(knot.alexander)})"
    return name if knot.chirality == 0 else f"{name} (chirality {knot.chirality:+d})"
