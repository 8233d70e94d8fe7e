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

Dense constraint rows (an integral phase condition) are pinned to one DOF in
the banded block and their remainder becomes extra borders (``k = 1 + 2r``
in all, :class:`BorderedFactor`), so that the band LU of :class:`_BandBordered`
still applies.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.linalg import splu

from supercoil._numba import njit
from supercoil.solvers.band import BandLayout, band_lu, factor_band_storage
from supercoil.solvers.kkt import (
    PinnedRows,
    SingularMatrixError,
    _is_canonical_float,
    _kkt_values,
    _permuted_kkt_entries,
    canonical,
    has_long_rows,
    kkt_band_layout,
    remembered_order,
)
from supercoil.solvers.patterns import (
    CSRArrays,
    PatternMemo,
    csr_matvec,
    csr_rmatvec,
    pattern_words,
    same_words,
)
from supercoil.solvers.problem import HessianParts

# The band LU takes K when its band kl + ku + 1 is at most this fraction of its size
# (else SuperLU). Measured at N = 100 on the tweezers' contact branch (387 unknowns):
# at the widest band met, 97 (0.25), the band LU 0.21 ms against 0.33 ms for SuperLU;
# at 61-95, 0.22-0.25 ms against 0.26-0.42 ms. A quarter sent 67 of its factorisations
# at 97 to SuperLU.
BAND_FRACTION = 1.0 / 3.0


