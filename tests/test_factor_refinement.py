"""Bordered solves by iterative refinement with the previous Newton step's bordered factor
(ContinuationOptions.factor_refinement) against a new factorisation at the point:
the same solve to round-off; a factor too far away is refused (None), not trusted."""

from __future__ import annotations

import numpy as np
import pytest
from test_point_stability_paths import contact_ring_system

from supercoil.continuation.corrector import bordered_factor, tangent


def nearby_state(system, x, size, seed=0):
    """A point of the extended system near ``x``: the free DOFs moved by ``size`` times
    a fixed smooth field, the multipliers by random amounts of that size, the
    parameter by ``size``."""
    rng = np.random.default_rng(seed)
    n = system.problem.n_dofs // 3
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    bump = np.stack([np.cos(2 * t + 0.3), np.sin(3 * t), np.cos(t)], axis=1).ravel()
    y = x.copy()
    y[:system.n] += size * bump[system.free]
    y[system.n:-1] += size * rng.standard_normal(system.size - system.n - 1)
    y[-1] += size
    return y


def _dense(system, y, row, H):
    n, J, column = system.n, system.jacobian(y).toarray(), system.parameter_derivative(y)
    m = J.shape[0]
    B = np.zeros((system.size, system.size))
    B[:n, :n] = H.dense()
    B[:n, n:n + m] = J.T
    B[n:n + m, :n] = J
    B[:-1, -1] = column
    B[-1] = row
    return B


@pytest.mark.parametrize("size", [1e-7, 1e-5])
def test_refined_solve_is_as_accurate_as_a_new_factor_solve(size):
    """Oracle: the dense solve. The bordered matrix of this bent ring is ill-conditioned
    (condition number ~1e12), so both are compared by their error against it."""
    system, x = contact_ring_system(excess_link=2.5)
    row = system.weights * np.linspace(1.0, 2.0, system.size)
    old = bordered_factor(system, x, row)
    y = nearby_state(system, x, size)
    H = system.hessian(y)
    fresh = bordered_factor(system, y, row, H)
    B = _dense(system, y, row, H)
    rng = np.random.default_rng(3)
    for rhs in (np.eye(system.size)[-1], rng.standard_normal(system.size)):
        z = old.refined_solve(H, system.jacobian(y), system.parameter_derivative(y), row, rhs)
        assert z is not None
        exact = np.linalg.solve(B, rhs)
        scale = np.max(np.abs(exact))
        error_fresh = np.max(np.abs(fresh.solve(rhs) - exact)) / scale
        error_refined = np.max(np.abs(z - exact)) / scale
        assert error_refined <= max(10 * error_fresh, 1e-12), (error_refined, error_fresh)
    t_refined = tangent(system, y, row, H, preconditioner=old)
    t_fresh = tangent(system, y, row, H)
    np.testing.assert_allclose(t_refined, t_fresh, rtol=0, atol=1e-7 * np.max(np.abs(t_fresh)))


def test_refined_solve_refuses_a_factor_too_far_away():
    system, x = contact_ring_system(excess_link=2.5)
    row = system.weights * np.linspace(1.0, 2.0, system.size)
    far = bordered_factor(system, nearby_state(system, x, 0.3, seed=1), row)
    H = system.hessian(x)
    e_last = np.eye(system.size)[-1]
    z = far.refined_solve(H, system.jacobian(x), system.parameter_derivative(x), row, e_last)
    if z is not None:  # accepted only when it meets the solve's own residual bound
        reference = bordered_factor(system, x, row, H).solve(e_last)
        np.testing.assert_allclose(z, reference, rtol=0, atol=1e-9 * np.max(np.abs(reference)))
    # another border row: the preconditioner is not used, the tangent is the fresh one
    other = bordered_factor(system, x, 2.0 * row, H)
    np.testing.assert_array_equal(tangent(system, x, row, H, preconditioner=other),
                                  tangent(system, x, row, H))


