"""The protocol the numerical layers see: an energy with equality constraints.

Solvers, stability and continuation never import the rod model; they work on
any object with this interface (tested on toy problems too).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.csr import csr_matvec, csr_restrict
from supercoil.solvers.csr_sum import csr_add


@dataclass(frozen=True)
class HessianParts:
    """A Hessian stored as sparse part plus a few symmetric rank-one terms.

    ``H = sparse + sum_k coefficients[k] * outer(vectors[k], vectors[k])``.
    ``sparse`` is ``(n, n)``; ``vectors`` is ``(r, n)``; ``coefficients`` ``(r,)``.
    The rank-one terms are kept apart so that the factorisation stays sparse
    (the uniform twist of an isotropic rod makes the writhe gradient dense).
    """

    sparse: sp.csr_matrix
    vectors: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    coefficients: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def restrict(self, free: np.ndarray) -> HessianParts:
        vectors = self.vectors[:, free] if self.vectors.size else np.zeros((0, free.size))
        return HessianParts(csr_restrict(self.sparse, free), vectors, self.coefficients)

    def plus_sparse(self, other: sp.spmatrix) -> HessianParts:
        return HessianParts(csr_add(self.sparse, other), self.vectors, self.coefficients)

    def dense(self) -> np.ndarray:
        full = self.sparse.toarray()
        for c, v in zip(self.coefficients, self.vectors):
            full += c * np.outer(v, v)
        return full

    def matvec(self, x: np.ndarray) -> np.ndarray:
        S = self.sparse
        if getattr(S, "format", None) == "csr" and S.dtype == np.float64 \
                and np.ndim(x) == 1 and np.shape(x)[0] == S.shape[1]:
            y = csr_matvec(S.indptr, S.indices, S.data, x, S.shape[1])  # scipy's sums
        else:
            y = S @ x
        for c, v in zip(self.coefficients, self.vectors):
            y = y + c * v * (v @ x)
        return y


class ConstrainedEnergy(Protocol):
    """Minimise (or make stationary) ``E(q)`` subject to ``c(q) = 0``, some DOFs fixed.

    ``mass`` (positive, shape ``(n_dofs,)``) is the metric in which eigenvalues
    are reported, so that they converge under mesh refinement. Optionally,
    ``gauge_dofs`` (a subset of ``fixed`` that only removes continuous
    symmetries) and ``symmetry_modes(q)`` (shape ``(r, n_dofs)``) let the
    stability analysis report eigenvalues independent of the pins.

    A problem is never changed by the numerical layers. Continuation needs a scalar
    parameter attribute and derives the problem at another value with
    ``at(**{name: value})`` (:mod:`supercoil.solvers.parameters`); a problem that
    carries reference frames from state to state gives ``carried_to(q)``, ``frames``
    and ``with_frames(frames)`` (:mod:`supercoil.solvers.carried`). A caller's own
    object without them is copied (shallowly) with the attribute set, or ``accept(q)``
    called, on the copy.
    """

    n_dofs: int
    n_constraints: int
    fixed: np.ndarray
    mass: np.ndarray

    def energy(self, q: np.ndarray) -> float: ...

    def gradient(self, q: np.ndarray) -> np.ndarray: ...

    def hessian(self, q: np.ndarray) -> HessianParts: ...

    def constraints(self, q: np.ndarray) -> np.ndarray: ...

    def constraint_jacobian(self, q: np.ndarray) -> sp.csr_matrix: ...

    def constraint_hessian(self, q: np.ndarray, multipliers: np.ndarray) -> sp.csr_matrix: ...


def free_dofs(problem: ConstrainedEnergy) -> np.ndarray:
    mask = np.ones(problem.n_dofs, dtype=bool)
    mask[np.asarray(problem.fixed, dtype=np.int64)] = False
    return np.flatnonzero(mask)
