"""Sparse symmetric KKT factorisation with inertia.

The saddle-point matrix of an energy ``E`` with constraints ``c`` is

    K = [[H, J^T], [J, 0]],   H = S + U diag(w) U^T,

with ``S`` sparse (banded for a rod) and a few dense rank-one terms. We
factor the sparse part ``K_S`` by a symmetric ``L D L^T`` (SuperLU with
symmetric ordering and no row pivoting, so that ``diag(U) = D``) and treat
the rank-one terms with the Woodbury identity.

Inertia (Sylvester's law): the number of negative pivots of ``K_S`` is its
number of negative eigenvalues. For the bordered matrix
``B = [[K_S, U], [U^T, -diag(1/w)]]`` the two Schur complements give
``neg(K) = neg(K_S) + neg(-W^-1 - U^T K_S^-1 U) - neg(-W^-1)``.
For a constrained problem with ``m`` independent constraints,
``neg(K) = neg(Z^T H Z) + m`` (Gould 1985), where ``Z`` spans ``ker J``: the
number of unstable directions is ``neg(K) - m``.

Ordering: reverse Cuthill–McKee on the pattern of ``S + J^T J``, each
multiplier placed right after the last unknown its constraint touches, so the
profile stays banded and no multiplier is eliminated before its unknowns.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.sparse.linalg import splu

from supercoil.solvers.problem import HessianParts


class SingularMatrixError(RuntimeError):
    """The KKT matrix is (numerically) singular."""


def _ordering(S: sp.csr_matrix, J: sp.csr_matrix) -> np.ndarray:
    n = S.shape[0]
    m = J.shape[0]
    graph = (abs(S) + abs(J.T @ J) + sp.identity(n)).tocsr()
    x_order = np.asarray(reverse_cuthill_mckee(graph, symmetric_mode=True), dtype=np.int64)
    if m == 0:
        return x_order
    position = np.empty(n, dtype=np.int64)
    position[x_order] = np.arange(n)
    Jc = J.tocsr()
    last = np.full(m, -1, dtype=np.int64)
    for j in range(m):
        cols = Jc.indices[Jc.indptr[j] : Jc.indptr[j + 1]]
        if cols.size:
            last[j] = position[cols].max()
    # Stable merge: unknown k gets key 2k, constraint j gets key 2*last_j + 1.
    keys = np.concatenate([2 * np.arange(n), 2 * last + 1])
    items = np.concatenate([x_order, n + np.arange(m)])
    return items[np.argsort(keys, kind="stable")]


class KKTFactor:
    """Factorisation of ``[[H - shift*M, J^T], [J, 0]]`` with its inertia.

    ``hessian`` holds the sparse part and rank-one terms of ``H`` on the free
    unknowns, ``jacobian`` is ``(m, n)``; ``shift`` and ``mass`` (diagonal,
    ``(n,)``) are for shift-invert eigenvalue computations.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix | None = None,
                 shift: float = 0.0, mass: np.ndarray | None = None):
        S = hessian.sparse.tocsr()
        n = S.shape[0]
        if shift != 0.0:
            S = (S - shift * sp.diags(mass if mass is not None else np.ones(n))).tocsr()
        J = sp.csr_matrix((0, n)) if jacobian is None else sp.csr_matrix(jacobian)
        self.n = n
        self.m = J.shape[0]
        K = sp.bmat([[S, J.T], [J, None]], format="csc")
        perm = _ordering(S, J)
        self._perm = perm
        Kp = K[perm][:, perm].tocsc()
        self._dense = None
        try:
            lu = splu(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                      options={"SymmetricMode": True})
            if not np.array_equal(lu.perm_r, np.arange(Kp.shape[0])):
                raise RuntimeError("row pivoting occurred")
            pivots = lu.U.diagonal()
            if not np.all(np.isfinite(pivots)) or np.min(np.abs(pivots)) == 0.0:
                raise RuntimeError("zero pivot")
            self._lu = lu
            self._neg = int(np.sum(pivots < 0))
            self._logdet_sign = float(np.prod(np.sign(pivots)))
        except RuntimeError:
            # Fall back to a dense Bunch–Kaufman factorisation (pivoted, stable).
            if Kp.shape[0] > 6000:
                raise SingularMatrixError(
                    "sparse LDL^T without pivoting broke down on a large system; "
                    "the matrix is (nearly) singular")
            dense = Kp.toarray()
            eig = np.linalg.eigvalsh(dense)
            if np.min(np.abs(eig)) == 0.0:
                raise SingularMatrixError("KKT matrix is exactly singular") from None
            self._lu = None
            self._dense = sla.lu_factor(dense)
            self._neg = int(np.sum(eig < 0))
            self._logdet_sign = float(np.prod(np.sign(eig)))
        # Rank-one terms (Woodbury).
        r = len(hessian.coefficients)
        self._U = np.zeros((n + self.m, r))
        if r:
            self._U[:n] = hessian.vectors.T
        self._w = np.asarray(hessian.coefficients, dtype=float)
        self._neg_total = self._neg
        self._sign_total = self._logdet_sign
        if r:
            KU = self._solve_sparse(self._U)
            small = np.diag(1.0 / self._w) + self._U.T @ KU
            self._KU = KU
            self._small = small
            small_eig = np.linalg.eigvalsh(-small)
            self._neg_total = (self._neg + int(np.sum(small_eig < 0))
                               - int(np.sum(-1.0 / self._w < 0)))
            self._sign_total = self._logdet_sign * float(
                np.prod(np.sign(self._w)) * np.sign(np.linalg.det(small)))

    def _solve_sparse(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        rp = rhs[self._perm]
        if self._lu is not None:
            sol = self._lu.solve(rp)
        else:
            sol = sla.lu_solve(self._dense, rp)
        out = np.empty_like(sol)
        out[self._perm] = sol
        return out

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``K z = rhs`` for the full matrix (rank-one terms included)."""
        z = self._solve_sparse(rhs)
        if len(self._w):
            z = z - self._KU @ np.linalg.solve(self._small, self._U.T @ z)
        return z

    @property
    def negative_count(self) -> int:
        """Number of negative eigenvalues of the full KKT matrix."""
        return self._neg_total

    @property
    def reduced_negative_count(self) -> int:
        """Negative eigenvalues of ``H`` restricted to ``ker J`` (``neg(K) - m``)."""
        return self._neg_total - self.m

    @property
    def determinant_sign(self) -> float:
        """Sign of ``det K``; ``(-1)^m`` times this is the sign of ``det(Z^T H Z)``."""
        return self._sign_total
