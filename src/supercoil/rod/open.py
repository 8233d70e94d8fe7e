"""Open discrete Kirchhoff rod with clamped ends along a pulling axis.

Both ends are clamped (position and frame) with their tangents along the
axis ``+z``: nodes 0 and 1 are fixed, nodes ``n-2`` and ``n-1`` stay on the
axis. The rod's ends are the midpoints of the first and last edges (edge
length ``L / (n - 2)``), so the clamps sit at ``s = 0`` and ``s = L`` to
second order. The turned end is rotated by ``turns`` (right-handed about ``+z``) and
either slides freely along the axis under a dead load ``tension`` F
(load control: total potential ``E - F (z_{n-1} - z_0)``) or is held at its
initial end-to-end distance (displacement control).

Twist (isotropic rod, uniform at equilibrium, material angles minimised out):
``Tw = turns + Phi / 2pi`` with ``Phi`` the sum of the reference twists of the
interior vertices; the reference director of the first edge is the clamp
director. With the rod closed by straight tails along the axis,
``turns = Tw + Wr`` (Fuller; fails when the rod wraps around a tail).
Rotating the whole centreline about the axis is an exact symmetry; it is
removed by fixing the azimuthal coordinate of the node farthest from the axis,
chosen at construction and re-picked for a new shape by :meth:`repin`
(continuation in :mod:`supercoil.problems.tweezers` does so between runs).
"""

from __future__ import annotations

import numpy as np

from supercoil.rod.energy import RodEnergy
from supercoil.rod.mirror import (
    mirror_pairs,
    symmetric_direction,
    symmetric_state,
)
from supercoil.rod.model import Rod
from supercoil.rod.sliding import (
    StructureSliding,
    sliding_threshold,
)

AXIS = np.array([0.0, 0.0, 1.0])


def straight_rod(n_nodes: int, length: float = 1.0) -> np.ndarray:
    """Straight rod along +z, shape ``(n_nodes, 3)``; its ends (mid-edges) at z = 0 and L."""
    h = length / (n_nodes - 2)
    z = (np.arange(n_nodes) - 0.5) * h
    return np.stack([np.zeros(n_nodes), np.zeros(n_nodes), z], axis=1)


# the rod has passed through itself where Fuller's closure fails by more than this (a
# crossing changes the writhe by 2; ClampedRodEnergy.admissible)
CROSSING_CLOSURE = 0.5