class _BandBordered:
    """Solves with ``B`` through the ``k``-bordered ``E = [[K, C], [R^T, D]]`` (``K`` banded).

    ``K`` ``(n, n)`` is factorised by LAPACK's band LU; ``C``, ``R`` are
    ``(n, k)`` and ``D`` ``(k, k)``. Block elimination (Govaerts 2000, ch. 3)

        K u = f,   Sigma = D - R^T K^-1 C   ((k, k), LU),
        Sigma y = g - R^T u,   x = u - (K^-1 C) y,

    then iterative refinement against ``B`` itself (its sparse product), so
    that the accuracy is that of ``B``, not of the nearly singular ``K`` near
    a fold (Govaerts, ch. 3, on why plain block elimination is not enough
    there). ``B`` ``(n + k_true)`` holds the first ``k_true`` borders of
    ``E``; the others are auxiliary unknowns with a zero right-hand side that
    carry a low-rank part of ``B``'s leading block: with
    ``[[K, U], [V^T, -I]]`` the first block row is ``(K + U V^T) x``.
    :meth:`from_storage` (the factor's path) and :meth:`from_parts` return None (the
    caller falls back to SuperLU on
    ``B``) when the band is wide, a pivot of ``K`` is exactly zero, or
    ``Sigma`` is numerically singular (the smallest singular value of
    ``Sigma`` equilibrated by the bounds ``|D_ij| + |R_i| |K^-1 C_j|`` of its
    entries below ``1e-13``; the borders' scales differ by orders of
    magnitude, so one norm bound for all of them rejected regular ``Sigma``
    at N = 200); :meth:`solve` falls back on its own when
    refinement stalls. Measured at N = 200 on a contact branch (n = 796,
    half-bandwidth 40, one border): the band LU itself 0.9 ms against 6-9 ms
    for SuperLU's factorisation of ``B``; a whole :class:`BorderedFactor`
    (assembly of ``B`` included) 2.9 ms against 8.4 ms.
    """

    MAX_REFINEMENTS = 4

    def __init__(self, B, lub, piv, kl, ku, C, R, D, b_max: float | None = None):
        self._B = B
        self._lub, self._piv, self._kl, self._ku = lub, piv, kl, ku
        self._C, self._R, self._D = C, R, D
        self._n = C.shape[0]
        self._k_true = B.shape[0] - self._n
        self._KC = self._k_solve(C)
        self._schur = None
        self._fallback = None
        # max |B_ij| (given by a caller that made B's entries)
        self._b_max = float(np.max(np.abs(B.data), initial=0.0)) if b_max is None else b_max

    @classmethod
    def factor(cls, B: sp.csc_matrix):
        """One border: ``B = [[K, c], [r^T, d]]`` with ``K`` its leading ``(n - 1)`` block."""
        size = B.shape[0]
        n = size - 1
        if n < 2:
            return None
        K = B[:n, :n].tocoo()
        column = B[:n, n].toarray()
        row = B[n, :n].toarray().T
        return cls.from_parts(B, K.row, K.col, K.data, column, row, B[n:, n:].toarray())

    @classmethod
    def from_parts(cls, B, k_rows: np.ndarray, k_cols: np.ndarray, k_values: np.ndarray,
                   C: np.ndarray, R: np.ndarray, D: np.ndarray):
        """Factor of ``E`` from ``K``'s stored entries (no duplicates) and the borders
        ``C``, ``R`` ``(n, k)``, ``D`` ``(k, k)`` (class doc)."""
        n = np.asarray(C).shape[0]
        if n < 2 or k_values.size == 0:
            return None
        factor = band_lu(n, k_rows, k_cols, k_values)
        return None if factor is None else cls._from_factor(B, factor, C, R, D)

    @classmethod
    def from_storage(cls, B, layout: BandLayout, flat: np.ndarray, C: np.ndarray,
                     R: np.ndarray, D: np.ndarray, b_max: float):
        """:meth:`from_parts` with the band layout of ``K``'s entries already made
        (:func:`~supercoil.solvers.kkt.kkt_band_layout`), ``K``'s band storage filled
        (``flat``, see :func:`~supercoil.solvers.band.factor_band_storage`) and
        ``max |B_ij|``."""
        return cls._from_factor(B, factor_band_storage(layout, flat), C, R, D, b_max)

    @classmethod
    def _from_factor(cls, B, factor, C: np.ndarray, R: np.ndarray, D: np.ndarray,
                     b_max: float | None = None):
        C = np.ascontiguousarray(np.asarray(C, dtype=float).reshape(C.shape[0], -1))
        R = np.asarray(R, dtype=float).reshape(C.shape)
        D = np.asarray(D, dtype=float).reshape(C.shape[1], C.shape[1])
        if factor[4] != 0:
            return None
        lub, piv, kl, ku, _info = factor
        out = cls(B, lub, piv, kl, ku, C, R, D, b_max)
        schur = D - R.T @ out._KC
        if schur.shape[0] == 1:
            return out._one_border(schur)
        if not np.all(np.isfinite(schur)):
            return None
        # |Sigma_ij| before cancellation is at most |D_ij| + |R_i| |K^-1 C_j|: Sigma is
        # equilibrated by those bounds (rows, then columns), which makes the rounding
        # error of every entry at most ~eps, and is numerically singular when its
        # smallest singular value falls below 1e-13 (for k = 1: |s| <= 1e-13 bound)
        bound = np.abs(D) + np.outer(np.linalg.norm(R, axis=0), np.linalg.norm(out._KC, axis=0))
        rows = np.max(bound, axis=1)
        rows[rows == 0.0] = 1.0
        columns = np.max(bound / rows[:, None], axis=0)
        columns[columns == 0.0] = 1.0
        scaled = schur / rows[:, None] / columns[None, :]
        if np.linalg.svd(scaled, compute_uv=False)[-1] <= 1e-13:
            return None
        lu, piv, _info = lapack.dgetrf(schur)  # lu_factor's LAPACK call, without its wrapper
        out._schur = (lu, piv)
        return out

    def _one_border(self, schur: np.ndarray):
        """:meth:`_from_factor`'s test of ``Sigma`` ``(1, 1)`` on Python floats: the
        same operations on the same numbers as its arrays (``np.linalg.norm(x,
        axis=0)`` is ``sqrt(add.reduce(x * x, axis=0))`` for real ``x``), without
        numpy's calls on 1-element arrays (outer, max, masks: ~30 µs of a factor at
        N = 100 under line_profiler)."""
        s = float(schur[0, 0])
        if not math.isfinite(s):
            return None
        norm_r = np.sqrt(np.add.reduce(self._R * self._R, axis=0))
        norm_kc = np.sqrt(np.add.reduce(self._KC * self._KC, axis=0))
        bound = abs(float(self._D[0, 0])) + float(norm_r[0]) * float(norm_kc[0])
        rows = bound if bound != 0.0 else 1.0
        columns = bound / rows
        if columns == 0.0:
            columns = 1.0
        if abs(s / rows / columns) <= 1e-13:
            return None
        self._schur = schur
        return self

    def _k_solve(self, f):
        x, _info = lapack.dgbtrs(self._lub, self._kl, self._ku, f, self._piv)
        return x

    def _once(self, rhs):
        """One block elimination for ``B``'s right-hand side ``(n + k_true[, p])``;
        the auxiliary borders get zero, and only ``B``'s unknowns are returned."""
        n, k_true = self._n, self._k_true
        f = rhs[:n]
        if k_true == self._C.shape[1]:
            g = rhs[n:]
        else:
            g = np.zeros((self._C.shape[1],) + rhs.shape[1:])
            g[:k_true] = rhs[n:]
        u = self._k_solve(f)
        if self._C.shape[1] == 1:
            y = (g - self._R.T @ u) / self._schur[0, 0]
        else:  # lu_solve's LAPACK call, without its wrapper
            y, _info = lapack.dgetrs(*self._schur, g - self._R.T @ u)
        x = u - self._KC @ y
        return np.concatenate([x, y[:k_true]])

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self._fallback is not None:
            return self._fallback.solve(rhs)
        rhs = np.asarray(rhs, dtype=float)
        z = self._once(rhs)
        B, b_max = self._B, self._b_max
        compiled = type(B) is CSRArrays and rhs.ndim <= 2
        size = None if compiled else float(np.max(np.abs(rhs), initial=0.0))
        previous = np.inf
        for it in range(self.MAX_REFINEMENTS + 1):
            if compiled:
                res, norm, z_max, rhs_max = _refinement_residual(B.indptr, B.indices, B.data,
                                                                 rhs, z)
                size = rhs_max if size is None else size
            else:
                res = rhs - B @ z
                norm = float(np.max(np.abs(res), initial=0.0))
                z_max = float(np.max(np.abs(z), initial=0.0))
            if norm <= 1e-14 * (size + b_max * z_max):
                return z
            if it == self.MAX_REFINEMENTS or not norm < 0.5 * previous:
                break
            previous = norm
            z = z + self._once(res)
        try:
            self._fallback = splu(self._B.tocsc(), permc_spec="NATURAL")
        except RuntimeError as exc:
            raise SingularMatrixError(f"bordered matrix is singular ({exc})") from None
        return self._fallback.solve(rhs)


