"""A problem's parameters change through ``at``: a new problem at the new values, the
original unchanged bit for bit; continuation never sets the parameter of the problem it
is given (invariants; the new problem against a deep copy with the values set in place)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation import ContinuationOptions, continuation
from supercoil.cosserat.clamped import ClampedCosseratEnergy
from supercoil.cosserat.ring import ring_problem
from supercoil.cosserat.rod import CosseratRod
from supercoil.errors import InputError
from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.solvers.parameters import problem_at


def _bent_ring(n: int = 40):
    x = circle(n)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x[:, 2] += 0.03 * np.sin(2 * t)
    x[:, 0] *= 1.0 + 0.1 * np.cos(2 * t)
    return x


def _bent_clamped(n: int = 30):
    x = straight_rod(n)
    s = np.clip(x[:, 2], 0, 1)
    bump = np.sin(np.pi * s) ** 3
    x[:, 0] += 0.05 * bump * np.cos(3 * s)
    x[:, 1] += 0.05 * bump * np.sin(2 * s)
    x[[0, 1, -2, -1], :2] = 0.0
    return x


def _ring(excess_link=2.5):
    x = _bent_ring()
    return ClosedRodEnergy(Rod(n_nodes=len(x), twist_stiffness=2 / 3), x, excess_link), x.ravel()


def _clamped(turns=0.8, tension=5.0):
    x = _bent_clamped()
    rod = Rod(len(x), twist_stiffness=0.7, closed=False)
    return ClampedRodEnergy(rod, x, turns, tension=tension), x.ravel()


def _cosserat_clamped(turns=0.3, tension=2.0):
    problem = ClampedCosseratEnergy(CosseratRod(12, twist_stiffness=0.8, shear_stiffness=1e3,
                                                stretch_stiffness=1e3, closed=False),
                                    turns, tension)
    q = problem.straight_state()
    return problem, q + 1e-3 * np.sin(np.arange(q.size))


def _cosserat_ring(excess_link=1.3):
    problem = ring_problem(0.8, excess_link, 16, 1e3, 1e3)
    return problem, problem.initial_state()


def _contact_ring(excess_link=2.5):
    base, q = _ring(excess_link)
    return ContactProblem(base, ContactOptions(diameter=0.05, treatment="barrier")), q


CASES = {
    "closed rod": (_ring, {"excess_link": 3.25}),
    "clamped rod": (_clamped, {"turns": 1.7, "tension": -2.0}),
    "contact ring": (_contact_ring, {"excess_link": 3.25}),
    "cosserat ring": (_cosserat_ring, {"excess_link": 1.9}),
    "cosserat clamped": (_cosserat_clamped, {"turns": 0.7, "tension": 4.0}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_at_leaves_the_original_unchanged_and_equals_a_problem_built_there(case):
    make, values = CASES[case]
    problem, q = make()
    energy, gradient = problem.energy(q), problem.gradient(q).copy()
    hessian = problem.hessian(q).dense()
    before = {name: getattr(problem, name) for name in values}
    moved = problem.at(**values)
    assert type(moved) is type(problem) and moved is not problem
    for name, value in values.items():
        assert getattr(moved, name) == value
    # the oracle: a deep copy with the attributes set in place (on the rod, for contact)
    fresh = copy.deepcopy(problem)
    for name, value in values.items():
        setattr(getattr(fresh, "base", fresh), name, value)
    # the new problem evaluated (its caches filled), then the old one again: bit for bit
    assert moved.energy(q) == fresh.energy(q)
    np.testing.assert_array_equal(moved.gradient(q), fresh.gradient(q))
    np.testing.assert_array_equal(moved.hessian(q).dense(), fresh.hessian(q).dense())
    assert {name: getattr(problem, name) for name in values} == before
    assert problem.energy(q) == energy
    np.testing.assert_array_equal(problem.gradient(q), gradient)
    np.testing.assert_array_equal(problem.hessian(q).dense(), hessian)


def test_at_refuses_an_unknown_parameter_by_name():
    problem, _ = _ring()
    with pytest.raises(InputError, match="'turns'.*valid: 'excess_link'"):
        problem.at(turns=1.0)
    contact, _ = _contact_ring()
    with pytest.raises(InputError, match="'tension'"):
        contact.at(tension=1.0)


def test_a_users_protocol_object_is_copied_with_the_parameter_set_on_the_copy():
    class Quartic:
        """``E = x^4 / 4 - lam x^2 / 2``: a plain attribute, no ``at``."""

        n_dofs, n_constraints, fixed, mass = 1, 0, np.zeros(0, dtype=np.int64), np.ones(1)

        def __init__(self, lam):
            self.lam = lam

        def gradient(self, q):
            return q**3 - self.lam * q

    user = Quartic(0.5)
    moved = problem_at(user, lam=2.0)
    assert user.lam == 0.5 and moved.lam == 2.0
    assert moved.gradient(np.array([2.0]))[0] == 4.0
    with pytest.raises(InputError, match="'mu'"):
        problem_at(user, mu=1.0)


def test_continuation_never_sets_the_parameter_of_the_problem_it_is_given():
    problem, q = _clamped(turns=0.0, tension=5.0)
    q = straight_rod(30).ravel()
    branch = continuation(problem, q, parameter="turns",
                          options=ContinuationOptions(parameter_bounds=(0.0, 1.0),
                                                      initial_step=0.1, max_step=0.25))
    assert branch.ok and branch.parameter_values[-1] == 1.0
    assert problem.turns == 0.0 and problem.tension == 5.0
