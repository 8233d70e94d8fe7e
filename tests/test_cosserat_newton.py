"""Newton with the symmetrised tangent on a Cosserat rod: its convergence rate, when it
is quadratic and when not; stability from the inertia beside the determinant's sign."""

import numpy as np
import pytest
from scipy.optimize import brentq

from supercoil.cosserat.newton import (
    ManifoldNewtonOptions,
    clamp_dofs,
    solve_equilibrium,
)
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod
from supercoil.errors import InputError
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import analyse
from supercoil.stability.bisection import locate_count_change

ROD = CosseratRod(20, shear_stiffness=100.0, stretch_stiffness=60.0)


def tip_loads(rod, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)):
    loads = np.zeros((rod.n_nodes, 6))
    loads[-1, :3], loads[-1, 3:] = force, moment
    return loads


def quadratic_constants(result, start=1e-2, floor=1e-10):
    """``r_{k+1} / r_k^2`` over the asymptotic steps (``r_k < start``), the steps that land
    on round-off (``r_{k+1} < floor``) left out: bounded for quadratic convergence, growing
    like ``1 / r_k`` for linear convergence."""
    r = np.array(result.residual_history)
    keep = (r[:-1] < start) & (r[1:] > floor)
    return r[1:][keep] / r[:-1][keep] ** 2


def test_symmetrised_newton_converges_quadratically_under_conservative_loads():
    # a dead force is conservative; the skew part of the tangent, -hat(m_i)/2, is
    # then part of the residual and the symmetrised tangent keeps the quadratic rate
    # (Crisfield 1990; Chamekh, Mani-Aouadi & Moakher 2009)
    x, R = ROD.straight()
    loads = tip_loads(ROD, force=(0.8, 1.5, 0.4))
    results = {tangent: solve_equilibrium(ROD, x, R, clamp_dofs(ROD.n_nodes, 0), loads,
                                          ManifoldNewtonOptions(tangent=tangent, tolerance=1e-11))
               for tangent in ("symmetric", "consistent")}
    for result in results.values():
        assert result.converged
        constants = quadratic_constants(result)
        assert constants.size >= 1 and np.all(constants < 100.0), constants
    assert np.allclose(results["symmetric"].positions, results["consistent"].positions,
                       atol=1e-11)


def test_symmetrised_newton_is_linear_under_a_dead_moment_in_space():
    # A moment of fixed spatial direction on a free node is not conservative on SO(3)
    # (Argyris 1982): the internal moment m_tip equals it at the solution, so the
    # symmetrised tangent misses -hat(m_tip)/2 there and Newton converges linearly,
    # at a constant ratio; the consistent tangent keeps the quadratic rate.
    x, R = ROD.straight()
    loads = tip_loads(ROD, moment=(0.25, 0.5, 0.125))
    options = {"tolerance": 1e-11, "max_iterations": 80}
    consistent = solve_equilibrium(ROD, x, R, clamp_dofs(ROD.n_nodes, 0), loads,
                                   ManifoldNewtonOptions(tangent="consistent", **options))
    symmetric = solve_equilibrium(ROD, x, R, clamp_dofs(ROD.n_nodes, 0), loads,
                                  ManifoldNewtonOptions(tangent="symmetric", **options))
    assert consistent.converged and symmetric.converged
    assert np.all(quadratic_constants(consistent) < 100.0)
    assert np.max(quadratic_constants(symmetric)) > 1e3
    history = np.array(symmetric.residual_history)
    tail = history[(history < 1e-4) & (history > 1e-10)]
    ratios = tail[1:] / tail[:-1]
    assert len(ratios) >= 4
    assert np.all((ratios > 0.05) & (ratios < 0.9)), ratios
    assert np.ptp(ratios) < 0.05  # a constant contraction: linear convergence
    assert symmetric.iterations > consistent.iterations + 4
    assert np.allclose(symmetric.positions, consistent.positions, atol=1e-10)


