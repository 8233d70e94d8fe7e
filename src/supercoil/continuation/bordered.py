"""Sparse LU of the bordered matrix of pseudo-arclength continuation.

    B = [[K, F_lambda], [b^T, b_lambda]],   K = [[H, J^T], [J, 0]],

``K`` the KKT matrix (singular at folds and bifurcation points), ``F_lambda``
the parameter derivative of the residual and ``b`` the arclength row. At a
regular point or a simple fold ``B`` is regular (Keller 1977), so ``B``
itself is factorised rather than ``K`` (block elimination through ``K^{-1}``
loses accuracy as ``K`` becomes singular; Govaerts 2000, ch. 3). The border
is appended after the banded KKT ordering of
:func:`supercoil.solvers.kkt.kkt_order` and factorised by SuperLU with partial
pivoting: the extra dense row and column add ``O(n)`` fill. The border row is
scaled to the size of ``K``'s entries (a row scaling of the equation, undone
in :meth:`BorderedFactor.solve`).

The rank-one terms of ``H = S + U diag(w) U^T`` (see
:class:`~supercoil.solvers.problem.HessianParts`) stay out of the sparse
matrix: with ``B = B_S + V diag(w) V^T`` (``V = [U; 0]``) the Woodbury identity
``B^-1 = B_S^-1 - B_S^-1 V (diag(1/w) + V^T B_S^-1 V)^-1 V^T B_S^-1`` gives
the solves.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from supercoil.solvers.kkt import SingularMatrixError, kkt_order
from supercoil.solvers.problem import HessianParts


class BorderedFactor:
    """Factorisation of ``[[H, J^T, f_x], [J, 0, f_mu], [b_x^T, b_mu^T, b_lambda]]``.

    ``hessian`` is on the ``n`` free DOFs, ``jacobian`` ``(m, n)``, ``column``
    (``F_lambda``) has length ``n + m`` and ``row`` (the arclength row, corner
    entry ``b_lambda`` last) ``n + m + 1``.
    ``order`` reuses a :func:`kkt_order` of the same pattern.
    Raises :class:`~supercoil.solvers.kkt.SingularMatrixError` when ``B`` is singular.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix, column: np.ndarray,
                 row: np.ndarray, order: np.ndarray | None = None):
        S = hessian.sparse.tocsr()
        n = S.shape[0]
        J = sp.csr_matrix(jacobian) if jacobian is not None else sp.csr_matrix((0, n))
        m = J.shape[0]
        size = n + m + 1
        column = np.asarray(column, dtype=float)
        row = np.asarray(row, dtype=float)
        if column.shape != (size - 1,) or row.shape != (size,):
            raise ValueError(f"border column and row must have lengths {size - 1}, {size}")
        K = sp.bmat([[S, J.T], [J, None]], format="csr") if m else S
        scale_k = float(abs(K).max()) if K.nnz else 1.0
        scale_row = float(np.max(np.abs(row)))
        if not np.isfinite(scale_row) or scale_row == 0.0:
            raise SingularMatrixError("the border row is zero or not finite")
        self.row_scale = scale_k / scale_row if scale_k > 0 else 1.0
        corner = row[-1] * self.row_scale
        B = sp.bmat([[K, sp.csr_matrix(column[:, None])],
                     [sp.csr_matrix(self.row_scale * row[None, :-1]), sp.csr_matrix([[corner]])]],
                    format="csc")
        self.kkt_order = kkt_order(S, J) if order is None else order
        self.order = np.concatenate([self.kkt_order, [size - 1]])
        try:
            self._lu = splu(B[self.order][:, self.order].tocsc(), permc_spec="NATURAL")
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise SingularMatrixError(f"bordered matrix is singular ({exc})") from None
        self.size = size
        r = len(hessian.coefficients)
        self._w = np.asarray(hessian.coefficients, dtype=float)
        self._V = np.zeros((size, r))
        if r:
            self._V[:n] = hessian.vectors.T
            self._BV = self._sparse_solve(self._V)
            self._small = np.diag(1.0 / self._w) + self._V.T @ self._BV

    def _sparse_solve(self, rhs: np.ndarray) -> np.ndarray:
        sol = self._lu.solve(np.ascontiguousarray(rhs[self.order]))
        out = np.empty_like(sol)
        out[self.order] = sol
        return out

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``B z = rhs`` (``rhs`` unscaled, ``(size,)`` or ``(size, k)``)."""
        rhs = np.array(rhs, dtype=float)
        rhs[-1] = rhs[-1] * self.row_scale
        z = self._sparse_solve(rhs)
        if len(self._w):
            z = z - self._BV @ np.linalg.solve(self._small, self._V.T @ z)
        if not np.all(np.isfinite(z)):
            raise SingularMatrixError("bordered solve produced non-finite values")
        return z
