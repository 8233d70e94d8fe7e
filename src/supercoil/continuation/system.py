"""The extended system ``F(q, mu, lambda) = 0`` that continuation follows.

A :class:`~supercoil.solvers.problem.ConstrainedEnergy` whose energy depends on
a scalar parameter: the system keeps the problem it was given, unchanged, and
evaluates at ``x[-1]`` the problem ``problem.at(**{parameter: x[-1]})``
(:func:`~supercoil.solvers.parameters.problem_at`; the last one is kept, so that
the evaluations at one iterate share one). At an accepted point the system follows
the problem carried there (:meth:`ExtendedSystem.carry_to`). On the free DOFs (``problem.fixed`` removed) the unknowns are

    x = [q_free (n), mu (m), nu (r), lambda (1)],

``mu`` the multipliers of the problem's constraints and ``nu`` those of the
``r`` optional phase conditions ``P (q_free - q_phase) = 0``, ``P = S^T M``
with ``S`` the problem's symmetry modes at the branch start (see
:class:`~supercoil.continuation.options.ContinuationOptions`). The residual is

    F(x) = [grad E + J^T mu + P^T nu ; c ; P (q_free - q_phase)]   ((n + m + r,))

and its parameter derivative ``F_lambda`` comes from the problem's optional
``parameter_derivative(q, multipliers, name)`` (``(n_dofs + n_constraints,)``,
on all DOFs; None for a parameter it does not know) or else from a central difference with step
``finite_difference_step * max(1, |lambda|)`` (error ``O(step^2)``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.carried import carried
from supercoil.solvers.csr import (
    CSRArrays,
    csr_columns,
    csr_columns_map,
    csr_rmatvec,
    stack_arrays,
    transpose_matvec,
)
from supercoil.solvers.newton import lagrangian_hessian
from supercoil.solvers.parameters import problem_at
from supercoil.solvers.problem import (
    ConstrainedEnergy,
    HessianParts,
    free_dofs,
    jacobian_arrays,
)


class ExtendedSystem:
    """Residual, derivatives and layout of ``x`` for one branch (see module doc)."""

    def __init__(self, problem: ConstrainedEnergy, parameter: str, q_template: np.ndarray,
                 phase_modes: np.ndarray | None = None, q_phase: np.ndarray | None = None,
                 parameter_weight: float = 1.0, finite_difference_step: float = 6e-6):
        if not hasattr(problem, parameter):
            raise ValueError(f"the problem has no parameter attribute {parameter!r}")
        known = getattr(problem, "parameters", None)
        if getattr(problem, "at", None) is not None and known is not None \
                and parameter not in known:
            raise ValueError(f"{parameter!r} is not a parameter of the problem; valid: "
                             f"{', '.join(map(repr, known))}")
        self.problem = problem
        self.parameter = parameter
        self.free = free_dofs(problem)
        self.n = self.free.size
        self.m = int(problem.n_constraints)
        self.q_template = np.array(q_template, dtype=float)
        mass = np.asarray(problem.mass, dtype=float)[self.free]
        self.mass = mass
        if phase_modes is None or np.size(phase_modes) == 0:
            self.phase_modes = np.zeros((0, problem.n_dofs))
            self.P = np.zeros((0, self.n))
            self.q_phase = np.zeros(self.n)
            self.q_phase_full = np.zeros(0)
        else:
            self.phase_modes = np.atleast_2d(np.asarray(phase_modes, dtype=float))
            self.P = self.phase_modes[:, self.free] * mass[None, :]
            self.q_phase_full = np.array(q_phase, dtype=float)
            self.q_phase = self.q_phase_full[self.free]
        self.r = self.P.shape[0]
        self.size = self.n + self.m + self.r + 1
        # metric of the arclength: mass on q, nothing on multipliers, weight^2 on lambda
        self.weights = np.concatenate([mass, np.zeros(self.m + self.r),
                                       [parameter_weight**2]])
        self.fd_step = finite_difference_step
        self._phase_rows: tuple[np.ndarray, sp.csr_matrix, bool] | None = None
        # (problem, value, the problem at that value): see problem_at
        self._at: tuple[object, float, object] | None = None

    def set_phase(self, phase_modes: np.ndarray, q_phase: np.ndarray) -> None:
        """New phase rows of the same number (a moved gauge); the layout of ``x`` is kept."""
        phase_modes = np.atleast_2d(np.asarray(phase_modes, dtype=float))
        if phase_modes.shape[0] != self.r:
            raise ValueError(f"set_phase needs {self.r} rows, got {phase_modes.shape[0]}")
        self.phase_modes = phase_modes
        self.P = phase_modes[:, self.free] * self.mass[None, :]
        self.q_phase_full = np.array(q_phase, dtype=float)
        self.q_phase = self.q_phase_full[self.free]

    # -- layout -------------------------------------------------------------------------
    def pack(self, q: np.ndarray, multipliers: np.ndarray, lam: float,
             phase_multipliers: np.ndarray | None = None) -> np.ndarray:
        nu = np.zeros(self.r) if phase_multipliers is None else phase_multipliers
        return np.concatenate([np.asarray(q, float)[self.free],
                               np.asarray(multipliers, float).reshape(self.m), nu, [lam]])

    def reduced(self, full: np.ndarray) -> np.ndarray:
        """A stored tangent ``[dq (n_dofs), dmu (m), dlambda]`` (``Branch.tangents[k]``) in
        the layout of ``x`` (the free DOFs; the phase multipliers' part zero)."""
        n_dofs = self.problem.n_dofs
        full = np.asarray(full, dtype=float)
        return np.concatenate([full[:n_dofs][self.free], full[n_dofs:n_dofs + self.m],
                               np.zeros(self.r), full[-1:]])

    def q(self, x: np.ndarray) -> np.ndarray:
        out = self.q_template.copy()
        out[self.free] = x[:self.n]
        return out

    def multipliers(self, x: np.ndarray) -> np.ndarray:
        return x[self.n:self.n + self.m].copy()

    def all_multipliers(self, x: np.ndarray) -> np.ndarray:
        return x[self.n:self.n + self.m + self.r]

    @staticmethod
    def parameter_value(x: np.ndarray) -> float:
        return float(x[-1])

    def norm(self, v: np.ndarray) -> float:
        return float(np.sqrt(v @ (self.weights * v)))

    def full_tangent(self, t: np.ndarray) -> np.ndarray:
        """Tangent on all DOFs: ``[dq (n_dofs), dmu (m), dlambda]``."""
        dq = np.zeros(self.problem.n_dofs)
        dq[self.free] = t[:self.n]
        return np.concatenate([dq, t[self.n:self.n + self.m], t[-1:]])

    # -- a family the problem holds the states on -----------------------------------------
    def held(self, x: np.ndarray) -> np.ndarray:
        """``x`` projected by the problem's ``held_part(q, multipliers)`` where its optional
        ``holding`` is true (a symmetric family:
        :meth:`~supercoil.rod.open.ClampedRodEnergy.held_part`); ``x`` itself where the
        problem holds none."""
        if not getattr(self.problem, "holding", False):
            return x
        held = self.problem.held_part(self.q(x), x[self.n:self.n + self.m])
        return x if held is None else self._replaced(x, *held)

    def held_direction(self, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """The part of a step or tangent ``dx`` at ``x`` that stays on the problem's
        family (its ``held_direction(q, dq, dmultipliers)`` where ``holding``); ``dx``
        itself where the problem holds none."""
        if not getattr(self.problem, "holding", False):
            return dx
        dq = np.zeros(self.problem.n_dofs)
        dq[self.free] = dx[:self.n]
        held = self.problem.held_direction(self.q(x), dq, dx[self.n:self.n + self.m])
        return dx if held is None else self._replaced(dx, *held)

    def _replaced(self, x: np.ndarray, q: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
        """``x`` with its free DOFs from ``q`` (all DOFs) and its multipliers replaced."""
        out = np.array(x, dtype=float)
        out[:self.n] = q[self.free]
        out[self.n:self.n + self.m] = multipliers
        return out

    # -- residual and derivatives ----------------------------------------------------------
    def problem_at(self, lam: float):
        """The problem at the parameter value ``lam`` (``problem.at``); the last one is
        kept, for the same problem object and value."""
        lam = float(lam)
        memo = self._at
        if memo is not None and memo[0] is self.problem and memo[1] == lam:
            return memo[2]
        at = problem_at(self.problem, **{self.parameter: lam})
        self._at = (self.problem, lam, at)
        return at

    def carry_to(self, q: np.ndarray) -> None:
        """Follow the problem carried to ``q`` (``problem.carried_to``,
        :func:`~supercoil.solvers.carried.carried`): ``problem`` is then that new problem,
        the one given before unchanged."""
        self.problem = carried(self.problem, q)

    def _free_columns(self, J: CSRArrays):
        """``(data, indices, indptr)`` of ``J[:, free]`` for the arrays of a CSR float64
        ``J`` (those of :func:`csr_columns`). The column map is kept for the last
        pattern (shape, ``indptr`` and ``indices`` compared as bytes): a Jacobian of
        that pattern is restricted without ``csr_columns``' checks of the free DOFs and
        memo look-up (15 -> 4 us at N = 100)."""
        remembered = self.__dict__.get("_free_columns_map")
        indptr, indices = J.indptr.tobytes(), J.indices.tobytes()
        if remembered is None or remembered[0] != J.shape or remembered[1] != indptr \
                or remembered[2] != indices or remembered[4] is not self.free:
            maps = csr_columns_map(J, self.free)
            if maps is None:
                return None
            remembered = (J.shape, indptr, indices, maps, self.free)
            self._free_columns_map = remembered
        selected, free_indices, free_indptr = remembered[3]
        return J.data[selected], free_indices, free_indptr

    def _kkt_residual(self, q: np.ndarray, mu: np.ndarray, p=None) -> np.ndarray:
        """``[grad E + J^T mu ; c]`` on the free DOFs of ``p`` (default: the problem).

        ``J^T mu`` is summed on all DOFs and its free entries taken: each free column
        gets the same terms in the same order as from ``J[:, free]`` (rows in order),
        so the same sums, without the restricted matrix."""
        p = self.problem if p is None else p
        g = p.gradient(q)
        if self.m:
            # scipy's J.T @ mu (csc_matvec on the transpose, the same sums) without the
            # transpose object and the operator dispatch (35 µs at N = 200), from the
            # Jacobian's arrays where the problem gives them
            J = jacobian_arrays(p, q)
            if J is None:
                g = g + transpose_matvec(p.constraint_jacobian(q), mu)
            else:
                g = g + csr_rmatvec(J.indptr, J.indices, J.data, mu, J.shape[1])
            return np.concatenate([g[self.free], p.constraints(q)])
        return g[self.free]

    def residual(self, x: np.ndarray) -> np.ndarray:
        q = self.q(x)
        mu = x[self.n:self.n + self.m]
        F = self._kkt_residual(q, mu, self.problem_at(x[-1]))
        if self.r:
            nu = x[self.n + self.m:self.n + self.m + self.r]
            F[:self.n] += self.P.T @ nu
            F = np.concatenate([F, self.P @ (x[:self.n] - self.q_phase)])
        return F

    def hessian(self, x: np.ndarray) -> HessianParts:
        """Hessian of the Lagrangian on the free DOFs (phase conditions are linear)."""
        return lagrangian_hessian(self.problem_at(x[-1]), self.q(x),
                                  x[self.n:self.n + self.m]).restrict(self.free)

    def full_hessian(self, x: np.ndarray) -> HessianParts:
        """Hessian of the Lagrangian on all DOFs: :meth:`hessian` is its restriction to
        the free ones (the same entries), the stability's eigenproblem another."""
        return lagrangian_hessian(self.problem_at(x[-1]), self.q(x), x[self.n:self.n + self.m])

    def jacobian(self, x: np.ndarray) -> sp.csr_matrix:
        """Constraint Jacobian on the free DOFs with the phase rows, ``(m + r, n)``: the
        scipy matrix of :meth:`jacobian_arrays`, returned again (the same object:
        callers must not modify it) while those are the same."""
        arrays = self.jacobian_arrays(x)
        made = self.__dict__.get("_jacobian_csr")
        if made is not None and made[0] is arrays:
            return made[1]
        out = arrays.tocsr() if isinstance(arrays, CSRArrays) else arrays
        self._jacobian_csr = (arrays, out)
        return out

    def jacobian_arrays(self, x: np.ndarray) -> CSRArrays | sp.csr_matrix:
        """The arrays of :meth:`jacobian` (:class:`~supercoil.solvers.csr.CSRArrays`),
        which the corrector's factors read without a ``scipy.sparse`` object: those of
        the problem's Jacobian restricted to the free columns and of the phase rows,
        stacked (:func:`~supercoil.solvers.csr.stack_arrays`); the scipy matrix itself
        for a problem whose Jacobian is not a float64 CSR matrix. Returned again (the
        same object: callers must not modify it) while the problem returns the same
        Jacobian and the phase rows are unchanged (a corrector's residual, factor and
        refinement at one iterate)."""
        p, q = self.problem_at(x[-1]), self.q(x)
        J = jacobian_arrays(p, q) if self.m else None
        if self.m and J is None:
            J = p.constraint_jacobian(q)
        if self.r and (self._phase_rows is None or self._phase_rows[0] is not self.P):
            P = sp.csr_matrix(self.P)
            self._phase_rows = (self.P, P, bool(P.has_canonical_format))
        stacked = self.__dict__.get("_stacked")
        if stacked is not None and stacked[0] is J and stacked[1] is self._phase_rows:
            return stacked[2]
        blocks, canonical = [], True
        if self.m:
            free = self._free_columns(J) if isinstance(J, CSRArrays) else None
            if free is None:  # not CSR float64: scipy's slicing and stacking
                rows = [sp.csr_matrix(csr_columns(J, self.free))]
                if self.r:
                    rows.append(self._phase_rows[1])
                out = sp.vstack(rows, format="csr")
                self._stacked = (J, self._phase_rows, out)
                return out
            blocks.append((*free, self.m))
            canonical = J.canonical
        if self.r:
            P = self._phase_rows[1]
            blocks.append((P.data, P.indices, P.indptr, self.r))
            canonical = canonical and self._phase_rows[2]
        if not blocks:
            out = CSRArrays(np.zeros(0), np.zeros(0, dtype=np.int32),
                            np.zeros(1, dtype=np.int32), (0, self.n), True)
        else:
            out = stack_arrays(blocks, self.n, canonical)
        self._stacked = (J, self._phase_rows, out)
        return out

    def parameter_derivative(self, x: np.ndarray) -> np.ndarray:
        """``dF/dlambda`` at ``x``, shape ``(n + m + r,)``."""
        lam = float(x[-1])
        q = self.q(x)
        mu = x[self.n:self.n + self.m]
        p = self.problem_at(lam)
        derivative = getattr(p, "parameter_derivative", None)
        full = None
        if derivative is not None:
            full = derivative(q, mu, self.parameter)
        if full is not None:
            full = np.asarray(full, dtype=float)
            out = np.concatenate([full[self.free], full[p.n_dofs:p.n_dofs + self.m]])
        else:
            step = self.fd_step * max(1.0, abs(lam))
            plus = self._kkt_residual(q, mu,
                                      problem_at(self.problem, **{self.parameter: lam + step}))
            minus = self._kkt_residual(q, mu,
                                       problem_at(self.problem, **{self.parameter: lam - step}))
            out = (plus - minus) / (2.0 * step)
        return np.concatenate([out, np.zeros(self.r)])
