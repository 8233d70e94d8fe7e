"""A Cosserat rod clamped at both ends on the ``z`` axis, turned and pulled.

The first node is clamped at the origin with the identity frame. The last node is
clamped in rotation, its frame turned by ``turns`` (right-handed about ``+z``:
``R_N = exp(2 pi turns hat(e_3))``), held on the axis (``x = y = 0``), and either
slides along it under the dead load ``tension`` (load control, potential
``-tension z_N``; a negative tension compresses) or is held at its initial height
(``end_distance_control``). Both ``turns`` and ``tension`` are attributes that
:func:`supercoil.continuation.continuation` can follow; :meth:`parameter_derivative`
gives their exact derivatives.

The straight, uniformly twisted rod stretched by ``tension / EA``
(:meth:`straight_state`) is an exact equilibrium of the discrete model for every
``turns`` and ``tension`` (each element carries the same strains
``Gamma = (0, 0, tension / EA)`` and ``K = (0, 0, 2 pi turns / L)``). It loses stability
at Greenhill's condition in the Kirchhoff limit (large GA and EA).
"""

from __future__ import annotations

import numpy as np

from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod
from supercoil.cosserat.rotations import exp_so3
from supercoil.errors import InputError

AXIS = np.array([0.0, 0.0, 1.0])


class ClampedCosseratEnergy(CosseratEnergy):
    """Clamped-clamped Cosserat rod under end rotation and axial load (module doc).

    ``positions``, ``rotations``: the initial state (default: :meth:`straight_state`'s);
    the end clamps must match it (first node at the origin with the identity frame,
    last node on the axis with the turned frame).
    """

    twist_parameter = "turns"
    parameters = ("turns", "tension")

    def __init__(self, rod: CosseratRod, turns: float = 0.0, tension: float = 0.0,
                 end_distance_control: bool = False, positions: np.ndarray | None = None,
                 rotations: np.ndarray | None = None):
        for name, value in (("turns", turns), ("tension", tension)):
            if not np.isfinite(value):
                raise InputError(f"{name} must be a finite number, got {value!r}")
        if tension <= -rod.stretch_stiffness:
            raise InputError(f"tension must exceed -EA = {-rod.stretch_stiffness:g} (a "
                             f"compression of EA squeezes the rod to a point), got {tension!r}")
        straight_x, straight_R = self.straight(rod, turns, tension)
        positions = straight_x if positions is None else np.asarray(positions, dtype=float)
        rotations = straight_R if rotations is None else np.asarray(rotations, dtype=float)
        n = rod.n_nodes
        scale = rod.length
        if positions.shape == (n, 3) and (np.max(np.abs(positions[0])) > 1e-9 * scale
                                          or np.max(np.abs(positions[-1, :2])) > 1e-9 * scale):
            raise InputError("the first node must lie at the origin and the last on the z axis")
        if rotations.shape == (n, 3, 3) and (
                not np.allclose(rotations[0], np.eye(3), atol=1e-9)
                or not np.allclose(rotations[-1], straight_R[-1], atol=1e-9)):
            raise InputError("the end frames must be the clamps': the identity at the first "
                             "node, the frame turned by `turns` about z at the last")
        fixed = list(range(6)) + [6 * (n - 1), 6 * (n - 1) + 1] + \
            [6 * (n - 1) + 3 + c for c in range(3)]
        if end_distance_control:
            fixed.append(6 * (n - 1) + 2)
        super().__init__(rod, positions, rotations, fixed=fixed)
        self.end_distance_control = bool(end_distance_control)
        self._turns = float(turns)
        self.tension = float(tension)

    @staticmethod
    def straight(rod: CosseratRod, turns: float, tension: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """The straight equilibrium: positions ``(1 + tension/EA) s e_3``, rotations
        ``exp(2 pi turns s / L hat(e_3))``."""
        x, R = rod.straight(turns)
        return x * (1 + tension / rod.stretch_stiffness), R

    def straight_state(self) -> np.ndarray:
        """``q`` of the straight equilibrium at the current ``turns`` and ``tension``
        (re-bases the chart there)."""
        return self.state(*self.straight(self.rod, self.turns, self.tension))

    def _restore_frames(self, frames) -> None:
        super()._restore_frames(frames)
        self.turns = self.turns  # the end clamp's rotation is this problem's

    @property
    def turns(self) -> float:
        return self._turns

    @turns.setter
    def turns(self, value: float) -> None:
        # the end node's rotation coordinate is fixed at its chart centre, so its
        # rotation is the reference one: the clamp's
        self._turns = float(value)
        rotations = self.reference_rotations.copy()  # rebound: at() shares the old array
        rotations[-1] = exp_so3(2 * np.pi * self._turns * AXIS)
        self.reference_rotations = rotations

    @property
    def tension(self) -> float:
        return self._tension

    @tension.setter
    def tension(self, value: float) -> None:
        self._tension = float(value)
        self.forces = np.zeros((self.rod.n_nodes, 3))
        if not self.end_distance_control:
            self.forces[-1, 2] = self._tension

    def parameter_derivative(self, q: np.ndarray, multipliers: np.ndarray,
                             parameter: str) -> np.ndarray | None:
        """``d gradient / d parameter`` ``(n_dofs,)``: for ``turns`` the end frame turns
        with the spin ``2 pi e_3`` per turn (the chart Hessian's column of the end
        node's rotation coordinates, which sit at the chart's centre); for ``tension``
        ``-1`` on the end's ``z``; None for another parameter."""
        out = np.zeros(self.n_dofs)
        last = 6 * (self.rod.n_nodes - 1)
        if parameter == "tension":
            if not self.end_distance_control:
                out[last + 2] = -1.0
            return out
        if parameter != "turns":
            return None
        # the end node's rotation rows (fixed) are left out: the chart adds d(T^T m) there
        H = self.hessian(q).sparse.tocsc()[:, last + 3:last + 6]
        out = H @ (2 * np.pi * AXIS)
        out[last + 3:] = 0.0
        return out

    def extension(self, q: np.ndarray) -> float:
        """End-to-end distance along the axis over ``L`` (1 for the unstretched straight rod)."""
        return float(np.asarray(q).reshape(-1, 6)[-1, 2]) / self.rod.length
