"""The lowest eigenpairs of a constrained pencil from the LU basis of ``ker J``
(``supercoil.stability.eigen.lowest_dense_pairs``).

Oracles: the dense reference (an SVD null space and the full generalized eigenproblem,
``dense_constrained_eigenpairs``), and a pencil built from its spectrum on ``ker J``
(M-orthonormal eigenvectors chosen), so the eigenvalues are known exactly; the spectrum
spans the range met on a plectoneme in contact (a sliding eigenvalue of -1e8 beside
positive ones from 500 to 1e7).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.linalg import eigh, null_space

from supercoil.solvers.problem import HessianParts
from supercoil.stability.eigen import dense_constrained_eigenpairs, lowest_dense_pairs


def chain_constraints(n: int, m: int, rng) -> sp.csr_matrix:
    """``m`` banded rows on ``n`` unknowns, each coupling three neighbours (as an
    inextensible rod's rows couple the positions of two nodes)."""
    rows, cols, data = [], [], []
    for i in range(m):
        start = (i * (n - 3)) // max(m - 1, 1)
        for j in range(3):
            rows.append(i)
            cols.append(start + j)
            data.append(rng.standard_normal())
    return sp.csr_matrix((data, (rows, cols)), shape=(m, n))


def spectral_pencil(spectrum: np.ndarray, J: sp.csr_matrix, mass: np.ndarray, rng):
    """``H`` (sparse part plus one rank-one term) whose pencil on ``ker J`` has exactly
    ``spectrum`` (ascending, one value per dimension of ``ker J``)."""
    Z = null_space(J.toarray())
    values, vectors = eigh(Z.T @ (mass[:, None] * Z))
    V = Z @ vectors / np.sqrt(values)  # M-orthonormal basis of ker J
    V = V @ np.linalg.qr(rng.standard_normal((V.shape[1], V.shape[1])))[0]
    MV = mass[:, None] * V
    H = MV @ np.diag(spectrum) @ MV.T
    u = rng.standard_normal(mass.size)
    # a rank-one term kept apart, as the writhe's gradient is; the sparse part holds
    # the rest, so the pencil is unchanged
    return HessianParts(sp.csr_matrix(H - 3.0 * np.outer(u, u)), u[None, :], np.array([3.0]))


@pytest.mark.parametrize("n, m, k", [(40, 12, 1), (61, 20, 3), (90, 29, 5)])
def test_the_lowest_pairs_are_the_references_and_the_exact_spectrum(n, m, k):
    rng = np.random.default_rng(n)
    J = chain_constraints(n, m, rng)
    mass = rng.uniform(0.5, 2.0, n)
    spectrum = np.sort(np.concatenate([[-1e8, -4e5], rng.uniform(500.0, 1e7, n - m - 2)]))
    H = spectral_pencil(spectrum, J, mass, rng)
    values, vectors = lowest_dense_pairs(H, J, mass, k)
    reference, ref_vectors = dense_constrained_eigenpairs(H, J, mass)
    assert values.shape == (k,) and vectors.shape == (n, k)
    np.testing.assert_allclose(values, spectrum[:k], rtol=1e-8)
    np.testing.assert_allclose(values, reference[:k], rtol=1e-8)
    np.testing.assert_allclose(J @ vectors, 0.0, atol=1e-10 * np.abs(vectors).max())
    np.testing.assert_allclose(vectors.T @ (mass[:, None] * vectors), np.eye(k), atol=1e-9)
    # the same eigenvectors as the reference's, up to sign (the eigenvalues are simple)
    overlap = np.abs(np.diag(vectors.T @ (mass[:, None] * ref_vectors[:, :k])))
    np.testing.assert_allclose(overlap, 1.0, atol=1e-7)
    residual = H.matmat(vectors) - mass[:, None] * vectors * values
    # H v - mu M v lies in the row space of J (the constraint forces)
    multipliers = np.linalg.lstsq(J.T.toarray(), residual, rcond=None)[0]
    assert np.abs(residual - J.T @ multipliers).max() <= 1e-7 * np.abs(values).max()


def test_a_rank_deficient_constraint_set_falls_back_to_the_reference():
    """A repeated row: the LU's pivot vanishes, and the null space is the SVD's (the
    LU basis would miss a direction of ``ker J``)."""
    rng = np.random.default_rng(5)
    n, m = 30, 8
    J = chain_constraints(n, m, rng).toarray()
    J = sp.csr_matrix(np.vstack([J, J[2]]))
    mass = rng.uniform(0.5, 2.0, n)
    H = HessianParts(sp.csr_matrix(np.diag(rng.uniform(-5.0, 50.0, n))))
    values, _ = lowest_dense_pairs(H, J, mass, n - m)
    reference, _ = dense_constrained_eigenpairs(H, J, mass)
    assert reference.size == n - m  # the repeated row removes no direction
    np.testing.assert_allclose(values, reference, rtol=1e-10, atol=1e-10)


def test_no_constraints_and_no_pairs_wanted():
    rng = np.random.default_rng(8)
    n = 12
    mass = rng.uniform(0.5, 2.0, n)
    diagonal = rng.uniform(-5.0, 50.0, n)
    H = HessianParts(sp.csr_matrix(np.diag(diagonal)))
    J = sp.csr_matrix((0, n))
    values, _ = lowest_dense_pairs(H, J, mass, 3)
    np.testing.assert_allclose(values, np.sort(diagonal / mass)[:3], rtol=1e-12)
    values, vectors = lowest_dense_pairs(H, J, mass, 0)
    assert values.shape == (0,) and vectors.shape == (n, 0)
