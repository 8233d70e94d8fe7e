"""Cosserat rod: rotations, energy, gradient and tangents against finite differences on
the manifold (perturbations ``x + eps dx``, ``exp(eps hat(w)) R``)."""

import numpy as np
import pytest

from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod, retract
from supercoil.cosserat.rotations import (
    coefficient_a,
    coefficient_a_prime,
    coefficient_b,
    coefficient_b_prime,
    coefficient_f,
    coefficient_f_prime,
    coefficient_t,
    coefficient_t_prime,
    dexp,
    dexp_transpose_derivative,
    exp_so3,
    log_so3,
    sinc,
)
from supercoil.errors import InputError


def random_state(rod, rng, spread=0.6):
    x, R = rod.straight(0.3)
    x = x + 0.1 * rng.standard_normal(x.shape)
    R = exp_so3(spread * rng.standard_normal((rod.n_nodes, 3))) @ R
    return x, R


@pytest.fixture
def rod():
    return CosseratRod(6, length=1.3, bending_stiffness=1.1, twist_stiffness=0.7,
                       shear_stiffness=5.0, stretch_stiffness=9.0)


@pytest.mark.parametrize("angle", [1e-9, 1e-3, 0.049, 0.3, 1.0, 2.5, 3.1, np.pi - 1e-7])
def test_exp_log_round_trip_and_tangent_map(angle, rng):
    v = rng.standard_normal(3)
    v *= angle / np.linalg.norm(v)
    R = exp_so3(v)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(log_so3(R), v, atol=1e-13 * max(1, 1 / (np.pi - angle)))
    # exp(phi + eps d) exp(phi)^T = exp(eps hat(T d)): T against central differences
    d, e = rng.standard_normal(3), 1e-6
    W = (exp_so3(v + e * d) - exp_so3(v - e * d)) / (2 * e) @ R.T
    assert np.allclose([W[2, 1], W[0, 2], W[1, 0]], dexp(v) @ d, atol=1e-9)
    m = rng.standard_normal(3)
    fd = (dexp(v + e * d).T @ m - dexp(v - e * d).T @ m) / (2 * e)
    assert np.allclose(dexp_transpose_derivative(v, m) @ d, fd, atol=1e-9)


@pytest.mark.parametrize("coefficient", [sinc, coefficient_a, coefficient_b, coefficient_a_prime,
                                         coefficient_b_prime, coefficient_f, coefficient_f_prime,
                                         coefficient_t, coefficient_t_prime])
def test_series_and_closed_forms_agree_at_the_switch(coefficient):
    for switch in (0.05, 0.25, 0.5):
        below, above = coefficient(np.array([switch * (1 - 1e-13), switch * (1 + 1e-13)]))
        assert below == pytest.approx(above, rel=1e-10)


@pytest.mark.parametrize("spread", [1e-4, 0.6, 1.2])
def test_gradient_and_tangents_on_the_manifold(rod, rng, spread):
    x, R = random_state(rod, rng, spread)
    energy = rod.energy(x, R)
    g = rod.gradient(x, R)
    Kc = rod.consistent_tangent(x, R).toarray()
    H0 = rod.symmetric_tangent(x, R).toarray()
    for _ in range(3):
        v = rng.standard_normal(rod.n_dofs)
        e = 1e-5
        fd = (rod.energy(*retract(x, R, e * v)) - rod.energy(*retract(x, R, -e * v))) / (2 * e)
        assert fd == pytest.approx(g @ v, rel=1e-8, abs=1e-9)
        # the consistent tangent linearises the gradient under the retraction
        fd_g = (rod.gradient(*retract(x, R, e * v)) - rod.gradient(*retract(x, R, -e * v))) / (2 * e)
        assert np.allclose(fd_g, Kc @ v, rtol=1e-7, atol=1e-7 * np.max(np.abs(Kc @ v)))
        # H0 is the second derivative along one-parameter subgroups
        e = 1e-4
        d2 = (rod.energy(*retract(x, R, e * v)) - 2 * energy
              + rod.energy(*retract(x, R, -e * v))) / e**2
        assert d2 == pytest.approx(v @ H0 @ v, rel=1e-6)
    assert np.array_equal(H0, H0.T)
    assert np.allclose(0.5 * (Kc + Kc.T), H0, atol=1e-13 * np.max(np.abs(H0)))
    # the skew part is -hat(m_i)/2 on each node's spins: proportional to the residual
    moments = g.reshape(-1, 6)[:, 3:]
    skew = 0.5 * (Kc - Kc.T)
    for i, m in enumerate(moments):
        block = skew[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6]
        assert np.allclose(block, -0.5 * np.array([[0, -m[2], m[1]], [m[2], 0, -m[0]],
                                                   [-m[1], m[0], 0]]), atol=1e-12)
    off = skew.copy()
    for i in range(rod.n_nodes):
        off[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6] = 0
    assert np.max(np.abs(off)) <= 1e-12 * np.max(np.abs(H0))


def test_chart_gradient_and_hessian_away_from_the_centre(rod, rng):
    x, R = random_state(rod, rng)
    problem = CosseratEnergy(rod, x, R, forces=rng.standard_normal((rod.n_nodes, 3)))
    q = problem.initial_state() + 0.3 * rng.standard_normal(rod.n_dofs)
    problem.accept(q.copy())
    q += 0.5 * rng.standard_normal(rod.n_dofs)  # rotation coordinates off the centre
    g, H = problem.gradient(q), problem.hessian(q).sparse.toarray()
    assert np.array_equal(H, H.T)
    e = 1e-5
    for _ in range(3):
        v = rng.standard_normal(rod.n_dofs)
        fd = (problem.energy(q + e * v) - problem.energy(q - e * v)) / (2 * e)
        assert fd == pytest.approx(g @ v, rel=1e-8)
        fd_g = (problem.gradient(q + e * v) - problem.gradient(q - e * v)) / (2 * e)
        assert np.allclose(fd_g, H @ v, rtol=1e-7, atol=1e-7 * np.max(np.abs(H @ v)))
    # accepting re-bases the chart without moving the state; at the centre the
    # chart's Hessian is the symmetrised tangent
    positions, rotations = problem.configuration(q)
    energy = problem.energy(q)
    problem.accept(q)
    assert problem.energy(q) == energy
    assert np.array_equal(problem.configuration(q)[1], rotations)
    H0 = rod.symmetric_tangent(positions, rotations).toarray()
    assert np.array_equal(problem.hessian(q).sparse.toarray(), H0)


def test_tangent_is_banded_so_a_newton_step_is_linear_in_n():
    for n in (10, 40):
        rod = CosseratRod(n)
        x, R = rod.straight(0.5)
        H = rod.symmetric_tangent(x, R)
        rows, cols = H.nonzero()
        assert np.max(np.abs(rows - cols)) <= 11
        # each element couples its 12 DOFs: 144 entries, 36 shared per interior node
        assert H.nnz == 144 * n - 36 * (n - 1)


def test_invalid_rods_are_refused():
    with pytest.raises(InputError, match="shear_stiffness"):
        CosseratRod(4, shear_stiffness=0.0)
    with pytest.raises(InputError, match="n_elements"):
        CosseratRod(1)
    with pytest.raises(InputError, match="poisson_ratio"):
        CosseratRod.circular_section(4, slenderness=100, poisson_ratio=0.7)
    rod = CosseratRod(4)
    x, R = rod.straight()
    with pytest.raises(InputError, match="positions"):
        rod.energy(x[:-1], R)
    with pytest.raises(InputError, match="rotation matrices"):
        CosseratEnergy(rod, x, 2 * R)
