"""Toy problems for the generic continuation layer (each with a known answer; no tests here)."""

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.problem import HessianParts

BRATU_FOLD = 3.513830719125162  # continuum fold of -u'' = lambda e^u on (0, 1)


def _no_rank_one(n):
    return np.zeros((0, n)), np.zeros(0)


class Unconstrained:
    """The constraint half of the protocol for toys without constraints."""

    n_constraints = 0

    def constraints(self, q):
        return np.zeros(0)

    def constraint_jacobian(self, q):
        return sp.csr_matrix((0, self.n_dofs))

    def constraint_hessian(self, q, multipliers):
        return sp.csr_matrix((self.n_dofs, self.n_dofs))

    def accept(self, q):
        pass


class Bratu(Unconstrained):
    """-u'' = lambda e^u on (0, 1), u(0) = u(1) = 0, by finite differences (energy form).

    ``E = sum_i (u_{i+1} - u_i)^2 / (2h) - lambda h sum_{interior} e^{u_i}``, DOFs
    ``u_0 ... u_N`` with both ends fixed; mass ``h``. ``nonlocal_`` adds
    ``kappa (h sum u_i)^2 / 2``, whose Hessian ``kappa h^2 1 1^T`` is kept as a
    rank-one term (``rank_one=True``) or assembled into the sparse part.
    """

    def __init__(self, n_intervals: int, lam: float = 0.0, nonlocal_: float = 0.0,
                 rank_one: bool = True):
        self.N = n_intervals
        self.h = 1.0 / n_intervals
        self.n_dofs = n_intervals + 1
        self.fixed = np.array([0, n_intervals])
        self.mass = np.full(self.n_dofs, self.h)
        self.lam = lam
        self.kappa = nonlocal_
        self.rank_one = rank_one
        self.accepted: list[np.ndarray] = []

    def _interior(self):
        w = np.ones(self.n_dofs)
        w[self.fixed] = 0.0
        return w

    def energy(self, q):
        mean = self.h * np.sum(self._interior() * q)
        return float(np.sum(np.diff(q) ** 2) / (2 * self.h) + 0.5 * self.kappa * mean**2
                     - self.lam * self.h * np.sum(self._interior() * np.exp(q)))

    def gradient(self, q):
        g = np.zeros(self.n_dofs)
        d = np.diff(q) / self.h
        g[:-1] -= d
        g[1:] += d
        w = self._interior()
        g += self.kappa * self.h**2 * np.sum(w * q) * w
        return g - self.lam * self.h * w * np.exp(q)

    def hessian(self, q):
        n = self.n_dofs
        main = np.full(n, 2.0 / self.h)
        main[0] = main[-1] = 1.0 / self.h
        main = main - self.lam * self.h * self._interior() * np.exp(q)
        off = np.full(n - 1, -1.0 / self.h)
        S = sp.diags([off, main, off], [-1, 0, 1], format="csr")
        w = self.h * self._interior()
        if self.kappa and self.rank_one:
            return HessianParts(S, w[None, :], np.array([self.kappa]))
        if self.kappa:
            S = (S + self.kappa * sp.csr_matrix(np.outer(w, w))).tocsr()
        return HessianParts(S, *_no_rank_one(n))

    def parameter_derivative(self, q, multipliers, name):
        assert name == "lam"
        return -self.h * self._interior() * np.exp(q)

    def accept(self, q):
        self.accepted.append(np.array(q))


def bratu_midpoint_exact(lam: float, upper: bool) -> float:
    """u(1/2) of the continuum Bratu solution on the lower / upper branch.

    ``u = -2 ln[cosh((x - 1/2) theta / 2) / cosh(theta / 4)]`` with
    ``theta = sqrt(2 lambda) cosh(theta / 4)``; ``u(1/2) = 2 ln cosh(theta / 4)``.
    """
    from scipy.optimize import brentq

    def f(theta):
        return theta - np.sqrt(2 * lam) * np.cosh(theta / 4)

    theta_fold = 4 * 1.1996786402577338  # theta at the fold: tanh(t) = 1/t, t = theta/4
    theta = brentq(f, theta_fold, 60.0) if upper else brentq(f, 1e-12, theta_fold)
    return 2 * np.log(np.cosh(theta / 4))