def _refinement_residual(indptr, indices, data, rhs, z):
    """``(rhs - B z, max |rhs - B z|, max |z|, max |rhs|)`` for ``B``'s CSR arrays and
    ``rhs``, ``z`` ``(size,)`` or ``(size, p)``: the products summed as
    :func:`~supercoil.solvers.patterns.csr_matvec` does (the same residual), the
    maxima NaN if an entry is (as ``np.max``), in one compiled pass."""
    if rhs.ndim == 1:
        res, norm, z_max, rhs_max = _residual_kernel(indptr, indices, data, rhs[:, None],
                                                     z[:, None])
        return res[:, 0], norm, z_max, rhs_max
    return _residual_kernel(indptr, indices, data, rhs, z)


@njit()
def _residual_kernel(indptr, indices, data, rhs, z):
    n, p = rhs.shape
    res = np.empty((n, p))
    norm = z_max = rhs_max = 0.0
    for i in range(n):
        for c in range(p):
            total = 0.0
            for jj in range(indptr[i], indptr[i + 1]):
                total += data[jj] * z[indices[jj], c]
            r = rhs[i, c] - total
            res[i, c] = r
            norm = _nan_max(norm, abs(r))
            z_max = _nan_max(z_max, abs(z[i, c]))
            rhs_max = _nan_max(rhs_max, abs(rhs[i, c]))
    return res, norm, z_max, rhs_max


@njit(inline="always")
def _nan_max(a, b):
    """``max(a, b)`` for ``b >= 0``, NaN once either is (``np.max``'s rule)."""
    return b if b > a or math.isnan(b) else a


