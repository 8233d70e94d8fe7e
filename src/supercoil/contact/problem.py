"""Self-contact of a rod as a constrained-energy problem.

:class:`ContactProblem` wraps a rod energy (closed or clamped) and adds the
condition that two points of the centreline farther apart along the rod than
the neighbour exclusion stay at least the tube diameter ``D`` apart, with the
distance ``d`` of the contact curve (:mod:`supercoil.contact.curve`: the
polygon's segments, or the B-spline pieces of those segments) and the gap
``g = d - D``:

* ``penalty``, ``augmented``, ``barrier``: ``E + sum_pairs psi(g)``
  (:mod:`supercoil.contact.potentials`), or its double integral over both
  strands (``formulation="integral"``, :mod:`supercoil.contact.integral`);
* ``exact``: ``g >= 0`` as inequality constraints; the active ones join the
  rod's equality constraints, and their multipliers are minus the contact
  forces (:mod:`supercoil.contact.solve` runs the active-set loop). Inactive
  pairs that penetrate during the search meet the penalty, which vanishes at
  a solution (no inactive pair penetrates there).

Three guards stay on the polygon whatever the curve: the linking number
(:meth:`ContactProblem.admissible` compares the writhe the energy carries
through the reference twist with the polygon's double sum), the knot type
(:class:`~supercoil.topology.knots.KnotGuard`: that of the first accepted
state, or of the curve given to :meth:`ContactProblem.keep_knot_type`) and the collision
detection of :meth:`ContactProblem.step_bound` (:mod:`supercoil.contact.step`),
which keeps any segment from passing through another. The knotted computations add
a fourth, ``curvature_limit``: a tube of diameter D overlaps itself locally where its
radius of curvature falls below D/2 (Carlen et al. 2005), which the neighbour
exclusion hides from the contact, so a state bent more tightly is refused.

The wrapper speaks the :class:`~supercoil.solvers.problem.ConstrainedEnergy`
protocol, so Newton, the inertia count and the eigenvalues see the contact
terms through the Hessian (energy treatments) or through the active
constraints (exact treatment): a direction that would open a contact carrying
a positive force is excluded from the tangent space. What belongs to the rod
(its frames, writhe, reference link) is asked of ``problem.base``; the load
parameters (``excess_link``, ``turns``, ``tension``) read the rod's, and
:meth:`ContactProblem.at` gives the contact problem over the rod at other values.

The centreline. Contact sees the points ``base.centreline(q)`` ``(3 n,)``, entry ``k``
the unknown ``q[base.centreline_dofs[k]]`` (the positions among a Cosserat rod's
unknowns, :mod:`supercoil.cosserat.centreline`), the first at arc length
``base.centreline_origin``: distances, guards and collision bounds are the
centreline's, and the contact derivatives are scattered into ``q`` by the map. A rod
without ``centreline_dofs`` (the Kirchhoff rod) has its nodes as its unknowns.

The problem's answers for its rod (unknowns, pins, parameters, symmetries, carried
frames) are :class:`~supercoil.contact.over_rod.OverRod`'s, and the guards of its
steps (topology, curvature, collisions) :class:`~supercoil.contact.step_guards.StepGuards`'.
"""

from __future__ import annotations

import copy

import numpy as np
import scipy.sparse as sp

from supercoil.contact import potentials
from supercoil.contact.curve import ContactCurve, PairState
from supercoil.contact.integral import integral_terms
from supercoil.contact.options import ContactOptions
from supercoil.contact.over_rod import OverRod
from supercoil.contact.step import LinkGuard
from supercoil.contact.step_guards import StepGuards
from supercoil.solvers.csr import CSRArrays
from supercoil.solvers.csr_sum import block_csr
from supercoil.solvers.problem import HessianParts, jacobian_arrays
from supercoil.topology.knots.guard import KnotGuard


