"""The sliding of a localised structure (a loop, a plectoneme) along a clamped rod.

``x(s) -> x(s - a) + a e_z`` moves a structure along a rod whose tails are straight
along the axis: an approximate symmetry of the clamped rod while the tails are straight
(:meth:`StructureSliding.near_symmetry_modes`), no symmetry once the structure reaches
towards the clamps (:meth:`StructureSliding.far_sliding_modes`), where the discrete
contact's ripple can still make it and the other motions of the material along the
centreline (:meth:`StructureSliding.tangent_rows`) stiff
(:mod:`supercoil.stability.sliding_count`). :class:`StructureSliding` gives
:class:`~supercoil.rod.open.ClampedRodEnergy` these, the phase row's anchor
(:meth:`StructureSliding.phase_offset`) and the generator itself.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.rod.mirror import mirror_offset

# the sliding of a localised structure is an approximate symmetry when the rod's outer
# SLIDING_ENDS of nodes at either end move by at most SLIDING_TAIL of its largest move
# (StructureSliding.near_symmetry_modes)
SLIDING_ENDS = 0.05
SLIDING_TAIL = 1e-4
SLIDING_NODES = 160  # ... at up to this many nodes; beyond, sliding_threshold


# the most a phase row's anchor moves a structure towards the rod's middle per step, in
# segments (StructureSliding.phase_offset)
RECENTRE = 0.1


def sliding_threshold(n_nodes: int) -> float:
    """The tail ratio below which the sliding of a localised structure is an approximate
    symmetry of a clamped rod of ``n_nodes`` (:meth:`StructureSliding.near_symmetry_modes`):
    ``SLIDING_TAIL``, times ``(n_nodes / SLIDING_NODES)^2`` on finer meshes. Newton moves
    along the sliding by the residual's round-off floor over the sliding's stiffness;
    the floor grows like ``N^3`` (``eps |H| |q|``, ``|H| ~ A / h^3``), the stiffness
    (mass-weighted eigenvalue times the lumped mass ``h``) like ``tail^2 h``, so the
    tail ratio at which the two meet grows like ``N^2``. Measured at L/D = 200,
    lambda = 20, N = 404: the corrector diverged at a tail ratio of 2.9e-4 (sliding
    eigenvalue 1e-2, floor 1e-6), above the threshold of N = 160 and below this one's
    (6.4e-4)."""
    return SLIDING_TAIL * max(1.0, (n_nodes / SLIDING_NODES) ** 2)


class StructureSliding:
    """The sliding of a localised structure along a clamped rod, for
    :class:`~supercoil.rod.open.ClampedRodEnergy` (its ``rod``, ``mass``,
    ``sliding_tail`` and ``mirror_hold``)."""

    def near_symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """Sliding a localised structure along the rod, ``(1, n_dofs)``, where it is an
        approximate symmetry; ``(0, n_dofs)`` elsewhere.

        ``x(s) -> x(s - a) + a e_z`` moves a loop or a plectoneme along a rod whose
        tails are straight along the axis, the material passing from one tail into
        the structure and out of it into the other; at the nodes its generator is
        ``g_i = (x_{i+1} - x_{i-1}) / 2 - h e_z`` (zero on straight tails and at the
        clamps). Its energy is that of the structure's interaction with the clamps,
        which decays like ``exp(-lambda s)`` along the tails, plus the discretisation's
        ripple, which a finer mesh changes: below ``sliding_tail`` (the largest
        ``|g_i|`` over the outer ``SLIDING_ENDS`` of the nodes at either end, over the
        largest overall) both are below what the computed eigenvalue resolves
        (measured at L/D = 100, F L^2/A = 1200, N = 160 along the localised loop:
        tail ratio 8e-5 with the sliding eigenvalue 4e-3, 1e-5 with 6e-5, against a
        next eigenvalue of 1.3e4), and the mode is returned; above it the sliding
        costs energy that the mesh resolves (the structure reaches the clamps) and
        it is not a symmetry at all. ``sliding_tail`` is :func:`sliding_threshold` by default;
        None: never (docs/continuation.md, "Sliding of a localised structure", for the
        rod in self-contact).
        """
        g, tail = self.sliding(q)
        if self.sliding_tail is None or tail > self.sliding_tail:
            return np.zeros((0, np.size(q)))
        return self.axial_free(g)[None, :]

    def far_sliding_modes(self, q: np.ndarray) -> np.ndarray:
        """The sliding ``(1, n_dofs)`` (as :meth:`near_symmetry_modes`) where it is no
        approximate symmetry, its tail ratio above ``sliding_tail`` (the structure
        reaches towards the clamps); ``(0, n_dofs)`` where it is one, on a straight rod
        and with ``sliding_tail`` None. In contact its discrete eigenvalue can still be the
        contact's ripple (:mod:`supercoil.stability.sliding_count`)."""
        g, tail = self.sliding(q)
        if self.sliding_tail is None or not np.isfinite(tail) or tail <= self.sliding_tail:
            return np.zeros((0, np.size(q)))
        return self.axial_free(g)[None, :]

    def tangent_rows(self, q: np.ndarray) -> sp.csr_matrix:
        """``(n_nodes, n_dofs)``: row ``i`` the unit tangent at node ``i`` (central
        differences, one-sided at the ends) on that node's DOFs, so that ``P v`` is the
        displacement ``v`` along the centreline, node by node: a mode mostly along it
        moves material along its own curve, which the continuum's inextensible rod
        bends only by ``u' / kappa`` and the discrete contact's ripple makes stiff
        (:mod:`supercoil.stability.sliding_count`)."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        n = x.shape[0]
        t = np.empty_like(x)
        t[1:-1] = x[2:] - x[:-2]
        t[0], t[-1] = x[1] - x[0], x[-1] - x[-2]
        t /= np.linalg.norm(t, axis=1)[:, None]
        rows = np.repeat(np.arange(n), 3)
        return sp.csr_matrix((t.ravel(), (rows, np.arange(3 * n))), shape=(n, 3 * n))

    def phase_offset(self, q: np.ndarray) -> np.ndarray:
        """The displacement along the sliding that carries the structure's centre towards
        the rod's middle, by at most ``RECENTRE`` segments (zeros where the sliding is no
        approximate symmetry): where the phase row of the sliding is anchored
        (``ContinuationOptions.midpoint_phase``).

        The centre is the mean arclength of the nodes weighted by ``|g_i|^2``, which the
        rotation by pi about an axis across the middle maps to its mirror image: a
        structure symmetric under it (a loop off the straight rod's symmetric critical
        mode) is centred, and no force acts along its sliding there; elsewhere the
        clamps pull it by ``exp(-lambda d)`` and the ripple of the discretisation, forces
        below what a step resolves, so that a row anchored at the last point held the
        structure wherever round-off had moved it (measured at L/D = 100, lambda = 80,
        N = 204: moved before the row was needed, the loop's radii lost their mirror
        symmetry by 4e-3, and the row's force grew to 1.3e-6 at the contact).

        With ``mirror_hold`` the anchor is the state's symmetric part instead
        (:func:`~supercoil.rod.mirror.mirror_offset`, not bounded): the row then takes
        out, at every step, the part of the sliding that round-off moved the structure
        off the symmetric position, and holds no force on a symmetric state. In
        contact the discrete contact's ripple makes the sliding stiff, of either sign
        (eigenvalues of -4e4 to 3e3 along the plectoneme at L/D = 200, lambda = 20,
        N = 404), and the centre's pull, at most a tenth of a segment a step, fed the
        ripple's force back: at L/D = 500, lambda = 10, N = 502 the structure's mirror
        asymmetry grew threefold a step from 8e-7 D to 0.06 D and the row held 4e-4."""
        g, tail = self.sliding(q)
        if self.sliding_tail is None or tail > self.sliding_tail:
            return np.zeros(np.size(q))
        if self.mirror_hold:
            return mirror_offset(q)
        h = self.rod.edge_length
        weight = np.sum(g.reshape(-1, 3) ** 2, axis=1)
        s = (np.arange(weight.size) - 0.5) * h
        shift = 0.5 * self.rod.length - float(weight @ s) / float(weight.sum())
        shift = float(np.clip(shift, -RECENTRE * h, RECENTRE * h))
        return -(shift / h) * g  # x(s) -> x(s - a) + a e_z is -(a / h) g to first order

    def axial_free(self, g: np.ndarray) -> np.ndarray:
        """``g`` less its M-orthogonal projection on the uniform axial translation.

        The turned end moves along the axis as the turns change (under a load), so the
        tangent of a branch symmetric about the rod's middle (a centred loop: the
        rotation by pi about an axis across the middle maps it onto itself) has the odd
        part ``u/2`` along that translation, ``u`` the end's axial speed; the sliding,
        odd too, is not M-orthogonal to it (its axial part is ``(t_z - 1) h`` in the
        structure). As a phase row the bare sliding then refused the symmetric branch
        and moved the structure along it at first order: measured on the localised
        loop at L/D = 100, F L^2/A = 1600, N = 102, the row's product with the
        symmetric tangent was 0.028 of their norms, on the way to its contact the
        loop's radii lost their mirror symmetry by 0.68 of the largest, and the row
        held a force of 2e-5 there; without the translation the product is 4e-7 of
        the norms."""
        g = np.array(g, dtype=float).reshape(-1, 3)
        m = np.asarray(self.mass, dtype=float).reshape(-1, 3)[:, 2]
        g[:, 2] -= float(m @ g[:, 2]) / float(m.sum())
        return g.ravel()

    def sliding(self, q: np.ndarray) -> tuple[np.ndarray, float]:
        """The sliding generator ``g`` (``(n_dofs,)``, :meth:`near_symmetry_modes`) and
        its tail ratio: the largest ``|g_i|`` over the outer ``SLIDING_ENDS`` of the
        nodes at either end over the largest overall (``inf`` for a straight rod, which
        has no structure to slide)."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        n = x.shape[0]
        g = np.zeros_like(x)
        g[1:-1] = 0.5 * (x[2:] - x[:-2])
        g[1:-1, 2] -= self.rod.edge_length
        g[[0, 1, n - 2, n - 1]] = 0.0
        size = np.linalg.norm(g, axis=1)
        largest = float(size.max())
        if largest <= 1e-6 * self.rod.edge_length:
            return g.ravel(), float("inf")
        ends = max(3, int(np.ceil(SLIDING_ENDS * n)))
        return g.ravel(), float(max(size[:ends].max(), size[-ends:].max())) / largest