class ClampedRodEnergy(StructureSliding, RodEnergy):
    """Constrained energy problem of a rod clamped at both ends on the ``z`` axis."""

    def __init__(self, rod: Rod, points: np.ndarray, turns: float, tension: float = 0.0,
                 end_distance_control: bool = False,
                 reference_directors: np.ndarray | None = None):
        points = np.asarray(points, dtype=float)
        n = rod.n_nodes
        if rod.closed:
            raise ValueError("ClampedRodEnergy needs an open Rod (closed=False)")
        if points.shape != (n, 3):
            raise ValueError(f"points must have shape ({n}, 3), got {points.shape}")
        if not np.isfinite(points).all():
            raise ValueError("points contain non-finite coordinates")
        for name, value in (("turns", turns), ("tension", tension)):
            if not np.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        h = rod.edge_length
        for label, a, b in (("first", 0, 1), ("last", n - 2, n - 1)):
            e = points[b] - points[a]
            if not np.allclose(e, h * AXIS, atol=1e-9 * rod.length):
                raise ValueError(f"the {label} edge must lie along +z with length L/(n_nodes-2) "
                                 "(clamped end on the pulling axis)")
        if np.any(np.abs(points[[0, 1, n - 2, n - 1], :2]) > 1e-9 * rod.length):
            raise ValueError("the clamped end nodes must lie on the z axis")
        self.turns = float(turns)
        self.tension = float(tension)
        self.end_distance_control = bool(end_distance_control)
        idx = np.arange(1, n - 1)
        if reference_directors is None:
            reference_directors = _transported_directors(points)
        self._setup(rod, points, np.stack([idx - 1, idx, idx + 1], 1),
                    np.stack([np.arange(n - 1), np.arange(1, n)], 1), idx - 1, idx,
                    reference_directors)
        fixed = [0, 1, 2, 3, 4, 5, 3 * (n - 2), 3 * (n - 2) + 1, 3 * (n - 1), 3 * (n - 1) + 1]
        if self.end_distance_control:
            fixed += [3 * (n - 2) + 2, 3 * (n - 1) + 2]
        self.gauge_dofs = np.array(_axis_rotation_pin(points), dtype=np.int64)
        self.fixed = np.array(sorted(fixed + list(self.gauge_dofs)), dtype=np.int64)
        # The clamped first edge (and, under displacement control, the last one)
        # has both ends fixed: its length is not a constraint on the unknowns.
        last = n - 2 if not self.end_distance_control else n - 3
        self.set_constrained_edges(np.arange(1, last + 1))
        # Angle (about +z) from the last reference director to the end clamp's
        # unturned director +x. The last edge stays along the axis, so the
        # director there never moves and this angle is a constant of the set-up.
        u_last = self._directors[-1]
        self._end_mismatch = float(np.arctan2(-u_last[1], u_last[0]))  # (u x e_x).e_z, u.e_x
        self._turn_offset = 0  # whole turns restored after a rebuild of the frames (accept)
        # the tail ratio below which near_symmetry_modes offers the sliding of a
        # localised structure (None: never)
        self.sliding_tail: float | None = sliding_threshold(n)
        # True: the states are held on the half-turn symmetry about an axis across the
        # middle (supercoil.rod.mirror; held_part, held_direction), and a phase row of
        # the sliding is anchored at the state's symmetric part (phase_offset); False:
        # free, the row anchored towards the structure centred on the rod's middle
        self.mirror_hold = False
        # a rod with self-contact does not pass through itself (admissible); a phantom
        # rod, without it, may
        self.impenetrable = False
        self._accepted: tuple[np.ndarray | None, float | None] = (None, None)
        self.refusal: str | None = None  # why admissible() refused the last state

    twist_parameter = "turns"
    parameters = ("turns", "tension")
    frame_attributes = RodEnergy.frame_attributes + (("end_mismatch", "_end_mismatch"),
                                                     ("turn_offset", "_turn_offset"))

    def twist_offset(self) -> float:
        return self.turns + self._end_mismatch / (2 * np.pi) + self._turn_offset

    def parameter_derivative(self, q: np.ndarray, multipliers: np.ndarray,
                             parameter: str) -> np.ndarray | None:
        """``d/d parameter`` of ``[gradient; constraints]`` ``(n_dofs + n_constraints,)``:
        ``turns`` as :meth:`RodEnergy.parameter_derivative`; ``tension`` (the dead
        load's potential ``-F (z_last - z_first)``, :meth:`gradient`) gives ``+1`` on
        the first node's ``z`` and ``-1`` on the last one's; None for another parameter."""
        if parameter != "tension":
            return super().parameter_derivative(q, multipliers, parameter)
        out = np.zeros(self.n_dofs + self.n_constraints)
        out[2] = 1.0
        out[self.n_dofs - 1] = -1.0
        return out

    # An accepted state whose edges turned by more than this (degrees) from the
    # last one is a jump (a stored state), not a step: see accept.
    jump_turn_degrees = 45.0

    def accept(self, q: np.ndarray) -> None:
        """Carry the reference directors to ``q``; rebuild them after a jump.

        ``Phi`` is a sum of per-vertex signed angles in ``(-pi, pi]``; along a
        branch time-parallel transport keeps them small, but a jump to a
        stored state (a consistency check, a hysteresis jump) can pile them up
        until one wraps and the twist slips by a whole turn. As for closed
        rods (:meth:`ClosedRodEnergy.accept`): after a jump (some edge turned
        by more than :attr:`jump_turn_degrees`) the directors are rebuilt by
        space-parallel transport from the clamp and the whole turns restored
        so that ``Tw = turns - Wr`` with the double-sum writhe (tails along
        the axis: valid unless the rod wraps around a tail); after a step
        whose vertex twist exceeds ``pi / 2`` they are rebuilt keeping the
        twist continuous.
        """
        from supercoil.rod import kernels

        q = np.asarray(q, dtype=float)
        self._accepted = (q.copy(), None)  # admissible's reference (its closure, lazily)
        t_new = self._edge_vectors(q)
        t_new = t_new / np.linalg.norm(t_new, axis=1, keepdims=True)
        jump = bool(np.min(np.sum(t_new * self._tangents, axis=1))
                    < np.cos(np.radians(self.jump_turn_degrees)))
        target = None
        if not jump:
            super().accept(q)
            if np.max(np.abs(kernels.twist_value(self._stencils(q), self._frames()))) \
                    <= np.pi / 2:
                return
            target = self.twist(q)
        points = q.reshape(-1, 3)
        self._set_frames(t_new, _transported_directors(points))
        u_last = self._directors[-1]
        self._end_mismatch = float(np.arctan2(-u_last[1], u_last[0]))
        self._turn_offset = 0
        if target is None:
            from supercoil.topology import writhe  # jumps only, never inside Newton

            target = self.turns - writhe(points, closure="axis")
        self._turn_offset = int(np.rint(target - self.twist(q)))

    def repin(self, q: np.ndarray) -> None:
        """Re-pick the azimuth pin (rotation about the axis) for the state ``q``.

        The pin chosen at construction is the azimuthal coordinate of the node
        then farthest from the axis; as the shape changes along a branch that
        node can come back towards the axis, and the pin then barely removes
        the rotation (a near-null mode: Newton and the count degrade). Call
        this between continuation runs: the pinned coordinate keeps its value
        at ``q``, so ``q`` stays a state of the problem.
        """
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        gauge = np.array(_axis_rotation_pin(x), dtype=np.int64)
        clamps = np.setdiff1d(self.fixed, self.gauge_dofs)
        self.gauge_dofs = gauge
        self.fixed = np.array(sorted(set(clamps.tolist()) | set(gauge.tolist())), dtype=np.int64)

    def pin_quality(self, q: np.ndarray) -> float:
        """How well the azimuth pin removes the rotation about the axis, in ``[0, 1]``.

        The rotation's component on the pinned coordinate over its largest
        nodal magnitude (1: the pin sits where the rotation moves the rod
        most, along the pinned coordinate; 0: no pin, or it does not see the
        rotation). Right after :meth:`repin` it is at least ``1/sqrt(2)`` (the larger
        of the two azimuthal components of the farthest node). 1 also for a straight
        rod, which has no rotation to remove.
        """
        mode = np.cross(AXIS, np.asarray(q, dtype=float).reshape(-1, 3))
        largest = float(np.max(np.linalg.norm(mode, axis=1)))
        if largest <= 1e-9 * self.rod.length:
            return 1.0
        if self.gauge_dofs.size == 0:
            return 0.0
        return float(np.max(np.abs(mode.ravel()[self.gauge_dofs]))) / largest

    def load_potential(self, q: np.ndarray) -> float:
        """``-F z``: the potential of the dead load, ``z`` the end-to-end distance."""
        return -self.tension * self.extension(q) * self.rod.length

    def energy(self, q: np.ndarray) -> float:
        """Total potential: elastic energy plus the load potential."""
        return self.elastic_energy(q) + self.load_potential(q)

    def gradient(self, q: np.ndarray) -> np.ndarray:
        g = super().gradient(q)
        g[2] += self.tension
        g[-1] -= self.tension
        return g

    def extension(self, q: np.ndarray) -> float:
        """End-to-end distance along the axis between the rod's ends (mid-edges), over L."""
        x = q.reshape(-1, 3)
        return (x[-1, 2] - x[0, 2] - self.rod.edge_length) / self.rod.length

    def writhe_local(self, q: np.ndarray) -> float:
        """Writhe with axial tails from the reference twist (no double sum): ``turns - Tw``."""
        return self.turns - self.twist(q)

    def admissible(self, q: np.ndarray) -> bool:
        """Whether the rod has not passed through itself at ``q`` (the continuation's
        per-step guard; ``refusal`` says why a state was refused); always True unless
        ``impenetrable`` (a phantom rod may cross itself).

        Without self-contact nothing stops a strand of the rod from crossing another
        within one continuation step, and a localised loop closing on itself does so
        (the loop of a thin rod, Coyne 1990: its crossing gap falls to zero as the
        torque does): between two accepted points the closest approach went 1.8 D,
        (crossing), 1.2 D, never below ``D`` at a point, and the contact onset was
        missed (L/D = 200, F L^2/A = 100, N = 202). A crossing changes the double-sum
        writhe of the rod closed by tails along the axis by 2, while ``turns - Tw``
        (:meth:`writhe_local`) is continuous: Fuller's closure ``Tw + Wr = turns``
        then fails by 2. The rod passing through a tail does the same, so the test is
        made only where every node lies strictly between the ends' planes, where no
        strand can have reached a tail, and against the closure of the last accepted
        state (which an earlier pass through a tail left off by 2)."""
        from supercoil.topology import writhe

        if not self.impenetrable:
            return True
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        z = x[:, 2]
        if not np.all((z[2:-2] > z[0]) & (z[2:-2] < z[-1])):
            return True
        if np.max(np.abs(x[:, :2])) <= 1e-9 * self.rod.length:
            return True  # straight: nothing to cross (and no double sum to pay)
        error = writhe(x, closure="axis", self_crossing="nan") - self.writhe_local(q)
        # against the accepted state's closure (an earlier pass through a tail leaves it
        # off by 2), computed once per accepted state
        accepted, before = self._accepted
        if before is None:
            before = 0.0
            if accepted is not None:
                before = writhe(accepted.reshape(-1, 3), closure="axis",
                                self_crossing="nan") - self.writhe_local(accepted)
                self._accepted = (accepted, before)
        if abs(error - before) <= CROSSING_CLOSURE:
            return True
        self.refusal = (f"the rod passed through itself (Fuller's closure Tw + Wr = turns "
                        f"changed by {error - before:.3g})")
        return False

    @property
    def holding(self) -> bool:
        """Whether the states are held on the half-turn symmetry (``mirror_hold``): the
        continuation then projects onto it (:meth:`held_part`, :meth:`held_direction`)."""
        return self.mirror_hold

    def held_part(self, q: np.ndarray, multipliers: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray] | None:
        """With ``mirror_hold``: ``(q, multipliers)`` projected onto the states symmetric
        under the half-turn (:func:`~supercoil.rod.mirror.symmetric_state`, in the gauge
        of the azimuth pin; the lengths' multipliers of exchanged edges averaged); None
        otherwise (the continuation's corrector then projects nothing)."""
        if not self.mirror_hold:
            return None
        return symmetric_state(q, self._pin()), self._even_multipliers(multipliers)

    def held_direction(self, q: np.ndarray, dq: np.ndarray, dmultipliers: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray] | None:
        """With ``mirror_hold``: the part of ``(dq, dmultipliers)`` at the symmetric state
        ``q`` that keeps it symmetric (:func:`~supercoil.rod.mirror.symmetric_direction`);
        None otherwise."""
        if not self.mirror_hold:
            return None
        return symmetric_direction(q, dq, self._pin()), self._even_multipliers(dmultipliers)

    def _pin(self) -> int | None:
        return int(self.gauge_dofs[0]) if self.gauge_dofs.size == 1 else None

    def _even_multipliers(self, multipliers: np.ndarray) -> np.ndarray:
        out = np.array(multipliers, dtype=float)
        pairs = mirror_pairs(self._constrained, self.rod.n_nodes)
        mean = 0.5 * (out[pairs[:, 0]] + out[pairs[:, 1]])
        out[pairs[:, 0]] = mean
        out[pairs[:, 1]] = mean
        return out

    def symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """Rotation of the centreline about the axis (empty when the rod is straight)."""
        x = q.reshape(-1, 3)
        mode = np.cross(AXIS, x).ravel()
        if np.max(np.abs(mode)) <= 1e-9 * self.rod.length:
            return np.zeros((0, q.size))
        return mode[None, :]


