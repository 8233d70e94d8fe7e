"""Closed discrete Kirchhoff rod at fixed excess link (isotropic, inextensible).

Model (Bergou et al. 2008, 2010, with the twist reduced to one scalar):

* centreline: a closed polygon of ``n_nodes`` vertices, edges of fixed rest
  length ``h = L / n_nodes`` (inextensibility as equality constraints
  ``c_j = (|e_j|^2 - h^2) / (2h) = 0``; their multipliers are edge tensions);
* bending: ``sum_i A k_i^2 / (2h)`` (see :mod:`supercoil.rod.kernels`);
* twist: for an isotropic rod the excess twist density is uniform at
  equilibrium, so the material angles can be minimised out exactly and the
  twist energy is ``E_t = 2 pi^2 C Tw^2 / L`` with ``Tw = dLk - Wr``
  (Coleman & Swigon eq. 3-5). The writhe is never evaluated as a double sum
  here: ``Wr = Lk_u - Phi / 2pi`` where ``Phi`` is the total reference twist
  (holonomy of discrete parallel transport, a sum of local terms) and ``Lk_u``
  the integer linking number of the reference ribbon, fixed at set-up and kept
  by time-parallel transport of the reference directors. Hence the Hessian is
  banded plus one rank-one term ``k g g^T`` with ``g = grad(Phi) / 2pi``.

Minimising out the material angles is a Schur complement with a positive
definite block, so the number of negative eigenvalues (stability) is the same
as for the full model with material angles.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.geometry.curves import edges, parallel_transport, perpendicular, signed_angle, unit
from supercoil.rod import kernels
from supercoil.rod.assembly import StencilPattern
from supercoil.solvers.csr import csr_from_arrays
from supercoil.solvers.problem import HessianParts


@dataclass(frozen=True)
class Rod:
    """Material and discretisation of an isotropic Kirchhoff rod.

    ``bending_stiffness`` A, ``twist_stiffness`` C, ``length`` L (A = L = 1 in
    the nondimensional default), ``n_nodes`` vertices, ``curvature`` form,
    ``closed`` (a ring has ``n_nodes`` edges, an open rod ``n_nodes - 1``).
    """

    n_nodes: int
    twist_stiffness: float = 1.0
    bending_stiffness: float = 1.0
    length: float = 1.0
    curvature: str = "angle"
    closed: bool = True

    def __post_init__(self) -> None:
        for name in ("twist_stiffness", "bending_stiffness", "length"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
        if int(self.n_nodes) != self.n_nodes or self.n_nodes < 8:
            raise ValueError(f"n_nodes must be an integer >= 8, got {self.n_nodes!r}")
        if self.curvature not in kernels.CURVATURE_FORMS:
            raise ValueError(
                f"curvature must be one of {kernels.CURVATURE_FORMS}, got {self.curvature!r}"
            )

    @property
    def twist_ratio(self) -> float:
        return self.twist_stiffness / self.bending_stiffness

    @property
    def n_edges(self) -> int:
        return self.n_nodes if self.closed else self.n_nodes - 1

    @property
    def edge_length(self) -> float:
        """Rest length ``h`` of every edge.

        A ring has ``L / n_nodes``. An open rod has ``L / (n_nodes - 2)``: its
        ends are the midpoints of the first and last edges, where the clamps
        act (with the clamps at the end nodes instead, the clamped rod would be
        ``h`` too short and its buckling load first-order accurate — measured).
        """
        return self.length / (self.n_nodes if self.closed else self.n_nodes - 2)


def initial_reference_frames(points: np.ndarray) -> np.ndarray:
    """Reference directors ``(n_edges, 3)`` of a closed polygon with equal reference twists.

    Space-parallel transport from edge 0 around the polygon, then each director
    is turned back by its share of the holonomy, so that every vertex carries
    the same reference twist (no single vertex holds the whole mismatch).
    """
    t = unit(edges(points, closed=True))
    n = len(t)
    u = np.empty_like(t)
    u[0] = perpendicular(t[:1])[0]
    for i in range(1, n):
        u[i] = parallel_transport(u[i - 1 : i], t[i - 1 : i], t[i : i + 1])[0]
    closing = parallel_transport(u[-1:], t[-1:], t[:1])[0]
    mismatch = float(signed_angle(closing[None], u[:1], t[:1])[0])  # total reference twist
    # Rotate u_i by -i * mismatch / n about t_i: each vertex then twists by mismatch / n.
    angle = -np.arange(n) * mismatch / n
    v = np.cross(t, u)
    return np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * v


@njit()
def _curvature_values(multipliers, h, first, second):
    """Entries of :meth:`RodEnergy.constraint_hessian` in its pattern's order: the COO
    terms ``data = [w, w, -w, -w]`` (``w`` the multipliers over ``h``, each three
    times) at ``first``, plus those at ``second`` where that is not -1."""
    block = 3 * multipliers.size  # terms of each of the four blocks of data
    out = np.empty(first.size)
    for k in range(first.size):
        d = first[k]
        value = multipliers[(d % block) // 3] / h
        if d >= 2 * block:
            value = -value
        e = second[k]
        if e >= 0:
            other = multipliers[(e % block) // 3] / h
            if e >= 2 * block:
                other = -other
            value = value + other
        out[k] = value
    return out


def _key(q: np.ndarray) -> bytes:
    """The exact value of ``q`` as a dictionary key (its float64 bytes)."""
    return np.ascontiguousarray(q, dtype=np.float64).tobytes()


class RodEnergy(abc.ABC):
    """Shared machinery of the discrete rods: stencils, frames, constraints.

    Subclasses set ``self.rod``, the vertex stencils ``vertex_nodes``
    ``(n_vertices, 3)``, the edges ``edge_nodes`` ``(n_edges, 2)``, the
    previous/next edge of each vertex, and :meth:`twist_offset` (turns).
    The excess twist is ``Tw = twist_offset + Phi / 2pi`` and its energy
    ``2 pi^2 C Tw^2 / L``.
    """

    def _setup(self, rod: Rod, points: np.ndarray, vertex_nodes: np.ndarray,
               edge_nodes: np.ndarray, prev_edge: np.ndarray, next_edge: np.ndarray,
               reference_directors: np.ndarray) -> None:
        self.rod = rod
        n = len(points)
        self.n_dofs = 3 * n
        self.edge_nodes = np.asarray(edge_nodes, dtype=np.int64)
        self.set_constrained_edges(np.arange(len(self.edge_nodes)))
        self._pattern = StencilPattern(vertex_nodes, 3 * n)
        self._prev_edge = np.asarray(prev_edge, dtype=np.int64)
        self._next_edge = np.asarray(next_edge, dtype=np.int64)
        self._bend_weight = np.full(len(vertex_nodes), rod.bending_stiffness / (2 * rod.edge_length))
        self._curvature = rod.curvature
        self._bending = kernels.bending_kernels(rod.curvature)
        self._twist_coefficient = 4.0 * np.pi**2 * rod.twist_stiffness / rod.length
        self._local_hessians: np.ndarray | None = None  # work array of hessian()
        self.mass = np.full(3 * n, rod.edge_length)
        self._set_frames(unit(self._edge_vectors(points.ravel())),
                         np.asarray(reference_directors, dtype=float))

    def set_constrained_edges(self, edges_index: np.ndarray) -> None:
        """Edges whose length is a constraint (edges with both ends fixed are left out)."""
        self._constrained = np.asarray(edges_index, dtype=np.int64)
        self.n_constraints = len(self._constrained)

    def _edge_vectors(self, q: np.ndarray) -> np.ndarray:
        x = q.reshape(-1, 3)
        return x[self.edge_nodes[:, 1]] - x[self.edge_nodes[:, 0]]

    @abc.abstractmethod
    def twist_offset(self) -> float:
        """Turns added to ``Phi / 2pi`` to give the excess twist (set by the boundary)."""

    # ----------------------------------------------------------------- pieces
    def _set_frames(self, tangents: np.ndarray, directors: np.ndarray) -> None:
        """New reference frames; forgets what was computed with the old ones."""
        self._tangents = tangents
        self._directors = directors
        p, nx = self._prev_edge, self._next_edge
        self._frame_data = np.stack([directors[p], tangents[p], directors[nx], tangents[nx]],
                                    axis=1)
        self._phi_cache: tuple[bytes, float] | None = None
        # gradient pieces of one state that the load parameters do not change
        self._gradient_cache: tuple[bytes, np.ndarray, float, np.ndarray] | None = None

    def _frames(self) -> np.ndarray:
        """Per-vertex reference data ``(n_vertices, 4, 3)``: u_prev, t_prev, u_next, t_next."""
        return self._frame_data

    def _stencils(self, q: np.ndarray) -> np.ndarray:
        """Stencil coordinates ``(n_vertices, 9)`` (float64, C order)."""
        return self._pattern.gather(np.asarray(q, dtype=np.float64))

    def _twist_terms(self, q: np.ndarray, order: int, hessians: np.ndarray | None = None,
                     scale: float = 1.0) -> tuple[float, np.ndarray]:
        """``Phi`` and the local twist gradients (order >= 1); Hessians added at order 2."""
        values, gradients, _ = kernels.twist_terms(self._stencils(q), self._frame_data, order,
                                                   hessians, scale)
        phi = float(values.sum())
        self._phi_cache = (_key(q), phi)
        return phi, gradients

    def reference_twist_total(self, q: np.ndarray) -> float:
        """``Phi``: the sum of the reference twists (radians).

        Cached for the last ``q`` (the energy, gradient and Hessian of one
        Newton iteration share it); the cache is emptied when the reference
        frames change (:meth:`accept`). Only ``Phi`` is cached, never an
        energy, so changing ``excess_link``, ``turns`` or ``tension`` is safe.
        """
        if self._phi_cache is not None and self._phi_cache[0] == _key(q):
            return self._phi_cache[1]
        return self._twist_terms(q, 0)[0]

    def twist(self, q: np.ndarray) -> float:
        """Excess twist in turns, ``twist_offset + Phi / 2pi``."""
        return self.twist_offset() + self.reference_twist_total(q) / (2 * np.pi)

    def bending_energy(self, q: np.ndarray) -> float:
        return float(np.sum(self._bending[0](self._stencils(q), self._bend_weight)))

    def twist_energy(self, q: np.ndarray) -> float:
        return 0.5 * self._twist_coefficient * self.twist(q) ** 2

    def elastic_energy(self, q: np.ndarray) -> float:
        return self.bending_energy(q) + self.twist_energy(q)

    # -------------------------------------------------------------- protocol
    def energy(self, q: np.ndarray) -> float:
        return self.elastic_energy(q)

    def _twist_gradient(self, q: np.ndarray) -> np.ndarray:
        """``grad(Phi) / 2pi`` (shape ``(n_dofs,)``) = minus the gradient of the writhe."""
        return self._pattern.scatter_vector(self._twist_terms(q, 1)[1]) / (2 * np.pi)

    def gradient(self, q: np.ndarray) -> np.ndarray:
        """Bending gradient plus ``k Tw / 2pi`` times ``grad(Phi)``.

        The bending gradient, ``Phi`` and ``grad(Phi)`` of the last ``q`` are
        kept (until the frames change): continuation evaluates the gradient at
        one state for several values of a load parameter (its
        finite-difference parameter derivative), which only changes ``Tw``.
        """
        key = _key(q)
        cached = self._gradient_cache
        if cached is not None and cached[0] == key:
            _, g, phi, twist_gradient = cached
        else:
            # the values of the bending kernel's and _twist_terms' gradients scattered
            # (scatter_vector), from one compiled call
            g, twists, twist_gradient = kernels.gradient_terms(
                np.asarray(q, dtype=np.float64), self._pattern.dofs, self._bend_weight,
                self._curvature, self._frame_data, self.n_dofs)
            phi = float(twists.sum())
            self._phi_cache = (key, phi)
            self._gradient_cache = (key, g, phi, twist_gradient)
        tw = self.twist_offset() + phi / (2 * np.pi)
        return g + (self._twist_coefficient * tw / (2 * np.pi)) * twist_gradient

    def hessian(self, q: np.ndarray) -> HessianParts:
        """Banded part (bending + ``k Tw`` times the twist Hessian) plus ``k g g^T``.

        The local Hessians are exactly symmetric and the scatter keeps that, so
        the sparse part needs no symmetrisation.
        """
        k = self._twist_coefficient
        tw = self.twist(q)
        # One buffer per problem: fresh (n, 9, 9) arrays cost page faults that
        # doubled the time at N = 10000 (measured).
        if self._local_hessians is None:
            self._local_hessians = np.zeros((len(self._bend_weight), 9, 9))
        local = self._local_hessians
        local.fill(0.0)
        kernels.bending_terms(self._stencils(q), self._bend_weight, self._curvature, 2, local)
        twist_local = self._twist_terms(q, 2, local, k * tw / (2 * np.pi))[1]
        g = self._pattern.scatter_vector(twist_local) / (2 * np.pi)
        return HessianParts(self._pattern.scatter_matrix(local), g[None, :], np.array([k]))

    def constraints(self, q: np.ndarray) -> np.ndarray:
        """Inextensibility ``c_j = (|e_j|^2 - h^2) / (2h)``; multipliers are tensions."""
        return self._edge_length_terms(q)[0].copy()

    def _edge_length_terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(constraints (m,), Jacobian data (6 m,))`` at ``q`` in the layout of
        :meth:`_constraint_jacobian` (:func:`~supercoil.rod.kernels.edge_length_terms`:
        the values of ``(np.sum(e * e, axis=1) - h * h) / (2 * h)`` and of the entries
        ``take_along_axis([-e / h, e / h], order)``). The last ``q``'s are kept: a
        residual asks for the Jacobian and then the constraints at one state (the two
        as numpy steps cost 14 and 22 us at N = 100; the methods with this one call 4
        and 8 us, the call itself 2-3 us)."""
        key = _key(q)
        cached = self.__dict__.get("_edge_terms_cache")
        if cached is not None and cached[0] == key and cached[1] is self._constrained:
            return cached[2], cached[3]
        layout = self._jacobian_layout_of_constrained()
        values, data = kernels.edge_length_terms(np.asarray(q, dtype=np.float64), layout[4],
                                                 self.rod.edge_length, layout[1])
        self._edge_terms_cache = (key, self._constrained, values, data)
        return values, data

    def _jacobian_layout_of_constrained(self):
        """``(constrained, order, indices, indptr, edges)``: the CSR layout of the
        Jacobian for the constrained edges (see :meth:`_constraint_jacobian`) and their
        end nodes ``(m, 2)``; made once per constrained set."""
        layout = self.__dict__.get("_jacobian_layout")
        if layout is None or layout[0] is not self._constrained:
            m = self.n_constraints
            nodes = self.edge_nodes[self._constrained]
            a = 3 * nodes[:, :1] + np.arange(3)
            b = 3 * nodes[:, 1:] + np.arange(3)
            cols = np.concatenate([a, b], axis=1).reshape(m, 6)
            order = np.argsort(cols, axis=1, kind="stable")
            index = np.int32 if max(self.n_dofs, 6 * m) < 2**31 - 1 else np.int64
            indices = np.take_along_axis(cols, order, axis=1).ravel().astype(index)
            indptr = np.arange(0, 6 * m + 1, 6, dtype=index)
            layout = (self._constrained, order, indices, indptr, np.ascontiguousarray(nodes))
            self._jacobian_layout = layout
        return layout

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        """Jacobian of :meth:`constraints`, ``(m, n_dofs)``; the last one is returned
        again (the same object: callers must not modify it) for the same ``q``."""
        key = _key(q)
        cached = self.__dict__.get("_jacobian_cache")
        if cached is not None and cached[0] == key and cached[1] is self._constrained:
            return cached[2]
        J = self._constraint_jacobian(q)
        self._jacobian_cache = (key, self._constrained, J)
        return J

    def _constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        """Row ``k``: ``-e_k`` on the first node of constrained edge ``k``, ``e_k`` on the
        second (``e_k`` the edge over its rest length). Built as the CSR matrix that
        scipy's COO path ``csr_matrix((data, (rows, cols)))`` gave (six distinct columns
        per row, sorted; zeros stored), from a layout remembered per constrained set:
        the COO path cost 0.5 ms of the corrector's every residual at N = 200."""
        m = self.n_constraints
        _, _, indices, indptr, _ = self._jacobian_layout_of_constrained()
        data = self._edge_length_terms(q)[1].copy()
        return csr_from_arrays(data, indices.copy(), indptr.copy(), (m, self.n_dofs),
                               canonical=True)

    def _constraint_hessian_entries(self):
        """``(rows, cols)`` of the constraint curvature's COO entries (see below)."""
        nodes = self.edge_nodes[self._constrained]
        a = 3 * nodes[:, :1] + np.arange(3)
        b = 3 * nodes[:, 1:] + np.arange(3)
        return np.concatenate([a, b, a, b]).ravel(), np.concatenate([a, b, b, a]).ravel()

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix:
        """``sum_j mu_j hess c_j``: ``+-mu_j / h`` on the blocks of edge ``j``'s two nodes.

        The CSR pattern of these entries is fixed by the constrained edges and is
        built once: an entry gets at most two terms (a node's diagonal from its two
        edges, summed in either order to the same value), so filling it directly
        gives the matrix that ``csr_matrix((data, (rows, cols)))`` gives. The values
        come from one compiled loop (:func:`_curvature_values`, the same quotients
        and sums; the values 20 -> 6 µs, the whole method 20 -> 10 µs at N = 100, at every
        corrector iteration), and the
        matrix is marked canonical (its pattern's keys are sorted and unique), which
        spares the sums that take it scipy's check.
        """
        pattern = self.__dict__.get("_curvature_pattern")
        if pattern is None or pattern[0] is not self._constrained:
            rows, cols = self._constraint_hessian_entries()
            key = rows * self.n_dofs + cols
            order = np.argsort(key, kind="stable")
            slots, first_at, counts = np.unique(key[order], return_index=True,
                                                return_counts=True)
            if counts.max(initial=0) > 2:
                raise AssertionError("an edge-length curvature entry with more than two terms")
            first = order[first_at]
            second = np.where(counts == 2, order[np.minimum(first_at + 1, order.size - 1)], -1)
            indptr = np.zeros(self.n_dofs + 1, dtype=np.int32)
            np.cumsum(np.bincount(slots // self.n_dofs, minlength=self.n_dofs), out=indptr[1:])
            pattern = (self._constrained, first, second, (slots % self.n_dofs).astype(np.int32),
                       indptr)
            self._curvature_pattern = pattern
        _, first, second, indices, indptr = pattern
        values = _curvature_values(np.ascontiguousarray(multipliers, dtype=np.float64),
                                   float(self.rod.edge_length), first, second)
        return csr_from_arrays(values, indices.copy(), indptr.copy(),
                               (self.n_dofs, self.n_dofs), canonical=True)

    # the load parameter that shifts ``twist_offset`` one for one (subclasses name it)
    twist_parameter: str = ""

    def parameter_derivative(self, q: np.ndarray, multipliers: np.ndarray,
                             parameter: str) -> np.ndarray | None:
        """``d/d parameter`` of the KKT residual ``[gradient; constraints]``
        ``(n_dofs + n_constraints,)`` for :attr:`twist_parameter`; None for another
        parameter (the caller then differentiates numerically).

        That parameter (the ring's ``excess_link``, the clamped rod's ``turns``)
        adds one for one to ``Tw = twist_offset + Phi / 2pi``, which enters the
        gradient as ``k Tw grad(Phi) / 2pi`` (:meth:`gradient`): the derivative is
        ``k grad(Phi) / 2pi``; the constraints (edge lengths) do not depend on it.
        Exact, where the continuation's central difference costs two residuals and
        carries an ``O(step^2)`` error.
        """
        if not parameter or parameter != self.twist_parameter:
            return None
        key = _key(q)
        cached = self._gradient_cache
        if cached is not None and cached[0] == key:
            twist_gradient = cached[3]
        else:
            twist_gradient = self._pattern.scatter_vector(self._twist_terms(q, 1)[1])
        derivative = (self._twist_coefficient / (2 * np.pi)) * twist_gradient
        return np.concatenate([derivative, np.zeros(self.n_constraints)])

    def accept(self, q: np.ndarray) -> None:
        """Carry the reference directors to the new tangents (time-parallel transport)."""
        t_new = unit(self._edge_vectors(q))
        u = parallel_transport(self._directors, self._tangents, t_new)
        u = unit(u - np.sum(u * t_new, axis=1, keepdims=True) * t_new)  # against drift
        self._set_frames(t_new, u)

    @property
    def reference_directors(self) -> np.ndarray:
        return self._directors.copy()


class ClosedRodEnergy(RodEnergy):
    """The constrained energy problem of a closed rod at excess link ``excess_link``.

    Implements :class:`supercoil.solvers.problem.ConstrainedEnergy`. Holds the
    reference directors as mutable state, carried along by :meth:`accept`.
    ``reference_link`` is ``Lk_u``; pass it to continue from a saved state.
    Rigid motions are removed by fixing six DOFs (:func:`rigid_pins`).
    """

    def __init__(self, rod: Rod, points: np.ndarray, excess_link: float,
                 reference_directors: np.ndarray | None = None,
                 reference_link: int | None = None):
        points = np.asarray(points, dtype=float)
        if points.shape != (rod.n_nodes, 3):
            raise ValueError(f"points must have shape ({rod.n_nodes}, 3), got {points.shape}")
        if not np.isfinite(points).all():
            raise ValueError("points contain non-finite coordinates")
        if not rod.closed:
            raise ValueError("ClosedRodEnergy needs a closed Rod (closed=True)")
        if not np.isfinite(excess_link):
            raise ValueError(f"excess_link must be finite, got {excess_link!r}")
        self.excess_link = float(excess_link)
        n = rod.n_nodes
        idx = np.arange(n)
        if reference_directors is None:
            reference_directors = initial_reference_frames(points)
        self._setup(rod, points, np.stack([(idx - 1) % n, idx, (idx + 1) % n], 1),
                    np.stack([idx, (idx + 1) % n], 1), (idx - 1) % n, idx, reference_directors)
        if reference_link is None:
            from supercoil.topology import writhe  # set-up only, never inside Newton

            frame_twist = self.reference_twist_total(points.ravel()) / (2 * np.pi)
            reference_link = int(np.rint(frame_twist + writhe(points)))
        self.reference_link = int(reference_link)
        self.fixed = rigid_pins(points)
        self.gauge_dofs = self.fixed  # all six pins only remove rigid motions

    twist_parameter = "excess_link"

    def twist_offset(self) -> float:
        return self.excess_link - self.reference_link

    def repin(self, q: np.ndarray) -> None:
        """Re-pick the six rigid-motion pins (:func:`rigid_pins`) for the state ``q``.

        The pins chosen on the circle remove rotations less and less well as
        the ring folds into a plectoneme (:meth:`pin_quality` fell to 0.1 on
        the alpha branch at L/D = 122): the pinned Hessian then keeps a nearly
        null rotation, whose eigenvalue the gauge's small force can push
        through zero, and a continuation folds back and forth there (measured:
        the branch snaked from dLk 3.40, N = 200). Call this between
        continuation runs: the pinned coordinates keep their values at ``q``.
        """
        self.fixed = rigid_pins(np.asarray(q, dtype=float).reshape(-1, 3))
        self.gauge_dofs = self.fixed

    def pin_grip(self, q: np.ndarray) -> float:
        """:func:`rotation_pin_determinant` of the current pins at ``q``: zero where they do
        not remove some rigid motion (cheap: one 6 x 6 determinant)."""
        return rotation_pin_determinant(np.asarray(q, dtype=float).reshape(-1, 3), self.fixed)

    def pin_quality(self, q: np.ndarray) -> float:
        """:func:`rotation_pin_determinant` of the current pins at ``q`` over that of the
        pins :func:`rigid_pins` would choose there, in ``[0, 1]`` (1 right after
        :meth:`repin`)."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        best = rotation_pin_determinant(x, rigid_pins(x))
        return min(1.0, rotation_pin_determinant(x, self.fixed) / best) if best > 0 else 0.0

    # An accepted state whose edges turned by more than this (degrees) from the
    # last one is a jump (a stored state), not a step: see accept.
    jump_turn_degrees = 45.0

    def accept(self, q: np.ndarray) -> None:
        """Carry the reference directors to ``q``; keep the reference twist well spread.

        ``Phi`` is the sum of per-vertex signed angles in ``(-pi, pi]``: a
        vertex whose reference twist reaches ``pi`` slips ``Phi`` by ``2 pi``
        and the tracked writhe by one. Along a branch the tangents turn by a
        few degrees per accepted point (at most 11 degrees measured on the
        ring's alpha branch at N = 40) and time-parallel transport keeps the
        per-vertex twists small. Going back to a stored state (branch
        switching, a consistency check) transports the frames in one jump:
        measured, from near the figure-eight back to the circle, the twists
        piled up so that a later small step slipped the writhe by one. So:

        * after a jump (some edge turned by more than :attr:`jump_turn_degrees`)
          the directors are rebuilt as at set-up (equal reference twists) and
          ``Lk_u`` is recomputed from the double-sum writhe (O(N^2), about
          20 ms at N = 1000): the tracked writhe is then the true one;
        * after a step, if some vertex carries more than ``pi / 2`` of reference
          twist, the directors are rebuilt the same way and ``Lk_u`` shifted by
          the whole turns this changes ``Phi`` by, so that the tracked writhe
          (continuous along the branch) is unchanged.
        """
        q = np.asarray(q, dtype=float)
        t_new = unit(self._edge_vectors(q))
        jump = bool(np.min(np.sum(t_new * self._tangents, axis=1))
                    < np.cos(np.radians(self.jump_turn_degrees)))
        super().accept(q)
        if not jump and np.max(np.abs(kernels.twist_value(self._stencils(q),
                                                           self._frames()))) <= np.pi / 2:
            return
        phi_old = self.reference_twist_total(q)
        points = q.reshape(-1, 3)
        self._set_frames(t_new, initial_reference_frames(points))
        phi_new = self.reference_twist_total(q)
        if jump:
            from supercoil.topology import writhe  # jumps only, never inside Newton

            self.reference_link = int(np.rint(phi_new / (2 * np.pi) + writhe(points)))
        else:
            self.reference_link += int(np.rint((phi_new - phi_old) / (2 * np.pi)))

    def writhe_local(self, q: np.ndarray) -> float:
        """Writhe from the reference twist: ``Lk_u - Phi / 2pi`` (no double sum)."""
        return self.reference_link - self.reference_twist_total(q) / (2 * np.pi)

    def symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """The six rigid motions at ``q`` (shape ``(6, n_dofs)``): translations, rotations.

        (Off the circle a homogeneous ring has a seventh, approximate symmetry,
        sliding the material along itself; the circle's sliding is a rotation.)
        """
        x = q.reshape(-1, 3)
        r = x - x.mean(axis=0)
        modes = []
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            modes.append(np.tile(e, len(x)))
            modes.append(np.cross(e, r).ravel())
        return np.array(modes)

    def near_symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """Sliding the material along the centreline, ``(x_{i+1} - x_{i-1}) / 2`` (shape
        ``(1, n_dofs)``): an exact symmetry of the continuous homogeneous ring,
        broken only by the discretisation. DESIGN.md removes it from the
        unstable count; on the circle it is a rigid rotation.
        """
        x = q.reshape(-1, 3)
        return (0.5 * (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0))).ravel()[None, :]

    def material_directors(self, q: np.ndarray) -> np.ndarray:
        """Material directors ``d1`` (shape ``(n, 3)``) with uniform excess twist.

        The material angle ``theta_i`` of edge ``i`` is chosen so that each
        vertex carries the same total twist ``Phi / n``; ``theta`` is single
        valued around the ring, so the material ribbon has linking number
        ``Lk_u`` and its twist, measured from these directors by
        :func:`supercoil.topology.twist_from_frames`, is an independent check
        of Lk = Tw + Wr.
        """
        self.accept(q)  # directors adapted to the current tangents
        ref = kernels.twist_value(self._stencils(q), self._frames())
        mean = ref.mean()
        theta = np.zeros(len(ref))
        theta[1:] = np.cumsum(mean - ref[1:])
        t = self._tangents
        u = self._directors
        v = np.cross(t, u)
        return np.cos(theta)[:, None] * u + np.sin(theta)[:, None] * v


def rotation_pin_determinant(points: np.ndarray, pins: np.ndarray) -> float:
    """``|det|`` of the response of the six pinned coordinates to the rigid motions:
    row ``(e_k, r_i x e_k)`` for each pinned DOF ``3 i + k`` (translations, then
    rotations about node 0; ``r_i = x_i - x_0``).

    Zero when the pins do not remove some rigid motion (or are not six); it scales as
    ``|r|^3``. With node 0 fully pinned it is the ``|det|`` of the three other rows'
    rotation parts.
    """
    x = np.asarray(points, dtype=float).reshape(-1, 3)
    pins = np.asarray(pins, dtype=np.int64)
    if pins.size != 6:
        return 0.0
    return float(abs(np.linalg.det(_rigid_rows(x, pins))))


def _rigid_rows(points: np.ndarray, dofs) -> np.ndarray:
    """Rows ``(e_k, (x_i - x_0) x e_k)`` of the DOFs ``3 i + k``, ``(len(dofs), 6)``."""
    dofs = np.asarray(dofs, dtype=np.int64)
    node, k = np.divmod(dofs, 3)
    unit = np.eye(3)[k]
    return np.hstack([unit, np.cross(points[node] - points[0], unit)])


# the equivariant pins (rigid_pins) are taken when they remove rotations at least this
# well relative to the best of all candidate sets
EQUIVARIANT_PIN_QUALITY = 0.25


def rigid_pins(points: np.ndarray) -> np.ndarray:
    """Six DOF indices whose fixing removes the rigid motions of a free body.

    By default node 0 is fixed (translations) and three coordinates of far nodes
    are chosen to maximise ``|det|`` of their response to infinitesimal rotations
    about node 0 (:func:`rotation_pin_determinant`; so rotations are removed
    as well as the geometry allows).
    At an equilibrium the rigid motions are null vectors of the Hessian, so
    fixing these DOFs restricts the Hessian to a complement of the rigid modes
    and leaves its inertia unchanged.

    Equivariant pins. For an even number of nodes and a state that the two-fold map
    ``x_i -> R x_{-i}`` (``R`` the half-turn about the line through node 0 along
    ``x``) leaves unchanged (:func:`_axis_through_node_0`), the six are taken, when
    they reach ``EQUIVARIANT_PIN_QUALITY`` of the best determinant, among sets
    that this map maps onto themselves (:func:`_equivariant_sets`). On the
    circle (node 0 on the ``x`` axis, :func:`~supercoil.geometry.curves.circle`)
    that line is the two-fold axis through nodes 0 and ``n/2``
    (:func:`~supercoil.problems.ring_diagram.primary.on_mesh_direction` switches the
    primary branches along it). With such pins the pinned equations are
    equivariant, so a state symmetric about that axis stays exactly so along a
    branch; with others the pins turn the axis a little at each step, the
    integral phase condition (invariant to rotations only to first order) then
    slides the material, and the symmetry is lost by ``O(step^2)`` per step
    (measured: alpha, N = 200, the axis 0.01 node spacings off the mesh by
    dLk 6), which unfolds the symmetry-breaking bifurcations of secondary
    branches.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(points)
    candidates = [3 * node + k for node in (n // 3, (2 * n) // 3, n // 2, n // 6)
                  for k in range(3)]
    best, best_det = None, -1.0
    for a in range(len(candidates)):
        for b in range(a + 1, len(candidates)):
            for c in range(b + 1, len(candidates)):
                dofs = [candidates[a], candidates[b], candidates[c]]
                if len(set(dofs)) < 3:
                    continue
                det = abs(np.linalg.det(_rigid_rows(points, [0, 1, 2] + dofs)))
                if det > best_det:
                    best, best_det = dofs, det
    if best is None or best_det <= 1e-12 * np.ptp(points) ** 3:
        raise ValueError("cannot remove rigid rotations: the curve is (nearly) a straight line")
    best = [0, 1, 2] + best
    if n % 2 == 0 and n >= 8 and _axis_through_node_0(points):
        sets = _equivariant_sets(n)
        rows = _rigid_rows(points, np.arange(3 * n))
        dets = np.abs(np.linalg.det(rows[sets]))
        k = int(np.argmax(dets))
        if dets[k] >= EQUIVARIANT_PIN_QUALITY * best_det:
            best = [int(d) for d in sets[k]]
    return np.array(sorted(best), dtype=np.int64)


def _equivariant_sets(n: int) -> np.ndarray:
    """Six-DOF pin sets (even ``n``) that ``x_i -> R x_{-i}`` maps onto themselves, ``R``
    the half-turn about the line through node 0 along ``x`` (coordinates map to
    coordinates), ``(k, 6)``. Nodes 0 and ``n/2`` are their own images, node ``k`` and
    ``n - k`` each other's: node 0 (all three) with one coordinate of node ``n/2`` and
    one coordinate of a pair ``k``, ``n - k``; or two coordinates of node 0 with two
    pairs (when nodes 0 and ``n/2`` come close, as at alpha's crossing, the first kind
    loses its grip on rotations)."""
    half = n // 2
    nodes = sorted({(j * n) // 24 for j in range(1, 12)} - {0, half})
    pairs = [(k, c) for k in nodes for c in range(3)]
    sets = []
    for k, c in pairs:
        for a in range(3):
            sets.append([0, 1, 2, 3 * half + a, 3 * k + c, 3 * (n - k) + c])
    for i in range(len(pairs)):
        for j in range(i + 1, len(pairs)):
            (k, c), (m, d) = pairs[i], pairs[j]
            for skipped in range(3):
                origin = [a for a in range(3) if a != skipped]
                sets.append(origin + [3 * k + c, 3 * (n - k) + c, 3 * m + d, 3 * (n - m) + d])
    return np.array(sets, dtype=np.int64)


def _axis_through_node_0(points: np.ndarray, tolerance: float = 1e-8) -> bool:
    """True when ``x_i = R x_{-i}`` for every node within ``tolerance`` times the curve's
    size, ``R`` the half-turn about the line through node 0 along ``x``: the curve has a
    two-fold axis on that line, through node 0 (and node ``n/2`` for even ``n``)."""
    x = np.asarray(points, dtype=float)
    n = x.shape[0]
    image = x[(-np.arange(n)) % n] - x[0]
    image[:, 1:] *= -1.0
    image += x[0]
    size = float(np.ptp(x, axis=0).max())
    return bool(np.max(np.abs(image - x)) <= tolerance * max(size, 1e-300))
