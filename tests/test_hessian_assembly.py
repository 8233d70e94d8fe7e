"""The Lagrangian Hessian's compiled assembly against the paths it replaced, bit for bit.

* csr_restrict (one compiled pass) against scipy's ``A[keep][:, keep]``: explicit
  zeros, -0.0, unsorted rows, both index dtypes, empty and full ``keep``; what it does
  not take (unsorted or out-of-range ``keep``) goes to scipy;
* csr_add_blocks with ``then`` against ``csr_add(csr_add(A, block_csr(...)), then)``:
  exact cancellations at either sum, repeated DOFs within a block, no blocks;
* ContactProblem.lagrangian_hessian against ``hessian(q).plus_sparse(
  constraint_hessian(q, mu))`` for each formulation, and through
  ``solvers.newton.lagrangian_hessian``; RodEnergy.lagrangian_hessian likewise;
* the rod's constraint curvature values against the numpy fill they replaced;
* the integral contact's pair Hessians against a Python loop of the kernel's formula
  in its order.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import same_bits
from contact_toys import integral_pair_hessians_loop, stadium_ring

from supercoil.contact.integral import integral_terms
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.sample_weights import polygon_weights, spline_weights
from supercoil.contact.spline_pieces import bspline_pieces
from supercoil.solvers.csr import csr_restrict
from supercoil.solvers.csr_sum import block_csr, csr_add, csr_add_blocks
from supercoil.solvers.newton import lagrangian_hessian


@pytest.mark.parametrize("seed", range(8))
def test_csr_restrict_equals_scipy_bit_for_bit(seed):
    rng = np.random.default_rng(40 + seed)
    n = int(rng.integers(1, 90))
    A = sp.random(n, n, density=0.2, random_state=seed, format="csr")
    A.data[::5] = 0.0
    A.data[1::7] = -0.0
    if seed % 2:  # a row stored out of column order keeps its stored order
        A.indices = A.indices.astype(np.int64)
        A.indptr = A.indptr.astype(np.int64)
        row = int(np.argmax(np.diff(A.indptr)))
        start, end = A.indptr[row], A.indptr[row + 1]
        A.indices[start:end] = A.indices[start:end][::-1].copy()
        A.data[start:end] = A.data[start:end][::-1].copy()
        A.has_sorted_indices = False
    keeps = [np.flatnonzero(rng.random(n) < 0.7), np.arange(n), np.zeros(0, dtype=np.int64),
             np.flatnonzero(rng.random(n) < 0.5).astype(np.int32)]
    for keep in keeps:
        ref = A[keep][:, keep].tocsr()
        mine = csr_restrict(A, keep)
        assert same_bits(mine, ref)
        assert np.array_equal(np.signbit(mine.data), np.signbit(ref.data))
        # the canonical flag, where set, is what scipy's own check finds
        fresh = sp.csr_matrix((mine.data, mine.indices, mine.indptr), shape=mine.shape)
        assert mine.has_canonical_format == fresh.has_canonical_format
    if n > 2:  # not strictly increasing, or out of range: scipy's own path
        for keep in (np.array([2, 0, 1]), np.array([0, 0, 1]), np.array([-1, 0])):
            assert (csr_restrict(A, keep) != A[keep][:, keep]).nnz == 0


def _canonical(M):
    M = sp.csr_matrix(M)
    M.sum_duplicates()
    M.sort_indices()
    return M


@pytest.mark.parametrize("seed", range(10))
def test_csr_add_blocks_then_is_two_csr_adds_bit_for_bit(seed):
    rng = np.random.default_rng(80 + seed)
    n, p, w = int(rng.integers(12, 200)), int(rng.integers(0, 40)), int(rng.choice([3, 6, 24]))
    A = _canonical(sp.random(n, n, density=0.08, random_state=seed) + sp.eye(n))
    A.data[::9] = 0.0  # explicit zeros of A: dropped by the sum
    if seed % 3 == 0:  # DOFs repeated within a block (summed in the block's order)
        dofs = rng.integers(0, n, (p, w))
    elif seed % 3 == 1:  # whole nodes, as the contact's pair blocks
        nodes = np.array([rng.choice(n // 3, size=w // 3, replace=False) for _ in range(p)],
                         dtype=np.int64).reshape(p, w // 3)
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(p, w)
    else:
        dofs = np.array([rng.choice(n, size=w, replace=False) for _ in range(p)],
                        dtype=np.int64).reshape(p, w)
    blocks = rng.standard_normal((p + 1, w, w))  # a row beyond p is ignored
    blocks[:, 0, :] = -0.0
    if p:  # a block entry that cancels A's entry exactly
        r, c = dofs[0, 1], dofs[0, 2]
        blocks[0, 1, 2] = -A[r, c] if A[r, c] != 0 else 0.0
    C = _canonical(sp.random(n, n, density=0.04, random_state=seed + 7))
    C.data[::4] = -0.0
    first = csr_add(A, block_csr(dofs, blocks, n))
    if first.nnz:  # an entry of C that cancels the first sum's exactly
        row = int(np.searchsorted(first.indptr, 0, side="right") - 1)
        C = _canonical(C + sp.csr_matrix(([-first.data[0]], ([row], [first.indices[0]])),
                                         shape=(n, n)))
    ref = csr_add(first, C)
    mine = csr_add_blocks(A, dofs, blocks, C)
    assert mine.has_canonical_format and same_bits(mine, ref)
    assert same_bits(csr_add_blocks(A, dofs, blocks), first)
    empty = np.zeros((0, w), dtype=np.int64)
    assert same_bits(csr_add_blocks(A, empty, np.zeros((0, w, w)), C),
                      csr_add(csr_add(A, sp.csr_matrix((n, n))), C))
    # no blocks given as an empty 1-D list (the former path; the kernel types 2-D DOFs)
    assert same_bits(csr_add_blocks(A, np.zeros(0, dtype=np.int64), np.zeros(0), C),
                      csr_add(csr_add(A, sp.csr_matrix((n, n))), C))
    # a non-canonical third operand goes through csr_add's own path
    unsorted = C.copy()
    unsorted.has_canonical_format = False
    assert (csr_add_blocks(A, dofs, blocks, unsorted) != ref).nnz == 0


D = 0.02


def _stadium(n=80, spacing=1.05):
    """A closed rod of length 1 whose two straight sides lie ``spacing`` D apart."""
    return stadium_ring(n, 0.5 * spacing * D)


@pytest.mark.parametrize("choice", [{"curve": "spline", "formulation": "integral"},
                                    {"formulation": "integral"}, {"curve": "spline"}, {}])
def test_contact_lagrangian_hessian_is_the_hessian_plus_the_curvature(choice):
    rod, x = _stadium()
    problem = ContactProblem(rod, ContactOptions(diameter=D, barrier_activation=0.1,
                                                 **choice))  # reach: 1.1 D
    rng = np.random.default_rng(5)
    for step in range(3):  # the first two at one pair list, then another
        q = (x + (1e-4 if step < 2 else 3e-3) * D * rng.standard_normal(x.shape)).ravel()
        mu = rng.standard_normal(problem.n_constraints)
        mu[::7] = 0.0
        ref = problem.hessian(q).plus_sparse(problem.constraint_hessian(q, mu))
        assert len(problem.pair_state(q, 1.1 * D).pairs)  # pairs within the barrier's reach
        for mine in (problem.lagrangian_hessian(q, mu), lagrangian_hessian(problem, q, mu)):
            assert same_bits(mine.sparse, ref.sparse)
            assert np.array_equal(mine.vectors, ref.vectors)
            assert np.array_equal(mine.coefficients, ref.coefficients)


def test_rod_lagrangian_hessian_is_the_hessian_plus_the_curvature():
    """RodEnergy.lagrangian_hessian (the curvature summed on arrays) against
    ``hessian(q).plus_sparse(constraint_hessian(q, mu))``, bit for bit, on the closed rod
    and on a clamped one, directly and through ``solvers.newton.lagrangian_hessian``."""
    from supercoil.rod.model import Rod
    from supercoil.rod.open import ClampedRodEnergy, straight_rod

    rod, x = _stadium(40)
    clamped = ClampedRodEnergy(Rod(n_nodes=30, length=1.0, closed=False), straight_rod(30), 1.5)
    rng = np.random.default_rng(11)
    for problem, state in ((rod, x.ravel()), (clamped, straight_rod(30).ravel())):
        q = state + 1e-3 * rng.standard_normal(state.size)
        mu = rng.standard_normal(problem.n_constraints)
        mu[::7] = 0.0
        ref = problem.hessian(q).plus_sparse(problem.constraint_hessian(q, mu))
        for mine in (problem.lagrangian_hessian(q, mu), lagrangian_hessian(problem, q, mu)):
            assert same_bits(mine.sparse, ref.sparse)
            assert np.array_equal(mine.vectors, ref.vectors)
            assert np.array_equal(mine.coefficients, ref.coefficients)


def test_rod_hessian_is_flagged_canonical_rightly():
    rod, x = _stadium(40)
    S = rod.hessian(x.ravel()).sparse
    fresh = sp.csr_matrix((S.data, S.indices, S.indptr), shape=S.shape)
    assert vars(S).get("_has_canonical_format") is True and fresh.has_canonical_format
    restricted = csr_restrict(S, np.arange(3, S.shape[0] - 2))
    assert vars(restricted).get("_has_canonical_format") is True


def test_rod_constraint_curvature_equals_the_numpy_fill_bit_for_bit():
    rod, x = _stadium(40)
    rng = np.random.default_rng(2)
    mu = rng.standard_normal(rod.n_constraints) * 10.0 ** rng.integers(-8, 3, rod.n_constraints)
    mu[::5] = 0.0
    mu[1::9] = -0.0
    H = rod.constraint_hessian(x.ravel(), mu)
    assert H.has_canonical_format and H.has_sorted_indices
    # the numpy fill of the remembered pattern that the compiled loop replaced
    _, first, second, indices, indptr = rod._shared["curvature_pattern"]
    w = np.repeat(mu / rod.rod.edge_length, 3)
    data = np.concatenate([w, w, -w, -w])
    values = data[first]
    double = second >= 0
    values[double] = values[double] + data[second[double]]
    assert np.array_equal(H.data.view(np.int64), values.view(np.int64))
    assert np.array_equal(H.indices, indices) and np.array_equal(H.indptr, indptr)
    ref = sp.csr_matrix((H.data, H.indices, H.indptr), shape=H.shape)
    ref.sum_duplicates()
    ref.sort_indices()
    assert same_bits(H, ref)


@pytest.mark.parametrize("spline", [False, True])
def test_integral_pair_hessians_equal_a_python_loop_bit_for_bit(spline):
    _rod, x = _stadium(40)
    rng = np.random.default_rng(9)
    x = x + 2e-3 * D * rng.standard_normal(x.shape)
    segments = np.stack([np.arange(40), (np.arange(40) + 1) % 40], 1)
    q = 4
    if spline:
        pieces = bspline_pieces(segments, True)
        stencil, weights = np.ascontiguousarray(pieces.stencil), spline_weights(
            pieces.coefficients, q)
    else:
        stencil, weights = segments, polygon_weights(40, q)
    pairs = np.array([[i, j] for i in range(40) for j in range(i + 5, 40)
                      if np.linalg.norm(x[i] - x[j]) < 3 * D])
    assert len(pairs)
    activation, stiffness, h = 0.5 * D, 3.0, 1.0 / 40
    scale = (h / q) ** 2 / (2.0 * D * activation)
    _e, _g, hess, _f, _p, _dofs = integral_terms(x, stencil, weights, pairs, D, "barrier",
                                                 stiffness, activation, h, order=2)
    ref = integral_pair_hessians_loop(x, stencil, weights, pairs, D, stiffness, activation, scale)
    assert np.abs(ref).max() > 0
    assert np.array_equal(hess.view(np.int64), ref.view(np.int64))