def test_protocol_newton_converges_quadratically_on_the_chart():
    # supercoil.solvers.newton on the ConstrainedEnergy: every accept re-centres the
    # chart, so each step is a symmetrised-tangent step; dead forces are conservative
    rod = ROD
    x, R = rod.straight()
    forces = np.zeros((rod.n_nodes, 3))
    forces[-1] = (0.8, 1.5, 0.4)
    problem = CosseratEnergy(rod, x, R, fixed=np.arange(6), forces=forces)
    result = newton(problem, problem.initial_state(),
                    NewtonOptions(tolerance=1e-11, mode="stationary"))
    assert result.converged
    constants = quadratic_constants(result)
    assert constants.size >= 1 and np.all(constants < 100.0), constants
    manifold = solve_equilibrium(rod, x, R, clamp_dofs(rod.n_nodes, 0),
                                 tip_loads(rod, force=forces[-1]))
    positions, _ = problem.configuration(result.q)
    assert np.allclose(positions, manifold.positions, atol=1e-10)


def compressed_column(rod, load, planar=False):
    """Straight column clamped at ``s = 0``, its other end clamped in rotation and
    sliding along the axis under the dead compression ``load``: an exact equilibrium
    (uniform stretch ``-load / EA``). ``planar``: the motion is held in the x-z plane."""
    x, R = rod.straight()
    x = x * (1 - load / rod.stretch_stiffness)
    n = rod.n_nodes
    fixed = list(range(6)) + clamp_dofs(n, n - 1, positions=False) + [6 * (n - 1), 6 * (n - 1) + 1]
    if planar:
        fixed += [6 * i + c for i in range(n) for c in (1, 3, 5)]
    forces = np.zeros((n, 3))
    forces[-1, 2] = -load
    return CosseratEnergy(rod, x, R, fixed=fixed, forces=forces)


def test_stability_inertia_beside_the_determinant_sign():
    rod = CosseratRod(16, shear_stiffness=200.0, stretch_stiffness=400.0)
    euler = 4 * np.pi**2  # clamped-clamped Kirchhoff load, A = L = 1

    def report(load, planar):
        problem = compressed_column(rod, load, planar)
        q = problem.initial_state()
        assert np.max(np.abs(problem.gradient(q)[np.setdiff1d(np.arange(rod.n_dofs),
                                                            problem.fixed)])) < 1e-10
        return analyse(problem, q, np.zeros(0))

    below, above = report(0.5 * euler, False), report(1.1 * euler, False)
    assert below.unstable_count == 0 and below.determinant_sign == 1
    # the isotropic column buckles in x and in y at once: two eigenvalues cross zero,
    # and the determinant keeps its sign while the inertia counts both
    assert above.unstable_count == 2 and above.determinant_sign == 1
    # held in a plane, one eigenvalue crosses: the determinant sees it too
    below, above = report(0.5 * euler, True), report(1.1 * euler, True)
    assert below.determinant_sign == 1 and above.determinant_sign == -1
    assert above.unstable_count == 1

    # the seed's bisection on the count, refined on the nearest eigenvalue, finds the
    # load where the lowest eigenvalue of the symmetrised Hessian vanishes
    def count(load):
        problem = compressed_column(rod, load, True)
        return analyse(problem, problem.initial_state(), np.zeros(0)).negative_count

    critical = locate_count_change(count, 0.5 * euler, 1.1 * euler, 1, rtol=1e-9)
    lowest = critical_load(rod, planar=True)
    assert critical == pytest.approx(lowest, rel=1e-7)


def lowest_eigenvalue(rod, load, planar=False):
    problem = compressed_column(rod, load, planar)
    free = np.setdiff1d(np.arange(rod.n_dofs), problem.fixed)
    H = problem.hessian(problem.initial_state()).sparse.toarray()[np.ix_(free, free)]
    scale = 1 / np.sqrt(problem.mass[free])
    return float(np.linalg.eigvalsh(scale[:, None] * H * scale[None, :])[0])


def critical_load(rod, planar=False, bracket=(0.3, 1.5)):
    euler = 4 * np.pi**2 * rod.bending_stiffness / rod.length**2
    return brentq(lambda p: lowest_eigenvalue(rod, p, planar), bracket[0] * euler,
                  bracket[1] * euler, xtol=1e-12 * euler)


def test_newton_options_are_validated():
    with pytest.raises(InputError, match="tangent"):
        ManifoldNewtonOptions(tangent="skew")
    with pytest.raises(InputError, match="line_search"):
        ManifoldNewtonOptions(line_search="armijo")
    x, R = ROD.straight()
    with pytest.raises(InputError, match="loads"):
        solve_equilibrium(ROD, x, R, loads=np.zeros(5))
