"""The clamped, turned and pulled Cosserat rod: exact straight state, parameter
derivatives, the tension oracle and Greenhill's buckling in the Kirchhoff limit."""

import numpy as np
import pytest
from scipy.optimize import brentq

from supercoil.continuation import ContinuationOptions, continuation
from supercoil.cosserat.clamped import ClampedCosseratEnergy
from supercoil.cosserat.newton import solve_equilibrium
from supercoil.cosserat.rod import CosseratRod
from supercoil.errors import InputError
from supercoil.problems.greenhill import critical_moment


def free_dofs(problem):
    return np.setdiff1d(np.arange(problem.n_dofs), problem.fixed)


def test_parameter_derivatives_against_finite_differences(rng):
    rod = CosseratRod(8, shear_stiffness=30.0, stretch_stiffness=20.0)
    problem = ClampedCosseratEnergy(rod, turns=0.7, tension=2.0)
    q = problem.straight_state()
    free = free_dofs(problem)
    q[free] += 0.1 * rng.standard_normal(free.size)
    problem.accept(q.copy())
    q[free] += 0.1 * rng.standard_normal(free.size)  # off the chart's centre too
    for parameter in ("turns", "tension"):
        exact = problem.parameter_derivative(q, np.zeros(0), parameter)
        value, e = getattr(problem, parameter), 1e-5
        setattr(problem, parameter, value + e)
        plus = problem.gradient(q)
        setattr(problem, parameter, value - e)
        minus = problem.gradient(q)
        setattr(problem, parameter, value)
        assert np.allclose((plus - minus)[free] / (2 * e), exact[free], atol=1e-8)
    assert problem.parameter_derivative(q, np.zeros(0), "length") is None


@pytest.mark.parametrize("turns", [0.0, 0.4])
def test_tension_extends_the_rod_by_exactly_t_l_over_ea(turns, rng):
    # uniform strains Gamma = (0, 0, T/EA), K = (0, 0, 2 pi turns / L) balance every node,
    # twisted or not: the rod extends by T L / EA exactly (to round-off), from any start
    rod = CosseratRod(12, length=2.0, bending_stiffness=1.5, twist_stiffness=0.8,
                      shear_stiffness=40.0, stretch_stiffness=25.0)
    tension = 3.0
    problem = ClampedCosseratEnergy(rod, turns=turns, tension=tension)
    x, R = ClampedCosseratEnergy.straight(rod, turns, 0.0)
    x[1:-1] += 0.01 * rng.standard_normal((rod.n_nodes - 2, 3))
    loads = np.zeros((rod.n_nodes, 6))
    loads[-1, 2] = tension
    result = solve_equilibrium(rod, x, R, problem.fixed, loads)
    assert result.converged
    extension = result.positions[-1, 2] - rod.length
    assert extension == pytest.approx(tension * rod.length / rod.stretch_stiffness, rel=1e-12)
    shear, curvature = rod.strains(result.positions, result.rotations)
    assert np.allclose(shear, [0, 0, tension / rod.stretch_stiffness], atol=1e-12)
    assert np.allclose(curvature, [0, 0, 2 * np.pi * turns / rod.length], atol=1e-12)
    # the problem's straight state is that equilibrium
    q = problem.straight_state()
    assert np.max(np.abs(problem.gradient(q)[free_dofs(problem)])) < 1e-11
    assert problem.extension(q) == pytest.approx(1 + tension / rod.stretch_stiffness, rel=1e-14)


def lowest_eigenvalue(rod, turns, tension):
    problem = ClampedCosseratEnergy(rod, turns=turns, tension=tension)
    q = problem.straight_state()
    free = free_dofs(problem)
    H = problem.hessian(q).sparse.toarray()[np.ix_(free, free)]
    scale = 1 / np.sqrt(problem.mass[free])
    return float(np.linalg.eigvalsh(scale[:, None] * H * scale[None, :])[0])


@pytest.mark.parametrize("tension", [0.0, 5.0])
def test_straight_rod_buckles_at_greenhill_in_the_kirchhoff_limit(tension):
    # EA = GA = 1e6 A/L^2: the onset converges to the Kirchhoff rod's (Greenhill 1883 with
    # tension, supercoil.problems.greenhill) at second order in the element size
    exact = critical_moment(tension) / (2 * np.pi)  # turns, C = A = L = 1
    errors = []
    for n in (10, 20, 40):
        rod = CosseratRod(n, shear_stiffness=1e6, stretch_stiffness=1e6)
        onset = brentq(lambda t, rod=rod: lowest_eigenvalue(rod, t, tension), 0.5 * exact,
                       1.5 * exact, xtol=1e-12)
        errors.append(onset - exact)
    assert abs(errors[-1]) < 5e-4 * exact
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2) < 0.1), orders


def test_continuation_in_turns_finds_the_greenhill_bifurcation():
    rod = CosseratRod(20, shear_stiffness=1e5, stretch_stiffness=1e5)
    problem = ClampedCosseratEnergy(rod)
    options = ContinuationOptions(parameter_bounds=(0.0, 2.0), initial_step=0.1, max_step=0.25,
                                  max_points=40)
    branch = continuation(problem, problem.straight_state(), parameter="turns", options=options)
    bifurcations = branch.points_of_kind("bifurcation")
    assert len(bifurcations) == 1
    point = bifurcations[0]
    # the isotropic rod: a double eigenvalue crosses (a circle of buckled modes)
    assert (point.count_before, point.count_after) == (0, 2)
    onset = brentq(lambda t: lowest_eigenvalue(rod, t, 0.0), 1.2, 1.7, xtol=1e-12)
    assert point.parameter == pytest.approx(onset, rel=1e-6)
    greenhill = critical_moment(0.0) / (2 * np.pi)
    assert point.parameter == pytest.approx(greenhill, rel=2e-3)


def test_invalid_clamped_problems_are_refused():
    rod = CosseratRod(6)
    with pytest.raises(InputError, match="turns"):
        ClampedCosseratEnergy(rod, turns=float("nan"))
    with pytest.raises(InputError, match="tension"):
        ClampedCosseratEnergy(rod, tension=-2 * rod.stretch_stiffness)
    x, R = rod.straight()
    with pytest.raises(InputError, match="end frames"):
        ClampedCosseratEnergy(rod, turns=0.3, positions=x, rotations=R)