def _permuted_bordered(S: sp.csr_matrix, J: sp.csr_matrix, column: np.ndarray,
                       border_row: np.ndarray, corner: float, order: np.ndarray,
                       matrix: bool | str = True, s_bytes: tuple[bytes, bytes] | None = None,
                       entries: bool = True):
    """``P B P^T`` as CSR (None without ``matrix``; its arrays, a
    :class:`~supercoil.solvers.patterns.CSRArrays` sharing the remembered index arrays,
    with ``matrix="arrays"``), and the stored entries of its
    leading block ``P K P^T`` (None without ``entries``). ``s_bytes``:
    ``(S.indptr.tobytes(), S.indices.tobytes())`` if already made (bytes keep their
    hash: a second key on them costs no rehash).

    ``B = [[S, J^T, column], [J, 0], [border_row, corner]]``; the stored
    entries are those of ``scipy.sparse.bmat`` of the blocks (explicit zeros
    of ``S`` and ``J`` kept, zeros of the dense border dropped), so that the
    refinement's products ``B z`` sum the same terms in the same order (by
    column within each row) as with the matrix ``bmat`` and fancy indexing
    built before (5 times slower). The sorting permutation is remembered per
    pattern (:data:`_LAYOUTS`): along a branch a few patterns repeat. Its index
    arrays are kept in the index type scipy would pick (int32 below 2^31), so
    that making the matrix does not convert them.
    """
    S, J = canonical(S), canonical(J)
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1
    col_at = np.flatnonzero(column)
    row_at = np.flatnonzero(border_row)
    layout = _remembered_layout(S, J, col_at, row_at, corner != 0.0, order, s_bytes)
    by_row, pcol, indptr, inner, inner_rows, inner_cols = layout
    parts = [S.data, J.data, J.data, column[col_at], border_row[row_at]]
    if corner != 0.0:
        parts.append(np.array([corner]))
    values = np.concatenate(parts)[by_row]
    k_entries = (inner_rows, inner_cols, values[inner]) if entries else None
    if not matrix:
        return None, k_entries
    if matrix == "arrays":
        return CSRArrays(values, pcol, indptr, (size, size)), k_entries
    Bp = sp.csr_matrix((values, pcol.copy(), indptr.copy()), shape=(size, size))
    Bp.has_canonical_format = True
    return Bp, k_entries


def _remembered_layout(S, J, col_at, row_at, has_corner, order, s_bytes=None):
    """:func:`_bordered_layout`, remembered per pattern (:data:`_LAYOUTS`)."""
    if s_bytes is None:
        s_bytes = (S.indptr.tobytes(), S.indices.tobytes())
    key = (S.shape[0], J.shape[0], *s_bytes, J.indptr.tobytes(),
           J.indices.tobytes(), col_at.tobytes(), row_at.tobytes(), bool(has_corner),
           np.asarray(order).tobytes())
    layout = _LAYOUTS.get(key)
    if layout is None:
        layout = _bordered_layout(S, J, col_at, row_at, has_corner, order)
        _LAYOUTS.put(key, layout)
    return layout


def _bordered_layout(S, J, col_at, row_at, has_corner, order):
    """Sorting permutation and permuted indices of :func:`_permuted_bordered`'s entries:
    ``(by_row, pcol, indptr, inner, inner_rows, inner_cols)``, the entries (those of
    ``S``, ``J^T``, ``J``, the column, the row and the corner, in that order) sorted by
    their permuted (row, column) (:func:`_sorted_entries`), their columns and the row
    pointers of the permuted CSR matrix (int32 below 2^31 entries), and the entries of
    its leading block ``P K P^T``."""
    n, m = S.shape[0], J.shape[0]
    size = n + m + 1
    position = np.empty(size, dtype=np.int64)
    position[order] = np.arange(size)
    by_row, prow, pcol, indptr = _sorted_entries(S.indptr, S.indices, J.indptr, J.indices,
                                                 col_at, row_at, bool(has_corner), position)
    inner = np.flatnonzero((prow < size - 1) & (pcol < size - 1))
    index = np.int32 if max(size, pcol.size) < 2**31 - 1 else np.int64
    pcol_stored, indptr = pcol.astype(index), indptr.astype(index)
    pcol_stored.flags.writeable = indptr.flags.writeable = False  # shared by the factors
    return by_row, pcol_stored, indptr, inner, prow[inner], pcol[inner]


