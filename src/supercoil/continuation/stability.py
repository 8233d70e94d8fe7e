"""Stability at a point of a branch: inertia count, zero modes, determinant sign.

``unstable_count`` is the exact number of negative eigenvalues of the Hessian
of the Lagrangian on the tangent space of the constraints (and of the phase
conditions, if any), from the inertia of the KKT matrix on the free DOFs
(:class:`~supercoil.solvers.kkt.KKTFactor`; the problem's pins remove rigid
motions and gauges). Eigenvalues of ``H v = mu M v`` nearest zero come from
the eigenproblem of :mod:`supercoil.stability.analysis` (gauge pins
released, the problem's symmetry and near-symmetry modes removed as
constraints; the near-symmetries are removed from the inertia count as
there): dense below 100 unknowns, shift-invert Lanczos above (measured at
N = 200 on a contact state: 10 ms against 81 ms dense, same eigenvalues). Those with ``|mu| <= zero_tolerance``
are ``zero_modes`` and never signed, so ``unstable_count = max(found below
-tol, inertia - zero_modes)`` (as :func:`~supercoil.stability.analysis.analyse`).
``determinant_sign`` is the sign of ``det(Z^T H Z)``, seed 000's test: it is
the parity of the inertia and misses eigenvalues that cross in pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.kkt import InertiaError, KKTFactor, SingularMatrixError
from supercoil.stability.analysis import (
    _eigen_system,
    _lowest_pairs,
    dense_constrained_eigenpairs,
    goldstone_modes,
    near_symmetry_gauge,
)

_DENSE_BELOW = 100


@dataclass(frozen=True)
class PointStability:
    unstable_count: int
    zero_modes: int
    negative_count: int  # raw inertia of the constrained Hessian
    determinant_sign: int
    eigenvalues: np.ndarray  # (k,) ascending, the computed ones nearest zero
    modes: np.ndarray  # (k, n_dofs) M-orthonormal full DOF vectors

    @property
    def nearest_eigenvalue(self) -> float:
        if self.eigenvalues.size == 0:
            return float("nan")
        return float(self.eigenvalues[np.argmin(np.abs(self.eigenvalues))])

    def critical_modes(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` eigenpairs nearest zero: ``(values (k,), modes (k, n_dofs))``."""
        idx = np.argsort(np.abs(self.eigenvalues))[:k]
        return self.eigenvalues[idx], self.modes[idx]


def count_gauge(system: ExtendedSystem, x: np.ndarray) -> np.ndarray:
    """Positions (in ``system.free``) of the DOFs pinned out of the count at ``x``.

    The approximate symmetries (a closed rod's material sliding) leave the
    count as in :func:`~supercoil.stability.analysis.analyse`: by pinning a DOF
    (:func:`~supercoil.stability.analysis.near_symmetry_gauge`), unless the
    system's phase rows already remove them (a continuation started with
    ``near_symmetry_gauge``: one row per mode, coupled to it).
    """
    problem = system.problem
    q = system.q(x)
    modes = goldstone_modes(problem, q)
    if modes.size == 0:
        return np.zeros(0, dtype=np.int64)
    if system.r:
        g = modes[:, system.free]
        coupling = np.abs(system.P @ g.T) / np.outer(np.linalg.norm(system.P, axis=1),
                                                      np.linalg.norm(g, axis=1))
        if np.all(coupling.max(axis=0) > 0.1 / np.sqrt(system.n)):
            return np.zeros(0, dtype=np.int64)
        touched = system.free[np.flatnonzero(np.any(system.P != 0, axis=0))]
    else:
        touched = None
    dofs = near_symmetry_gauge(problem, q, exclude=touched)
    return np.searchsorted(system.free, dofs)