class DiagonalQuartic(Unconstrained):
    """``E = sum_i (d_i - lambda) x_i^2 / 2 + (sum_i x_i^2)^2 / 4``.

    The trivial branch ``x = 0`` has unstable count ``#{d_i < lambda}``; pitchforks
    at ``lambda = d_i`` send branches ``x = a e_i, a^2 = lambda - d_i``. Equal
    ``d_i`` give an O(k) symmetry (eigenvalues crossing together). ``rotation_pairs``
    lists coordinate pairs rotated by the declared symmetry modes.
    """

    def __init__(self, d, lam: float = 0.0, rotation_pairs=()):
        self.d = np.asarray(d, dtype=float)
        self.n_dofs = self.d.size
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.ones(self.n_dofs)
        self.lam = lam
        self.rotation_pairs = tuple(rotation_pairs)
        self.max_move = np.inf
        self._counts = {"step_bound": 0}  # shared by the copies a continuation makes

    def energy(self, q):
        return float(0.5 * np.sum((self.d - self.lam) * q**2) + 0.25 * (q @ q) ** 2)

    def gradient(self, q):
        return (self.d - self.lam) * q + (q @ q) * q

    def hessian(self, q):
        diag = self.d - self.lam + (q @ q)
        return HessianParts(sp.csr_matrix(np.diag(diag) + 2 * np.outer(q, q)),
                            *_no_rank_one(self.n_dofs))

    def step_bound(self, q, dq):
        """Collision-guard stand-in: no step moves a coordinate by more than ``max_move``."""
        self._counts["step_bound"] += 1
        largest = float(np.max(np.abs(dq)))
        return 1.0 if largest <= self.max_move else self.max_move / largest

    @property
    def step_bound_calls(self) -> int:
        return self._counts["step_bound"]

    def symmetry_modes(self, q):
        """Generators of the rotations in the declared coordinate pairs, ``(r, n_dofs)``."""
        modes = np.zeros((len(self.rotation_pairs), self.n_dofs))
        for k, (i, j) in enumerate(self.rotation_pairs):
            modes[k, i], modes[k, j] = -q[j], q[i]
        return modes


class LoadedSphere:
    """A point on the unit sphere of R^n under a load: ``E = -lambda x_0 + sum_i d_i x_i^2 / 2``.

    Constraint ``c = (|x|^2 - 1) / 2``; the last DOF is fixed at 0 (exercises
    ``fixed``). With ``d_0 > d_i``, the pole ``x = e_0`` is stable for ``lambda
    > d_0 - d_1`` and bifurcates at ``lambda = d_0 - d_i``; the branch from
    ``d_0 - d_1`` has ``x_0 = lambda / (d_0 - d_1)``, ``x_1^2 = 1 - x_0^2``, and the
    multiplier ``mu = -x . grad E``. No ``parameter_derivative``: finite differences.
    """

    n_constraints = 1

    def __init__(self, d, lam: float):
        self.d = np.concatenate([np.asarray(d, dtype=float), [1.0]])
        self.n_dofs = self.d.size
        self.fixed = np.array([self.n_dofs - 1])
        self.mass = np.ones(self.n_dofs)
        self.lam = lam

    def energy(self, q):
        return float(-self.lam * q[0] + 0.5 * np.sum(self.d * q**2))

    def gradient(self, q):
        g = self.d * q
        g[0] -= self.lam
        return g

    def hessian(self, q):
        return HessianParts(sp.diags(self.d, format="csr"), *_no_rank_one(self.n_dofs))

    def constraints(self, q):
        return np.array([0.5 * (q @ q - 1.0)])

    def constraint_jacobian(self, q):
        return sp.csr_matrix(q[None, :])

    def constraint_hessian(self, q, multipliers):
        return sp.identity(self.n_dofs, format="csr") * float(multipliers[0])

    def accept(self, q):
        pass


def _one_active_dof(problem, d, lam: float) -> None:
    """The fields of a toy whose ``x_0`` carries the branch and whose other DOFs are
    ``d_i x_i^2 / 2`` (``d`` their stiffnesses), unit mass, nothing fixed."""
    problem.d = np.concatenate([[0.0], np.asarray(d, dtype=float)])
    problem.n_dofs = problem.d.size
    problem.fixed = np.zeros(0, dtype=np.int64)
    problem.mass = np.ones(problem.n_dofs)
    problem.lam = lam