class ContactProblem(OverRod, StepGuards):
    """A rod energy plus impenetrability; see the module docstring.

    ``base`` is a :class:`~supercoil.rod.energy.RodEnergy` (closed or clamped);
    ``curve`` the :class:`~supercoil.contact.curve.ContactCurve` whose pairs carry the
    contact terms.
    """

    def __init__(self, base, options: ContactOptions):
        self.base = base
        self.options = options
        rod = base.rod
        dofs = getattr(base, "centreline_dofs", None)  # (module doc); None: the identity
        self._dof_map = None if dofs is None or np.array_equal(dofs, np.arange(base.n_dofs)) \
            else np.asarray(dofs, dtype=np.int64)
        self.curve = ContactCurve(base.edge_nodes, rod.closed, rod.edge_length, rod.length,
                                  options, getattr(base, "centreline_origin", None))
        self.diameter = self.curve.diameter
        self.closed = self.curve.closed
        self.edge_length = self.curve.edge_length
        self.segments = self.curve.segments
        self.spline = self.curve.spline
        self.integral = self.curve.integral
        self.default_stiffness = (options.stiffness if options.stiffness is not None
                                  else options.default_stiffness(rod.bending_stiffness,
                                                                    rod.edge_length))
        self.stiffness = self.default_stiffness  # the augmented Lagrangian may raise it
        # augmented Lagrangian multipliers (contact forces) per segment pair
        self.pair_multipliers: dict[tuple[int, int], float] = {}
        # exact treatment: active pairs, constraints g_p = d_p - D = 0
        self.active = np.zeros((0, 2), dtype=np.int64)
        self._slide_pin: tuple[int, np.ndarray, np.ndarray] | None = None
        # see stability_view()
        self.stability_mode = False
        self.refusal: str | None = None  # see admissible()
        self.link_guard = LinkGuard()  # see admissible()
        self.knot_guard = KnotGuard()  # see admissible()
        # the smallest radius of curvature a state may have (None: not checked; the
        # knotted computations set D/2), see admissible()
        self.curvature_limit: float | None = None
        self._integral_memo = None  # see _integral()
        self.summary_memo: dict = {}  # contact_summary's (supercoil.contact.report)

    # ----------------------------------------------------------- geometry
    def centreline(self, q: np.ndarray) -> np.ndarray:
        """The centreline ``(3 n,)`` of ``q`` (module doc), linear in ``q``."""
        return np.asarray(q, dtype=float) if self._dof_map is None else self.base.centreline(q)

    def _scatter(self, dofs: np.ndarray) -> np.ndarray:
        """Indices into :meth:`centreline` as indices into ``q``."""
        return dofs if self._dof_map is None else self._dof_map[dofs]

    @property
    def treatment(self) -> str:
        return self.options.treatment

    @property
    def n_equalities(self) -> int:
        """Constraints before the contact ones: the rod's, plus the sliding gauge if set."""
        return self.base.n_constraints + (self._slide_pin is not None)

    @property
    def n_constraints(self) -> int:
        return self.n_equalities + len(self.active)

    def pin_sliding(self, q: np.ndarray) -> None:
        """Remove the material-sliding near-symmetry of a closed homogeneous rod.

        Off the circle, sliding the material along the centreline leaves the
        continuum energy unchanged; the discretisation breaks the symmetry
        only weakly (a ripple of period one edge), so the mode is nearly null:
        unremoved, it lets Newton wander along the rod and lets the
        augmented-Lagrangian multipliers (attached to segment pairs) drag the
        state along it (docs/continuation.md, "Closed rods: the sliding gauge and
        the pins"). The gauge is the linear constraint
        ``t_k . (x_k - x_k(q)) = 0`` on one node ``k`` (tangential motion of
        that node), whose multiplier is the ripple's reaction. With contact the
        ripple is not small (a
        reaction of 4 % of the contact forces measured at N = 100), so the
        gauge only steers the augmented-Lagrangian outer iterations; every
        returned state is an equilibrium without it.
        """
        x = self.centreline(q).reshape(-1, 3)
        n = len(x)
        held = np.isin(self._scatter(np.arange(3 * n)), self.base.fixed).reshape(n, 3)
        fixed_nodes = set(np.flatnonzero(held.any(axis=1)).tolist())
        k = next(i for i in range(n // 4, n // 4 + n) if i % n not in fixed_nodes) % n
        t = x[(k + 1) % n] - x[(k - 1) % n]
        self._slide_pin = (k, t / np.linalg.norm(t), x[k].copy())
        self.invalidate()

    def release_sliding(self) -> None:
        """Remove the sliding gauge (see :meth:`pin_sliding`)."""
        self._slide_pin = None
        self.invalidate()

    def pair_distances(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, s, t)`` ``(m,)`` of pairs ``(m, 2)`` on the contact curve (exact minima)."""
        return self.curve.pair_distances(self.centreline(q), pairs)

    def pair_state(self, q: np.ndarray, cutoff: float, polygon: bool = False,
                   shadows: bool = False) -> PairState:
        """Pairs within ``cutoff`` at ``q``: :meth:`ContactCurve.pair_state`."""
        return self.curve.pair_state(self.centreline(q), cutoff, polygon, shadows)

    def min_distance(self, q: np.ndarray, polygon: bool = False) -> float:
        """Smallest distance of non-neighbour pairs: :meth:`ContactCurve.min_distance`."""
        return self.curve.min_distance(self.centreline(q), polygon)

    def arclength(self, segment: np.ndarray, param: np.ndarray) -> np.ndarray:
        """Arc-length fraction ``s/L`` of the point ``param`` along ``segment``."""
        return self.curve.arclength(segment, param)

    def invalidate(self) -> None:
        """Forget the remembered pair states (they are keyed by state and cutoff, so
        this only frees them; the multipliers and active set change the cutoff)."""
        self.curve.forget_pair_states()

    def _pair_derivatives(self, q: np.ndarray, pairs: np.ndarray):
        """``(d, gradient, Hessian, dofs)`` of the pairs' distances
        (:meth:`ContactCurve.pair_derivatives`), ``dofs`` indices into ``q``."""
        d, grad, hess, dofs = self.curve.pair_derivatives(self.centreline(q), pairs)
        return d, grad, hess, self._scatter(dofs)

    def _cutoff(self) -> float:
        """Distance below which a pair contributes to the energy or may become active."""
        D = self.diameter
        if self.treatment == "penalty":
            return D
        if self.treatment == "barrier":
            return D * (1.0 + self.options.barrier_activation)
        if self.treatment == "augmented":
            lam_max = max(self.pair_multipliers.values(), default=0.0)
            return D + lam_max / self.stiffness
        return D

    def _state(self, q: np.ndarray) -> PairState:
        return self.pair_state(q, self._cutoff())

    def _multipliers_of(self, pairs: np.ndarray) -> np.ndarray:
        get = self.pair_multipliers.get
        return np.array([get((int(i), int(j)), 0.0) for i, j in pairs], dtype=float)

    def _psi(self, gap: np.ndarray, pairs: np.ndarray):
        opts = self.options
        if self.treatment == "penalty":
            return potentials.penalty(gap, self.stiffness)
        if self.treatment == "augmented":
            return potentials.augmented(gap, self._multipliers_of(pairs), self.stiffness)
        if self.treatment == "barrier":
            return potentials.barrier(gap, self.stiffness, opts.barrier_activation * self.diameter)
        # exact: the active pairs are constraints; any other pair that
        # penetrates meets the penalty (a guard while the active set is being
        # found: it vanishes at a solution, where no inactive pair penetrates)
        value, first, second = potentials.penalty(gap, self.stiffness)
        if len(self.active):
            active = {(int(i), int(j)) for i, j in self.active}
            inactive = np.array([(int(i), int(j)) not in active for i, j in pairs], dtype=bool)
            value, first, second = value * inactive, first * inactive, second * inactive
        return value, first, second

    def _integral(self, q: np.ndarray, order: int):
        """:func:`~supercoil.contact.integral.integral_terms` of the pairs within reach
        at ``q``; the last call is remembered, and serves lower orders too."""
        st = self._state(q)
        x = self.centreline(q)
        key = np.ascontiguousarray(x, dtype=np.float64).tobytes()
        cached = self._integral_memo
        if cached is not None and cached[0] == key and cached[1] >= order \
                and cached[2] == self.stiffness:
            return st, cached[3]
        opts = self.options
        # the sample points of the pair state's search (remembered for this q), not
        # formed again per pair in the kernel
        terms = integral_terms(x.reshape(-1, 3), self.curve.sample_stencil,
                               self.curve.sample_weights, st.pairs, self.diameter, self.treatment,
                               self.stiffness, opts.barrier_activation * self.diameter,
                               self.edge_length, order, points=self.curve.sample_points(x))
        terms = (*terms[:5], self._scatter(terms[5]))  # the pair blocks' DOFs in q
        self._integral_memo = (key, order, self.stiffness, terms)
        return st, terms

    # ------------------------------------------------------------ energy
    def contact_energy(self, q: np.ndarray) -> float:
        if self.integral:
            return float(np.sum(self._integral(q, 0)[1][0]))
        st = self._state(q)
        if len(st.pairs) == 0:
            return 0.0
        value, _, _ = self._psi(st.distance - self.diameter, st.pairs)
        return float(np.sum(value))

    def energy(self, q: np.ndarray) -> float:
        return self.base.energy(q) + self.contact_energy(q)

    def gradient(self, q: np.ndarray) -> np.ndarray:
        g = self.base.gradient(q)
        if self.integral:
            _st, (_e, grad, _h, _f, _p, dofs) = self._integral(q, 1)
            np.add.at(g, dofs.ravel(), grad[: len(dofs)].ravel())
            return g
        st = self._state(q)
        if len(st.pairs):
            d, grad, _hess, dofs = self._pair_derivatives(q, st.pairs)
            _, first, _ = self._psi(d - self.diameter, st.pairs)
            np.add.at(g, dofs.ravel(), (first[:, None] * grad).ravel())
        return g

    def contact_hessian(self, q: np.ndarray) -> sp.csr_matrix:
        if self.integral:
            # the pair blocks in one compiled pass (scipy's COO path took 0.6 ms at
            # N = 200; the same pattern, duplicates summed in another order)
            dofs, local = self._integral_blocks(q)
            return block_csr(dofs, local, self.n_dofs)
        return self._pairs_contact_hessian(q)

    def _integral_blocks(self, q: np.ndarray):
        """``(dofs, blocks)`` of the integral formulation's contact Hessian at ``q``."""
        # a sample pair touching without force (penalty) weighs nothing here: the
        # one-sided closing stiffness of the pairs formulation is not added
        _st, (_e, _g, local, _f, _p, dofs) = self._integral(q, 2)
        return dofs, local

    def _pairs_contact_hessian(self, q: np.ndarray) -> sp.csr_matrix:
        one_sided = self.stability_mode and self.treatment in ("penalty", "augmented")
        D = self.diameter
        if one_sided:
            st = self.pair_state(q, max(self._cutoff(), D * (1 + self.options.tolerance)))
        else:
            st = self._state(q)
        n = self.n_dofs
        if len(st.pairs) == 0:
            return sp.csr_matrix((n, n))
        d, grad, hess, dofs = self._pair_derivatives(q, st.pairs)
        _, first, second = self._psi(d - D, st.pairs)
        if one_sided:
            # A pair touching without force sits on the kink of psi (C^1 only):
            # closing it costs k g^2/2, opening it nothing. Admissible second-order
            # directions cannot penetrate it, so its closing stiffness counts.
            touching = (second == 0) & (d - D <= self.options.tolerance * D)
            second = np.where(touching, self.stiffness, second)
        local = (second[:, None, None] * grad[:, :, None] * grad[:, None, :]
                 + first[:, None, None] * hess)
        return block_csr(dofs, local, n)

    def hessian(self, q: np.ndarray) -> HessianParts:
        """The rod's Hessian plus :meth:`contact_hessian`. The integral formulation's pair
        blocks are merged into the rod's matrix directly (:meth:`HessianParts.plus_blocks`,
        the entries of ``csr_add(rod, contact_hessian)`` bit for bit, without the
        intermediate matrix)."""
        parts = self.base.hessian(q)
        if self.integral:
            dofs, local = self._integral_blocks(q)
            return parts.plus_blocks(dofs, local)
        return parts.plus_sparse(self.contact_hessian(q))

    def lagrangian_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> HessianParts:
        """``hessian(q)`` plus ``constraint_hessian(q, multipliers)`` (the sum of
        :func:`~supercoil.solvers.newton.lagrangian_hessian`), bit for bit. The integral
        formulation's pair blocks and the constraint curvature are merged into the rod's
        matrix in one compiled pass (:meth:`HessianParts.plus_blocks` with ``then``)
        instead of a merge for the blocks and another for the curvature (``plus_sparse``)."""
        if not self.integral:
            parts = self.hessian(q)
            if self.n_constraints:
                parts = parts.plus_sparse(self.constraint_hessian(q, multipliers))
            return parts
        parts = self.base.hessian(q)
        dofs, local = self._integral_blocks(q)
        curvature = None
        if self.base.n_constraints and not len(self.active):
            # the rod's curvature as its arrays (constraint_curvature: the entries of
            # constraint_hessian, no matrix made), the only term without active pairs
            curvature = self.base.constraint_curvature(
                q, np.asarray(multipliers, dtype=float)[:self.base.n_constraints])
        elif self.n_constraints:
            curvature = self.constraint_hessian(q, multipliers)
        return parts.plus_blocks(dofs, local, curvature)

    def stability_view(self) -> ContactProblem:
        """This problem as the stability analysis must see it (shares the state).

        Penalty and augmented Lagrangian energies are only C¹ where a pair just
        touches without force; the view adds the closing stiffness of such
        pairs so that the unstable count does not include directions that
        would push through a touching pair (docs/model.md, "Stability").
        """
        view = copy.copy(self)
        view.stability_mode = True
        return view

    # ------------------------------------------------------- constraints
    def constraints(self, q: np.ndarray) -> np.ndarray:
        c = self.base.constraints(q)
        if self._slide_pin is not None:
            k, t, xk = self._slide_pin
            x = self.centreline(q).reshape(-1, 3)
            c = np.concatenate([c, [float(t @ (x[k] - xk))]])
        if len(self.active) == 0:
            return c
        d, _, _ = self.pair_distances(q, self.active)
        return np.concatenate([c, d - self.diameter])

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix:
        J = self.base.constraint_jacobian(q)
        if self._slide_pin is not None:
            k, t, _ = self._slide_pin
            row = sp.csr_matrix((t, (np.zeros(3, dtype=np.int64),
                                     self._scatter(3 * k + np.arange(3)))),
                                shape=(1, self.n_dofs))
            J = sp.vstack([J, row]).tocsr()
        if len(self.active) == 0:
            return J
        _d, grad, _hess, dofs = self._pair_derivatives(q, self.active)
        m = len(self.active)
        rows = np.repeat(np.arange(m), dofs.shape[1])
        Jc = sp.csr_matrix((grad.ravel(), (rows, dofs.ravel())), shape=(m, self.n_dofs))
        return sp.vstack([J, Jc]).tocsr()

    def constraint_jacobian_arrays(self, q: np.ndarray) -> CSRArrays | None:
        """The arrays of :meth:`constraint_jacobian`: the rod's own
        (:func:`~supercoil.solvers.problem.jacobian_arrays`) without a sliding pin or
        active contact constraints, else those of the stacked matrix."""
        if self._slide_pin is None and len(self.active) == 0:
            return jacobian_arrays(self.base, q)
        return CSRArrays.of(self.constraint_jacobian(q))

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix:
        m0 = self.n_equalities  # the sliding gauge is linear: no Hessian
        lam = np.asarray(multipliers, dtype=float)
        H = self.base.constraint_hessian(q, lam[: self.base.n_constraints])
        if len(self.active) == 0:
            return H
        _d, _grad, hess, dofs = self._pair_derivatives(q, self.active)
        return (H + block_csr(dofs, lam[m0:, None, None] * hess, self.n_dofs)).tocsr()

    # ------------------------------------------------------------ forces
    def pair_forces(self, q: np.ndarray, multipliers: np.ndarray | None = None):
        """``(PairState, force)`` of the pairs that carry a contact force at ``q``.

        Energy treatments: ``force = -psi'(g)``; exact: minus the multipliers
        of the active constraints (``multipliers`` is the full vector).
        """
        if self.treatment == "exact":
            m0 = self.n_equalities
            lam = np.zeros(len(self.active)) if multipliers is None else \
                np.asarray(multipliers, dtype=float)[m0:]
            if len(self.active) == 0:
                return self.pair_state(q, 0.0), np.zeros(0)
            d, s, t = self.pair_distances(q, self.active)
            return PairState(self.active.copy(), d, s, t), -lam
        if self.integral:
            # per pair: the integrated force and its force-weighted sample positions
            st, (_e, _g, _h, force, param, _dofs) = self._integral(q, 1)
            keep = force > 0
            return (PairState(st.pairs[keep], st.distance[keep], param[keep, 0],
                              param[keep, 1]), force[keep])
        st = self.pair_state(q, self._cutoff())
        if len(st.pairs) == 0:
            return st, np.zeros(0)
        _, first, _ = self._psi(st.distance - self.diameter, st.pairs)
        force = -first
        keep = force > 0
        return PairState(st.pairs[keep], st.distance[keep], st.s[keep], st.t[keep]), force[keep]
