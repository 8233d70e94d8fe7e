"""solvers.csr_sum.block_csr (the integral contact's Hessian assembly) against scipy's
COO path: the same pattern (explicit zeros too) and stored order, values equal to
round-off (duplicates summed in another order), exactly where there are none; and
csr_add_blocks (the blocks merged into the rod's Hessian) against
csr_add(A, block_csr(...)) bit for bit and scipy's A + B to round-off."""

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import same_bits

from supercoil.solvers.csr_sum import block_csr, csr_add, csr_add_blocks


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


@pytest.mark.parametrize("seed", range(6))
def test_csr_add_blocks_is_csr_add_of_block_csr_bit_for_bit(seed):
    rng = np.random.default_rng(900 + seed)
    n, p, w = int(rng.integers(30, 250)), int(rng.integers(0, 50)), int(rng.choice([6, 12, 24]))
    A = sp.random(n, n, density=0.08, random_state=seed, format="csr")
    A = (A + A.T + sp.eye(n)).tocsr()
    A.data[::9] = 0.0  # explicit zeros of A: dropped by the sum, as scipy drops them
    A.sort_indices()
    dofs = np.array([rng.choice(n, size=w, replace=False) for _ in range(p)],
                    dtype=np.int64).reshape(p, w)
    blocks = rng.standard_normal((p, w, w))
    if p:  # a block entry that cancels A's entry exactly (the sum is dropped)
        r, c = dofs[0, 1], dofs[0, 2]
        blocks[0, 1, 2] = -A[r, c] if A[r, c] != 0 else 0.0
        blocks[0, 3, 4] = -0.0
    mine = csr_add_blocks(A, dofs, blocks)
    former = csr_add(A, block_csr(dofs, blocks, n))
    assert mine.has_canonical_format and same_bits(mine, former)
    reference = (A + _scipy(dofs, blocks, n)).tocsr()
    assert np.array_equal(mine.indptr, reference.indptr)
    assert np.array_equal(mine.indices, reference.indices)
    np.testing.assert_allclose(mine.data, reference.data, rtol=0,
                               atol=1e-13 * max(1.0, np.abs(reference.data).max()))


def test_merged_arrays_widen_indices_that_would_overflow():
    """canonical_arrays keeps the operands' index dtype unless the entry count or the
    shape exceeds it (then wider, as scipy upcasts; int8 operands stand in for int32
    ones past 2^31 entries)."""
    from supercoil.solvers.csr_sum import canonical_arrays

    A = sp.random(200, 200, density=0.01, format="csr", random_state=3)
    A.sum_duplicates()
    narrow = canonical_arrays(A.data, A.indices, A.indptr, A.shape, np.int8, np.int8)
    # not wrapped around int8 (scipy may then take int32, the smallest that holds them)
    assert np.iinfo(narrow.indptr.dtype).max >= A.nnz and (narrow.tocsr() != A).nnz == 0
    kept = canonical_arrays(A.data, A.indices, A.indptr, A.shape, np.int32, np.int32)
    assert kept.indices.dtype == kept.indptr.dtype == np.int32
    assert (kept.tocsr() != A).nnz == 0
