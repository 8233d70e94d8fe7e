"""The analytic load-parameter derivatives of the KKT residual against central differences.

``RodEnergy.parameter_derivative`` (the ring's excess link, the clamped rod's
turns; ``ClampedRodEnergy`` adds its tension) and ``ContactProblem``'s, which
adds zeros for the contact constraints, replace the continuation's central
difference of the residual: both must agree, on a bent, twisted ring and a bent,
twisted clamped rod, bare, with integral barrier contact and with the exact
treatment.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation.system import ExtendedSystem
from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod


def _bent_ring(n: int = 60):
    x = circle(n)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x[:, 2] += 0.03 * np.sin(2 * t)  # out of plane: writhe, twist gradient non-zero
    x[:, 0] *= 1.0 + 0.1 * np.cos(2 * t)
    rod = Rod(n_nodes=n, twist_stiffness=2 / 3)
    return ClosedRodEnergy(rod, x, 2.5), x.ravel()


def _central_difference(problem, q, mu, step=1e-4, parameter="excess_link"):
    def kkt(lam):
        at = problem.at(**{parameter: lam})
        return np.concatenate([at.gradient(q) + at.constraint_jacobian(q).T @ mu,
                               at.constraints(q)])
    lam = getattr(problem, parameter)
    return (kkt(lam + step) - kkt(lam - step)) / (2 * step)


def _bent_clamped_rod(n: int = 50):
    """A clamped rod at 1.7 turns under F L^2/A = 20, its interior nodes moved off the
    axis (a non-planar hump: writhe, so the twist gradient is not zero)."""
    x = straight_rod(n)
    rod = Rod(n_nodes=n, twist_stiffness=4 / 3, closed=False)
    problem = ClampedRodEnergy(rod, x, 1.7, tension=20.0)
    s = np.linspace(0.0, 1.0, n)
    bump = np.sin(np.pi * s) ** 2
    bump[[0, 1, n - 2, n - 1]] = 0.0  # the clamped nodes stay on the axis
    y = x.copy()
    y[:, 0] += 0.08 * bump * np.cos(3 * s)
    y[:, 1] += 0.05 * bump * np.sin(5 * s)
    return problem, y.ravel()


@pytest.mark.parametrize("wrap", [None, "barrier", "exact"])
def test_excess_link_derivative_matches_central_differences(wrap):
    rod, q = _bent_ring()
    problem = rod if wrap is None else ContactProblem(
        rod, ContactOptions(diameter=0.05, treatment=wrap, formulation="integral"
                            if wrap == "barrier" else "pairs"))
    mu = np.linspace(-1.0, 1.0, problem.n_constraints)
    exact = problem.parameter_derivative(q, mu, "excess_link")
    assert exact.shape == (problem.n_dofs + problem.n_constraints,)
    expected = _central_difference(problem, q, mu)
    scale = np.max(np.abs(expected))
    assert scale > 1.0  # the twist gradient of a non-planar ring is not zero
    np.testing.assert_allclose(exact, expected, rtol=0, atol=1e-9 * scale)
    assert problem.parameter_derivative(q, mu, "twist_ratio") is None


def test_extended_system_uses_it_and_falls_back_for_other_parameters():
    rod, q = _bent_ring()
    problem = ContactProblem(rod, ContactOptions(diameter=0.05, formulation="integral"))
    system = ExtendedSystem(problem, "excess_link", q)
    x = system.pack(q, np.linspace(-1, 1, problem.n_constraints), 2.5)
    analytic = system.parameter_derivative(x)
    rod.parameter_derivative = lambda *args: None  # the wrapper returns None: differences
    numeric = system.parameter_derivative(x)
    np.testing.assert_allclose(analytic, numeric, rtol=0, atol=1e-6 * np.max(np.abs(analytic)))


@pytest.mark.parametrize("wrap", [None, "barrier", "exact"])
@pytest.mark.parametrize("parameter", ["turns", "tension"])
def test_clamped_rod_turns_and_tension_derivatives_match_central_differences(wrap, parameter):
    rod, q = _bent_clamped_rod()
    problem = rod if wrap is None else ContactProblem(
        rod, ContactOptions(diameter=0.03, treatment=wrap, formulation="integral"
                            if wrap == "barrier" else "pairs"))
    mu = np.linspace(-1.0, 1.0, problem.n_constraints)
    exact = problem.parameter_derivative(q, mu, parameter)
    assert exact.shape == (problem.n_dofs + problem.n_constraints,)
    expected = _central_difference(problem, q, mu, parameter=parameter)
    scale = np.max(np.abs(expected))
    assert scale > 0.5  # turns: the hump's twist gradient; tension: the end loads (1)
    np.testing.assert_allclose(exact, expected, rtol=0, atol=1e-9 * scale)
    assert problem.parameter_derivative(q, mu, "twist_ratio") is None
    assert problem.parameter_derivative(q, mu, "excess_link") is None
