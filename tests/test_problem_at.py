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
    delta = 1e-3 * np.sin(np.arange(q.size))
    delta[problem.fixed] = 0.0  # the clamps' values
    return problem, q + delta


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
    problem, bent = _clamped(turns=0.0, tension=5.0)
    frames, energy = problem.frames, problem.energy(bent)
    q = straight_rod(30).ravel()
    branch = continuation(problem, q, parameter="turns",
                          options=ContinuationOptions(parameter_bounds=(0.0, 1.0),
                                                      initial_step=0.1, max_step=0.25))
    assert branch.ok and branch.parameter_values[-1] == 1.0
    assert problem.turns == 0.0 and problem.tension == 5.0
    assert problem.frames.equals(frames) and problem.energy(bent) == energy
    assert len(branch.frames) == len(branch)


@pytest.mark.parametrize("case", sorted(CASES))
def test_carried_to_and_with_frames_leave_the_original_unchanged(case):
    make, _ = CASES[case]
    problem, q = make()
    delta = 1e-3 * np.cos(np.arange(q.size))
    delta[np.asarray(problem.fixed, dtype=np.int64)] = 0.0  # the clamps stay
    moved = q + delta
    energy, gradient = problem.energy(moved), problem.gradient(moved).copy()
    frames = problem.frames
    carried = problem.carried_to(moved)
    # the oracle: a deep copy accepting the state in place
    oracle = copy.deepcopy(problem)
    oracle.accept(moved)
    assert carried.frames.equals(oracle.frames) and not carried.frames.equals(frames)
    assert carried.energy(moved) == oracle.energy(moved)
    assert problem.frames.equals(frames)
    assert problem.energy(moved) == energy
    np.testing.assert_array_equal(problem.gradient(moved), gradient)
    # the carried frames, restored on the original: the carried problem bit for bit
    restored = problem.with_frames(carried.frames)
    assert restored.energy(moved) == carried.energy(moved)
    np.testing.assert_array_equal(restored.gradient(moved), carried.gradient(moved))
    assert problem.frames.equals(frames)
    with pytest.raises(ValueError):
        next(iter(frames.values.values()))[...] = 0.0  # read-only


def _ring_runs(n_nodes: int = 24):
    from supercoil.problems.ring_branches import circle_branch, mode_bifurcation

    circle, problem = circle_branch(2 / 3, n_nodes, 4.0)
    points = {mode: mode_bifurcation(circle, mode, [])[1] for mode in (2,)}
    options = ContinuationOptions(initial_step=2e-3, max_step=0.1, max_points=8)
    return circle, problem, points, options


def _same(a, b):
    for name in ("parameter_values", "states", "multipliers", "tangents", "arclength",
                 "unstable_count"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in a.records:
        np.testing.assert_array_equal(a.records[name], b.records[name], err_msg=name)
    assert len(a.frames) == len(b.frames) == len(a)
    assert all(f.equals(g) for f, g in zip(a.frames, b.frames))


def test_a_branch_does_not_depend_on_what_was_computed_before_on_its_problem():
    """The same primary branch switched from the circle twice, with other branches
    computed on the same problem in between, and on a fresh problem: bit for bit."""
    from supercoil.continuation import switch_branch
    from supercoil.problems.ring_branches import ring_records

    circle, problem, points, options = _ring_runs()
    frames, q = problem.frames, circle.states[-1]
    energy = problem.energy(q)

    def alpha(on):
        return switch_branch(on, circle, points[2], options, amplitude=2e-3, name="alpha",
                             records=ring_records(on))

    first = alpha(problem)
    beta = switch_branch(problem, circle, points[2], options, side=-1, amplitude=4e-3,
                         name="beta", records=ring_records(problem))
    onwards = continuation(problem, first.states[-1], first.multipliers[-1], "excess_link",
                           ContinuationOptions(max_points=4, max_step=0.1),
                           start=float(first.parameter_values[-1]))
    assert len(beta) > 1 and len(onwards) > 1
    again = alpha(problem)
    _same(first, again)
    _same(first, alpha(_ring_runs()[1]))  # a fresh problem, nothing computed on it
    # the problem the runs were given is unchanged
    assert problem.frames.equals(frames) and problem.energy(q) == energy
    assert problem.excess_link == 0.0