@njit()
def _sorted_entries(s_ptr, s_idx, j_ptr, j_idx, col_at, row_at, has_corner, position):
    """The entries of ``B = [[S, J^T, column], [J, 0], [row, corner]]`` (``col_at``,
    ``row_at`` the border's nonzeros) at their permuted places ``position[i],
    position[j]``, sorted by (row, column): ``(by_row, rows, columns, indptr)`` with
    ``by_row`` the sorting permutation of the entries in the order ``S``, ``J^T``,
    ``J``, column, row, corner, and ``indptr`` ``(size + 1,)`` int64.

    Two stable counting sorts, by column then by row (the places are distinct, so the
    result is ``np.argsort`` of the row-major keys). 137 of the 716 bordered factors of
    the tweezers' contact branch (N = 100) meet a new pattern; its layout (12 100
    entries) took 0.32 ms with numpy's argsort, 0.16 ms so.
    """
    n, m = s_ptr.size - 1, j_ptr.size - 1
    size = n + m + 1
    k_rows, k_cols = _permuted_kkt_entries(s_ptr, s_idx, j_ptr, j_idx, position)
    e = k_rows.size
    total = e + col_at.size + row_at.size + has_corner
    rows = np.empty(total, dtype=np.int64)
    cols = np.empty(total, dtype=np.int64)
    rows[:e], cols[:e] = k_rows, k_cols
    last = position[size - 1]
    for i in range(col_at.size):
        rows[e], cols[e] = position[col_at[i]], last
        e += 1
    for i in range(row_at.size):
        rows[e], cols[e] = last, position[row_at[i]]
        e += 1
    if has_corner:
        rows[e], cols[e] = last, last
    by_column = _counting_sort(cols, np.arange(total), size)
    by_row = _counting_sort(rows, by_column, size)
    indptr = np.zeros(size + 1, dtype=np.int64)
    for e in range(total):
        indptr[rows[e] + 1] += 1
    for r in range(size):
        indptr[r + 1] += indptr[r]
    return by_row, rows[by_row], cols[by_row], indptr


@njit()
def _counting_sort(keys, items, n_keys):
    """``items`` stably sorted by ``keys[items]`` (integers in ``[0, n_keys)``)."""
    start = np.zeros(n_keys + 1, dtype=np.int64)
    for e in range(items.size):
        start[keys[items[e]] + 1] += 1
    for k in range(n_keys):
        start[k + 1] += start[k]
    out = np.empty(items.size, dtype=np.int64)
    for e in range(items.size):
        k = keys[items[e]]
        out[start[k]] = items[e]
        start[k] += 1
    return out


_LAYOUTS = PatternMemo()


