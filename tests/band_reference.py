"""References of :mod:`supercoil.solvers.inertia` for the tests: the eigh-only block
elimination (Haynsworth's inertia additivity, every pivot block diagonalised) and the
Ruiz-scaled entries built with numpy, which the compiled kernels must reproduce."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.inertia import MAX_CARRIED, MAX_CONDITION


def equilibrated_entries(A: sp.csr_matrix, order: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nonzero entries ``(rows, columns, values)`` of ``P D A D P^T``, ``D`` Ruiz's scaling.

    Ruiz equilibration (8 sweeps; a congruence: inertia unchanged) balances
    the stiff bending rows against the constraint rows of a KKT matrix;
    ``P`` puts row ``order[k]`` at ``k``. The scaled entries are
    ``(d_i a_ij) d_j``, the products ``diag(d) @ A @ diag(d)`` of
    scipy.sparse form (which drop exact zeros), so the inertia is the same bit
    for bit as with them; formed on the entry arrays they cost a tenth.
    """
    A = sp.csr_matrix(A, dtype=float, copy=True)
    A.sum_duplicates()
    n = A.shape[0]
    row = np.repeat(np.arange(n), np.diff(A.indptr))
    col, data = A.indices, A.data
    d = np.ones(n)
    filled = np.diff(A.indptr) > 0
    starts = A.indptr[:-1][filled]
    for _ in range(8):
        row_max = np.zeros(n)
        if data.size:
            row_max[filled] = np.maximum.reduceat(np.abs((d[row] * data) * d[col]), starts)
        d = d / np.sqrt(np.where(row_max > 0, row_max, 1.0))
    values = (d[row] * data) * d[col]
    stored = values != 0.0
    position = np.empty(n, dtype=np.int64)
    position[np.asarray(order, dtype=np.int64)] = np.arange(n)
    return position[row[stored]], position[col[stored]], values[stored]


def block_inertia(blocks: np.ndarray, n: int, s: int) -> tuple[int, int, int]:
    """Haynsworth's elimination (module doc) over the row blocks of a permuted matrix."""
    neg = zero = pos = 0
    start, stop = 0, min(s, n)
    pending = blocks[0, :stop, :stop].copy()
    carried = 0  # leading rows of ``pending`` that are carried near-null directions
    while True:
        values, vectors = np.linalg.eigh(pending)
        if stop >= n:
            neg += int(np.sum(values < 0))
            pos += int(np.sum(values > 0))
            zero += int(np.sum(values == 0))
            return neg, zero, pos
        biggest = float(np.max(np.abs(values))) if values.size else 0.0
        small = np.abs(values) <= biggest / MAX_CONDITION
        if np.count_nonzero(small) > MAX_CARRIED * s:
            # keep only the smallest ones; the others are divided by (still >= round-off)
            keep = np.argsort(np.abs(values))[: MAX_CARRIED * s]
            small = np.zeros_like(small)
            small[keep] = True
        nxt = min(stop + s, n)
        k = start // s
        coupling = np.zeros((pending.shape[0], nxt - stop))
        coupling[carried:] = blocks[k, :stop - start, s:s + nxt - stop]
        projected = vectors.T @ coupling
        r = int(np.count_nonzero(small))
        if r == 0:
            # the usual block: every direction eliminated (the same products as
            # below, without selecting all of them)
            neg += int(np.count_nonzero(values < 0))
            pos += int(np.count_nonzero(values > 0))
            schur = blocks[k + 1, :nxt - stop, :nxt - stop] - projected.T @ (
                projected / values[:, None])
            pending, carried = 0.5 * (schur + schur.T), 0
            start, stop = stop, nxt
            continue
        big = ~small
        neg += int(np.sum(values[big] < 0))
        pos += int(np.sum(values[big] > 0))
        schur = blocks[k + 1, :nxt - stop, :nxt - stop] - projected[big].T @ (
            projected[big] / values[big][:, None])
        grown = np.zeros((r + nxt - stop, r + nxt - stop))
        grown[:r, :r] = np.diag(values[small])
        grown[:r, r:] = projected[small]
        grown[r:, :r] = projected[small].T
        grown[r:, r:] = 0.5 * (schur + schur.T)
        pending, carried = grown, r
        start, stop = stop, nxt
