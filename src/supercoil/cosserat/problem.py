"""A Cosserat rod as a :class:`~supercoil.solvers.problem.ConstrainedEnergy`.

The numerical layers add increments to a flat vector (``q + dq``), so the rotations
are carried by exponential coordinates in an updated-Lagrangian chart: node ``i``
owns ``q[6i:6i+3] = x_i`` and ``q[6i+3:6i+6] = theta_i`` with

    R_i = exp(hat(theta_i - c_i)) R0_i,

``R0_i`` a reference rotation and ``c_i`` the chart's centre. :meth:`accept` re-bases
the chart at the accepted state, ``R0_i <- R_i(q)``, ``c_i <- theta_i(q)``: the caller's
``q`` is left as it is (it is the caller's vector, so it cannot be zeroed), and the
state it describes is unchanged; the last accepted state also keeps its rotations
exactly in the new chart (``exp(0) R0``), older ones to second order in the step.
The rotation coordinates thus accumulate along a path instead of being reset.

In this chart (``phi = theta - c``, ``T = dexp(phi)``, ``m`` the spatial moments):

* gradient ``[f_i, T_i^T m_i]``;
* Hessian ``J^T K_c J + blockdiag(d(T^T m)/dphi)`` with ``J = blockdiag(I, T_i)``,
  the exact second derivative, symmetric. At the chart's centre (every accepted
  state) ``T = I``, ``d(T^T m)/dphi = hat(m) / 2``, and it is the symmetrised tangent
  ``H0``: Newton on this problem is Newton with the symmetrised tangent
  and a multiplicative update (Simo & Vu-Quoc 1986), a step later re-based.

The lumped metric (``mass``) is ``h`` per position coordinate and ``h A / EA`` (the
section's squared radius of gyration times ``h``) per rotation coordinate (half
at the ends of an open rod), so that eigenvalues converge under refinement.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.cosserat.rod import DOFS_PER_NODE, CosseratRod, node_rotation_blocks
from supercoil.cosserat.rotations import dexp, dexp_transpose_derivative, exp_so3, hat
from supercoil.errors import InputError
from supercoil.solvers.csr_sum import block_csr
from supercoil.solvers.problem import HessianParts


class CosseratEnergy:
    """Energy of a Cosserat rod under dead nodal forces, with some DOFs fixed.

    ``positions`` ``(n_nodes, 3)`` and ``rotations`` ``(n_nodes, 3, 3)``: the initial
    state, which is ``q0 = initial_state()`` (zero rotation coordinates). ``fixed``:
    indices into ``q`` held at their values (clamps). ``forces`` ``(n_nodes, 3)``:
    dead loads, potential ``-sum f_i . x_i``.
    """

    n_constraints = 0

    def __init__(self, rod: CosseratRod, positions: np.ndarray, rotations: np.ndarray,
                 fixed=(), forces: np.ndarray | None = None):
        rod.elements(positions, rotations)  # validates the shapes
        rotations = np.asarray(rotations, dtype=float)
        if not np.allclose(rotations @ np.swapaxes(rotations, 1, 2), np.eye(3), atol=1e-10):
            raise InputError("rotations must be rotation matrices (R R^T = I)")
        self.rod = rod
        self.n_dofs = rod.n_dofs
        self._positions0 = np.array(positions, dtype=float)
        self.reference_rotations = rotations.copy()
        self.centres = np.zeros((rod.n_nodes, 3))
        fixed = np.unique(np.asarray(fixed, dtype=np.int64))
        if fixed.size and (fixed.min() < 0 or fixed.max() >= self.n_dofs):
            raise InputError(f"fixed DOFs must lie in [0, {self.n_dofs}), got {fixed.min()}, "
                             f"{fixed.max()}")
        self.fixed = fixed
        self.forces = (np.zeros((rod.n_nodes, 3)) if forces is None
                       else np.array(forces, dtype=float).reshape(rod.n_nodes, 3))
        h = rod.element_length
        weights = np.full(rod.n_nodes, h)
        if not rod.closed:
            weights[[0, -1]] = h / 2
        radius2 = rod.bending_stiffness / rod.stretch_stiffness
        self.mass = np.repeat(weights, DOFS_PER_NODE) * np.tile(
            [1.0, 1.0, 1.0, radius2, radius2, radius2], rod.n_nodes)

    # -- the chart ----------------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        q = np.zeros(self.n_dofs)
        q.reshape(-1, 6)[:, :3] = self._positions0
        return q

    def configuration(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(positions (n_nodes, 3), rotations (n_nodes, 3, 3))`` of the state ``q``."""
        nodes = np.asarray(q, dtype=float).reshape(-1, DOFS_PER_NODE)
        return nodes[:, :3].copy(), exp_so3(nodes[:, 3:] - self.centres) @ \
            self.reference_rotations

    def state(self, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
        """A ``q`` that describes ``(positions, rotations)`` in the current chart: the
        chart is re-based there (``R0 <- rotations``, ``c <- 0``), as after an accept."""
        self.reference_rotations = np.array(rotations, dtype=float)
        self.centres = np.zeros((self.rod.n_nodes, 3))
        q = np.zeros(self.n_dofs)
        q.reshape(-1, 6)[:, :3] = positions
        return q

    def accept(self, q: np.ndarray) -> None:
        """Re-base the chart at ``q`` (module doc): ``R0 <- R(q)``, ``c <- theta(q)``."""
        nodes = np.asarray(q, dtype=float).reshape(-1, DOFS_PER_NODE)
        self.reference_rotations = self.configuration(q)[1]
        self.centres = nodes[:, 3:].copy()

    def _chart(self, q):
        nodes = np.asarray(q, dtype=float).reshape(-1, DOFS_PER_NODE)
        return nodes[:, 3:] - self.centres

    # -- the protocol -------------------------------------------------------------------
    def energy(self, q: np.ndarray) -> float:
        x, R = self.configuration(q)
        return self.rod.energy(x, R) - float(np.sum(self.forces * x))

    def _spatial_gradient(self, x, R) -> np.ndarray:
        g = self.rod.gradient(x, R).reshape(-1, DOFS_PER_NODE)
        g[:, :3] -= self.forces
        return g

    def gradient(self, q: np.ndarray) -> np.ndarray:
        x, R = self.configuration(q)
        g = self._spatial_gradient(x, R)
        T = dexp(self._chart(q))
        g[:, 3:] = np.einsum("nji,nj->ni", T, g[:, 3:])
        return g.ravel()

    def hessian(self, q: np.ndarray) -> HessianParts:
        """Exact Hessian in the chart (module doc), symmetric and banded."""
        x, R = self.configuration(q)
        rod = self.rod
        state = rod.elements(x, R)
        phi = self._chart(q)
        T = dexp(phi)
        local = state.local_hessian()
        J = np.zeros((rod.n_nodes, 6, 6))
        J[:, :3, :3] = np.eye(3)
        J[:, 3:, 3:] = T
        Je = np.zeros((rod.n_elements, 12, 12))
        nodes = rod.element_nodes()
        Je[:, :6, :6], Je[:, 6:, 6:] = J[nodes[:, 0]], J[nodes[:, 1]]
        local = np.swapaxes(Je, 1, 2) @ local @ Je
        H = block_csr(rod.element_dofs(), 0.5 * (local + np.swapaxes(local, 1, 2)), self.n_dofs)
        if np.any(phi):
            m = self._spatial_gradient(x, R)[:, 3:]
            blocks = dexp_transpose_derivative(phi, m) \
                - 0.5 * np.swapaxes(T, 1, 2) @ hat(m) @ T
            H = (H + node_rotation_blocks(0.5 * (blocks + np.swapaxes(blocks, 1, 2)))).tocsr()
        return HessianParts(H)

    def constraints(self, q: np.ndarray) -> np.ndarray:
        return np.zeros(0)

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((0, self.n_dofs))

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((self.n_dofs, self.n_dofs))

    # -- outputs ------------------------------------------------------------------------
    def strains(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Gamma, K)`` per element of the state ``q`` (:meth:`CosseratRod.strains`)."""
        return self.rod.strains(*self.configuration(q))

    def max_stretch_strain(self, q: np.ndarray) -> float:
        return float(np.max(np.abs(self.strains(q)[0][:, 2])))

    def max_shear_strain(self, q: np.ndarray) -> float:
        return float(np.max(np.linalg.norm(self.strains(q)[0][:, :2], axis=1)))
