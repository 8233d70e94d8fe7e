"""The compiled block elimination of solvers.band (_block_inertia_compiled) against
its Python reference (_block_inertia) and the dense eigenvalues: the same inertia,
on matrices whose pivot blocks have near-null directions to carry."""

import numpy as np
import pytest

from supercoil.solvers import band


def _blocks(A, s):
    """The row blocks of the band matrix ``A`` (already ordered) as _symmetric_inertia
    builds them."""
    n = A.shape[0]
    rows, cols = np.nonzero(A)
    values = A[rows, cols]
    blocks = np.zeros((-(-n // s), s, 2 * s))
    block = rows // s
    upper = cols >= block * s
    blocks[block[upper], rows[upper] - block[upper] * s, cols[upper] - block[upper] * s] = \
        values[upper]
    return blocks


def _carrying_matrix(rng, n, b):
    """Symmetric, half-bandwidth ``b``, with rank-deficient diagonal stretches (pivot
    blocks with eigenvalues far below their largest: carried to the next block)."""
    A = np.zeros((n, n))
    for k in range(b + 1):
        d = rng.standard_normal(n - k)
        A += np.diag(d, k) + (np.diag(d, -k) if k else 0.0)
    for start in range(0, n - b, 3 * b):
        u = rng.standard_normal(b)
        A[start:start + b, start:start + b] = 1e6 * np.outer(u, u)  # rank one, huge
    return A


@pytest.mark.parametrize("seed", range(8))
def test_compiled_block_inertia_equals_the_python_reference_and_the_dense_count(seed):
    rng = np.random.default_rng(1300 + seed)
    n, b = int(rng.integers(40, 200)), int(rng.integers(2, 12))
    if seed % 2:
        A = _carrying_matrix(rng, n, b)
    else:  # a plain random band matrix
        near = np.abs(np.subtract.outer(np.arange(n), np.arange(n))) <= b
        A = rng.standard_normal((n, n)) * near
        A = A + A.T
    s = max(b, 16)
    blocks = _blocks(A, s)
    compiled = band._block_inertia_compiled(blocks, n, s, band._MAX_CONDITION,
                                            band._MAX_CARRIED)
    reference = band._block_inertia(blocks, n, s)
    assert tuple(int(v) for v in compiled) == reference
    ev = np.linalg.eigvalsh(A)
    scale = np.max(np.abs(ev))
    if np.min(np.abs(ev)) > 1e-9 * scale:  # the dense count is certain
        assert reference == (int(np.sum(ev < 0)), 0, int(np.sum(ev > 0)))


def test_the_carrying_matrices_do_carry():
    """The oracle above exercises the carried directions (not only full elimination)."""
    rng = np.random.default_rng(1301)
    A = _carrying_matrix(rng, 120, 6)
    s = 16
    first = A[:s, :s]
    values = np.linalg.eigvalsh(first)
    assert np.sum(np.abs(values) <= np.max(np.abs(values)) / band._MAX_CONDITION) > 0
