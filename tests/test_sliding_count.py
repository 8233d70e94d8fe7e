"""The stiff sliding's eigenvalue left out of the unstable count
(``supercoil.stability.sliding_count``).

Oracle: a constrained Hessian built from its spectrum on ``ker J`` (M-orthonormal
eigenvectors chosen), with a sliding eigenvector ``v_s`` that is the approximate
symmetry's generator ``g`` only to an overlap ``cos(theta)``. The count with the
sliding's eigenvalue left out is the count on the M-complement of ``v_s`` itself,
computed densely; the count on the complement of ``g`` (the phase row's) is corrected
by :func:`sliding_left_out` to it, whatever the signs.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.linalg import eigh, null_space

from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.problem import HessianParts
from supercoil.stability.sliding_count import sliding_left_out, without_sliding_pairs


def spectral_problem(sliding: float, others: list[float], share: float, seed: int = 3,
                     n: int = 14):
    """``(H, J, mass, g, v_s)``: ``n`` unknowns, 3 constraint rows; on ``ker J`` the
    eigenvalues ``sliding`` (eigenvector ``v_s``) and ``others`` (the first one, ``w``,
    with ``v_s`` and ``g`` in one plane: ``g = cos v_s - sin w``, ``cos^2 = share``),
    the rest of ``ker J`` at 5e3."""
    rng = np.random.default_rng(seed)
    m = 3
    J = rng.standard_normal((m, n))
    mass = rng.uniform(0.5, 2.0, n)
    Z = null_space(J)
    # M-orthonormal basis of ker J
    values, vectors = eigh(Z.T @ (mass[:, None] * Z))
    V = Z @ vectors / np.sqrt(values)
    spectrum = np.full(V.shape[1], 5e3)
    spectrum[0] = sliding
    spectrum[1:1 + len(others)] = others
    MV = mass[:, None] * V
    H = MV @ np.diag(spectrum) @ MV.T
    c, s = np.sqrt(share), np.sqrt(1.0 - share)
    g = c * V[:, 0] - s * V[:, 1]
    return H, sp.csr_matrix(J), mass, g, V[:, 0]


def count_on_complement(H, J, mass, v) -> int:
    """The dense count of negative eigenvalues of ``H`` on ``ker J`` less ``v`` (M-orth.)."""
    Z = null_space(np.vstack([J.toarray(), mass * v]))
    return int(np.sum(eigh(Z.T @ H @ Z, Z.T @ (mass[:, None] * Z), eigvals_only=True) < 0))


@pytest.mark.parametrize("sliding, others, share", [
    (-1e4, [600.0], 0.7),          # the ripple's leak: the complement of g counts one
    (-1e4, [600.0, -50.0], 0.7),   # ... with a genuine unstable mode besides
    (1e4, [600.0, -50.0], 0.7),    # the sliding stable: the genuine mode alone
    (-1e4, [600.0, -50.0], 0.95),  # the row takes the sliding's eigenvalue out itself
    (-1e4, [600.0], 0.95),
    (-30.0, [600.0, 900.0], 0.9),  # a nearly free sliding: the row takes it out
])
def test_the_count_on_the_complement_of_g_corrected_is_the_one_without_the_sliding_mode(
        sliding, others, share):
    H, J, mass, g, v_s = spectral_problem(sliding, others, share)
    parts = HessianParts(sp.csr_matrix(H))
    with_row = sp.vstack([J, sp.csr_matrix(mass * g)], format="csr")
    counted = KKTFactor(parts, with_row).reduced_negative_count
    assert counted == count_on_complement(H, J, mass, g)  # the factor's inertia
    corrected = counted - sliding_left_out(parts, J, g[None, :], mass, counted)
    assert corrected == count_on_complement(H, J, mass, v_s)
    if (sliding, others, share) == (-1e4, [600.0], 0.7):
        assert (counted, corrected) == (1, 0)  # the case the correction is for


def test_the_lowest_pairs_beyond_the_dense_size_by_shift_invert_below_the_spectrum():
    """With ``ker J`` of more than 400 dimensions the negative eigenpairs come from
    Lanczos shifted below the spectrum: the same correction."""
    H, J, mass, g, v_s = spectral_problem(-1e4, [600.0, -50.0], 0.7, n=420)
    parts = HessianParts(sp.csr_matrix(H))
    with_row = sp.vstack([J, sp.csr_matrix(mass * g)], format="csr")
    counted = KKTFactor(parts, with_row).reduced_negative_count
    assert counted == 2
    assert counted - sliding_left_out(parts, J, g[None, :], mass, counted) == 1 == \
        count_on_complement(H, J, mass, v_s)


def test_no_sliding_or_no_negative_count_leaves_the_count():
    H, J, mass, g, _ = spectral_problem(-1e4, [600.0], 0.7)
    parts = HessianParts(sp.csr_matrix(H))
    assert sliding_left_out(parts, J, g[None, :], mass, 0) == 0
    assert sliding_left_out(parts, J, np.zeros((0, g.size)), mass, 1) == 0


@pytest.mark.parametrize("sliding, others, share, left_out", [
    (-2e5, [180.0, 3600.0], 0.9, 1),    # the ripple: a thousand times the next eigenvalue
    (-2e5, [180.0, -50.0], 0.9, 1),     # ... beside a genuine unstable mode, which stays
    (-300.0, [180.0, 3600.0], 0.9, 0),  # the elastic scale: a genuine instability
    (-2e5, [180.0, -3e4], 0.9, 0),      # another mode as stiff: not told apart, counted
    (-2e5, [180.0, 3600.0], 0.3, 0),    # the stiff mode is not the sliding
])
def test_a_sliding_that_is_no_symmetry_is_left_out_only_as_the_ripple(sliding, others, share,
                                                                      left_out):
    """Where the sliding is no approximate symmetry (no phase row: the count is on all of
    ``ker J``), ``ratio`` leaves its negative eigenvalue out only where its eigenvector
    is mostly the sliding and it exceeds ``ratio`` times the other eigenvalues of the
    ``negative + 1`` lowest (brute force: the spectrum built in). The count left is the
    count on the complement of that eigenvector."""
    H, J, mass, g, v_s = spectral_problem(sliding, others, share)
    parts = HessianParts(sp.csr_matrix(H))
    counted = KKTFactor(parts, J).reduced_negative_count
    assert counted == sum(v < 0 for v in [sliding, *others])
    assert sliding_left_out(parts, J, g[None, :], mass, counted, ratio=10.0) == left_out
    if left_out:
        assert counted - 1 == count_on_complement(H, J, mass, v_s)


def centreline_problem(spectrum: list[float], along: float = 1.0, seed: int = 5,
                       nodes: int = 8):
    """``(H, J, mass, tangents, modes)``: ``3 nodes`` unknowns (a node's three positions),
    uniform mass, 3 constraint rows; on ``ker J`` the eigenvalues ``spectrum`` of
    ``modes`` (M-orthonormal columns): the first two along the centreline (the unit
    tangents ``tangents``, one row a node), the second with only the share ``along`` of
    its norm so, the third across it; the rest of ``ker J`` at 5e3."""
    rng = np.random.default_rng(seed)
    n = 3 * nodes
    t = rng.standard_normal((nodes, 3))
    t /= np.linalg.norm(t, axis=1)[:, None]
    tangents = sp.csr_matrix((t.ravel(), (np.repeat(np.arange(nodes), 3), np.arange(n))),
                             shape=(nodes, n))
    T = tangents.T.toarray()  # (n, nodes): the tangential directions
    N = null_space(T.T)       # (n, 2 nodes): across the centreline
    a, b = np.linalg.qr(T @ rng.standard_normal((nodes, 2)))[0].T
    c, d = np.linalg.qr(N @ rng.standard_normal((N.shape[1], 2)))[0].T
    b = np.sqrt(along) * b + np.sqrt(1.0 - along) * d
    chosen = np.column_stack([a, b, c])
    J = rng.standard_normal((3, n))
    J -= (J @ chosen) @ chosen.T  # chosen orthonormal: J chosen = 0
    rest = null_space(np.vstack([J, chosen.T]))
    mass = np.full(n, 0.25)
    V = np.column_stack([chosen, rest]) / np.sqrt(0.25)  # M-orthonormal basis of ker J
    values = np.full(V.shape[1], 5e3)
    values[:len(spectrum)] = spectrum
    MV = mass[:, None] * V
    return MV @ np.diag(values) @ MV.T, sp.csr_matrix(J), mass, tangents, V[:, :3]


@pytest.mark.parametrize("spectrum, along, sliding, ripple", [
    ([-2e5, -3e4, 180.0], 1.0, 0, (0, 1)),  # the sliding and a harmonic of it: the ripple's
    ([-2e5, -3e4, 180.0], 0.97, 0, (0, 1)),  # ... the harmonic bending the curve by 3 %
    ([-2e5, -3e4, -50.0, 180.0], 1.0, 0, (0, 1)),  # ... beside a genuine unstable one, kept
    ([-2e5, -300.0, 180.0], 1.0, 0, (0,)),  # a mode along the centreline on the elastic scale
    ([1e3, -3e4, 180.0], 1.0, 0, (1,)),     # the harmonic's alone, the sliding stable
    ([-2e5, -3e4, 180.0], 0.3, 0, ()),      # mostly across the centreline: a shape, counted
    ([180.0, -3e4, -2e5], 1.0, 2, (1, 2)),  # the sliding across it, known by its share of g
    ([-2e5, 180.0, -2e5], 1.0, 1, ()),      # one as stiff across it: not told apart, counted
])
def test_the_ripple_leaves_out_the_modes_along_the_centreline(spectrum, along, sliding,
                                                              ripple):
    """Where the sliding is no approximate symmetry, ``tangents`` makes every negative
    eigenpair mostly along the centreline (``TANGENTIAL_SHARE``) the ripple's too, where
    it lies ``ratio`` times beyond the eigenvalues not left out. Brute force, the
    spectrum built in: the count left is the count on the complement of the ripple's
    eigenvectors, and the eigenpairs that ``without_sliding_pairs`` drops from the dense
    spectrum are exactly theirs."""
    H, J, mass, tangents, modes = centreline_problem(spectrum, along)
    parts = HessianParts(sp.csr_matrix(H))
    counted = KKTFactor(parts, J).reduced_negative_count
    assert counted == sum(v < 0 for v in spectrum)
    g = modes[:, sliding]  # the sliding, its own eigenvector here
    found = sliding_left_out(parts, J, g[None, :], mass, counted, ratio=10.0,
                             tangents=tangents)
    assert found == len(ripple)
    Z = null_space(np.vstack([J.toarray(), (mass[:, None] * modes[:, list(ripple)]).T]))
    remaining = eigh(Z.T @ H @ Z, Z.T @ (mass[:, None] * Z), eigvals_only=True)
    assert counted - found == int(np.sum(remaining < 0))
    Zk = null_space(J.toarray())
    values, vectors = eigh(Zk.T @ H @ Zk, Zk.T @ (mass[:, None] * Zk))
    kept, _ = without_sliding_pairs(values, (Zk @ vectors).T, g[None, :], mass, tangents,
                                    count=found)
    left = sorted(v for k, v in enumerate(spectrum) if k not in ripple)
    np.testing.assert_allclose(kept[:len(left)], left, rtol=1e-8)
    # without the tangents only the sliding's own eigenvalue can be left out, and only
    # beyond ratio times every other of the lowest
    others = [abs(v) for k, v in enumerate(spectrum) if k != sliding]
    alone = spectrum[sliding] < 0 and abs(spectrum[sliding]) >= 10.0 * max(others)
    assert sliding_left_out(parts, J, g[None, :], mass, counted, ratio=10.0) == int(alone)


def test_the_rod_tangent_rows_take_the_motion_along_the_centreline():
    """``ClampedRodEnergy.tangent_rows``: unit rows, one a node, on that node's DOFs; a
    motion of every node along its central-difference tangent is all along the
    centreline, one across it (the tangent crossed with a fixed direction) none of it."""
    from supercoil.rod.model import Rod
    from supercoil.rod.open import ClampedRodEnergy, straight_rod

    n = 24
    x = straight_rod(n)
    s = np.clip(x[:, 2], 0.0, 1.0)
    x[:, 0] += 0.05 * np.sin(np.pi * s) ** 3
    x[[0, 1, -2, -1], :2] = 0.0
    rod = ClampedRodEnergy(Rod(n, closed=False), x, 0.5, tension=1.0)
    P = rod.tangent_rows(x.ravel())
    assert P.shape == (n, 3 * n)
    np.testing.assert_allclose(np.sqrt(np.asarray(P.multiply(P).sum(axis=1))).ravel(), 1.0)
    assert all(set(P[i].indices) <= {3 * i, 3 * i + 1, 3 * i + 2} for i in range(n))
    t = np.vstack([x[1] - x[0], x[2:] - x[:-2], x[-1] - x[-2]])
    t /= np.linalg.norm(t, axis=1)[:, None]
    u = np.linspace(0.5, 2.0, n)
    along = (u[:, None] * t).ravel()
    np.testing.assert_allclose(P @ along, u, rtol=1e-12)
    across = (u[:, None] * np.cross(t, [0.0, 1.0, 0.0])).ravel()
    np.testing.assert_allclose(P @ across, 0.0, atol=1e-12)
