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
from supercoil.rod.open import _axis_rotation_pin

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
        self.gauge_dofs = np.zeros(0, dtype=np.int64)  # the azimuth pin (hold_azimuth)
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

    def hold_azimuth(self, dofs) -> None:
        """Pin the rotation about the axis by the coordinates ``dofs`` (none: not
        pinned), in place of the pin held so far; the clamps are kept.

        Turning the centreline about the axis together with every section about its
        ``d3`` leaves the clamps' frames and the energy unchanged (an isotropic
        section): off the axis a zero mode, removed by holding a coordinate it moves."""
        clamps = np.setdiff1d(self.fixed, self.gauge_dofs)
        self.gauge_dofs = np.unique(np.asarray(dofs, dtype=np.int64))
        self.fixed = np.union1d(clamps, self.gauge_dofs)

    def repin(self, q: np.ndarray) -> None:
        """Re-pick the azimuth pin for the state ``q``: the azimuthal coordinate of its
        node farthest from the axis (as :meth:`ClampedRodEnergy.repin
        <supercoil.rod.open.ClampedRodEnergy.repin>`), none for a straight rod."""
        pins = _axis_rotation_pin(np.asarray(q, dtype=float).reshape(-1, 6)[:, :3])
        self.hold_azimuth([6 * (d // 3) + d % 3 for d in pins])

    def end_force(self, q: np.ndarray) -> float:
        """The axial force on the end: the dead load under load control, the
        reaction ``dE/dz_N`` of the elastic energy under end-distance control."""
        if not self.end_distance_control:
            return self.tension
        return float(self.gradient(q)[6 * (self.rod.n_nodes - 1) + 2])

    def extension(self, q: np.ndarray) -> float:
        """End-to-end distance along the axis over ``L`` (1 for the unstretched straight rod)."""
        return float(np.asarray(q).reshape(-1, 6)[-1, 2]) / self.rod.length


def planar_buckle(rod: CosseratRod, end_distance: float, turns: float = 0.0
                  ) -> tuple[np.ndarray, np.ndarray]:
    """A planar clamped buckle in the x-z plane with the end at height
    ``end_distance * L`` on the axis, unstretched and unsheared, its sections turned
    by ``turns`` uniformly: ``(positions, rotations)``, a start for Newton under
    end-distance control.

    Each element's tangent makes the angle ``a sin(2 pi s)`` with the axis (``s`` its
    midpoint over L, so the sum of the ``x`` steps vanishes by the antisymmetry
    about ``s = 1/2``); ``a`` solves ``sum h cos = z`` (Brent). Node ``i`` has the
    frame ``exp(a sin(2 pi s_i) hat(e_2)) exp(2 pi turns s_i hat(e_3))``: identity at
    the first clamp, the turned frame at the last."""
    from scipy.optimize import brentq

    if not 0.0 < end_distance < 1.0:
        raise InputError(f"end_distance must lie in (0, 1) for a buckle, got {end_distance!r}")
    h = rod.element_length
    middle = (np.arange(rod.n_elements) + 0.5) / rod.n_elements

    def height(a):
        return float(np.sum(h * np.cos(a * np.sin(2 * np.pi * middle)))) / rod.length \
            - end_distance

    a = brentq(height, 0.0, 2.5)
    angles = a * np.sin(2 * np.pi * middle)
    steps = h * np.stack([np.sin(angles), np.zeros_like(angles), np.cos(angles)], axis=1)
    positions = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    positions[-1, 0] = 0.0  # zero up to round-off
    s = np.linspace(0.0, 1.0, rod.n_nodes)
    bend = exp_so3(np.outer(a * np.sin(2 * np.pi * s), [0.0, 1.0, 0.0]))
    spin = exp_so3(np.outer(2 * np.pi * turns * s, AXIS))
    bend[[0, -1]] = np.eye(3)
    return positions, bend @ spin
