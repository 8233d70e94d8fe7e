"""solvers.patterns.block_csr (the integral contact's Hessian assembly) against scipy's
COO path: the same pattern (explicit zeros too) and stored order, values equal to
round-off (duplicates summed in another order), exactly where there are none."""

import numpy as np
import pytest
import scipy.sparse as sp

from supercoil.solvers.patterns import block_csr


def _scipy(dofs, blocks, n):
    w = dofs.shape[1]
    rows = np.repeat(dofs, w, axis=1).ravel()
    cols = np.tile(dofs, (1, w)).ravel()
    return sp.csr_matrix((blocks[:len(dofs)].ravel(), (rows, cols)), shape=(n, n))


@pytest.mark.parametrize("seed", range(6))
def test_block_csr_equals_scipy_coo_assembly(seed):
    rng = np.random.default_rng(700 + seed)
    n, p, w = int(rng.integers(20, 300)), int(rng.integers(1, 60)), int(rng.choice([3, 12, 24]))
    w = min(w, n)
    if seed % 2:  # contact-like: two stretches of the rod facing each other
        base = rng.integers(0, n - w, p)
        dofs = np.array([np.r_[np.arange(b, b + w // 2), np.arange(n - w + w // 2 - b,
                                                                n - b)][:w] for b in base])
        dofs = np.clip(dofs, 0, n - 1)
        dofs = np.array([d if np.unique(d).size == w else rng.choice(n, w, replace=False)
                         for d in dofs])
    else:
        dofs = np.array([rng.choice(n, size=w, replace=False) for _ in range(p)])
    blocks = rng.standard_normal((p + 2, w, w))  # extra rows beyond p are ignored
    blocks[:, 0, -1] = 0.0  # explicit zeros are stored, as scipy stores them
    mine, ref = block_csr(dofs, blocks, n), _scipy(dofs, blocks, n)
    assert mine.has_canonical_format and ref.has_canonical_format
    assert np.array_equal(mine.indptr, ref.indptr) and np.array_equal(mine.indices, ref.indices)
    np.testing.assert_allclose(mine.data, ref.data, rtol=0, atol=1e-14 * np.abs(ref.data).max())
    # without repeated DOFs across blocks there is nothing to sum: bit for bit
    single = block_csr(dofs[:1], blocks, n)
    assert np.array_equal(single.data, _scipy(dofs[:1], blocks, n).data)


def test_block_csr_of_no_blocks_is_the_zero_matrix():
    empty = block_csr(np.zeros((0, 24), dtype=np.int64), np.zeros((0, 24, 24)), 50)
    assert empty.shape == (50, 50) and empty.nnz == 0
    with pytest.raises(ValueError):
        block_csr(np.array([[0, 50]]), np.zeros((1, 2, 2)), 50)