def _count_system(system: ExtendedSystem, x: np.ndarray, hessian=None):
    """``(H, J)`` of the count at ``x``: the system's, less the near-symmetry gauge
    (``hessian``: ``system.hessian(x)`` if already known)."""
    J = system.jacobian(x)
    H = system.hessian(x) if hessian is None else hessian
    drop = count_gauge(system, x)
    if drop.size:
        keep = np.setdiff1d(np.arange(system.n), drop)
        H = H.restrict(keep)
        J = J[:, keep]
    return H, J


def inertia(system: ExtendedSystem, x: np.ndarray, zero_tolerance: float | None = None,
            hessian=None) -> tuple[int, int]:
    """``(negative count, determinant sign)`` of the constrained Hessian at ``x``.

    Near-symmetry directions are removed from the count as in
    :func:`~supercoil.stability.analysis.analyse` (:func:`count_gauge`). With
    ``zero_tolerance``, an exactly singular Hessian (a special point located
    exactly) is handled: the count is then that of the eigenvalues below
    ``-zero_tolerance / 2`` (the inertia of ``H + M zero_tolerance / 2``) and
    the determinant sign is 0. ``hessian``: ``system.hessian(x)`` if already known.
    """
    H, J = _count_system(system, x, hessian)
    try:
        factor = KKTFactor(H, J, band=True)
        negative = factor.reduced_negative_count
        return negative, int(factor.determinant_sign * (-1) ** J.shape[0])
    except (SingularMatrixError, InertiaError):
        if zero_tolerance is None:
            raise
        mass = system.mass[np.setdiff1d(np.arange(system.n), count_gauge(system, x))]
        factor = KKTFactor(H, J, shift=-0.5 * zero_tolerance, mass=mass, band=True)
        return factor.reduced_negative_count, 0


def eigenpairs(system: ExtendedSystem, x: np.ndarray, n_wanted: int,
               full=None, fast: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of the constrained Hessian nearest zero: ``(values, (k, n_dofs) modes)``.

    ``full``: ``system.full_hessian(x)`` if already assembled; ``fast``: the
    shift-invert factor on the band LU and Lanczos in ARPACK's standard mode
    (:func:`~supercoil.stability.analysis._lowest_pairs`), eigenvalues equal to
    round-off, not bit for bit."""
    problem = system.problem
    system.set_parameter(x[-1])
    dofs, H, J, mass, sym = _eigen_system(problem, system.q(x), system.multipliers(x), full)
    m = J.shape[0] if J is not None else 0
    dim = dofs.size - m - sym.shape[1]
    if dim <= 0:
        return np.zeros(0), np.zeros((0, problem.n_dofs))
    if dim <= _DENSE_BELOW:
        values, vectors = dense_constrained_eigenpairs(H, J, mass, sym)
    else:
        values, vectors = _lowest_pairs(H, J, mass, n_wanted=min(n_wanted, dim - 2), n=dofs.size,
                                        m=m, symmetry=sym, force_sparse=True, fast=fast)
    modes = np.zeros((values.size, problem.n_dofs))
    modes[:, dofs] = vectors.T
    return values, modes


def point_stability(system: ExtendedSystem, x: np.ndarray, zero_tolerance: float,
                    n_modes: int, full=None, fast: bool = False) -> PointStability:
    """Stability report at the point ``x`` of the extended system (see module doc).

    ``full``: ``system.full_hessian(x)`` if already assembled (a converged
    correction's); ``fast``: as :func:`eigenpairs`.
    """
    full = system.full_hessian(x) if full is None else full
    neg, det_sign = inertia(system, x, zero_tolerance, full.restrict(system.free))
    values, modes = eigenpairs(system, x, neg + n_modes, full, fast)
    zero = int(np.sum(np.abs(values) <= zero_tolerance))
    below = int(np.sum(values < -zero_tolerance))
    # as analyse: at least what the eigensolver found below -tol, at least the
    # inertia less zero modes; the inertia wins when the eigensolver finds more
    # negatives than it counts
    unstable = max(below, neg - zero) if below <= neg else neg
    return PointStability(unstable, zero, neg, det_sign, values, modes)
