"""The L D L^T-first block elimination of solvers.inertia (block_inertia_pivoted, what
symmetric_inertia runs) against the dense eigenvalues' signs and the eigh-only Python
reference (band_reference.block_inertia), on band and saddle-point matrices whose pivot blocks have
near-null directions (deferred by the L D L^T, carried by the eigh step), and on two
KKT matrices captured from the N = 200 ring continuation; its compiled Ruiz scaling
and block building against the numpy ones, bit for bit."""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from band_reference import block_inertia, equilibrated_entries

from supercoil.solvers import inertia

DATA = Path(__file__).parent / "data"


def _blocks(A, s):
    """The row blocks of the (already ordered) dense band matrix ``A``."""
    n = A.shape[0]
    rows, cols = np.nonzero(A)
    blocks = np.zeros((-(-n // s), s, 2 * s))
    block = rows // s
    upper = cols >= block * s
    blocks[block[upper], rows[upper] - block[upper] * s, cols[upper] - block[upper] * s] = \
        A[rows, cols][upper]
    return blocks


def _dense_count(A):
    """``(neg, 0, pos)`` from eigvalsh, or None when an eigenvalue is within 100 n u of
    the largest (eigvalsh's error bound, with margin): the sign is then not certain."""
    ev = np.linalg.eigvalsh(A)
    scale = np.max(np.abs(ev))
    if np.min(np.abs(ev)) <= 100 * A.shape[0] * np.finfo(float).eps * scale:
        return None
    return int(np.sum(ev < 0)), 0, int(np.sum(ev > 0))


def _near_null_blocks(rng, n_blocks, s, eps):
    """Block tridiagonal, blocks of size ``s``: diagonal blocks ``Q diag(mu) Q^T`` (Q
    random orthogonal) with one to three ``mu`` of size ``eps`` (or exactly 0), the
    others of either sign in [0.5, 2]; lower-triangular O(1) couplings, so the near-null
    directions of a pivot block are coupled to the next one (the matrix itself stays
    regular while ``P^{-1}`` of the pivot block is huge)."""
    n = n_blocks * s
    A = np.zeros((n, n))
    for k in range(n_blocks):
        mu = rng.choice((-1.0, 1.0), s) * rng.uniform(0.5, 2.0, s)
        r = int(rng.integers(1, 4))
        mu[:r] = eps * rng.standard_normal(r)
        Q, _ = np.linalg.qr(rng.standard_normal((s, s)))
        A[k * s:(k + 1) * s, k * s:(k + 1) * s] = (Q * mu) @ Q.T
        if k + 1 < n_blocks:
            C = np.tril(rng.standard_normal((s, s)))
            A[k * s:(k + 1) * s, (k + 1) * s:(k + 2) * s] = C
            A[(k + 1) * s:(k + 2) * s, k * s:(k + 1) * s] = C.T
    return 0.5 * (A + A.T)


def _saddle_band(rng, n, m):
    """A KKT matrix ``[[H, J^T], [J, 0]]`` of a chain (``H`` pentadiagonal, indefinite
    when ``rng`` says so; constraint ``j`` on unknowns ``j, j + 1, j + 2``), each
    multiplier placed right after its first unknown (kkt_order's rule): a band matrix
    with zero diagonal entries, the case plain L D L^T without pivoting fails on."""
    H = np.zeros((n, n))
    for k in range(3):
        d = rng.standard_normal(n - k)
        H += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
    H += rng.choice((2.0, -0.5)) * np.eye(n)
    J = np.zeros((m, n))
    for j in range(m):
        J[j, j:j + 3] = rng.standard_normal(3)
    K = np.block([[H, J.T], [J, np.zeros((m, m))]])
    order = []
    for i in range(n):
        order.append(i)
        if i < m:
            order.append(n + i)
    order = np.array(order)
    return K[np.ix_(order, order)]


@pytest.mark.parametrize("seed", range(12))
def test_pivoted_block_inertia_equals_the_dense_count_and_the_eigh_reference(seed):
    rng = np.random.default_rng(900 + seed)
    kind = seed % 3
    if kind == 0:  # near-null pivot blocks, coupled
        s = int(rng.integers(8, 24))
        A = _near_null_blocks(rng, int(rng.integers(3, 9)), s,
                              (1e-6, 1e-9, 1e-12, 0.0)[seed // 3 % 4])
    elif kind == 1:  # saddle point band
        n = int(rng.integers(30, 120))
        A = _saddle_band(rng, n, int(rng.integers(n // 3, n - 2)))
        s = 16
    else:  # rank-one huge stretches: pivot blocks whose directions are carried
        n, b = int(rng.integers(60, 200)), int(rng.integers(2, 12))
        A = np.zeros((n, n))
        for k in range(b + 1):
            d = rng.standard_normal(n - k)
            A += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
        for start in range(0, n - b, 3 * b):
            u = rng.standard_normal(b)
            A[start:start + b, start:start + b] = 1e6 * np.outer(u, u)
        s = max(b, 16)
    n = A.shape[0]
    blocks = _blocks(A, s)
    pivoted = tuple(int(v) for v in inertia.block_inertia_pivoted(
        blocks, n, s, inertia.MAX_CONDITION, inertia.MAX_CARRIED, inertia.MIN_PIVOT))
    dense = _dense_count(A)
    assert dense is not None  # the generators make regular matrices (else no oracle)
    assert pivoted == dense
    assert block_inertia(blocks, n, s) == dense
    assert inertia.symmetric_inertia(sp.csr_matrix(A)) == dense


def test_near_null_pivot_blocks_are_deferred_not_divided_by():
    """The oracle above exercises the deferral: the first pivot block of a near-null
    matrix leaves its near-null directions (and no more than a few others) to eigh, and
    every pivot it divides by is above the tolerance."""
    rng = np.random.default_rng(901)
    s = 16
    A = _near_null_blocks(rng, 3, s, 1e-12)
    P = A[:s, :s]
    M = np.hstack([P, A[:s, s:2 * s]])
    tol = inertia.MIN_PIVOT * np.max(np.abs(P))
    e, widths, neg, pos, biggest = inertia.partial_ldl(M, s, tol)
    small = int(np.sum(np.abs(np.linalg.eigvalsh(P)) < 1e-9))
    assert small >= 1 and s - e >= small
    p, largest = 0, 0.0
    while p < e:  # each pivot (1 x 1, or the smaller eigenvalue of a 2 x 2) above tol
        w = widths[p]
        magnitudes = np.abs(np.linalg.eigvalsh(M[p:p + w, p:p + w]))
        assert np.min(magnitudes) > tol
        largest = max(largest, np.max(magnitudes))
        p += w
    assert np.isclose(biggest, largest, rtol=1e-12)
    # the congruence: the eliminated pivots' signs plus the deferred rest's = P's inertia
    rest = M[e:, e:s]
    ev_rest = np.linalg.eigvalsh(0.5 * (rest + rest.T))
    ev = np.linalg.eigvalsh(P)
    big_rest = np.abs(ev_rest) > 1e-6
    big = np.abs(ev) > 1e-6
    assert neg + int(np.sum(ev_rest[big_rest] < 0)) == int(np.sum(ev[big] < 0))
    assert pos + int(np.sum(ev_rest[big_rest] > 0)) == int(np.sum(ev[big] > 0))


def _captured(name):
    f = np.load(DATA / name)
    n = int(f["n"])
    return sp.csr_matrix((f["data"], f["indices"], f["indptr"]), shape=(n, n)), f["order"]


def _numpy_blocks(rows, cols, values, n):
    """The row blocks of the permuted scaled entries as the numpy reference builds them
    (the layout of ``equilibrated_blocks``): ``(blocks, s)``."""
    s = max(int(np.max(np.abs(rows - cols))) if values.size else 0, 16)
    blocks = np.zeros((-(-n // s), s, 2 * s))
    block = rows // s
    upper = cols >= block * s
    blocks[block[upper], rows[upper] - block[upper] * s, cols[upper] - block[upper] * s] = \
        values[upper]
    return blocks, s


@pytest.mark.parametrize("name", ["kkt_ring200_contact.npz", "kkt_ring200_free.npz"])
def test_captured_ring_kkt_matrices(name):
    """KKT matrices of the N = 200 ring (alpha with contact, b = 43; without, b = 19):
    symmetric_inertia against the dense count of the Ruiz-scaled matrix (a congruence;
    unscaled, the smallest eigenvalue is 4e-19 of the largest, not certain) and the
    eigh-only reference; the compiled blocks are those of the numpy scaling, bit for bit."""
    A, order = _captured(name)
    n = A.shape[0]
    rows, cols, values = equilibrated_entries(A, order)
    scaled = sp.coo_matrix((values, (rows, cols)), shape=(n, n)).toarray()
    dense = _dense_count(0.5 * (scaled + scaled.T))
    assert dense is not None
    assert inertia.symmetric_inertia(A, order) == dense
    blocks, s = _numpy_blocks(rows, cols, values, n)
    position = np.empty(n, dtype=np.int64)
    position[order] = np.arange(n)
    compiled, s_compiled = inertia.equilibrated_blocks(A.indptr, A.indices, A.data, position)
    assert s_compiled == s and compiled.tobytes() == blocks.tobytes()
    assert block_inertia(blocks, n, s) == dense


@pytest.mark.parametrize("seed", range(4))
def test_compiled_blocks_equal_the_numpy_ones_bit_for_bit(seed):
    """Random symmetric sparse matrices with rows of very different sizes and explicit
    zeros: equilibrated_blocks against equilibrated_entries + the numpy block build."""
    rng = np.random.default_rng(910 + seed)
    n = int(rng.integers(20, 150))
    A = sp.random(n, n, density=0.05, random_state=rng, format="csr")
    A = (A + A.T).tocsr()
    A = sp.csr_matrix(A.multiply(10.0 ** rng.uniform(-4, 4, n)[:, None]))
    A = (A + A.T).tocsr()
    A.data[rng.random(A.data.size) < 0.1] = 0.0  # stored zeros, dropped by both
    order = rng.permutation(n)
    rows, cols, values = equilibrated_entries(A, order)
    blocks, s = _numpy_blocks(rows, cols, values, n)
    position = np.empty(n, dtype=np.int64)
    position[order] = np.arange(n)
    compiled, s_compiled = inertia.equilibrated_blocks(A.indptr, A.indices, A.data, position)
    assert s_compiled == s and compiled.tobytes() == blocks.tobytes()