def _transported_directors(points: np.ndarray) -> np.ndarray:
    """Reference directors by space-parallel transport from the clamp director ``+x``."""
    from supercoil.geometry.curves import parallel_transport, unit

    t = unit(np.diff(points, axis=0))
    u = np.empty_like(t)
    u[0] = [1.0, 0.0, 0.0]
    for i in range(1, len(t)):
        u[i] = parallel_transport(u[i - 1 : i], t[i - 1 : i], t[i : i + 1])[0]
    return u


def _axis_rotation_pin(points: np.ndarray) -> list[int]:
    """The azimuthal coordinate of the node farthest from the axis (if any is off it).

    The first node within a relative ``1e-6`` of the largest distance: a state symmetric
    about the rod's middle has two such nodes at exactly the same distance, and round-off
    would pick either (a resumed run, whose states equal the uninterrupted run's to
    round-off, then pinned the other and followed the branch in another gauge)."""
    radius = np.linalg.norm(points[:, :2], axis=1)
    k = int(np.flatnonzero(radius >= (1.0 - 1e-6) * radius.max())[0])
    if radius[k] <= 1e-6 * np.ptp(points[:, 2]):
        return []
    azimuth = np.array([-points[k, 1], points[k, 0]]) / radius[k]
    return [3 * k + int(np.argmax(np.abs(azimuth)))]
