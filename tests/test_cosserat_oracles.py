"""Exact solutions of the Cosserat rod: roll-up by an end moment, objectivity and path
independence, shear-deformable (Haringx) buckling and the Kirchhoff limit."""

import numpy as np
import pytest
from scipy.optimize import brentq

from supercoil.cosserat.clamped import ClampedCosseratEnergy
from supercoil.cosserat.newton import clamp_dofs, solve_incrementally
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod
from supercoil.cosserat.rotations import exp_so3


@pytest.mark.parametrize("shear, stretch", [(3.0, 10.0), (100.0, 100.0), (1e4, 3e3), (1e6, 1e6)])
def test_end_moment_rolls_a_cantilever_into_a_full_circle(shear, stretch):
    # Simo & Vu-Quoc 1986: under the end moment M = 2 pi A / L the stress resultant
    # vanishes (Gamma = 0) and the curvature is M / A everywhere, whatever GA and EA;
    # the discrete rod is exact too (chords of length h along R_m e_3, turning by
    # 2 pi / N), so the end comes back onto the clamp with the clamp's frame.
    rod = CosseratRod(16, length=1.5, bending_stiffness=2.0, shear_stiffness=shear,
                      stretch_stiffness=stretch)
    moment = 2 * np.pi * rod.bending_stiffness / rod.length
    loads = np.zeros((rod.n_nodes, 6))
    loads[-1, 4] = moment  # about +y: the rod rolls up in the x-z plane
    x, R = rod.straight()
    result, fractions = solve_incrementally(rod, x, R, clamp_dofs(rod.n_nodes, 0), loads)
    assert result.converged and fractions[-1] == 1.0
    x, R = result.positions, result.rotations
    # exact up to the solver's tolerance (residual 1e-10, or the round-off floor)
    assert np.max(np.abs(x[-1] - x[0])) < 1e-9 * rod.length
    assert np.allclose(R[-1], np.eye(3), atol=1e-9)
    shear_strain, curvature = rod.strains(x, R)
    assert np.allclose(shear_strain, 0.0, atol=1e-10)
    assert np.allclose(curvature, [0.0, moment / rod.bending_stiffness, 0.0], rtol=1e-10)
    assert rod.energy(x, R) == pytest.approx(moment**2 * rod.length
                                             / (2 * rod.bending_stiffness), rel=1e-9)
    # the nodes lie on the circle through the chords' ends
    radius = rod.element_length / (2 * np.sin(np.pi / rod.n_elements))
    centre = np.array([-radius, 0.0, 0.0]) if x[rod.n_elements // 2, 0] < 0 else \
        np.array([radius, 0.0, 0.0])
    assert np.allclose(np.linalg.norm(x - centre, axis=1), radius, rtol=1e-10)


def random_state(rod, rng):
    x, R = rod.straight(0.4)
    return (x + 0.15 * rng.standard_normal(x.shape),
            exp_so3(1.0 * rng.standard_normal((rod.n_nodes, 3))) @ R)


def test_rigid_motions_change_no_strain_and_no_energy(rng):
    rod = CosseratRod(9, shear_stiffness=7.0, stretch_stiffness=11.0, twist_stiffness=0.6)
    x, R = random_state(rod, rng)
    Q = exp_so3(rng.standard_normal(3) * 2.0)
    shift = rng.standard_normal(3)
    x2, R2 = x @ Q.T + shift, Q @ R
    for a, b in zip(rod.strains(x, R), rod.strains(x2, R2)):
        assert np.allclose(a, b, atol=1e-13)
    assert rod.energy(x2, R2) == pytest.approx(rod.energy(x, R), rel=1e-13)
    # forces and moments are spatial vectors: they turn with the rod
    g, g2 = rod.gradient(x, R).reshape(-1, 2, 3), rod.gradient(x2, R2).reshape(-1, 2, 3)
    assert np.allclose(g2, g @ Q.T, atol=1e-12 * np.max(np.abs(g)))
    # so do the tangents: K(Q state) = Q K Q^T blockwise
    big = np.kron(np.eye(2 * rod.n_nodes), Q)
    for tangent in (rod.symmetric_tangent, rod.consistent_tangent):
        K, K2 = tangent(x, R).toarray(), tangent(x2, R2).toarray()
        assert np.allclose(K2, big @ K @ big.T, atol=1e-12 * np.max(np.abs(K)))


def test_closed_cycles_of_large_rotations_return_the_energy(rng):
    # The energy depends on the current nodal rotations only (no incremental
    # interpolation, Crisfield & Jelenic 1999): a node turned once round an axis in
    # accepted chart steps, and a cycle of large rotations undone in reverse order,
    # come back to the starting energy and strains although the states between differ.
    rod = CosseratRod(7, shear_stiffness=7.0, stretch_stiffness=11.0)
    x, R = random_state(rod, rng)
    problem = CosseratEnergy(rod, x, R)
    q = problem.initial_state()
    start = problem.energy(q)
    strains = problem.strains(q)
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    energies = []
    for _ in range(12):  # a full turn of node 3
        q[6 * 3 + 3:6 * 3 + 6] += (2 * np.pi / 12) * axis
        problem.accept(q)
        energies.append(problem.energy(q))
    assert np.ptp(energies) > 1.0
    assert energies[-1] == pytest.approx(start, rel=1e-12)
    increments = 1.3 * rng.standard_normal((5, rod.n_nodes, 3))
    for sequence in (increments, -increments[::-1]):
        for w in sequence:
            q.reshape(-1, 6)[:, 3:] += w
            problem.accept(q)
            energies.append(problem.energy(q))
    assert energies[-1] == pytest.approx(start, rel=1e-12)
    for a, b in zip(problem.strains(q), strains):
        assert np.allclose(a, b, atol=1e-12)


def lowest_eigenvalue(rod, load):
    problem = ClampedCosseratEnergy(rod, tension=-load)
    q = problem.straight_state()
    free = np.setdiff1d(np.arange(rod.n_dofs), problem.fixed)
    H = problem.hessian(q).sparse.toarray()[np.ix_(free, free)]
    scale = 1 / np.sqrt(problem.mass[free])
    return float(np.linalg.eigvalsh(scale[:, None] * H * scale[None, :])[0])


def buckling_load(rod):
    euler = 4 * np.pi**2 * rod.bending_stiffness / rod.length**2
    return brentq(lambda p: lowest_eigenvalue(rod, p), 0.3 * euler, 1.5 * euler,
                  xtol=1e-13 * euler)


def haringx(euler, shear, stretch):
    """Root of ``P (1 + P (1/GA - 1/EA)) = P_E``: the critical compression of the
    Simo-Reissner column (see the test below)."""
    a = 1 / shear - 1 / stretch
    return euler if a == 0 else (np.sqrt(1 + 4 * a * euler) - 1) / (2 * a)


def test_shear_deformable_column_buckles_at_haringx_load_at_second_order():
    # Linearising about the straight column compressed by P (stretch lambda = 1 - P/EA),
    # with a small rotation phi: the force P e_3, resolved in the rotated section, has
    # the shear component P phi, so Gamma_1 = P phi / GA (the shear strain is measured
    # in the section's frame) and the tangent x' = (lambda + P/GA) phi e_1 + lambda e_3.
    # Moment balance A phi'' + P x'_1 = 0 gives A phi'' + P (lambda + P/GA) phi = 0:
    # buckling at P (1 - P/EA + P/GA) = P_E = 4 pi^2 A / L^2 (clamped ends), Haringx's
    # formula (Haringx 1948) with extensibility, not Engesser's P_E / (1 + P_E / GA)
    # (which resolves the shear force normal to the deformed axis instead).
    shear, stretch = 200.0, 400.0
    euler = 4 * np.pi**2
    exact = haringx(euler, shear, stretch)
    engesser = euler / (1 + euler / shear)
    errors = []
    for n in (8, 16, 32, 64):
        errors.append(buckling_load(CosseratRod(n, shear_stiffness=shear,
                                                stretch_stiffness=stretch)) - exact)
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2) < 0.15), orders
    assert abs(errors[-1]) < 2e-3 * exact
    assert abs(exact - engesser) > 50 * abs(errors[-1])


