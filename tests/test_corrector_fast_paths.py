"""Pieces of one corrector iteration against direct computations.

Oracles: scipy's KKT ordering (``_kkt_order_scipy``: the pattern of ``|S| + |J^T J|``
formed by scipy.sparse) for the merged one, LAPACK's band LU of a band storage filled
by fancy indexing, dense solves, scipy's row sums for the round-off floor: the same
arrays bit for bit (or solves to round-off), also on patterns with explicit zeros,
exact cancellation in ``J^T J`` and entries scipy keeps or drops.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from supercoil.solvers import kkt_matrix, ordering


def contact_like_kkt(rng, nodes, pairs, zero_rows=0):
    """A rod-like KKT pattern: ``S`` banded over 3 DOFs a node (half-bandwidth 8) plus
    ``pairs`` dense 12 x 12 blocks coupling two far segments (contact pairs), with
    ``zero_rows`` rows of explicit zeros (a straight rod's lateral DOFs); ``J`` one
    inextensibility row per edge (6 DOFs) and a few one-DOF pins."""
    n = 3 * nodes
    S = np.zeros((n, n))
    for k in range(9):
        d = rng.standard_normal(n - k)
        S += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
    for _ in range(pairs):
        i, j = rng.choice(nodes - 1, size=2, replace=False)
        dofs = np.concatenate([np.arange(3 * i, 3 * i + 6), np.arange(3 * j, 3 * j + 6)])
        block = rng.standard_normal((12, 12))
        S[np.ix_(dofs, dofs)] += block + block.T
    S = sp.csr_matrix(S)
    for r in rng.choice(n, size=zero_rows, replace=False):
        S.data[S.indptr[r]:S.indptr[r + 1]] = 0.0  # stored, zero
    r, c, v = [], [], []
    for e in range(nodes - 1):  # every window stored, lateral entries zero on a straight rod
        values = rng.standard_normal(6)
        if zero_rows:
            values[::3] = 0.0
        r += [e] * 6
        c += list(range(3 * e, 3 * e + 6))
        v += list(values)
    for k, dof in enumerate(rng.choice(n, size=3, replace=False)):
        r.append(nodes - 1 + k)
        c.append(dof)
        v.append(1.0)
    J = sp.csr_matrix((v, (r, c)), shape=(nodes + 2, n))
    return S, J


@pytest.mark.parametrize("seed", range(8))
def test_merged_kkt_order_equals_scipys_on_contact_patterns(seed):
    rng = np.random.default_rng(700 + seed)
    S, J = contact_like_kkt(rng, int(rng.integers(15, 60)), int(rng.integers(0, 12)),
                            zero_rows=int(rng.integers(1, 6)) if seed % 2 else 0)
    assert J.has_canonical_format and (not seed % 2 or np.any(J.data == 0.0))
    merged = ordering._kkt_order_merged(S, J)
    assert merged is not None  # the fast path takes these
    assert np.array_equal(merged, ordering._kkt_order_scipy(S, J))
    assert np.array_equal(ordering.kkt_order(S, J), merged)


def test_merged_kkt_order_sees_exact_cancellation_and_refuses_near_cancellation():
    """Two-term entries of ``J^T J`` that cancel exactly are dropped by scipy (and the
    merged path); an entry of three terms that nearly cancels cannot be certified:
    the merged path declines (None) and kkt_order takes scipy's, the same ordering."""
    rng = np.random.default_rng(11)
    n = 30
    S = sp.csr_matrix(np.diag(rng.uniform(1.0, 2.0, n)) + np.diag(np.ones(n - 1), 1)
                      + np.diag(np.ones(n - 1), -1))

    def jacobian(rows):
        J = np.zeros((len(rows), n))
        for k, entries in enumerate(rows):
            for col, value in entries:
                J[k, col] = value
        return sp.csr_matrix(J)

    base = [[(a, 1.0), (a + 1, rng.standard_normal())] for a in range(0, n - 1, 3)]
    cancelled = jacobian(base + [[(2, 1.0), (20, 1.0)], [(2, 1.0), (20, -1.0)]])
    kept = jacobian(base + [[(2, 1.0), (20, 1.0)], [(2, 1.0), (20, -0.5)]])
    for J in (cancelled, kept):
        merged = ordering._kkt_order_merged(S, J)
        assert merged is not None
        assert np.array_equal(merged, ordering._kkt_order_scipy(S, J))
    assert not np.array_equal(ordering._kkt_order_merged(S, cancelled),
                              ordering._kkt_order_merged(S, kept))
    three = jacobian(base + [[(2, 1.0), (20, 1.0)], [(2, 1.0), (20, 1.0)],
                             [(2, 1.0), (20, -2.0 + 1e-12)]])
    assert ordering._kkt_order_merged(S, three) is None
    assert np.array_equal(ordering._kkt_order(S, three), ordering._kkt_order_scipy(S, three))


def dense_bordered(hessian, J, column, row):
    n, m = hessian.sparse.shape[0], J.shape[0]
    B = np.zeros((n + m + 1, n + m + 1))
    B[:n, :n] = hessian.dense()
    B[:n, n:-1] = J.toarray().T
    B[n:-1, :n] = J.toarray()
    B[:-1, -1] = column
    B[-1] = row
    return B


def test_band_layout_of_nonzeros_drops_far_stored_zeros():
    """Stored zeros far outside the nonzero band are dropped: the band LU is that of the
    nonzero entries alone, bit for bit (LAPACK's band LU of a fancy-indexed ``ab``); a
    nonzero value at a dropped entry is not held."""
    from scipy.linalg import lapack

    from supercoil.solvers.band import band_factor, band_layout, band_layout_of_nonzeros

    rng = np.random.default_rng(21)
    n = 60
    A = sp.coo_matrix(np.diag(rng.uniform(2.0, 3.0, n)) + np.diag(rng.standard_normal(n - 1), 1)
                      + np.diag(rng.standard_normal(n - 2), -2))
    far_rows, far_cols = np.array([0, 50, 3]), np.array([55, 2, 40])
    rows = np.concatenate([A.row, far_rows])
    cols = np.concatenate([A.col, far_cols])
    values = np.concatenate([A.data, np.zeros(3)])
    assert band_layout(n, rows, cols) is None  # the stored band is too wide
    layout = band_layout_of_nonzeros(n, rows, cols, values)
    assert (layout.kl, layout.ku) == (2, 1) and layout.holds(values)
    lub, piv, kl, ku, info = band_factor(layout, values)
    ab = np.zeros((2 * kl + ku + 1, n))
    ab[kl + ku + A.row - A.col, A.col] = A.data
    reference_lub, reference_piv, _info = lapack.dgbtrf(ab, kl, ku)
    assert info == 0 and np.array_equal(lub, reference_lub) and np.array_equal(piv, reference_piv)
    values[-1] = 1e-300
    assert not layout.holds(values)


def test_bordered_factor_takes_the_band_lu_on_stored_zeros_and_wide_bands():
    """A straight-rod-like KKT matrix (stored zeros coupling far unknowns) and a
    contact-like one whose band is 0.25-1/3 of its size went to SuperLU before: both
    now take the band LU, and solve as the dense matrix does; with a nonzero where the
    layout dropped a stored zero, the same pattern goes to SuperLU, as correct."""
    from supercoil.continuation.band_bordered import BandBordered
    from supercoil.continuation.bordered import BAND_FRACTION, BorderedFactor
    from supercoil.solvers.problem import HessianParts

    rng = np.random.default_rng(31)
    cases = []
    S, J = contact_like_kkt(rng, 30, 0)
    coo = S.tocoo()  # stored zeros at (1, 80) and (80, 1): the COO conversion keeps them
    far = sp.csr_matrix((np.concatenate([coo.data, [0.0, 0.0]]),
                         (np.concatenate([coo.row, [1, 80]]),
                          np.concatenate([coo.col, [80, 1]]))), shape=S.shape)
    assert far.nnz > S.nnz
    cases.append((far, J, "zeros"))
    S, J = contact_like_kkt(np.random.default_rng(5), 30, 1)  # one far pair
    order = ordering.kkt_order(S, J)
    size = S.shape[0] + J.shape[0]
    rows, cols, _values = kkt_matrix.kkt_entries(S, J)
    position = np.empty(size, dtype=np.int64)
    position[order] = np.arange(size)
    width = np.max(position[rows] - position[cols]) + np.max(position[cols] - position[rows]) + 1
    assert 0.25 * size < width <= BAND_FRACTION * size  # 39 of 122
    cases.append((S, J, "wide"))
    for S, J, _kind in cases:
        hessian = HessianParts(S)
        size = S.shape[0] + J.shape[0] + 1
        column, row = rng.standard_normal(size - 1), rng.standard_normal(size)
        factor = BorderedFactor(hessian, J, column, row)
        assert isinstance(factor._lu, BandBordered)
        B = dense_bordered(hessian, J, column, row)
        rhs = rng.standard_normal(size)
        exact = np.linalg.solve(B, rhs)
        assert np.max(np.abs(factor.solve(rhs) - exact)) <= \
            1e-13 * np.linalg.cond(B) * np.max(np.abs(exact))
    S, J, _ = cases[0]
    filled = S.copy()
    row_of = np.repeat(np.arange(S.shape[0]), np.diff(S.indptr))
    filled.data[((row_of == 1) & (S.indices == 80)) | ((row_of == 80) & (S.indices == 1))] = 1e-3
    hessian = HessianParts(filled)
    column, row = rng.standard_normal(size - 1), rng.standard_normal(size)
    factor = BorderedFactor(hessian, J, column, row, order=ordering.kkt_order(S, J))
    assert not isinstance(factor._lu, BandBordered)
    B = dense_bordered(hessian, J, column, row)
    rhs = rng.standard_normal(size)
    exact = np.linalg.solve(B, rhs)
    assert np.max(np.abs(factor.solve(rhs) - exact)) <= \
        1e-13 * np.linalg.cond(B) * np.max(np.abs(exact))


@pytest.mark.parametrize("seed", range(4))
def test_roundoff_floor_equals_scipys_row_sums_bit_for_bit(seed):
    """The round-off floor from the stored entries against scipy's
    ``abs(S).sum(axis=1).max()`` (scipy's row sums): empty rows, stored zeros,
    duplicates (a non-canonical matrix) and rows of very different sizes."""
    from supercoil.solvers.newton import roundoff_floor
    from supercoil.solvers.problem import HessianParts

    rng = np.random.default_rng(60 + seed)
    n = int(rng.integers(5, 80))
    k = int(rng.integers(1, 6 * n))
    rows, cols = rng.integers(0, n, k), rng.integers(0, n, k)
    values = rng.standard_normal(k) * 10.0 ** rng.uniform(-8, 8, k)
    values[::5] = 0.0
    S = sp.csr_matrix((values, (rows, cols)), shape=(n, n))
    if seed % 2:  # duplicates kept: scipy sums them as stored
        order = np.argsort(rows, kind="stable")
        indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
        S = sp.csr_matrix((values[order], cols[order], indptr), shape=(n, n))
    q = rng.standard_normal(3 * n)
    reference = np.finfo(float).eps * float(abs(S).sum(axis=1).max()) * float(np.max(np.abs(q)))
    assert roundoff_floor(HessianParts(S), q) == reference
