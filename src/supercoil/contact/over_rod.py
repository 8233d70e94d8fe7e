"""What a contact problem takes from the rod under it.

:class:`OverRod` is the part of :class:`~supercoil.contact.problem.ContactProblem`
that answers for its rod ``base``: the unknowns, metric and pins, the load
parameters (read from the rod; :meth:`OverRod.at` gives the contact problem over the
rod at other values, this one unchanged), the rod's symmetries and the reference
frames it carries from point to point (:mod:`supercoil.solvers.carried`), and the
parameter derivative, which the contact terms (functions of the state alone) leave
as the rod's.
"""

from __future__ import annotations

import copy

import numpy as np


class OverRod:
    """The rod's part of a contact problem (module doc): ``self.base`` is the rod; the
    carried frames also hand the contact problem's ``knot_guard`` the centreline
    (``centreline(q)``) of a closed rod's accepted states."""

    @property
    def n_dofs(self) -> int:
        return self.base.n_dofs

    @property
    def mass(self) -> np.ndarray:
        return self.base.mass

    @property
    def fixed(self) -> np.ndarray:
        """The rod's pinned DOFs (clamps and gauge pins; re-pinning moves them)."""
        return self.base.fixed

    @fixed.setter
    def fixed(self, value: np.ndarray) -> None:
        self.base.fixed = value

    @property
    def gauge_dofs(self) -> np.ndarray:
        return getattr(self.base, "gauge_dofs", np.zeros(0, dtype=np.int64))

    @property
    def parameters(self) -> tuple[str, ...]:
        """The rod's load parameters (:meth:`at`)."""
        return self.base.parameters

    def at(self, **values: float) -> OverRod:
        """This contact problem over the rod at other parameter values
        (``base.at(**values)``); the contact state (active set, multipliers, guards,
        curve) is shared, and this problem is unchanged."""
        new = copy.copy(self)
        new.base = self.base.at(**values)
        return new

    @property
    def excess_link(self) -> float:
        """The closed rod's excess link, a continuation parameter (:meth:`at`)."""
        return self.base.excess_link

    @property
    def turns(self) -> float:
        """The clamped rod's turns of the end clamp, a continuation parameter (:meth:`at`)."""
        return self.base.turns

    @property
    def tension(self) -> float:
        """The clamped rod's dead load, a continuation parameter (:meth:`at`)."""
        return self.base.tension

    @property
    def symmetry_modes(self):
        """The rod's ``symmetry_modes(q)`` (the contact terms share its symmetries:
        rigid motions, the rotation about the pulling axis); absent if the rod has none."""
        return self.base.symmetry_modes

    @property
    def near_symmetry_modes(self):
        """The rod's ``near_symmetry_modes(q)`` (a ring's material sliding); absent if
        the rod has none."""
        return self.base.near_symmetry_modes

    @property
    def far_sliding_modes(self):
        """The rod's ``far_sliding_modes(q)`` (its sliding where that is no approximate
        symmetry); absent if the rod has none."""
        return self.base.far_sliding_modes

    @property
    def tangent_rows(self):
        """The rod's ``tangent_rows(q)`` (its unit tangents on the nodes' DOFs); absent
        if the rod has none."""
        return self.base.tangent_rows

    @property
    def phase_offset(self):
        """The rod's ``phase_offset(q)`` (where a phase row of its sliding is anchored);
        absent if the rod has none."""
        return self.base.phase_offset

    @property
    def holding(self) -> bool:
        """The rod's ``holding`` (its states held on a symmetric family); False if it has
        none."""
        return bool(getattr(self.base, "holding", False))

    def held_part(self, q: np.ndarray, multipliers: np.ndarray):
        """The rod's ``held_part`` (a projection onto a symmetric family; None where it
        holds none), the contact's multipliers unchanged."""
        return self._held(getattr(self.base, "held_part", None), q, multipliers)

    def held_direction(self, q: np.ndarray, dq: np.ndarray, dmultipliers: np.ndarray):
        """The rod's ``held_direction`` (None where it holds none), as :meth:`held_part`."""
        part = getattr(self.base, "held_direction", None)
        return self._held(None if part is None else
                          (lambda dq_, dm_: part(q, dq_, dm_)), dq, dmultipliers)

    def _held(self, part, q: np.ndarray, multipliers: np.ndarray):
        if part is None:
            return None
        m0 = self.base.n_constraints
        multipliers = np.asarray(multipliers, dtype=float)
        held = part(q, multipliers[:m0])
        if held is None:
            return None
        return held[0], np.concatenate([held[1], multipliers[m0:]])

    def accept(self, q: np.ndarray) -> None:
        self.base.accept(q)
        if self.closed:
            self.knot_guard.accept(self.centreline(q))

    @property
    def frames(self):
        """The rod's carried frames (:mod:`supercoil.solvers.carried`)."""
        return self.base.frames

    @property
    def accept_moves_coordinates(self) -> bool:
        """Whether the rod's ``accept`` re-bases its coordinates (a Cosserat rod's chart:
        :class:`~supercoil.continuation.tracer.Tracer` then assembles the Hessian again)."""
        return bool(getattr(self.base, "accept_moves_coordinates", False))

    def with_frames(self, frames) -> OverRod:
        """This contact problem over the rod carrying ``frames``; this one unchanged."""
        new = copy.copy(self)
        new.base = self.base.with_frames(frames)
        return new

    def carried_to(self, q: np.ndarray) -> OverRod:
        """This contact problem over the rod carried to ``q`` (the knot guard, shared,
        takes ``q``'s knot type if it has none yet); this one unchanged."""
        new = copy.copy(self)
        new.base = self.base.carried_to(q)
        if self.closed:
            self.knot_guard.accept(self.centreline(q))
        return new

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
