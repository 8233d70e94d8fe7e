"""The guards of a contact problem's steps: topology, curvature and collisions.

:class:`StepGuards` is the part of :class:`~supercoil.contact.problem.ContactProblem`
that Newton and the continuation ask before they accept a state or take a step:
``admissible(q)`` (a closed rod keeps its linking number and knot type, and a tube
its radius of curvature at least ``curvature_limit``: Carlen et al. 2005),
``step_bound(q, dq)`` (the fraction of a step free of collisions: continuous
collision detection) and ``step_size_ratio(q, dq)`` (the step against the trust
radius of one edge). It reads the contact problem's ``closed``, ``curve``,
``diameter``, ``edge_length``, ``treatment``, ``base`` (and its ``rotations_admissible``,
if it has one), ``centreline(q)``,
``link_guard``, ``knot_guard`` and ``curvature_limit``.
"""

from __future__ import annotations

import copy

import numpy as np

from supercoil.contact.step import step_bound
from supercoil.geometry.curves import min_radius_of_curvature


class StepGuards:
    """Admissibility and step bounds of a contact problem (module doc)."""

    def keep_knot_type(self, points: np.ndarray, known=None):
        """Make the knot type of ``points`` ``(n, 3)`` the one every state must keep
        (else the first accepted state's); returns it (a ``KnotType``). ``known``: the
        type of the curve it was deformed from (:meth:`KnotGuard.keep`)."""
        return self.knot_guard.keep(points, known)

    def admissible(self, q: np.ndarray) -> bool:
        """Whether the closed rod kept its linking number and its knot type at ``q``
        (Newton's and the continuation's per-step guard,
        :class:`supercoil.contact.step.LinkGuard`,
        :class:`supercoil.topology.knots.KnotGuard`) and, with a ``curvature_limit``, a
        discrete radius of curvature of at least that everywhere
        (:func:`supercoil.geometry.curves.min_radius_of_curvature`); open rods: always True.
        A rod whose unknowns hold more than the centreline guards the rest itself
        (``base.rotations_admissible(q)``: a Cosserat ring's element rotations below
        ``pi / 2``, :meth:`~supercoil.cosserat.closed.ClosedCosseratEnergy.rotations_admissible`).
        ``refusal`` says why the last refused state was refused."""
        own = getattr(self.base, "rotations_admissible", None)
        if own is not None and not own(q):
            self.refusal = self.base.refusal
            return False
        if not self.closed:
            return True
        x = self.centreline(q)
        if not self.link_guard.admissible(self.curve, x, lambda: self.base.writhe_local(q)):
            self.refusal = "the linking number would change (a strand through another)"
            return False
        if not self.knot_guard.admissible(
                x, clearance=lambda state: self.curve.min_distance(state, polygon=True)):
            self.refusal = self.knot_guard.refusal
            return False
        if self.curvature_limit is not None:
            radius, vertex = min_radius_of_curvature(x.reshape(-1, 3))
            if radius < self.curvature_limit:
                self.refusal = (f"the radius of curvature would fall to {radius / self.diameter:.4g}"
                                f" D at node {vertex}, below "
                                f"{self.curvature_limit / self.diameter:.4g} D (a tube "
                                "overlapping itself locally)")
                return False
        return True

    def admissible_over(self, q: np.ndarray, problem=None) -> bool:
        """:meth:`admissible` with the rod of ``problem`` (the rod a continuation carried
        to the point, whose frames give the writhe it tracks): the guard of a run without
        contact terms, which this problem only watches."""
        if problem is None:
            return self.admissible(q)
        watched = copy.copy(self)
        watched.base = getattr(problem, "base", problem)
        return watched.admissible(q)

    def step_size_ratio(self, q: np.ndarray, dq: np.ndarray) -> float:
        """Largest node displacement of ``dq`` over the trust radius (one edge length)."""
        dx = self.centreline(dq).reshape(-1, 3)
        return float(np.max(np.linalg.norm(dx, axis=1))) / self.edge_length if dx.size else 0.0

    def step_bound(self, q: np.ndarray, dq: np.ndarray) -> float:
        """Largest fraction of the step ``dq`` free of collisions
        (:func:`supercoil.contact.step.step_bound`)."""
        return step_bound(self.curve, self.centreline(q), self.centreline(dq),
                          self.treatment == "barrier")
