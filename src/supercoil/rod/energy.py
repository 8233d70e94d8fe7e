"""Shared machinery of the discrete Kirchhoff rods: stencils, frames, constraints.

:class:`RodEnergy` holds what the closed rod (:mod:`supercoil.rod.closed`) and the
clamped one (:mod:`supercoil.rod.open`) share: the bending energy of the vertex
stencils (:mod:`supercoil.rod.kernels`), the twist energy ``2 pi^2 C Tw^2 / L``
with ``Tw = twist_offset + Phi / 2pi`` (``Phi`` the total reference twist, a sum
of local terms), the inextensibility constraints and their derivatives, and the
reference frames carried by time-parallel transport (``accept``).
"""

from __future__ import annotations

import abc

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit
from supercoil.geometry.curves import parallel_transport, unit
from supercoil.rod import kernels
from supercoil.rod.assembly import StencilPattern
from supercoil.rod.model import Rod
from supercoil.solvers.carried import Carried, Frames
from supercoil.solvers.csr import CSRArrays
from supercoil.solvers.parameters import Parametrised
from supercoil.solvers.problem import HessianParts


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


class RodEnergy(Parametrised, Carried, abc.ABC):
    """Shared machinery of the discrete rods: stencils, frames, constraints.

    Subclasses set ``self.rod``, the vertex stencils ``vertex_nodes``
    ``(n_vertices, 3)``, the edges ``edge_nodes`` ``(n_edges, 2)``, the
    previous/next edge of each vertex, and :meth:`twist_offset` (turns). Its load
    parameters (:attr:`parameters`) change through :meth:`at`, a new problem that
    shares the rod, the patterns, the layouts and the frames (the caches are keyed by
    the state and hold no parameter-dependent values).
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
        # what depends on neither the parameters nor the frames, made once and shared by
        # the problems ``at`` and ``carried_to`` derive from this one: hessian()'s work
        # array, the Jacobian's and the constraint curvature's layouts (by constrained
        # set), the last state's edge-length terms and Jacobian
        self._shared: dict = {}
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
    # the carried state (supercoil.solvers.carried): the reference frames, and what a
    # subclass keeps with them
    frame_attributes = (("tangents", "_tangents"), ("directors", "_directors"))

    def _restore_frames(self, frames: Frames) -> None:
        super()._restore_frames(frames)
        self._set_frames(frames.values["tangents"], frames.values["directors"])

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
        local = self._shared.get("local_hessians")
        if local is None:
            local = self._shared["local_hessians"] = np.zeros((len(self._bend_weight), 9, 9))
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
        :meth:`constraint_jacobian_arrays` (:func:`~supercoil.rod.kernels.edge_length_terms`:
        the values of ``(np.sum(e * e, axis=1) - h * h) / (2 * h)`` and of the entries
        ``take_along_axis([-e / h, e / h], order)``). The last ``q``'s are kept: a
        residual asks for the Jacobian and then the constraints at one state (the two
        as numpy steps cost 14 and 22 us at N = 100; the methods with this one call 4
        and 8 us, the call itself 2-3 us)."""
        key = _key(q)
        cached = self._shared.get("edge_terms")
        if cached is not None and cached[0] == key and cached[1] is self._constrained:
            return cached[2], cached[3]
        layout = self._jacobian_layout_of_constrained()
        values, data = kernels.edge_length_terms(np.asarray(q, dtype=np.float64), layout[4],
                                                 self.rod.edge_length, layout[1])
        self._shared["edge_terms"] = (key, self._constrained, values, data)
        return values, data

    def _jacobian_layout_of_constrained(self):
        """``(constrained, order, indices, indptr, edges)``: the CSR layout of the
        Jacobian for the constrained edges (see :meth:`constraint_jacobian_arrays`) and their
        end nodes ``(m, 2)``; made once per constrained set."""
        layout = self._shared.get("jacobian_layout")
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
            self._shared["jacobian_layout"] = layout
        return layout

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        """Jacobian of :meth:`constraints`, ``(m, n_dofs)``: the scipy matrix of
        :meth:`constraint_jacobian_arrays`; the last one is returned again (the same
        object: callers must not modify it) for the same ``q`` and constrained edges,
        also to the problems :meth:`at` and ``carried_to`` derive from this one."""
        key = _key(q)
        cached = self._shared.get("jacobian")
        if cached is not None and cached[0] == key and cached[1] is self._constrained:
            return cached[2]
        J = self.constraint_jacobian_arrays(q).tocsr()
        self._shared["jacobian"] = (key, self._constrained, J)
        return J

    def constraint_jacobian_arrays(self, q: np.ndarray) -> CSRArrays:
        """The arrays of :meth:`constraint_jacobian` (:class:`~supercoil.solvers.csr.
        CSRArrays`, canonical), without a ``scipy.sparse`` object: what the continuation's
        residual (``J^T mu``) and its factor (the free columns) read at every corrector
        iterate (a scipy matrix made from them costs 10-30 us of checks, at each of the
        about 950 iterates of the tweezers benchmark). The last one is returned again
        (the same object) for the same ``q`` and constrained edges, as
        :meth:`constraint_jacobian`.

        Row ``k``: ``-e_k`` on the first node of constrained edge ``k``, ``e_k`` on the
        second (``e_k`` the edge over its rest length), the matrix that scipy's COO path
        ``csr_matrix((data, (rows, cols)))`` gives (six distinct columns per row,
        sorted; zeros stored), from a layout remembered per constrained set."""
        key = _key(q)
        cached = self._shared.get("jacobian_arrays")
        if cached is not None and cached[0] == key and cached[1] is self._constrained:
            return cached[2]
        m = self.n_constraints
        _, _, indices, indptr, _ = self._jacobian_layout_of_constrained()
        data = self._edge_length_terms(q)[1].copy()
        J = CSRArrays(data, indices, indptr, (m, self.n_dofs), canonical=True)
        self._shared["jacobian_arrays"] = (key, self._constrained, J)
        return J

    def _constraint_hessian_entries(self):
        """``(rows, cols)`` of the constraint curvature's COO entries (see below)."""
        nodes = self.edge_nodes[self._constrained]
        a = 3 * nodes[:, :1] + np.arange(3)
        b = 3 * nodes[:, 1:] + np.arange(3)
        return np.concatenate([a, b, a, b]).ravel(), np.concatenate([a, b, b, a]).ravel()

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix:
        """``sum_j mu_j hess c_j``: ``+-mu_j / h`` on the blocks of edge ``j``'s two nodes
        (the matrix of :meth:`constraint_curvature`)."""
        return self.constraint_curvature(q, multipliers).tocsr()

    def lagrangian_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> HessianParts:
        """``hessian(q)`` plus ``constraint_hessian(q, multipliers)`` (the sum of
        :func:`~supercoil.solvers.newton.lagrangian_hessian`), bit for bit, summed on
        the arrays of both: no matrix is made for the curvature."""
        return self.hessian(q).plus_sparse(self.constraint_curvature(q, multipliers))

    def constraint_curvature(self, q: np.ndarray, multipliers: np.ndarray) -> CSRArrays:
        """The canonical CSR arrays of :meth:`constraint_hessian` (read only: the index
        arrays are the pattern's), for the sums that take them without a matrix
        (:meth:`lagrangian_hessian`, a contact problem's).

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
        pattern = self._shared.get("curvature_pattern")
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
            self._shared["curvature_pattern"] = pattern
        _, first, second, indices, indptr = pattern
        values = _curvature_values(np.ascontiguousarray(multipliers, dtype=np.float64),
                                   float(self.rod.edge_length), first, second)
        return CSRArrays(values, indices, indptr, (self.n_dofs, self.n_dofs), canonical=True)

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