class _FactorPattern:
    """What :class:`BorderedFactor` takes from the pattern of its operands
    (:meth:`BorderedFactor._pattern`): ``words`` (the key's, None when not remembered),
    ``order_memo`` (the ordering's certificate), ``kkt_order`` and ``order`` (with the
    border last), the border's nonzeros ``col_at``, ``row_at``, ``layout``
    (:func:`_bordered_layout`) and ``band`` (the band layout of ``K``, None for
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


@njit()
def _bordered_values(s_data, j_data, kj_data, column, col_at, border_row, row_at, corner,
                     by_row, positions, storage_size, kkt_order):
    """The values of a factor in one compiled pass: ``(values, b_max, flat, C, R)``.

    ``values``: those of ``P B P^T``, the entries of ``S``, ``J``, ``J``, the border's
    nonzeros and the corner if not zero (:func:`_permuted_bordered`'s ``parts``) taken
    in the layout's order ``by_row``; ``b_max``: ``max |values|`` (NaN if one is);
    ``flat``: the band storage of ``K`` (``storage_size``, 0 for none), the values of
    ``S``, ``J_banded``, ``J_banded`` (``kj_data``: :func:`~supercoil.solvers.kkt.
    _kkt_values`) at their ``positions``; ``C``, ``R`` ``(n + m, 1)``: the column and
    the border row in ``kkt_order``, -0.0 made 0.0 (as a sparse matrix of them stores
    them). It replaces a dozen numpy calls (concatenations, gathers, the scatter into
    ``ab``, ``max |B|``): the scatter alone, 11 600 entries into ``ab`` of 51 000 at
    N = 100, 19 µs compiled against numpy's 25 µs."""
    n_s, n_j = s_data.size, j_data.size
    source = np.empty(n_s + 2 * n_j + col_at.size + row_at.size + 1)
    source[:n_s] = s_data
    source[n_s:n_s + n_j] = j_data
    source[n_s + n_j:n_s + 2 * n_j] = j_data
    e = n_s + 2 * n_j
    for i in range(col_at.size):
        source[e + i] = column[col_at[i]]
    e += col_at.size
    for i in range(row_at.size):
        source[e + i] = border_row[row_at[i]]
    source[e + row_at.size] = corner
    values = np.empty(by_row.size)
    b_max = 0.0
    for i in range(by_row.size):
        v = source[by_row[i]]
        values[i] = v
        a = abs(v)
        if a > b_max or math.isnan(a):
            b_max = a
    flat = np.zeros(storage_size)
    if storage_size:
        n_kj = kj_data.size
        for i in range(n_s):
            flat[positions[i]] = s_data[i]
        for i in range(n_kj):
            flat[positions[n_s + i]] = kj_data[i]
        for i in range(n_kj):
            flat[positions[n_s + n_kj + i]] = kj_data[i]
    C = np.empty((kkt_order.size, 1))
    R = np.empty((kkt_order.size, 1))
    for i in range(kkt_order.size):
        c, r = column[kkt_order[i]], border_row[kkt_order[i]]
        C[i, 0] = c if c != 0.0 else 0.0
        R[i, 0] = r if r != 0.0 else 0.0
    return values, b_max, flat, C, R


class BorderedFactor:
    """Factorisation of ``[[H, J^T, f_x], [J, 0, f_mu], [b_x^T, b_mu^T, b_lambda]]``.

    ``hessian`` is on the ``n`` free DOFs, ``jacobian`` ``(m, n)``, ``column``
    (``F_lambda``) has length ``n + m`` and ``row`` (the arclength row, corner
    entry ``b_lambda`` last) ``n + m + 1``.
    ``order`` reuses a :func:`kkt_order` of the same pattern (of the pinned
    ``J`` when it has dense rows).

    Dense rows of ``J`` (:func:`~supercoil.solvers.kkt.dense_rows`: an
    integral phase condition, Doedel's ``<M g, q - q_0> = 0``) would make the
    band as wide as the matrix and send the factorisation to SuperLU. Each is
    pinned instead (:class:`~supercoil.solvers.kkt.PinnedRows`): the banded
    block is ``K_pin``, the KKT matrix with the row replaced by its entry on
    one DOF (as regular as with a node gauge), and the rest of the row and of
    its column, ``E Delta^T + Delta E^T``, goes into ``2r`` auxiliary borders
    of :class:`_BandBordered`; refinement is against the true ``B``.
    Raises :class:`~supercoil.solvers.kkt.SingularMatrixError` when ``B`` is singular.
    """

    def __init__(self, hessian: HessianParts, jacobian: sp.spmatrix, column: np.ndarray,
                 row: np.ndarray, order: np.ndarray | None = None):
        S = hessian.sparse.tocsr()
        n = S.shape[0]
        if jacobian is None:
            J = sp.csr_matrix((0, n))
        else:  # scipy's csr_matrix of a csr_matrix shares its arrays (and costs 50 µs)
            J = jacobian if type(jacobian) is sp.csr_matrix else sp.csr_matrix(jacobian)
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
        pattern, pinned, S, J, J_banded = self._pattern(S, J, column, border_row, corner,
                                                        scaled_row, order)
        self.kkt_order = pattern.kkt_order.copy()
        self.order = pattern.order
        band = pattern.band
        by_row, pcol, indptr = pattern.layout[:3]
        values, b_max, flat, C, R = _bordered_values(
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
            self._lu = _BandBordered.from_storage(Bp, band, flat, C, R, D, b_max)
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
    def _pattern(S, J, column, border_row, corner, scaled_row, order):
        """What the factor of these operands takes from their pattern:
        ``(pattern, pinned, S, J, J_banded)`` (a :class:`_FactorPattern`, the
        :class:`~supercoil.solvers.kkt.PinnedRows` of ``J`` or None, the canonical
        ``S``, ``J`` and the banded block's ``J``).

        Remembered per pattern (:data:`_PATTERNS`) when ``S``, ``J`` are canonical
        float64 CSR, ``order`` is None and ``J`` has no row long enough to be dense
        (:func:`~supercoil.solvers.kkt.has_long_rows`; a ring's phase condition: its
        pins depend on the values, and its factors keep the memos below): keyed by
        :func:`~supercoil.solvers.patterns.pattern_words` of ``S``, ``J`` and the
        border's zeros, and used when the words are equal and the ordering's
        certificate holds for ``J``'s values (:meth:`~supercoil.solvers.kkt._OrderMemo.
        certifies`; else the ordering and layouts are looked up or made as without the
        memo). Everything else in it depends on the words only: the layouts of ``P B
        P^T`` and of ``K``'s band (whether the band holds the values, and a band too
        wide, included). The three memos it replaces at
        a hit (:func:`~supercoil.solvers.kkt.kkt_order`, :func:`_remembered_layout`,
        :func:`~supercoil.solvers.kkt.kkt_band_layout`) each made and hashed bytes of
        the patterns (Python's hash of ``S.indices``' bytes alone is 25 µs at N = 100),
        and the dense rows were looked for anew: under line_profiler on the replayed
        contact branch (N = 100), 0.18 ms a factor for keys, certificate, dense rows and
        the Jacobian's CSR conversion before, 0.06 ms for the words, their comparison and
        the certificate."""
        n, m, size = S.shape[0], J.shape[0], S.shape[0] + J.shape[0] + 1
        words = None
        if order is None and _is_canonical_float(S) and _is_canonical_float(J) \
                and not has_long_rows(J):  # then J has no dense rows (no pins)
            words, fingerprint = pattern_words(S, J, column, scaled_row)
            key = (n, m, S.shape[1], J.shape[1], fingerprint)
            found = _PATTERNS.get(key)
            if found is not None and same_words(found[0].words, words) \
                    and found[0].order_memo.certifies(J):
                return found[0], None, S, J, J
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
        pattern.layout = _remembered_layout(S, J, pattern.col_at, pattern.row_at,
                                            corner != 0.0, pattern.order, s_bytes)
        # the banded block K (K_pin with pins): its band layout is remembered per
        # pattern and filled with its values in the order of _kkt_entries
        pattern.band = kkt_band_layout(S, J_banded, kkt_ordering, s_bytes, BAND_FRACTION,
                                       _kkt_values(S, J_banded))
        if words is not None and order_memo is not None:
            _PATTERNS.put(key, (pattern,))
        return pattern, pinned, S, J, J_banded

    def _sparse_solve(self, rhs: np.ndarray, refine: bool = True) -> np.ndarray:
        ordered = np.ascontiguousarray(rhs[self.order])
        if not refine and isinstance(self._lu, _BandBordered) and self._lu._fallback is None:
            sol = self._lu._once(ordered)  # one block elimination, no refinement
        else:
            sol = self._lu.solve(ordered)
        out = np.empty_like(sol)
        out[self.order] = sol
        return out

    def refined_solve(self, hessian: HessianParts, jacobian: sp.spmatrix, column: np.ndarray,
                      row: np.ndarray, rhs: np.ndarray, max_steps: int = 6
                      ) -> np.ndarray | None:
        """Solve ``B' z = rhs`` (``(size,)``) for the bordered matrix ``B'`` of these
        arguments (as the constructor's) by iterative refinement with this factor, of a
        nearby ``B`` (one Newton step away): ``z += B^-1 (rhs - B' z)`` while the
        residual (the border row scaled as in the factor) at least halves, at most
        ``max_steps`` times, so that it ends at the round-off floor as a new factor's
        solve does. None (then factorise ``B'``) unless it meets the bound of
        :class:`_BandBordered`'s own refinement, ``1e-14`` of ``|rhs| + max|B'| |z|``.
        Each step's solve with ``B`` is one block elimination (``solve(refine=False)``):
        refining it against ``B`` too would not make the result closer to ``B'``'s."""
        S = hessian.sparse
        J = jacobian if isinstance(jacobian, sp.csr_matrix) else sp.csr_matrix(jacobian)
        n = S.shape[0]
        column = np.asarray(column, dtype=float)
        row = np.asarray(row, dtype=float)
        rhs = np.asarray(rhs, dtype=float)
        if rhs.shape != (self.size,) or row.shape != (self.size,) or n + J.shape[0] + 1 \
                != self.size:
            raise ValueError("refined_solve: sizes differ from the factor's")

        canonical_j = J.dtype == np.float64

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
