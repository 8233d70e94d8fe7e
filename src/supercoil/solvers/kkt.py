"""Sparse symmetric KKT factorisation with inertia.

The saddle-point matrix of an energy ``E`` with constraints ``c`` is

    K = [[H, J^T], [J, 0]],   H = S + U diag(w) U^T,

with ``S`` sparse (banded for a rod) and a few dense rank-one terms
(treated with the Woodbury identity in both parts below).

Solves use an LU with partial pivoting on ``K`` in a banded ordering (stable for
saddle points): LAPACK's band LU where the ordered band is narrow, SuperLU
where it is wider than a quarter of the matrix (see :class:`KKTFactor` and
:mod:`supercoil.solvers.lu`), in the ordering of :mod:`supercoil.solvers.ordering`;
the matrix's entries come from :mod:`supercoil.solvers.kkt_matrix`.

Inertia. ``L D L^T`` without pivoting breaks down on saddle-point matrices
(element growth; measured wrong counts on a ring), and an augmented Hessian
``H + rho J^T J`` mis-signs eigenvalues of size ``O(1/rho)`` (measured: the
count flickers near Michell's threshold). The count is exact instead: block
elimination with look-ahead on the banded ordering and Haynsworth's inertia
additivity (:mod:`supercoil.solvers.inertia`). Since
``neg(K) = neg(Z^T H Z) + m`` (Gould 1985) for ``m`` independent constraints,
at least ``m`` must be found (checked).
With the rank-one terms, from the two Schur complements of
``[[K_S, U], [U^T, -W^-1]]`` (Haynsworth's inertia additivity, both ways):
``neg(K_S + U W U^T) = neg(K_S) + neg(-W^-1 - U^T K_S^-1 U) - neg(-W^-1)``.

Dense constraint rows (:func:`~supercoil.solvers.pinned_rows.dense_rows`: Doedel's integral phase condition
``<M g, q - q_0> = 0``, whose row is a whole symmetry mode) would make the
banded ordering as wide as the matrix. Each is replaced in the factorised
matrix by a *pin*, its own entry on one DOF (:class:`~supercoil.solvers.pinned_rows.PinnedRows`), which
keeps ``K_pin`` banded and as regular as with a node gauge; the rest of the
row and of its column is the symmetric rank-``2r`` term
``K = K_pin + E Delta^T + Delta E^T = K_pin + U W U^T``, ``U = [E, Delta]``,
``W = [[0, I], [I, 0]]`` (``E`` the unit columns of the pinned rows'
multipliers, ``Delta`` the dense rows less their pins), taken by the formula
above like the rank-one terms of ``H``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.inertia import symmetric_inertia
from supercoil.solvers.kkt_matrix import (
    canonical,
    kkt_band_layout,
    kkt_csr,
    kkt_entries,
    kkt_values,
    shifted,
)
from supercoil.solvers.lu import BandLU, OrderedLU
from supercoil.solvers.ordering import kkt_order
from supercoil.solvers.pinned_rows import PinnedRows
from supercoil.solvers.problem import HessianParts


def _woodbury_negatives(solve, U: np.ndarray, w_inverse: np.ndarray, w_negatives: int):
    """Return (H^-1 U, small, correction) for ``H + U W U^T``, ``w_inverse = W^-1``
    symmetric ``(k, k)`` with ``w_negatives = neg(-W^-1)``: ``small = W^-1 + U^T H^-1 U``
    and the correction ``neg(-small) - neg(-W^-1)`` of the negative count (module doc)."""
    HU = solve(U)
    small = w_inverse + U.T @ HU
    correction = int(np.sum(np.linalg.eigvalsh(-small) < 0)) - w_negatives
    return HU, small, correction


def kkt_negative_count(K: sp.spmatrix, n_constraints: int = 0,
                       order: np.ndarray | None = None) -> int:
    """Number of negative eigenvalues of a sparse symmetric (KKT) matrix.

    At least ``n_constraints`` must be found when the constraints are independent.
    """
    neg, zero, _ = symmetric_inertia(K, order)
    if zero or neg < n_constraints:
        raise InertiaError(
            f"the KKT matrix has {neg} negative and {zero} zero eigenvalues with "
            f"{n_constraints} constraints: it is singular or the constraints are dependent")
    return neg


class KKTFactor:
    """Factorisation of ``[[H - shift*M, J^T], [J, 0]]`` with its inertia.

    ``hessian`` holds the sparse part and rank-one terms of ``H`` on the free
    unknowns, ``jacobian`` is ``(m, n)``; ``shift`` and ``mass`` (diagonal,
    ``(n,)``) are for shift-invert eigenvalue computations; ``order`` reuses
    the :func:`~supercoil.solvers.ordering.kkt_order` of an earlier factor of the same pattern
    (:attr:`order`). The matrix is factorised by LAPACK's band LU (:class:`BandLU`)
    when the ordered band is narrow, else by SuperLU (:class:`OrderedLU`). The inertia is
    computed on first use of :attr:`reduced_negative_count`, from the matrices given
    (referenced, not copied: a caller must not change their entries in place while
    it uses the factor; none in the package does). Dense rows of
    ``J`` are pinned and their remainder taken by Woodbury's identity
    (module doc), so the sparse factorisation and the banded inertia see
    ``K_pin``; :attr:`order` is then :func:`~supercoil.solvers.ordering.kkt_order` of ``K_pin``'s pattern.
    Where ``K_pin`` is singular but ``K`` is not (the mode a dense row removes
    vanishes on its pinned DOF), ``K`` itself is factorised, as without pins.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix | None = None,
                 shift: float = 0.0, mass: np.ndarray | None = None,
                 order: np.ndarray | None = None):
        arrays = hessian.csr_arrays()
        if shift != 0.0 and arrays is not None and arrays.canonical:
            S = arrays  # only the shifted matrix is made
        else:
            S = hessian.sparse.tocsr()
        n = S.shape[0]
        if shift != 0.0:
            S = shifted(S, shift, mass if mass is not None else np.ones(n))
        if jacobian is None:
            J = sp.csr_matrix((0, n))
        else:  # scipy's csr_matrix of a csr_matrix shares its arrays
            J = jacobian if type(jacobian) is sp.csr_matrix else sp.csr_matrix(jacobian)
        self.n = n
        self.m = J.shape[0]
        self._S = S
        self._J = J
        self._hessian = hessian
        pinned = PinnedRows.of(J) if self.m else None
        if pinned is not None:
            try:
                self._factor(pinned, order)
                if np.all(np.isfinite(self._small)):
                    return
            except SingularMatrixError:
                pass
            order = None  # an order of the pinned pattern
        self._factor(None, order)

    def _factor(self, pinned: PinnedRows | None, order: np.ndarray | None) -> None:
        """Factorise ``K_pin`` (or ``K`` when ``pinned`` is None) and the low-rank terms."""
        S, J, hessian = self._S, self._J, self._hessian
        n, size = self.n, self.n + self.m
        self._pinned = pinned is not None
        J_factored = J if pinned is None else pinned.sparse
        # A banded ordering keeps the partial-pivoting LU within twice the band.
        self._order = kkt_order(S, J_factored) if order is None else order
        S, J_factored = canonical(S), canonical(J_factored)
        self._factored = (S, J_factored)
        # with the values: a straight rod stores zeros that couple far unknowns, whose
        # stored band is too wide (SuperLU then) where its nonzero band is narrow
        values = kkt_values(S, J_factored)
        layout = kkt_band_layout(S, J_factored, self._order, values=values)
        self._lu = BandLU.from_layout(self._order, layout, values)
        if self._lu is None:
            try:
                self._lu = OrderedLU(size, *kkt_entries(S, J_factored), self._order)
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularMatrixError(f"KKT matrix is singular ({exc})") from None
        r = len(hessian.coefficients)
        w = np.asarray(hessian.coefficients, dtype=float)
        columns = [np.zeros((size, r))]
        if r:
            columns[0][:n] = hessian.vectors.T
        w_inverse = np.diag(1.0 / w) if r else np.zeros((0, 0))
        w_negatives = int(np.sum(-1.0 / w < 0)) if r else 0
        # sign of det W (module doc): prod sign(w), times (-1)^k for [[0, I], [I, 0]]
        self._w_sign = int(np.prod(np.sign(w))) if r else 1
        if pinned is not None:
            E, Delta, gamma = pinned.low_rank(n, size)
            root = np.sqrt(gamma)
            columns += [E * root, Delta / root]  # balanced: E D^T = (E root)(D / root)^T
            k = pinned.rows.size
            swap = np.block([[np.zeros((k, k)), np.eye(k)], [np.eye(k), np.zeros((k, k))]])
            w_inverse = np.block([[w_inverse, np.zeros((r, 2 * k))],
                                  [np.zeros((2 * k, r)), swap]])
            self._w_sign *= (-1) ** k
            w_negatives += k  # -[[0, I], [I, 0]] has k eigenvalues -1 and k eigenvalues 1
        self._U = np.hstack(columns) if len(columns) > 1 else columns[0]
        self._has_low_rank = self._U.shape[1] > 0
        if self._has_low_rank:
            self._KU, self._small, self._woodbury_correction = _woodbury_negatives(
                self._lu.solve, self._U, w_inverse, w_negatives)
        self._reduced_neg: int | None = None

    @property
    def order(self) -> np.ndarray:
        return self._order

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``K z = rhs`` for the full matrix (rank-one terms included)."""
        z = self._lu.solve(np.asarray(rhs, dtype=float))
        if self._has_low_rank:
            z = z - self._KU @ np.linalg.solve(self._small, self._U.T @ z)
        return z

    @property
    def reduced_negative_count(self) -> int:
        """Negative eigenvalues of ``H`` restricted to ``ker J`` (exact inertia)."""
        if self._reduced_neg is None:
            K = kkt_csr(*self._factored)
            try:
                neg = kkt_negative_count(K, self.m, self._order)
            except InertiaError:
                if not self._pinned:
                    raise
                self._factor(None, None)
                return self.reduced_negative_count
            if self._has_low_rank:
                neg += self._woodbury_correction
            self._reduced_neg = neg - self.m
        return self._reduced_neg

    @property
    def negative_count(self) -> int:
        """Negative eigenvalues of the full KKT matrix (``reduced + m``)."""
        return self.reduced_negative_count + self.m

    @property
    def determinant_sign(self) -> int:
        """Sign of ``det K`` from the pivoted LU (permutation parities included)."""
        sign = self._lu.determinant_sign()
        if self._has_low_rank:
            # det(K_S + U W U^T) = det(K_S) det(W) det(W^-1 + U^T K_S^-1 U)
            sign *= self._w_sign * int(np.sign(np.linalg.det(self._small)))
        return sign
