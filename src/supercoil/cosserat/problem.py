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

from supercoil.cosserat.centreline import CosseratCentreline
from supercoil.cosserat.rod import DOFS_PER_NODE, CosseratRod
from supercoil.cosserat.rotations import dexp, dexp_transpose_derivative, exp_so3, hat
from supercoil.errors import InputError
from supercoil.solvers.carried import Carried
from supercoil.solvers.csr_sum import block_csr
from supercoil.solvers.parameters import Parametrised
from supercoil.solvers.problem import HessianParts


class CosseratEnergy(CosseratCentreline, Parametrised, Carried):
    """Energy of a Cosserat rod under dead nodal forces, with some DOFs fixed.

    ``positions`` ``(n_nodes, 3)`` and ``rotations`` ``(n_nodes, 3, 3)``: the initial
    state, which is ``q0 = initial_state()`` (zero rotation coordinates). ``fixed``:
    indices into ``q`` held at their values (clamps). ``forces`` ``(n_nodes, 3)``:
    dead loads, potential ``-sum f_i . x_i``. Its centreline (the nodes' positions) is
    what self-contact sees (:mod:`supercoil.cosserat.centreline`).
    """

    n_constraints = 0
    # the carried state (supercoil.solvers.carried): the chart
    frame_attributes = (("reference_rotations", "reference_rotations"), ("centres", "centres"))
    # a result file keeps them with every point: at an accepted point they are its
    # sections' rotation matrices and rotation coordinates (accept), what a centreline
    # stored as the branch's state lacks (supercoil.io.branch_codec)
    frames_stored = True
    # accept re-bases the chart: the rotation coordinates, hence the Hessian and the
    # tangents written in them, change at first order in the step (the continuation
    # assembles the Hessian again at an accepted point)
    accept_moves_coordinates = True

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
        self._memo = None
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

    def elements_at(self, q: np.ndarray):
        """``(positions, rotations, ElementState)`` of the state ``q``. The last ones are
        kept, keyed by ``q``, the chart and the rod: a corrector asks for the gradient,
        the Hessian and the parameter derivative at one iterate."""
        q = np.asarray(q, dtype=float)
        memo = self._memo
        if memo is not None and memo[0] is self.rod and np.array_equal(memo[1], q) \
                and np.array_equal(memo[2], self.centres) \
                and np.array_equal(memo[3], self.reference_rotations):
            return memo[4]
        x, R = self.configuration(q)
        found = (x, R, self.rod.elements(x, R))
        self._memo = (self.rod, q.copy(), self.centres.copy(),
                      self.reference_rotations.copy(), found)
        return found

    # -- the protocol -------------------------------------------------------------------
    def energy(self, q: np.ndarray) -> float:
        x, _, state = self.elements_at(q)
        return float(np.sum(state.energy_density())) - float(np.sum(self.forces * x))

    def _nodal(self, local: np.ndarray) -> np.ndarray:
        """Element vectors ``(n_elements, 12)`` summed on the nodes, ``(n_nodes, 6)``."""
        return np.bincount(self.rod.element_dofs().ravel(), weights=local.ravel(),
                           minlength=self.n_dofs).reshape(-1, DOFS_PER_NODE)

    def gradient(self, q: np.ndarray) -> np.ndarray:
        g = self._nodal(self.elements_at(q)[2].local_gradient())
        g[:, :3] -= self.forces
        T = dexp(self._chart(q))
        g[:, 3:] = np.einsum("nji,nj->ni", T, g[:, 3:])
        return g.ravel()

    def hessian(self, q: np.ndarray) -> HessianParts:
        """Exact Hessian in the chart (module doc), symmetric and banded.

        One element pass serves the tangent and the moments; the rotation blocks of
        ``J`` act on the elements' spin rows and columns only, and each node's block
        ``d(T^T m)/dphi`` is added to an element that holds the node before the one
        sparse assembly."""
        rod = self.rod
        state = self.elements_at(q)[2]
        phi = self._chart(q)
        local = state.local_hessian()
        if np.any(phi):
            T = dexp(phi)
            nodes = rod.element_nodes()
            Te = np.zeros((rod.n_elements, 6, 6))
            Te[:, :3, :3], Te[:, 3:, 3:] = T[nodes[:, 0]], T[nodes[:, 1]]
            spins = np.r_[3:6, 9:12]
            local[:, spins, :] = np.swapaxes(Te, 1, 2) @ local[:, spins, :]
            local[:, :, spins] = local[:, :, spins] @ Te
            moments = self._nodal(state.local_gradient())[:, 3:]
            blocks = dexp_transpose_derivative(phi, moments) \
                - 0.5 * np.swapaxes(T, 1, 2) @ hat(moments) @ T
            blocks = 0.5 * (blocks + np.swapaxes(blocks, 1, 2))
            # node i is node a of element i (b of the last element for an open rod's end)
            local[:, 3:6, 3:6] += blocks[:rod.n_elements]
            if not rod.closed:
                local[-1, 9:12, 9:12] += blocks[-1]
            local = 0.5 * (local + np.swapaxes(local, 1, 2))
        return HessianParts(block_csr(rod.element_dofs(), local, self.n_dofs))

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
