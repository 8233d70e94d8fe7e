"""Newton's method for equality-constrained energies (Newton–KKT / SQP).

Each iteration solves the KKT system

    [[H_L, J^T], [J, 0]] [dq; lambda+] = -[grad E; c],
    H_L = hess E + sum_j lambda_j hess c_j,

on the free unknowns (fixed DOFs removed). Two globalisations:

* ``mode="minimize"``: the inertia of the KKT matrix is checked and ``H_L`` is
  shifted by ``delta * M`` until it is positive definite on ``ker J``
  (inertia correction, Nocedal & Wright 2006, sec. 18.3); the step is then a
  descent direction of the exact-penalty merit ``E + mu ||c||_1`` and an
  Armijo backtracking line search is applied to it. With
  ``inertia_test="curvature"`` the (costlier) inertia is replaced by the
  inertia-free test of Chiang & Zavala (2016): the shift is raised until the
  curvature ``dq^T H dq`` along the step is clearly positive. When the first
  test fails, a step along the most negative curvature direction is added
  (saddle escape, see :func:`_add_negative_curvature`). The curvature test
  only sees the step, so it can converge to a saddle whose unstable direction
  the steps never touched: callers that need a minimum check the inertia of
  the result (``solve_supercoiled_ring`` does, and restarts along the unstable
  mode).
* ``mode="stationary"``: plain Newton steps with backtracking on the norm of
  the KKT residual, which converges to saddle points as well (needed on
  unstable branches).

A problem may offer ``step_bound(q, dq)``: the largest admissible fraction of
the step (self-contact uses continuous collision detection); every step,
full steps included, is shortened to it; and ``admissible(q)``: a state it
refuses (e.g. a closed rod whose linking number or knot type changed) makes
the step be retried shorter; its optional ``refusal`` (a string) says why. In
``minimize`` mode a problem may also offer ``step_size_ratio(q, dq)`` (step length over its trust radius): a
longer step is replaced by the shifted step ``(H + delta M) dq = -g`` with
``delta`` raised until it fits (Levenberg–Marquardt-style damping).

Near the solution (residual below ``full_step_below``) full steps are taken,
so the local convergence is quadratic. Failures are returned as a status,
never raised or printed.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from supercoil.errors import InputError
from supercoil.solvers.errors import SingularMatrixError
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.problem import ConstrainedEnergy, HessianParts, free_dofs

log = logging.getLogger(__name__)

# the trust radius of a minimisation step is at least this many times the size of the
# constraints' own correction (_normal_step_ratio), which no shift shortens: below it the
# shift was raised without end (to 1e46 at a kicked straight rod whose edges were
# stretched by twice their length, L/D = 100, F L^2/A = 22500, N = 102) and the step
# overflowed
NORMAL_MARGIN = 1.5


class Status(enum.Enum):
    CONVERGED = "converged"
    ROUNDOFF_LIMITED = "converged to the round-off floor (the tolerance is below it)"
    MAX_ITERATIONS = "maximum number of iterations reached"
    LINE_SEARCH_FAILED = "line search failed to reduce the merit function"
    SINGULAR = "singular KKT matrix"
    NONFINITE = "non-finite energy, gradient or Newton step"

    @property
    def ok(self) -> bool:
        return self in (Status.CONVERGED, Status.ROUNDOFF_LIMITED)


@dataclass(frozen=True)
class NewtonOptions:
    """Options of :func:`newton`; validated on construction."""

    tolerance: float = 1e-10
    max_iterations: int = 60
    mode: str = "minimize"
    full_step_below: float = 1e-6
    armijo: float = 1e-4
    min_step: float = 1e-10
    max_step_norm: float = float("inf")
    inertia_test: str | None = None  # None: "exact" (callers such as contact pick otherwise)

    def __post_init__(self) -> None:
        if not (self.tolerance > 0):
            raise InputError(f"tolerance must be positive, got {self.tolerance!r}")
        if self.max_iterations < 1:
            raise InputError(f"max_iterations must be >= 1, got {self.max_iterations!r}")
        if self.mode not in ("minimize", "stationary"):
            raise InputError(f"mode must be 'minimize' or 'stationary', got {self.mode!r}")
        if self.inertia_test not in (None, "exact", "curvature"):
            raise InputError(f"inertia_test must be 'exact' or 'curvature', got "
                             f"{self.inertia_test!r}")
        if not (self.max_step_norm > 0):
            raise InputError(f"max_step_norm must be positive, got {self.max_step_norm!r}")


@dataclass(frozen=True)
class NewtonResult:
    q: np.ndarray
    multipliers: np.ndarray
    status: Status
    message: str
    iterations: int
    residual: float
    residual_history: tuple[float, ...] = field(default_factory=tuple)

    @property
    def converged(self) -> bool:
        return self.status.ok


def kkt_residual(problem: ConstrainedEnergy, q: np.ndarray, lam: np.ndarray,
                 free: np.ndarray) -> np.ndarray:
    g = problem.gradient(q)[free]
    if problem.n_constraints:
        g = g + problem.constraint_jacobian(q)[:, free].T @ lam
        return np.concatenate([g, problem.constraints(q)])
    return g


def least_squares_multipliers(problem: ConstrainedEnergy, q: np.ndarray,
                              free: np.ndarray) -> np.ndarray:
    """Multipliers minimising ``|grad E + J^T lambda|`` (``J J^T lambda = -J grad E``)."""
    if not problem.n_constraints:
        return np.zeros(0)
    from scipy.sparse.linalg import spsolve

    J = problem.constraint_jacobian(q)[:, free].tocsc()
    g = problem.gradient(q)[free]
    return np.atleast_1d(spsolve((J @ J.T).tocsc(), -(J @ g)))


def roundoff_floor(H, q: np.ndarray) -> float:
    """Smallest residual that round-off lets us certify: ``eps ||H||_inf ||q||_inf``.

    A rod's stiffness grows like ``A / h^3``, so the gradient of an exact
    equilibrium evaluated in floating point carries an error of about
    ``eps * ||H|| * ||q||`` (measured on the exact discrete circle: 0.04 to 0.3
    times this bound); asking for less would make Newton wander.
    """
    arrays = H.csr_arrays()
    if arrays is not None:
        # scipy's abs(S).sum(axis=1).max() (np.add.reduceat over the stored entries of
        # each non-empty row, the same sums) without the copy and matrix objects: 30 of
        # 35 us at N = 100, at every corrector iteration
        filled = np.flatnonzero(np.diff(arrays.indptr))
        norm_h = float(np.max(np.add.reduceat(np.abs(arrays.data), arrays.indptr[filled]))) \
            if filled.size else 0.0
    else:
        S = H.sparse
        norm_h = float(abs(S).sum(axis=1).max()) if S.nnz else 0.0
    return np.finfo(float).eps * norm_h * max(float(np.max(np.abs(q))), 1e-300)


def lagrangian_hessian(problem, q, lam) -> HessianParts:
    """Hessian of the Lagrangian ``E + lam . c`` on all ``n_dofs`` DOFs (restrict it to
    the DOFs wanted: one assembly can serve several restrictions). A problem may
    provide ``lagrangian_hessian(q, lam)``, the same matrix bit for bit in fewer passes
    (:meth:`~supercoil.contact.problem.ContactProblem.lagrangian_hessian`)."""
    own = getattr(problem, "lagrangian_hessian", None)
    if own is not None:
        return own(q, lam)
    parts = problem.hessian(q)
    if problem.n_constraints:
        parts = parts.plus_sparse(problem.constraint_hessian(q, lam))
    return parts


def _hessian(problem, q, lam, free):
    return lagrangian_hessian(problem, q, lam).restrict(free)


def _shifted_step(problem, q, free, H, J, mass, rhs, radius, opts):
    """Step of ``(H + delta M) dq + J^T lam = -g, J dq = -c`` for minimisation.

    ``delta`` starts at 0 and is raised until (i) the shifted Hessian is
    positive definite on ``ker J`` (``inertia_test="exact"``) or has clearly
    positive curvature along the step (``"curvature"``), and (ii) the step fits
    the problem's trust radius (``step_size_ratio <= radius``) when it defines
    one: a longer step is replaced by a shorter, better-conditioned one rather
    than scaled down, so near-null directions (a closed rod's material sliding)
    get gradient-like steps instead of huge ones (Levenberg–Marquardt). Returns
    ``(factor, solution, delta, whether the unshifted test failed)``.
    """
    n = len(free)
    diag_scale = float(np.max(np.abs(H.sparse.diagonal()))) / float(np.mean(mass))
    delta, order, negatives = 0.0, None, False
    sized = hasattr(problem, "step_size_ratio")
    if sized and J is not None and np.any(rhs[n:]):
        # the shift shortens the step towards the constraints' own correction, never
        # below it: a radius under that one is out of the shift's reach
        radius = max(radius, NORMAL_MARGIN * _normal_step_ratio(problem, q, free, J, mass,
                                                                 -rhs[n:]))
    factor = sol = None
    for attempt in range(80):
        factor = KKTFactor(H, J, shift=-delta, mass=mass, order=order)
        order = factor.order
        if opts.inertia_test in (None, "exact"):
            curved = factor.reduced_negative_count == 0
            sol = factor.solve(rhs) if curved or attempt == 79 else None
        else:
            sol = factor.solve(rhs)
            s = sol[:n]
            mass_norm = float(s @ (mass * s))
            curved = float(s @ H.matvec(s)) + delta * mass_norm > 1e-8 * diag_scale * mass_norm
        if not curved:
            negatives = negatives or attempt == 0
            # the curvature test starts from a small shift: a near-null direction
            # (a closed rod's material sliding) needs only a little
            delta = (max(2.0 * delta, 1e-4 * diag_scale) if opts.inertia_test != "curvature"
                     else max(4.0 * delta, 1e-8 * diag_scale))
            continue
        if sized:
            full = np.zeros_like(q)
            full[free] = sol[:n]
            if problem.step_size_ratio(q, full) > radius:
                delta = max(4.0 * delta, 1e-10 * diag_scale)
                continue
        break
    return factor, sol, delta, negatives


def _normal_step_ratio(problem, q, free, J, mass, c) -> float:
    """``step_size_ratio`` of the shortest step (M-norm) that corrects the linearised
    constraints, ``J s = -c``: ``s = -M^-1 J^T (J M^-1 J^T)^-1 c``, the limit of the
    shifted step ``(H + delta M, J)`` as ``delta`` grows (its energy part vanishes like
    ``1/delta``). 0 where ``J M^-1 J^T`` is singular (dependent constraints)."""
    J = sp.csr_matrix(J)
    scaled = J @ sp.diags(1.0 / mass)
    try:
        y = spla.splu(sp.csc_matrix(scaled @ J.T)).solve(np.asarray(c, dtype=float))
    except RuntimeError:  # "Factor is exactly singular"
        return 0.0
    if not np.all(np.isfinite(y)):
        return 0.0
    full = np.zeros_like(q)
    full[free] = -(scaled.T @ y)
    return float(problem.step_size_ratio(q, full))


def _symmetry_basis(problem, q, free, mass, factor, m: int) -> np.ndarray:
    """M-orthonormal basis ``(len(free), r)`` of the problem's ``near_symmetry_modes``
    (a closed rod's material sliding) as directions of ``ker J`` (``r = 0`` if it has
    none). A mode ``s`` on the free DOFs is generally not tangent to the constraints;
    one solve with the shifted factor, ``(H + delta M)^-1 M s`` on ``ker J``, keeps
    its nearly null part (the one inverse iteration would amplify) and is tangent."""
    getter = getattr(problem, "near_symmetry_modes", None)
    if getter is None:
        return np.zeros((len(free), 0))
    modes = np.asarray(getter(q), dtype=float).reshape(-1, problem.n_dofs)[:, free]
    if modes.size == 0:
        return np.zeros((len(free), 0))
    n = len(free)
    tangent = np.array([factor.solve(np.concatenate([mass * s, np.zeros(m)]))[:n]
                        for s in modes])
    root = np.sqrt(mass)
    qmat, rfac = np.linalg.qr(root[:, None] * tangent.T)
    diag = np.abs(np.diag(rfac))
    if not np.all(np.isfinite(diag)) or diag.max() == 0.0:
        return np.zeros((n, 0))
    return qmat[:, diag > 1e-10 * diag.max()] / root[:, None]


def _add_negative_curvature(problem, q, free, H, factor, sol, g, mass, n, m, radius):
    """Add a step along the most negative curvature direction (saddle escape).

    Near a saddle the shifted Newton step ``(H + delta M)^-1 g`` is short in the
    unstable direction (its gradient component is small), so minimisation
    creeps away from saddles. An eigenvector ``v`` of ``H v = mu M v`` on
    ``ker J`` is found by inverse iteration with the shifted factor (the
    eigenvalue nearest ``-delta``: the lowest one when ``H + delta M`` is
    positive definite on ``ker J``, as with the exact inertia test; with the
    curvature test it need not be), and, if ``mu < 0``, a multiple
    of ``v`` pointing downhill is added (Moré & Sorensen 1979): as long as the
    trust radius (at most 1) when the problem defines one, else as long as the
    Newton step.

    The problem's approximate symmetries (:func:`_symmetry_basis`: a closed rod's
    material sliding) are projected out of ``v``: along them the curvature is
    nearly null and its sign is noise, the energy gains nothing, and a long
    straight step along a sliding leaves the constraints at second order, so
    the line search cut every step to nothing (measured: a ring's winding under
    the contact barrier stalled for hundreds of iterations). A sliding step also
    carries a closed rod off its symmetric position on the mesh, where the
    discretisation's sliding ripple acts.
    """
    basis = _symmetry_basis(problem, q, free, mass, factor, m)
    v = np.random.default_rng(0).standard_normal(n)
    for _ in range(12):
        v = v - basis @ (basis.T @ (mass * v))
        z = factor.solve(np.concatenate([mass * v, np.zeros(m)]))[:n]
        z = z - basis @ (basis.T @ (mass * z))
        norm = float(np.sqrt(z @ (mass * z)))
        if not np.isfinite(norm) or norm == 0.0:
            return sol
        v = z / norm
    curvature = float(v @ H.matvec(v))
    if curvature >= 0:
        return sol
    if float(g @ v) > 0:
        v = -v
    full = np.zeros_like(q)
    full[free] = v
    if hasattr(problem, "step_size_ratio"):
        tau = min(radius, 1.0) / max(problem.step_size_ratio(q, full), 1e-300)
    else:
        tau = float(np.sqrt(sol[:n] @ (mass * sol[:n])))
    out = sol.copy()
    out[:n] += tau * v
    return out


def newton(problem: ConstrainedEnergy, q0: np.ndarray, options: NewtonOptions | None = None,
           multipliers: np.ndarray | None = None) -> NewtonResult:
    """Find an equilibrium of ``problem`` starting from ``q0`` (full DOF vector)."""
    opts = options or NewtonOptions()
    q = np.array(q0, dtype=float)
    free = free_dofs(problem)
    n, m = free.size, problem.n_constraints
    lam = (least_squares_multipliers(problem, q, free) if multipliers is None
           else np.array(multipliers, dtype=float))
    history: list[float] = []
    mu = 1.0
    # Trust radius in units of the problem's step_size_ratio, in [1/16, 1]:
    # shrunk when the line search cuts a step, regrown after full steps.
    radius = 1.0
    mass = problem.mass[free]

    def done(status: Status, message: str, it: int) -> NewtonResult:
        res = history[-1] if history else float("nan")
        return NewtonResult(q, lam, status, message, it, res, tuple(history))

    for it in range(opts.max_iterations + 1):
        g = problem.gradient(q)[free]
        c = problem.constraints(q) if m else np.zeros(0)
        J = problem.constraint_jacobian(q)[:, free] if m else None
        r = np.concatenate([g + J.T @ lam if m else g, c])
        if not np.all(np.isfinite(r)):
            return done(Status.NONFINITE, f"non-finite residual at iteration {it}", it)
        res = float(np.max(np.abs(r))) if r.size else 0.0
        history.append(res)
        if res <= opts.tolerance:
            return done(Status.CONVERGED,
                        f"converged in {it} iterations, residual {res:.2e} "
                        f"(tolerance {opts.tolerance:.1e})", it)
        H = _hessian(problem, q, lam, free)
        floor = roundoff_floor(H, q)
        if res <= floor:
            return done(Status.ROUNDOFF_LIMITED,
                        f"converged to the round-off floor in {it} iterations: residual "
                        f"{res:.2e} > tolerance {opts.tolerance:.1e}, but below "
                        f"eps*||H||*||q|| = {floor:.1e}, the accuracy to which the forces "
                        f"of {q.size // 3} nodes can be evaluated", it)
        if it == opts.max_iterations:
            break
        rhs = -np.concatenate([g, c])
        delta = 0.0
        try:
            if opts.mode == "minimize":
                factor, sol, delta, negatives = _shifted_step(problem, q, free, H, J, mass, rhs,
                                                              radius, opts)
                if negatives:
                    sol = _add_negative_curvature(problem, q, free, H, factor, sol, g, mass,
                                                  n, m, radius)
            else:
                factor = KKTFactor(H, J)
                sol = factor.solve(rhs)
        except SingularMatrixError as exc:
            return done(Status.SINGULAR, f"iteration {it}: {exc}", it)
        dq_free, lam_new = sol[:n], sol[n:]
        step_norm = float(np.linalg.norm(dq_free))
        if not np.isfinite(step_norm):
            # the shifted factor's solve overflowed (a KKT matrix near singular at every
            # shift tried): no step to take, rather than a non-finite state
            return done(Status.NONFINITE, f"iteration {it}: the Newton step is not finite",
                        it)
        if step_norm > opts.max_step_norm:
            dq_free *= opts.max_step_norm / step_norm
        dq = np.zeros_like(q)
        dq[free] = dq_free
        # Problems with an admissible set (self-contact) bound the step so that
        # nothing inadmissible happens along it (continuous collision detection).
        bound = problem.step_bound(q, dq) if hasattr(problem, "step_bound") else 1.0
        alpha = min(1.0, float(bound))
        if alpha < opts.min_step:
            return done(Status.LINE_SEARCH_FAILED,
                        f"iteration {it}: the step guard allows no step (fraction {bound:.1e}): "
                        f"the state is at the edge of the admissible set", it)
        if res > opts.full_step_below:
            if opts.mode == "minimize":
                mu = max(mu, 2.0 * float(np.max(np.abs(lam_new))) if m else 0.0)
                c0 = float(np.sum(np.abs(c)))
                phi0 = problem.energy(q) + mu * c0
                slope = float(g @ dq_free) - mu * c0

                def merit(qt, mu=mu):
                    ct = np.sum(np.abs(problem.constraints(qt))) if m else 0.0
                    return problem.energy(qt) + mu * ct

                first = True
                while alpha >= opts.min_step:
                    qt = q + alpha * dq
                    phit = merit(qt)
                    if np.isfinite(phit) and phit <= phi0 + opts.armijo * alpha * min(slope, 0.0):
                        break
                    if first and alpha == 1.0 and delta == 0.0 and np.isfinite(phit):
                        # A pure Newton step (no shift was needed) that halves the KKT
                        # residual is taken even if the merit rises: kinks of the
                        # contact terms (changes of distance type, C¹ only) otherwise
                        # stall the merit line search next to the solution (a
                        # filter-like second acceptance test, Fletcher & Leyffer 2002).
                        rt = kkt_residual(problem, qt, lam_new, free)
                        if np.all(np.isfinite(rt)) and np.max(np.abs(rt)) <= 0.5 * res:
                            break
                    if first and m and alpha == 1.0:
                        # Second-order correction (Nocedal & Wright 2006, alg. 18.3): the
                        # curvature of the constraints can make the l1 merit reject a good
                        # full step (Maratos effect); project it back onto c = 0 first.
                        soc = factor.solve(np.concatenate(
                            [np.zeros(n), -problem.constraints(qt)]))[:n]
                        q_soc = qt.copy()
                        q_soc[free] += soc
                        phis = merit(q_soc)
                        if np.isfinite(phis) and phis <= phi0 + opts.armijo * min(slope, 0.0):
                            dq = q_soc - q
                            bound_soc = (problem.step_bound(q, dq)
                                         if hasattr(problem, "step_bound") else 1.0)
                            if bound_soc >= 1.0:
                                break
                            dq = qt - q
                    first = False
                    alpha *= 0.5
            else:
                norm0 = float(np.linalg.norm(r))
                while alpha >= opts.min_step:
                    qt = q + alpha * dq
                    lt = lam + alpha * (lam_new - lam)
                    rt = kkt_residual(problem, qt, lt, free)
                    if np.all(np.isfinite(rt)) and np.linalg.norm(rt) <= (1 - 1e-4 * alpha) * norm0:
                        break
                    alpha *= 0.5
            if alpha < opts.min_step:
                log.debug("line search failed: slope %.3e, step %.3e, bound %.3g, delta %.3g",
                          slope if opts.mode == "minimize" else float("nan"),
                          float(np.max(np.abs(dq))), bound, delta)
                return done(Status.LINE_SEARCH_FAILED,
                            f"iteration {it}: no step length reduced the merit function "
                            f"(residual {res:.2e})", it)
        # A problem may refuse a state (a closed rod whose linking number
        # changed): the step is then retried shorter.
        if hasattr(problem, "admissible"):
            while alpha >= opts.min_step and not problem.admissible(q + alpha * dq):
                alpha *= 0.5
            if alpha < opts.min_step:
                reason = getattr(problem, "refusal", None)
                return done(Status.LINE_SEARCH_FAILED,
                            f"iteration {it}: every step length gave an inadmissible state"
                            + (f" ({reason})" if reason else ""), it)
        q = q + alpha * dq
        lam = lam + alpha * (lam_new - lam)
        problem.accept(q)
        # The trust radius grows after full steps and shrinks when the line
        # search (not the collision guard) had to cut the step.
        if alpha == 1.0:
            radius = min(2.0 * radius, 1.0)
        elif alpha < min(1.0, float(bound)):
            radius = max(0.5 * radius, 1 / 16)
        log.debug("newton it=%d residual=%.3e alpha=%.3g delta=%.3g bound=%.3g radius=%.3g", it, res, alpha, delta, bound, radius)
    return done(Status.MAX_ITERATIONS,
                f"no convergence in {opts.max_iterations} iterations "
                f"(residual {history[-1]:.2e} > tolerance {opts.tolerance:.1e})",
                opts.max_iterations)