def test_column_buckling_tends_to_the_kirchhoff_load():
    # A solid circular section of growing slenderness L/r (EA = 4A/r^2, GA = 1.2 A/r^2
    # for nu = 0.5): the onset tends to Euler's 4 pi^2 A / L^2 with the deviation
    # P_E^2 (1/GA - 1/EA) = O((r/L)^2) of Haringx's formula. At a fixed mesh the discrete
    # onset follows that formula to the mesh's own error.
    euler = 4 * np.pi**2
    n = 48
    onsets = []
    for slenderness in (40, 80, 160, 320):
        rod = CosseratRod.circular_section(n, slenderness)
        onset = buckling_load(rod)
        formula = haringx(euler, rod.shear_stiffness, rod.stretch_stiffness)
        assert onset == pytest.approx(formula, rel=4e-3)
        onsets.append(onset)
    # the deviation shrinks as (r/L)^2: consecutive differences fall fourfold
    steps = -np.diff(onsets)
    assert np.all(steps < 0)
    orders = np.log2(steps[:-1] / steps[1:])
    assert np.all(np.abs(orders - 2) < 0.1), orders
    # and the limit (Richardson) is the Kirchhoff load, to the mesh's error: the
    # discrete column is stiffer by O(h^2), 3e-3 at 48 elements
    limit = onsets[-1] - steps[-1] / 3
    assert euler < limit < euler * (1 + 4e-3)