def test_newton_steps_by_refinement_converge_as_with_new_factors(monkeypatch):
    """correct(refine_below=...): late Newton steps solved by refinement with the last
    factor are the exact Newton steps to round-off: the same iteration count and the
    same converged point as with a new factor at every step (a ring bent off the
    circle, corrected back at fixed excess link), with refinement actually used."""
    from supercoil.continuation import bordered
    from supercoil.continuation.corrector import correct
    from supercoil.continuation.options import ContinuationOptions
    from supercoil.continuation.phase import branch_phase_modes
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.problems.ring import twisted_circle_problem

    n = 60
    rod, q = twisted_circle_problem(2 / 3, 1.5, n)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    bent = q.reshape(-1, 3).copy()
    bent[:, 2] += 0.02 * np.sin(2 * t)
    bent = bent.ravel()
    modes = branch_phase_modes(rod, bent, ContinuationOptions(gauge="integral"))
    system = ExtendedSystem(rod, "excess_link", bent, modes, bent)
    x0 = system.pack(bent, np.zeros(rod.n_constraints), 1.5)
    e_lam = np.eye(system.size)[-1]
    used = []
    original = bordered.BorderedFactor.refined_solve

    def counted(self, *args, **kwargs):
        z = original(self, *args, **kwargs)
        used.append(z is not None)
        return z

    monkeypatch.setattr(bordered.BorderedFactor, "refined_solve", counted)
    fresh = correct(system, x0, e_lam, x0, 0.0, 1e-10, 40)
    assert not used
    refined = correct(system, x0, e_lam, x0, 0.0, 1e-10, 40, refine_below=1e-2)
    assert any(used)
    assert fresh.ok and refined.ok and fresh.iterations == refined.iterations
    np.testing.assert_allclose(refined.x, fresh.x, rtol=0, atol=1e-10 * np.max(np.abs(fresh.x)))


def test_the_stacked_jacobian_is_reused_only_while_its_parts_are():
    """ExtendedSystem.jacobian returns the same stacked matrix for the same problem
    Jacobian object and phase rows, a new one (with the new rows) once either changes;
    its entries are those of a fresh stack."""
    import scipy.sparse as sp

    from supercoil.solvers.csr import csr_columns

    system, x = contact_ring_system(excess_link=2.5)
    first = system.jacobian(x)
    assert system.jacobian(x.copy()) is first
    problem = system.problem_at(x[-1])
    fresh = sp.vstack([csr_columns(problem.constraint_jacobian(system.q(x)), system.free),
                       sp.csr_matrix(system.P)], format="csr")
    assert (first != fresh).nnz == 0
    moved = nearby_state(system, x, 1e-3)
    other = system.jacobian(moved)
    assert other is not first and (other != first).nnz > 0
    system.set_phase(2.0 * system.phase_modes, system.q_phase_full)
    rephased = system.jacobian(moved)
    assert rephased is not other
    np.testing.assert_array_equal(rephased.toarray()[-1], 2.0 * other.toarray()[-1])


def test_rephased_tangents_by_refinement_equal_those_of_new_factors(monkeypatch):
    """The integral phase condition re-anchored at each point (rephase) needs the tangent
    in the new gauge; with factor_refinement it is solved by refinement with the step's
    corrector factor under that factor's row and oriented by the orientation row. Oracle:
    the same run with a new factor for every solve (factor_refinement=False): the same
    points and tangents to round-off, with fewer tangent factorisations."""
    from supercoil.continuation import phase, step
    from supercoil.continuation.options import ContinuationOptions
    from supercoil.continuation.switching import switch_branch
    from supercoil.problems.ring_branches import circle_branch

    circle, problem = circle_branch(2 / 3, 24, 3.0)
    point = circle.points_of_kind("bifurcation")[0]
    calls = []
    original = step.tangent

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    for module in (step, phase):  # the tangents of the steps and of the moved gauges
        monkeypatch.setattr(module, "tangent", counted)
    runs = {}
    for refine in (False, True):
        calls.clear()
        opts = ContinuationOptions(initial_step=0.01, max_step=0.05, max_points=8,
                                   gauge="integral", rephase=True, factor_refinement=refine)
        runs[refine] = (switch_branch(problem, circle, point, opts), len(calls))
    (fresh, fresh_calls), (refined, refined_calls) = runs[False], runs[True]
    assert len(fresh) == len(refined) == 8
    np.testing.assert_allclose(refined.states, fresh.states, rtol=0, atol=1e-9)
    np.testing.assert_allclose(refined.tangents, fresh.tangents, rtol=0, atol=1e-8)
    assert refined_calls < fresh_calls