class CircleOfEquilibria(Unconstrained):
    """``E = x_0^3 / 3 + (lambda^2 - 1) x_0 + sum_{i>=1} d_i x_i^2 / 2``.

    Its equilibria are the circle ``x_0^2 + lambda^2 = 1`` (the other ``x_i = 0``): a
    closed branch with folds at ``lambda = +-1``, stable (``d_i > 0``) where ``x_0 > 0``.
    """

    def __init__(self, d=(1.0, 2.0), lam: float = 0.0):
        _one_active_dof(self, d, lam)

    def energy(self, q):
        return float(q[0] ** 3 / 3 + (self.lam**2 - 1) * q[0] + 0.5 * np.sum(self.d * q**2))

    def gradient(self, q):
        g = self.d * q
        g[0] = q[0] ** 2 + self.lam**2 - 1
        return g

    def hessian(self, q):
        diag = self.d.copy()
        diag[0] = 2 * q[0]
        return HessianParts(sp.diags(diag, format="csr"), *_no_rank_one(self.n_dofs))

    def parameter_derivative(self, q, multipliers, name):
        assert name == "lam"
        g = np.zeros(self.n_dofs)
        g[0] = 2 * self.lam
        return g


class Helix(Unconstrained):
    """``E = |q - c(lambda)|^2 / 2`` with ``c = (cos(lambda/eps), sin(lambda/eps))``: the
    equilibria ``q = c(lambda)`` form a helix of pitch ``2 pi eps`` in ``(q, lambda)``, an
    open branch without folds that passes near its own earlier points every turn."""

    def __init__(self, eps: float, lam: float = 0.0):
        self.eps = eps
        self.n_dofs = 2
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.ones(2)
        self.lam = lam

    def _c(self):
        return np.array([np.cos(self.lam / self.eps), np.sin(self.lam / self.eps)])

    def energy(self, q):
        return float(0.5 * np.sum((q - self._c()) ** 2))

    def gradient(self, q):
        return q - self._c()

    def hessian(self, q):
        return HessianParts(sp.identity(2, format="csr"), *_no_rank_one(2))

    def parameter_derivative(self, q, multipliers, name):
        assert name == "lam"
        phase = self.lam / self.eps
        return np.array([np.sin(phase), -np.cos(phase)]) / self.eps



class Corner(Unconstrained):
    """``E = (lambda - 1) x_0 + a (x_0 r + delta^2 asinh(x_0 / delta)) / 2 + sum_{i>=1} d_i
    x_i^2 / 2`` with ``r = sqrt(x_0^2 + delta^2)``.

    Its equilibria are ``lambda = 1 - a sqrt(x_0^2 + delta^2)`` (the other ``x_i = 0``):
    two straight legs of slopes ``-+a`` joined by a fold at ``x_0 = 0``,
    ``lambda = 1 - a delta``, of radius of curvature ``delta (1 + a^2)^(3/2) / a``, where
    the tangent turns by ``2 atan(a)`` (a stand-in for a branch that runs into a stiff
    obstacle and turns back).
    """

    def __init__(self, a: float, delta: float, d=(1.0, 2.0), lam: float = 0.0):
        self.a, self.delta = a, delta
        _one_active_dof(self, d, lam)

    def energy(self, q):
        x, delta = q[0], self.delta
        bend = 0.5 * self.a * (x * np.hypot(x, delta) + delta**2 * np.arcsinh(x / delta))
        return float((self.lam - 1.0) * x + bend + 0.5 * np.sum(self.d[1:] * q[1:] ** 2))

    def gradient(self, q):
        g = self.d * q
        g[0] = self.lam - 1.0 + self.a * np.hypot(q[0], self.delta)
        return g

    def hessian(self, q):
        diag = self.d.copy()
        diag[0] = self.a * q[0] / np.hypot(q[0], self.delta)
        return HessianParts(sp.diags(diag, format="csr"), *_no_rank_one(self.n_dofs))

    def parameter_derivative(self, q, multipliers, name):
        assert name == "lam"
        g = np.zeros(self.n_dofs)
        g[0] = 1.0
        return g
