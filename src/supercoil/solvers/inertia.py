"""Exact inertia of sparse symmetric (indefinite, saddle-point) band matrices.

After a bandwidth-reducing ordering, a symmetric matrix of half-bandwidth
``b`` is block tridiagonal with blocks of size ``s >= b``. Block Gaussian
elimination produces Schur complements

    P_1 = D_1,   P_{k+1} = D_{k+1} - C_k^T P_k^{-1} C_k,

and by Haynsworth's inertia additivity ``In(A) = sum_k In(P_k)``. Each
``P_k`` is a small dense symmetric matrix, diagonalised (backward stable):
``P_k = V diag(mu) V^T``. Only its well-conditioned eigen-directions
(``|mu| > max|mu| / 1e4``) are eliminated; the near-null ones are carried,
still diagonal, into the next pivot block together with their coupling to it.
Every step is an exact congruence, so no tiny pivot is ever divided by — the
failure of plain ``L D L^T`` without pivoting on saddle-point matrices, and of
an earlier version of this routine that merged blocks a bounded number of
times and then eliminated them anyway (measured: a stable ring reported
unstable at N >= 2000). Cost ``O(n s^2)`` while few directions are carried.

The eigendecomposition is the expensive part (measured 122 us of a 150 us step
at s = 43), so each pivot block is first reduced by a Bunch–Kaufman
``L D L^T`` (:func:`partial_ldl`) that divides only by pivots of magnitude
above ``MIN_PIVOT`` (1e-3) times the block's largest entry; a leading column
whose pivot is smaller is deferred. ``P = L diag(D, R) L^T`` is again an exact
congruence, and the deferred rest ``R`` (a few rows: the near-null directions)
goes through the eigh step above. Measured on the N = 200 ring's KKT matrices:
15 of 19 pivot blocks have ``|mu|`` below ``max|mu| / 1e4`` (so a fast path for
well-conditioned blocks only would rarely apply), while ``R`` has 0 to 6 rows;
the Schur complements' largest entries are those of the eigh-only elimination
(no extra growth), and the counts are the same (the eigh-only elimination is the
tests' reference, ``tests/band_reference.py``).

(LAPACK's band tridiagonalisation ``dsbtrd`` would also give the inertia,
but it costs ``O(n^2 b)``: measured 77 s at n = 40 000.)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from threadpoolctl import ThreadpoolController

from supercoil._numba import njit
from supercoil.solvers.band import bandwidth_order

# Eigen-directions of a pivot block smaller than its largest eigenvalue over
# this are not divided by: they are carried into the next block.
MAX_CONDITION = 1e4
# At most this many blocks' worth of directions are carried at once.
MAX_CARRIED = 4
# The L D L^T first pass over a pivot block divides only by pivots (1 x 1, or the
# smaller eigenvalue of a 2 x 2) of magnitude above this times its largest entry.
MIN_PIVOT = 1e-3
_CONTROLLER: ThreadpoolController | None = None


def symmetric_inertia(A: sp.spmatrix, order: np.ndarray | None = None) -> tuple[int, int, int]:
    """``(n_negative, n_zero, n_positive)`` of a sparse symmetric matrix (see module doc)."""
    # Hundreds of tiny dense eigenproblems: BLAS threads only add contention
    # (measured 10x slower with two OpenBLAS threads on a loaded 2-core machine).
    # One controller per process: threadpool_limits() re-scans the loaded
    # libraries on every call (measured 1.9 ms of a 4.5 ms inertia at N = 100).
    global _CONTROLLER
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    with _CONTROLLER.limit(limits=1, user_api="blas"):
        return _symmetric_inertia(A, order)


def _symmetric_inertia(A: sp.spmatrix, order: np.ndarray | None = None) -> tuple[int, int, int]:
    """``(n_negative, n_zero, n_positive)`` of a sparse symmetric matrix.

    ``order`` is a bandwidth-reducing permutation (computed if omitted).
    Every eigenvalue gets the sign it is computed with (the caller decides
    which ones are numerically zero, e.g. from the eigenvalues themselves).
    """
    A = sp.csr_matrix(A, dtype=float)  # no copy: read only
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    n = A.shape[0]
    if n == 0:
        return 0, 0, 0
    if order is None:
        order = bandwidth_order(A)
    position = np.empty(n, dtype=np.int64)
    position[np.asarray(order, dtype=np.int64)] = np.arange(n)
    blocks, s = equilibrated_blocks(A.indptr, A.indices, A.data, position)
    neg, zero, pos = block_inertia_pivoted(blocks, n, s, MAX_CONDITION, MAX_CARRIED,
                                           MIN_PIVOT)
    return int(neg), int(zero), int(pos)


@njit()
def equilibrated_blocks(indptr, indices, data, position):
    """The row blocks of :func:`_symmetric_inertia` from a csr matrix without
    duplicates, compiled: ``(blocks, s)``.

    The entries are those of the tests' ``equilibrated_entries`` (the same Ruiz sweeps,
    the same products ``(d_i a_ij) d_j`` in the same order, exact zeros dropped:
    the same bits), put by ``position`` (``position[order[k]] = k``) into
    ``blocks[k]`` of shape ``(s, 2 s)``, ``s = max(b, 16)`` for the half-bandwidth
    ``b`` after the permutation: row block ``k`` (rows ``k s .. k s + s``) on the
    columns ``k s .. k s + 2 s``. numpy's version of the two steps cost 0.6 ms
    of a 2 ms inertia at N = 200 (contact state, b = 43).
    """
    n = indptr.size - 1
    d = np.ones(n)
    for _ in range(8):
        scaled = np.empty(n)
        for i in range(n):
            row_max = 0.0
            for p in range(indptr[i], indptr[i + 1]):
                row_max = max(row_max, abs((d[i] * data[p]) * d[indices[p]]))
            scaled[i] = d[i] / np.sqrt(row_max if row_max > 0 else 1.0)
        d = scaled
    b = 0
    for i in range(n):
        for p in range(indptr[i], indptr[i + 1]):
            if (d[i] * data[p]) * d[indices[p]] != 0.0:
                b = max(b, abs(position[i] - position[indices[p]]))
    s = max(b, 16)
    blocks = np.zeros((-(-n // s), s, 2 * s))
    for i in range(n):
        row = position[i]
        k = row // s
        for p in range(indptr[i], indptr[i + 1]):
            value = (d[i] * data[p]) * d[indices[p]]
            col = position[indices[p]]
            if value != 0.0 and col >= k * s:
                blocks[k, row - k * s, col - k * s] = value
    return blocks, s


@njit()
def _swap(M, m, a, b, deferred):
    """Symmetric interchange of positions ``a`` and ``b`` of the window ``M[:, :m]`` (rows
    also in the coupling columns ``M[:, m:]``)."""
    if a == b:
        return
    for j in range(M.shape[1]):
        M[a, j], M[b, j] = M[b, j], M[a, j]
    for i in range(m):
        M[i, a], M[i, b] = M[i, b], M[i, a]
    deferred[a], deferred[b] = deferred[b], deferred[a]


@njit()
def partial_ldl(M, m, tol):
    """Bunch–Kaufman ``L D L^T`` of the window ``M[:, :m]`` (rows carry their coupling
    ``M[:, m:]``), in place, that divides only by pivots of magnitude above ``tol``.

    Returns ``(e, widths, neg, pos, biggest)``: positions ``0 .. e - 1`` hold the
    eliminated pivots (``widths[p]`` 1 or 2 at a pivot's first position, their
    rows of ``L^{-1} C`` in ``M[:e, m:]``), ``neg`` / ``pos`` the signs of their
    eigenvalues, ``biggest`` the largest magnitude; positions ``e .. m - 1`` the
    deferred rows (a leading column whose Bunch–Kaufman pivot has an eigenvalue of
    magnitude ``<= tol``), their updated window ``M[e:m, e:m]`` and coupling.
    """
    alpha = (1.0 + 17.0 ** 0.5) / 8.0
    width = M.shape[1]
    deferred = np.zeros(m, dtype=np.bool_)
    widths = np.zeros(m, dtype=np.int64)
    e = 0
    neg = 0
    pos = 0
    biggest = 0.0
    while True:
        k = e
        while k < m and deferred[k]:
            k += 1
        if k == m:
            return e, widths, neg, pos, biggest
        omega1 = 0.0
        r = k
        for i in range(e, m):
            if i != k and abs(M[i, k]) > omega1:
                omega1 = abs(M[i, k])
                r = i
        pivot = k
        two = False
        if abs(M[k, k]) < alpha * omega1:
            omega_r = 0.0
            for i in range(e, m):
                if i != r and abs(M[i, r]) > omega_r:
                    omega_r = abs(M[i, r])
            if abs(M[k, k]) * omega_r >= alpha * omega1 * omega1:
                pivot = k
            elif abs(M[r, r]) >= alpha * omega_r:
                pivot = r
            else:
                two = True
        if not two:
            d = M[pivot, pivot]
            if not abs(d) > tol:
                deferred[k] = True
                continue
            _swap(M, m, e, pivot, deferred)
            if d < 0:
                neg += 1
            else:
                pos += 1
            biggest = max(biggest, abs(d))
            widths[e] = 1
            for i in range(e + 1, m):
                f = M[i, e] / d
                if f != 0.0:
                    for j in range(e + 1, width):
                        M[i, j] -= f * M[e, j]
            e += 1
            continue
        a, b, c = M[k, k], M[k, r], M[r, r]
        det = a * c - b * b
        half = 0.5 * (a + c)
        radius = (0.25 * (a - c) ** 2 + b * b) ** 0.5
        top = abs(half) + radius  # the larger eigenvalue magnitude
        if not abs(det) > tol * top:  # the smaller one, |det| / top, at most tol
            deferred[k] = True
            continue
        _swap(M, m, e, k, deferred)
        if r == e:
            r = k
        _swap(M, m, e + 1, r, deferred)
        for lam in (half + radius, half - radius):
            if lam < 0:
                neg += 1
            elif lam > 0:
                pos += 1
        biggest = max(biggest, top)
        widths[e] = 2
        for i in range(e + 2, m):
            f1 = (M[i, e] * c - M[i, e + 1] * b) / det
            f2 = (M[i, e + 1] * a - M[i, e] * b) / det
            if f1 != 0.0 or f2 != 0.0:
                for j in range(e + 2, width):
                    M[i, j] -= f1 * M[e, j] + f2 * M[e + 1, j]
        e += 2


@njit()
def block_inertia_pivoted(blocks, n, s, max_condition, max_carried, min_pivot):
    """Haynsworth's elimination (module doc) with each pivot block first reduced by
    :func:`partial_ldl`: pivots above ``min_pivot`` times the block's largest entry
    are eliminated by ``L D L^T``, the deferred rest ``R`` diagonalised by ``eigh``
    and treated as the eigh-only elimination (module doc) treats a whole block (eigen-directions
    with ``|mu| <= biggest / max_condition`` carried, ``biggest`` the largest
    pivot or eigenvalue magnitude of the congruent ``diag(D, R)``)."""
    neg = 0
    zero = 0
    pos = 0
    start = 0
    stop = min(s, n)
    pending = blocks[0, :stop, :stop].copy()
    carried = 0
    while True:
        m = pending.shape[0]
        nxt = min(stop + s, n)
        t = nxt - stop
        k = start // s
        M = np.zeros((m, m + t))
        M[:, :m] = pending
        if t:
            M[carried:, m:] = blocks[k, :stop - start, s:s + t]
        scale = np.max(np.abs(pending)) if m else 0.0
        e, widths, n_neg, n_pos, biggest = partial_ldl(M, m, min_pivot * scale)
        neg += n_neg
        pos += n_pos
        q = m - e
        rest = M[e:, e:m]
        rest = 0.5 * (rest + rest.T)
        if stop >= n:
            for v in np.linalg.eigvalsh(rest):
                if v < 0:
                    neg += 1
                elif v > 0:
                    pos += 1
                else:
                    zero += 1
            return neg, zero, pos
        schur = blocks[k + 1, :t, :t].copy()
        if e:
            Y = M[:e, m:]
            Z = np.empty((e, t))
            p = 0
            while p < e:
                if widths[p] == 1:
                    Z[p] = Y[p] / M[p, p]
                    p += 1
                else:
                    a, b, c = M[p, p], M[p, p + 1], M[p + 1, p + 1]
                    det = a * c - b * b
                    Z[p] = (c * Y[p] - b * Y[p + 1]) / det
                    Z[p + 1] = (a * Y[p + 1] - b * Y[p]) / det
                    p += 2
            schur -= np.ascontiguousarray(Y.T) @ Z
        if q == 0:
            pending = 0.5 * (schur + schur.T)
            carried = 0
            start, stop = stop, nxt
            continue
        values, vectors = np.linalg.eigh(rest)
        biggest = max(biggest, np.max(np.abs(values)))
        small = np.abs(values) <= biggest / max_condition
        if np.count_nonzero(small) > max_carried * s:
            keep = np.argsort(np.abs(values))[: max_carried * s]
            small = np.zeros(q, dtype=np.bool_)
            small[keep] = True
        projected = np.ascontiguousarray(vectors.T) @ np.ascontiguousarray(M[e:, m:])
        big_at = np.flatnonzero(~small)
        small_at = np.flatnonzero(small)
        for i in big_at:
            if values[i] < 0:
                neg += 1
            elif values[i] > 0:
                pos += 1
        if big_at.size:
            p_big = projected[big_at]
            schur -= np.ascontiguousarray(p_big.T) @ (p_big / values[big_at].reshape(-1, 1))
        r = small_at.size
        p_small = projected[small_at]
        grown = np.zeros((r + t, r + t))
        for i in range(r):
            grown[i, i] = values[small_at[i]]
        grown[:r, r:] = p_small
        grown[r:, :r] = p_small.T
        grown[r:, r:] = 0.5 * (schur + schur.T)
        pending = grown
        carried = r
        start, stop = stop, nxt
