"""Sparse LU of the bordered matrix of pseudo-arclength continuation.

    B = [[K, F_lambda], [b^T, b_lambda]],   K = [[H, J^T], [J, 0]],

``K`` the KKT matrix (singular at folds and bifurcation points), ``F_lambda``
the parameter derivative of the residual and ``b`` the arclength row. At a
regular point or a simple fold ``B`` is regular (Keller 1977), so ``B``
itself is factorised rather than ``K`` (block elimination through ``K^{-1}``
loses accuracy as ``K`` becomes singular; Govaerts 2000, ch. 3). The border
is appended after the banded KKT ordering of
:func:`supercoil.solvers.ordering.kkt_order` and factorised by SuperLU with partial
pivoting: the extra dense row and column add ``O(n)`` fill. The border row is
scaled to the size of ``K``'s entries (a row scaling of the equation, undone
in :meth:`BorderedFactor.solve`).

The rank-one terms of ``H = S + U diag(w) U^T`` (see
:class:`~supercoil.solvers.problem.HessianParts`) stay out of the sparse
matrix: with ``B = B_S + V diag(w) V^T`` (``V = [U; 0]``) the Woodbury identity
``B^-1 = B_S^-1 - B_S^-1 V (diag(1/w) + V^T B_S^-1 V)^-1 V^T B_S^-1`` gives
the solves.

Dense constraint rows (an integral phase condition) are pinned to one DOF in
the banded block and their remainder becomes extra borders (``k = 1 + 2r``
in all, :class:`BorderedFactor`), so that the band LU of
:class:`~supercoil.continuation.band_bordered.BandBordered` still applies. The
entries of ``B`` in the factor's ordering are made by
:mod:`supercoil.continuation.bordered_matrix`.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from supercoil._numba import njit
from supercoil.continuation.band_bordered import BandBordered
from supercoil.continuation.bordered_matrix import bordered_values, remembered_layout
from supercoil.solvers.csr import CSRArrays, csr_matvec, csr_rmatvec, is_canonical_float
from supercoil.solvers.errors import SingularMatrixError
from supercoil.solvers.kkt_matrix import canonical, kkt_band_layout, kkt_values
from supercoil.solvers.ordering import remembered_order
from supercoil.solvers.patterns import PatternMemo, pattern_words, same_words
from supercoil.solvers.pinned_rows import PinnedRows, has_long_rows
from supercoil.solvers.problem import HessianParts

# The band LU takes K when its band kl + ku + 1 is at most this fraction of its size
# (else SuperLU). Measured at N = 100 on the tweezers' contact branch (387 unknowns):
# at the widest band met, 97 (0.25), the band LU 0.21 ms against 0.33 ms for SuperLU;
# at 61-95, 0.22-0.25 ms against 0.26-0.42 ms. A quarter sent 67 of its factorisations
# at 97 to SuperLU.
BAND_FRACTION = 1.0 / 3.0


class _FactorPattern:
    """What :class:`BorderedFactor` takes from the pattern of its operands
    (:meth:`BorderedFactor._pattern`): ``words`` (the key's, None when not remembered),
    ``order_memo`` (the ordering's certificate), ``kkt_order`` and ``order`` (with the
    border last), the border's nonzeros ``col_at``, ``row_at``, ``layout``
    (:func:`~supercoil.continuation.bordered_matrix.bordered_layout`) and ``band`` (the band layout of ``K``, None for
    SuperLU)."""

    __slots__ = ("band", "col_at", "kkt_order", "layout", "order", "order_memo", "row_at",
                 "words")

    @property
    def nbytes(self) -> int:
        """For PatternMemo's memory bound: everything it holds, the layouts shared with
        their own memos included (they stay alive while this does)."""
        arrays = [self.col_at, self.kkt_order, self.order, self.row_at, self.words,
                  *self.layout]
        return sum(int(a.nbytes) for a in arrays) \
            + (0 if self.band is None else self.band.nbytes)


_PATTERNS = PatternMemo()
_NO_INDICES = np.zeros(0, dtype=np.int64)


@njit()
def _all_finite(values) -> bool:
    """``np.all(np.isfinite(values))``, compiled (12 µs of numpy's calls a solve)."""
    for x in values:
        if not math.isfinite(x):
            return False
    return True

class BorderedFactor:
    """Factorisation of ``[[H, J^T, f_x], [J, 0, f_mu], [b_x^T, b_mu^T, b_lambda]]``.

    ``hessian`` is on the ``n`` free DOFs, ``jacobian`` ``(m, n)`` (a CSR matrix or
    its :class:`~supercoil.solvers.csr.CSRArrays`), ``column``
    (``F_lambda``) has length ``n + m`` and ``row`` (the arclength row, corner
    entry ``b_lambda`` last) ``n + m + 1``.
    ``order`` reuses a :func:`~supercoil.solvers.ordering.kkt_order` of the same pattern (of the pinned
    ``J`` when it has dense rows).

    Dense rows of ``J`` (:func:`~supercoil.solvers.pinned_rows.dense_rows`: an
    integral phase condition, Doedel's ``<M g, q - q_0> = 0``) would make the
    band as wide as the matrix and send the factorisation to SuperLU. Each is
    pinned instead (:class:`~supercoil.solvers.pinned_rows.PinnedRows`): the banded
    block is ``K_pin``, the KKT matrix with the row replaced by its entry on
    one DOF (as regular as with a node gauge), and the rest of the row and of
    its column, ``E Delta^T + Delta E^T``, goes into ``2r`` auxiliary borders
    of :class:`~supercoil.continuation.band_bordered.BandBordered`; refinement is against the true ``B``.
    Raises :class:`~supercoil.solvers.errors.SingularMatrixError` when ``B`` is singular.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix | CSRArrays, column: np.ndarray,
                 row: np.ndarray, order: np.ndarray | None = None):
        # the sparse part's arrays where they are canonical (a pattern met before needs
        # nothing else of it); its scipy matrix for a new pattern (_pattern)
        S = hessian.csr_arrays()
        if S is None or not S.canonical:
            S = hessian.sparse.tocsr()
        n = S.shape[0]
        if jacobian is None:
            J = sp.csr_matrix((0, n))
        elif isinstance(jacobian, CSRArrays) or type(jacobian) is sp.csr_matrix:
            J = jacobian  # the arrays are read; a pattern not remembered converts them
        else:
            J = sp.csr_matrix(jacobian)
        m = J.shape[0]
        size = n + m + 1
        column = np.asarray(column, dtype=float)
        row = np.asarray(row, dtype=float)
        if column.shape != (size - 1,) or row.shape != (size,):
            raise ValueError(f"border column and row must have lengths {size - 1}, {size}")
        k_data = np.concatenate([S.data, J.data]) if m else S.data
        scale_k = float(np.max(np.abs(k_data))) if k_data.size else 1.0
        scale_row = float(np.max(np.abs(row)))
        if not math.isfinite(scale_row) or scale_row == 0.0:
            raise SingularMatrixError("the border row is zero or not finite")
        self.row_scale = scale_k / scale_row if scale_k > 0 else 1.0
        scaled_row = self.row_scale * row  # the border row, then the corner
        border_row, corner = scaled_row[:-1], scaled_row[-1]
        pattern, pinned, S, J, J_banded = self._pattern(S, hessian, J, column, border_row,
                                                        corner, scaled_row, order)
        self.kkt_order = pattern.kkt_order.copy()
        self.order = pattern.order
        band = pattern.band
        by_row, pcol, indptr = pattern.layout[:3]
        values, b_max, flat, C, R = bordered_values(
            S.data, J.data, J_banded.data, column, pattern.col_at, border_row,
            pattern.row_at, corner, by_row, _NO_INDICES if band is None else band.positions,
            0 if band is None else band.storage_size, self.kkt_order)
        Bp = CSRArrays(values, pcol, indptr, (size, size))
        D = np.array([[corner if corner != 0.0 else 0.0]])  # -0.0 as the matrix stores it
        if pinned is not None:
            # K_pin banded, the rest of the dense rows and columns as 2r auxiliary
            # borders (class doc): [[K_pin, c, root E, Delta / root], [r^T, d, 0, 0],
            # [Delta^T / root, 0, -I, 0], [root E^T, 0, 0, -I]]
            E, Delta, gamma = pinned.low_rank(n, size - 1)
            E, Delta, root = E[self.kkt_order], Delta[self.kkt_order], np.sqrt(gamma)
            C = np.hstack([C, E * root, Delta / root])
            R = np.hstack([R, Delta / root, E * root])
            k = 2 * pinned.rows.size
            D = np.block([[D, np.zeros((1, k))], [np.zeros((k, 1)), -np.eye(k)]])
        self._lu = None
        if band is not None and band.size >= 2 and S.data.size + 2 * J_banded.data.size:
            self._lu = BandBordered.from_storage(Bp, band, flat, C, R, D, b_max)
        if self._lu is None:
            try:
                self._lu = splu(Bp.tocsc(), permc_spec="NATURAL")
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularMatrixError(f"bordered matrix is singular ({exc})") from None
        self.size = size
        self.row = row
        r = len(hessian.coefficients)
        self._w = np.asarray(hessian.coefficients, dtype=float)
        self._V = np.zeros((size, r))
        if r:
            self._V[:n] = hessian.vectors.T
            self._BV = self._sparse_solve(self._V)
            self._small = np.diag(1.0 / self._w) + self._V.T @ self._BV

    @staticmethod
    def _pattern(S, hessian, J, column, border_row, corner, scaled_row, order):
        """What the factor of these operands takes from their pattern:
        ``(pattern, pinned, S, J, J_banded)`` (a :class:`_FactorPattern`, the
        :class:`~supercoil.solvers.pinned_rows.PinnedRows` of ``J`` or None, the canonical
        ``S``, ``J`` and the banded block's ``J``). ``S``: the sparse part of ``hessian``
        or its canonical :class:`~supercoil.solvers.csr.CSRArrays`; a pattern not
        remembered takes its scipy matrix (``hessian.sparse``).

        Remembered per pattern (:data:`_PATTERNS`) when ``S``, ``J`` are canonical
        float64 CSR, ``order`` is None and ``J`` has no row long enough to be dense
        (:func:`~supercoil.solvers.pinned_rows.has_long_rows`; a ring's phase condition: its
        pins depend on the values, and its factors keep the memos below): keyed by
        :func:`~supercoil.solvers.patterns.pattern_words` of ``S``, ``J`` and the
        border's zeros, and used when the words are equal and the ordering's
        certificate holds for ``J``'s values (:meth:`~supercoil.solvers.ordering.OrderMemo.
        certifies`; else the ordering and layouts are looked up or made as without the
        memo). Everything else in it depends on the words only: the layouts of ``P B
        P^T`` and of ``K``'s band (whether the band holds the values, and a band too
        wide, included). The three memos it replaces at
        a hit (:func:`~supercoil.solvers.ordering.kkt_order`, :func:`~supercoil.continuation.bordered_matrix.remembered_layout`,
        :func:`~supercoil.solvers.kkt_matrix.kkt_band_layout`) each made and hashed bytes of
        the patterns (Python's hash of ``S.indices``' bytes alone is 25 µs at N = 100),
        and the dense rows were looked for anew: under line_profiler on the replayed
        contact branch (N = 100), 0.18 ms a factor for keys, certificate, dense rows and
        the Jacobian's CSR conversion before, 0.06 ms for the words, their comparison and
        the certificate."""
        n, m, size = S.shape[0], J.shape[0], S.shape[0] + J.shape[0] + 1
        words = None
        if order is None and is_canonical_float(S) and is_canonical_float(J) \
                and not has_long_rows(J):  # then J has no dense rows (no pins)
            words, fingerprint = pattern_words(S, J, column, scaled_row)
            key = (n, m, S.shape[1], J.shape[1], fingerprint)
            found = _PATTERNS.get(key)
            if found is not None and same_words(found[0].words, words) \
                    and found[0].order_memo.certifies(J):
                return found[0], None, S, J, J
        S = hessian.sparse.tocsr()
        if isinstance(J, CSRArrays):
            J = J.tocsr()
        pinned = PinnedRows.of(J) if m else None
        J_banded = J if pinned is None else pinned.sparse
        if order is None:
            kkt_ordering, order_memo = remembered_order(S, J_banded)
        else:
            kkt_ordering, order_memo = np.asarray(order), None
        S, J, J_banded = canonical(S), canonical(J), canonical(J_banded)
        s_bytes = (S.indptr.tobytes(), S.indices.tobytes())
        pattern = _FactorPattern()
        pattern.words, pattern.order_memo = words, order_memo
        pattern.kkt_order = kkt_ordering
        pattern.order = np.concatenate([kkt_ordering, [size - 1]])
        pattern.order.flags.writeable = False  # shared by the factors of the pattern
        pattern.col_at, pattern.row_at = np.flatnonzero(column), np.flatnonzero(border_row)
        pattern.layout = remembered_layout(S, J, pattern.col_at, pattern.row_at,
                                            corner != 0.0, pattern.order, s_bytes)
        # the banded block K (K_pin with pins): its band layout is remembered per
        # pattern and filled with its values in the order of kkt_entries
        pattern.band = kkt_band_layout(S, J_banded, kkt_ordering, s_bytes, BAND_FRACTION,
                                       kkt_values(S, J_banded))
        if words is not None and order_memo is not None:
            _PATTERNS.put(key, (pattern,))
        return pattern, pinned, S, J, J_banded

    def _sparse_solve(self, rhs: np.ndarray, refine: bool = True) -> np.ndarray:
        ordered = np.ascontiguousarray(rhs[self.order])
        if not refine and isinstance(self._lu, BandBordered) and self._lu._fallback is None:
            sol = self._lu._once(ordered)  # one block elimination, no refinement
        else:
            sol = self._lu.solve(ordered)
        out = np.empty_like(sol)
        out[self.order] = sol
        return out

    def refined_solve(self, hessian: HessianParts, jacobian: sp.spmatrix | CSRArrays,
                      column: np.ndarray, row: np.ndarray, rhs: np.ndarray, max_steps: int = 6
                      ) -> np.ndarray | None:
        """Solve ``B' z = rhs`` (``(size,)``) for the bordered matrix ``B'`` of these
        arguments (as the constructor's) by iterative refinement with this factor, of a
        nearby ``B`` (one Newton step away): ``z += B^-1 (rhs - B' z)`` while the
        residual (the border row scaled as in the factor) at least halves, at most
        ``max_steps`` times, so that it ends at the round-off floor as a new factor's
        solve does. None (then factorise ``B'``) unless it meets the bound of
        :class:`~supercoil.continuation.band_bordered.BandBordered`'s own refinement, ``1e-14`` of ``|rhs| + max|B'| |z|``.
        Each step's solve with ``B`` is one block elimination (``solve(refine=False)``):
        refining it against ``B`` too would not make the result closer to ``B'``'s."""
        S = hessian.csr_arrays()  # its values and shape
        if S is None:
            S = hessian.sparse
        J = jacobian if isinstance(jacobian, (sp.csr_matrix, CSRArrays)) \
            else sp.csr_matrix(jacobian)
        n = S.shape[0]
        column = np.asarray(column, dtype=float)
        row = np.asarray(row, dtype=float)
        rhs = np.asarray(rhs, dtype=float)
        if rhs.shape != (self.size,) or row.shape != (self.size,) or n + J.shape[0] + 1 \
                != self.size:
            raise ValueError("refined_solve: sizes differ from the factor's")

        canonical_j = J.data.dtype == np.float64

        def residual(z):
            x, multipliers, lam = z[:n], z[n:-1], z[-1]
            if canonical_j:  # the sums of J.T @ mu and J @ x, without scipy's dispatch
                jt_mu = csr_rmatvec(J.indptr, J.indices, J.data, multipliers, n)
                j_x = csr_matvec(J.indptr, J.indices, J.data, x, J.shape[1])
            else:
                jt_mu, j_x = J.T @ multipliers, J @ x
            top = hessian.matvec(x) + jt_mu + column[:n] * lam
            middle = j_x + column[n:] * lam
            res = rhs - np.concatenate([top, middle, [row @ z]])
            res[-1] *= self.row_scale
            return res

        b_max = max(float(np.max(np.abs(S.data), initial=0.0)),
                    float(np.max(np.abs(J.data), initial=0.0)),
                    float(np.max(np.abs(column), initial=0.0)),
                    self.row_scale * float(np.max(np.abs(row))))
        size = max(float(np.max(np.abs(rhs[:-1]), initial=0.0)), self.row_scale * abs(rhs[-1]))
        z = self.solve(rhs, refine=False)
        best, best_norm = None, np.inf
        for _ in range(max_steps + 1):
            res = residual(z)
            norm = float(np.max(np.abs(res)))
            if not norm < 0.5 * best_norm:
                break
            best, best_norm = z, norm
            res[-1] /= self.row_scale
            z = z + self.solve(res, refine=False)
        if best is not None and best_norm <= 1e-14 * (size + b_max * float(np.max(np.abs(best)))):
            return best
        return None

    def solve(self, rhs: np.ndarray, refine: bool = True) -> np.ndarray:
        """Solve ``B z = rhs`` (``rhs`` unscaled, ``(size,)`` or ``(size, k)``;
        ``refine=False``: the band LU's block elimination without its refinement)."""
        rhs = np.array(rhs, dtype=float)
        rhs[-1] = rhs[-1] * self.row_scale
        z = self._sparse_solve(rhs, refine)
        if len(self._w):
            z = z - self._BV @ np.linalg.solve(self._small, self._V.T @ z)
        if not _all_finite(z.reshape(-1)):
            raise SingularMatrixError("bordered solve produced non-finite values")
        return z
