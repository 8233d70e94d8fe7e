"""Solves with a bordered matrix through the band LU of its leading block, refined.

``B = [[K, C], [R^T, D]]`` with ``K`` banded (the KKT matrix in its banded
ordering) and ``k`` dense borders: ``K`` is factorised by LAPACK's band LU and
the borders by block elimination (Govaerts 2000, ch. 3), then the solution is
refined against ``B`` itself (:class:`BandBordered`).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.linalg import splu

from supercoil._numba import njit
from supercoil.solvers.band import BandLayout, band_lu, factor_band_storage
from supercoil.solvers.csr import CSRArrays
from supercoil.solvers.errors import SingularMatrixError


class BandBordered:
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
    for SuperLU's factorisation of ``B``; a whole
    :class:`~supercoil.continuation.bordered.BorderedFactor` (assembly of ``B``
    included) 2.9 ms against 8.4 ms.
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
        (:func:`~supercoil.solvers.kkt_matrix.kkt_band_layout`), ``K``'s band storage filled
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
    :func:`~supercoil.solvers.csr.csr_matvec` does (the same residual), the
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
