"""The protocol the numerical layers see: an energy with equality constraints.

Solvers, stability and continuation never import the rod model; they work on
any object with this interface (tested on toy problems too).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.csr import CSRArrays, csr_matvec, csr_restrict, restrict_arrays
from supercoil.solvers.csr_sum import add_arrays, add_blocks_arrays, csr_add, csr_add_blocks


class HessianParts:
    """A Hessian stored as sparse part plus a few symmetric rank-one terms.

    ``H = sparse + sum_k coefficients[k] * outer(vectors[k], vectors[k])``.
    ``sparse`` is ``(n, n)``; ``vectors`` is ``(r, n)``; ``coefficients`` ``(r,)``.
    The rank-one terms are kept apart so that the factorisation stays sparse
    (the uniform twist of an isotropic rod makes the writhe gradient dense).

    The sparse part is given as a ``scipy.sparse`` matrix or as the
    :class:`~supercoil.solvers.csr.CSRArrays` of a canonical CSR matrix (a rod's
    assembly, its sums and restrictions): :attr:`sparse` is then made from them on
    first use, once. A Hessian is assembled, summed and restricted several times per
    Newton iteration, and most of those intermediate matrices were read by nobody but
    the next step (one ``scipy.sparse`` construction, with its checks, each).
    """

    def __init__(self, sparse, vectors: np.ndarray | None = None,
                 coefficients: np.ndarray | None = None):
        self._arrays = sparse if isinstance(sparse, CSRArrays) else None
        self._matrix = None if self._arrays is not None else sparse
        self.vectors = np.zeros((0, 0)) if vectors is None else vectors
        self.coefficients = np.zeros(0) if coefficients is None else coefficients

    @property
    def sparse(self) -> sp.spmatrix:
        """The sparse part as a ``scipy.sparse`` matrix (made once from the arrays)."""
        if self._matrix is None:
            self._matrix = self._arrays.tocsr()
        return self._matrix

    @property
    def shape(self) -> tuple[int, int]:
        return self.sparse.shape if self._arrays is None else self._arrays.shape

    def csr_arrays(self) -> CSRArrays | None:
        """The arrays of the sparse part if it is float64 CSR (shared: read only), else
        None."""
        return self._arrays if self._arrays is not None else CSRArrays.of(self._matrix)

    def restrict(self, free: np.ndarray) -> HessianParts:
        vectors = self.vectors[:, free] if self.vectors.size else np.zeros((0, free.size))
        arrays = self._arrays
        restricted = None if arrays is None else restrict_arrays(arrays, free)
        if restricted is None:
            restricted = csr_restrict(self.sparse, free)
        return HessianParts(restricted, vectors, self.coefficients)

    def plus_sparse(self, other) -> HessianParts:
        """The sparse part plus ``other`` (a ``scipy.sparse`` matrix or the
        :class:`~supercoil.solvers.csr.CSRArrays` of one):
        :func:`~supercoil.solvers.csr_sum.csr_add`, on the arrays when both are held
        as canonical arrays."""
        a = self._arrays
        b = other if isinstance(other, CSRArrays) else CSRArrays.of(other)
        if a is not None and a.canonical and b is not None and b.canonical \
                and a.shape == b.shape:
            return HessianParts(add_arrays(a, b), self.vectors, self.coefficients)
        if isinstance(other, CSRArrays):
            other = other.tocsr()
        return HessianParts(csr_add(self.sparse, other), self.vectors, self.coefficients)

    def plus_blocks(self, dofs: np.ndarray, blocks: np.ndarray, then=None) -> HessianParts:
        """The sparse part plus the dense ``blocks`` at ``dofs``, then plus ``then`` (a
        ``scipy.sparse`` matrix or the :class:`~supercoil.solvers.csr.CSRArrays` of one):
        :func:`~supercoil.solvers.csr_sum.csr_add_blocks`, the same entries bit for bit,
        on the arrays when the sparse part is held as arrays."""
        arrays = self._arrays
        c = then if then is None or isinstance(then, CSRArrays) else CSRArrays.of(then)
        summed = None
        if arrays is not None and (then is None or c is not None):
            summed = add_blocks_arrays(arrays, dofs, blocks, c)
        if summed is None:
            if isinstance(then, CSRArrays):
                then = then.tocsr()
            summed = csr_add_blocks(self.sparse, dofs, blocks, then)
        return HessianParts(summed, self.vectors, self.coefficients)

    def dense(self) -> np.ndarray:
        full = self.sparse.toarray()
        for c, v in zip(self.coefficients, self.vectors):
            full += c * np.outer(v, v)
        return full

    def matmat(self, X: np.ndarray) -> np.ndarray:
        """``H X`` for a dense ``(n, k)`` block ``X``."""
        Y = self.sparse @ X
        for c, v in zip(self.coefficients, self.vectors):
            Y += c * np.outer(v, v @ X)
        return Y

    def matvec(self, x: np.ndarray) -> np.ndarray:
        arrays = self.csr_arrays()
        if arrays is not None and np.ndim(x) == 1 and np.shape(x)[0] == arrays.shape[1]:
            y = csr_matvec(arrays.indptr, arrays.indices, arrays.data, x,
                           arrays.shape[1])  # scipy's sums
        else:
            y = self.sparse @ x
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


def jacobian_arrays(problem: ConstrainedEnergy, q: np.ndarray) -> CSRArrays | None:
    """The arrays of ``problem.constraint_jacobian(q)`` as :class:`~supercoil.solvers.csr.
    CSRArrays`: the problem's optional ``constraint_jacobian_arrays(q)`` (the rods' and
    contact problems', which make no ``scipy.sparse`` object), else those of its
    Jacobian; None for a Jacobian that is not a float64 CSR matrix."""
    own = getattr(problem, "constraint_jacobian_arrays", None)
    if own is not None:
        return own(q)
    return CSRArrays.of(problem.constraint_jacobian(q))
