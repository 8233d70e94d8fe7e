"""A special Cosserat (Simo-Reissner) rod discretised by two-node elements.

The configuration is a pair ``(positions, rotations)``: ``(n_nodes, 3)`` centreline
points and ``(n_nodes, 3, 3)`` rotations whose columns are the directors
``d_1, d_2, d_3`` (``d_3`` the unsheared tangent). An open rod has
``n_elements + 1`` nodes; a closed one (a ring) ``n_elements``, its last element
joining the last node back to node 0 (nodes and rotations periodic). The configuration space is
``(R^3 x SO(3))^n``, not a vector space: a tangent vector is ``v`` ``(6 n_nodes,)``,
node ``i`` owning ``v[6i:6i+3]`` (a displacement) and ``v[6i+3:6i+6]`` (a spatial
spin ``w``), and :func:`retract` moves along it, ``x + dx``, ``exp(hat(w)) R``.

Gradient and tangents are expressed in that tangent space (see
:mod:`supercoil.cosserat.element`): ``gradient`` holds nodal forces and spatial
moments, ``consistent_tangent`` its linearisation (nonsymmetric away from
equilibrium), ``symmetric_tangent`` the symmetric part, which is the Hessian of
the energy in exponential coordinates centred at the configuration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil.cosserat.element import ElementState
from supercoil.cosserat.rotations import exp_so3, hat
from supercoil.errors import InputError
from supercoil.solvers.csr_sum import block_csr

DOFS_PER_NODE = 6


@dataclass(frozen=True)
class CosseratRod:
    """Material and discretisation of an intrinsically straight, isotropic Cosserat rod.

    ``n_elements`` two-node elements of rest length ``h = length / n_elements``;
    ``bending_stiffness`` A (both principal axes), ``twist_stiffness`` C,
    ``shear_stiffness`` GA (both shear directions) and ``stretch_stiffness`` EA.
    As GA and EA grow the rod tends to the inextensible, unshearable Kirchhoff rod.
    ``intrinsic_twist`` ``tau0``: the twist at rest (curvature at rest ``(0, 0, tau0)``;
    the rod is straight at rest). ``closed``: a ring of ``n_elements`` nodes.
    """

    n_elements: int
    length: float = 1.0
    bending_stiffness: float = 1.0
    twist_stiffness: float = 1.0
    shear_stiffness: float = 1e4
    stretch_stiffness: float = 1e4
    intrinsic_twist: float = 0.0
    closed: bool = False

    def __post_init__(self) -> None:
        smallest = 3 if self.closed else 2
        if not isinstance(self.n_elements, (int, np.integer)) or self.n_elements < smallest:
            raise InputError(f"n_elements must be an integer >= {smallest} for "
                             f"{'a closed' if self.closed else 'an open'} rod, got "
                             f"{self.n_elements!r}")
        if not (isinstance(self.intrinsic_twist, (int, float, np.floating, np.integer))
                and np.isfinite(self.intrinsic_twist)):
            raise InputError(f"intrinsic_twist must be a finite number, got "
                             f"{self.intrinsic_twist!r}")
        for name in ("length", "bending_stiffness", "twist_stiffness", "shear_stiffness",
                     "stretch_stiffness"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.floating, np.integer))
                    and np.isfinite(value) and value > 0):
                raise InputError(f"{name} must be a positive finite number, got {value!r}")

    @classmethod
    def circular_section(cls, n_elements: int, slenderness: float, poisson_ratio: float = 0.5,
                         length: float = 1.0, bending_stiffness: float = 1.0) -> CosseratRod:
        """A solid circular section of radius ``r = length / slenderness``.

        With ``A = E pi r^4 / 4``: ``EA = 4 A / r^2``, ``C = A / (1 + nu)`` and
        ``GA = kappa E pi r^2 / (2 (1 + nu))`` with Cowper's (1966) shear coefficient
        ``kappa = 6 (1 + nu) / (7 + 6 nu)``, i.e. ``GA = 12 A / ((7 + 6 nu) r^2)``.
        """
        if not (np.isfinite(slenderness) and slenderness > 0):
            raise InputError(f"slenderness must be a positive finite number, got {slenderness!r}")
        if not (np.isfinite(poisson_ratio) and -1 < poisson_ratio <= 0.5):
            raise InputError(f"poisson_ratio must lie in (-1, 0.5], got {poisson_ratio!r}")
        r2 = (length / slenderness) ** 2
        A = float(bending_stiffness)
        return cls(n_elements, length, A, A / (1 + poisson_ratio),
                   12 * A / ((7 + 6 * poisson_ratio) * r2), 4 * A / r2)

    @property
    def n_nodes(self) -> int:
        return self.n_elements if self.closed else self.n_elements + 1

    @property
    def n_dofs(self) -> int:
        return DOFS_PER_NODE * self.n_nodes

    @property
    def element_length(self) -> float:
        return self.length / self.n_elements

    @property
    def edge_length(self) -> float:
        """The rest length of the centreline's segments: :attr:`element_length`."""
        return self.element_length

    @property
    def bending_moduli(self) -> np.ndarray:
        """``C_K = diag(A, A, C)`` as ``(3,)``."""
        return np.array([self.bending_stiffness, self.bending_stiffness, self.twist_stiffness])

    @property
    def shear_moduli(self) -> np.ndarray:
        """``C_G = diag(GA, GA, EA)`` as ``(3,)``."""
        return np.array([self.shear_stiffness, self.shear_stiffness, self.stretch_stiffness])

    def elements(self, positions: np.ndarray, rotations: np.ndarray) -> ElementState:
        positions = np.asarray(positions, dtype=float)
        rotations = np.asarray(rotations, dtype=float)
        n = self.n_nodes
        if positions.shape != (n, 3):
            raise InputError(f"positions must have shape ({n}, 3), got {positions.shape}")
        if rotations.shape != (n, 3, 3):
            raise InputError(f"rotations must have shape ({n}, 3, 3), got {rotations.shape}")
        if self.closed:  # the last element joins the last node to node 0
            positions = np.concatenate([positions, positions[:1]])
            rotations = np.concatenate([rotations, rotations[:1]])
        return ElementState(positions, rotations, self.element_length, self.bending_moduli,
                            self.shear_moduli, self.intrinsic_twist)

    def element_nodes(self) -> np.ndarray:
        """``(n_elements, 2)``: the nodes ``a, b`` of each element (``b = 0`` closes a ring)."""
        a = np.arange(self.n_elements)
        return np.stack([a, (a + 1) % self.n_nodes], axis=1)

    def element_dofs(self) -> np.ndarray:
        """``(n_elements, 12)`` tangent-space indices of each element's two nodes."""
        nodes = self.element_nodes()
        return (DOFS_PER_NODE * nodes[:, :, None] + np.arange(DOFS_PER_NODE)).reshape(-1, 12)

    # -- energy and derivatives on the manifold -----------------------------------------
    def energy(self, positions: np.ndarray, rotations: np.ndarray) -> float:
        return float(np.sum(self.elements(positions, rotations).energy_density()))

    def gradient(self, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
        """Nodal forces and spatial moments ``(6 n_nodes,)``: ``dE = gradient . v``."""
        local = self.elements(positions, rotations).local_gradient()
        return np.bincount(self.element_dofs().ravel(), weights=local.ravel(),
                           minlength=self.n_dofs)

    def symmetric_tangent(self, positions: np.ndarray, rotations: np.ndarray) -> sp.csr_matrix:
        """``H0`` ``(6n, 6n)``, symmetric, banded (bandwidth 11)."""
        local = self.elements(positions, rotations).local_hessian()
        return block_csr(self.element_dofs(), local, self.n_dofs)

    def consistent_tangent(self, positions: np.ndarray, rotations: np.ndarray) -> sp.csr_matrix:
        """``K_c = H0 - blockdiag(hat(m_i)) / 2``: the linearisation of :meth:`gradient`
        under :func:`retract` (nonsymmetric unless the moments ``m_i`` vanish)."""
        state = self.elements(positions, rotations)
        local = state.local_gradient()
        moments = np.bincount(self.element_dofs().ravel(), weights=local.ravel(),
                              minlength=self.n_dofs).reshape(-1, 6)[:, 3:]
        H0 = block_csr(self.element_dofs(), state.local_hessian(), self.n_dofs)
        return (H0 - 0.5 * node_rotation_blocks(hat(moments))).tocsr()

    def strains(self, positions: np.ndarray, rotations: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """``(Gamma, K)`` per element, each ``(n_elements, 3)``, in the material frame:
        ``Gamma = (shear_1, shear_2, stretch)``, ``K = (kappa_1, kappa_2, twist)``."""
        state = self.elements(positions, rotations)
        return state.shear.copy(), state.curvature.copy()

    def straight(self, twist_turns: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The unstressed straight rod along ``+z`` from the origin (``twist_turns = 0``),
        or one twisted uniformly by ``twist_turns`` turns about its axis (open rods)."""
        if self.closed:
            raise InputError("a closed rod has no straight state")
        s = np.linspace(0.0, self.length, self.n_nodes)
        positions = np.stack([np.zeros_like(s), np.zeros_like(s), s], axis=1)
        angles = 2 * np.pi * twist_turns * s / self.length
        rotations = exp_so3(angles[:, None] * np.array([0.0, 0.0, 1.0]))
        return positions, rotations


def node_rotation_blocks(blocks: np.ndarray) -> sp.csr_matrix:
    """Block-diagonal matrix with ``blocks[i]`` ``(3, 3)`` on node ``i``'s spin DOFs."""
    n = len(blocks)
    rows = DOFS_PER_NODE * np.arange(n)[:, None] + 3 + np.arange(3)[None, :]
    return block_csr(rows, np.asarray(blocks, dtype=float), DOFS_PER_NODE * n)


def retract(positions: np.ndarray, rotations: np.ndarray, v: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """Move along the tangent vector ``v`` ``(6 n_nodes,)``: ``x + dx``, ``exp(hat(w)) R``."""
    v = np.asarray(v, dtype=float).reshape(-1, DOFS_PER_NODE)
    return positions + v[:, :3], exp_so3(v[:, 3:]) @ rotations
