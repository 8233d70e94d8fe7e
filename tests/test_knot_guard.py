"""The knot type guard: a state whose strand passed through another is refused.

Oracles:

- a crossing change constructed exactly: one strand of the trefoil pushed in z
  under the strand it crossed over (the projection, hence every other crossing,
  unchanged) is an unknot (unknotting number of 3_1 is 1), and the guard refuses
  it; the same push stopped short keeps the trefoil and is admitted;
- Newton on a toy energy whose minimum is the unknotted curve, started from the
  trefoil, never leaves the trefoil's knot type: every step that would cross is
  cut short, and the run stops with a status naming the knot type;
- the displacement test: within half the clearance of a verified state no
  invariant is computed, beyond it one is.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from knot_toys import pushed_down

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions, Status, newton
from supercoil.solvers.problem import HessianParts
from supercoil.topology.knots import KnotGuard, identify, knot_curve


def test_constructed_crossing_change_unknots_the_trefoil_and_is_refused():
    x = knot_curve("3_1", 120)
    guard = KnotGuard()
    assert guard.keep(x).name == "3_1"
    assert identify(pushed_down(x, 1.0)).name == "0_1"
    assert not guard.admissible(pushed_down(x, 1.0))
    assert "3_1" in guard.refusal and "0_1" in guard.refusal
    assert guard.admissible(pushed_down(x, 0.4))
    rotated = x @ np.linalg.qr(np.random.default_rng(3).standard_normal((3, 3)))[0].T
    assert guard.admissible(rotated + 0.7)


def test_contact_problem_refuses_a_strand_passage():
    x = knot_curve("3_1", 120)
    base = ClosedRodEnergy(Rod(n_nodes=120, twist_stiffness=1.0), x, 0.0)
    problem = ContactProblem(base, ContactOptions(diameter=0.01))
    problem.accept(x.ravel())  # the first accepted state is the reference
    assert problem.knot_guard.reference.name == "3_1"
    assert problem.admissible(pushed_down(x, 0.4).ravel())
    assert not problem.admissible(pushed_down(x, 1.0).ravel())
    assert problem.refusal  # the linking number is the first guard to see it


class _Spring:
    """``E(q) = |q - target|^2 / 2``, no constraints; admissible: the knot guard."""

    def __init__(self, start: np.ndarray, target: np.ndarray):
        self.target = target.ravel()
        self.n_dofs, self.n_constraints = self.target.size, 0
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.ones(self.n_dofs)
        self.guard = KnotGuard()
        self.guard.keep(start)
        self.refusal = None

    def energy(self, q):
        return 0.5 * float((q - self.target) @ (q - self.target))

    def gradient(self, q):
        return q - self.target

    def hessian(self, q):
        return HessianParts(sp.identity(self.n_dofs, format="csr"))

    def constraints(self, q):
        return np.zeros(0)

    def constraint_jacobian(self, q):
        return sp.csr_matrix((0, self.n_dofs))

    def constraint_hessian(self, q, multipliers):
        return sp.csr_matrix((self.n_dofs, self.n_dofs))

    def accept(self, q):
        pass

    def admissible(self, q):
        ok = self.guard.admissible(q)
        self.refusal = None if ok else self.guard.refusal
        return ok


def test_newton_never_crosses_and_says_why_it_stopped():
    x = knot_curve("3_1", 60)
    target = pushed_down(x, 1.0)
    assert identify(target).name == "0_1"
    result = newton(_Spring(x, target), x.ravel(),
                    NewtonOptions(mode="stationary", max_iterations=40, min_step=1e-6))
    assert result.status is not Status.CONVERGED
    assert identify(result.q.reshape(-1, 3)).name == "3_1"
    assert "knot type" in result.message
    # it went as far as the knot type allows: most of the way to the crossing
    assert np.max(np.abs(result.q - x.ravel())) > 0.5 * np.max(np.abs(target - x))


def test_displacement_test_skips_the_invariant_near_a_verified_state():
    x = knot_curve("4_1", 100)
    guard = KnotGuard()
    guard.keep(x)
    clearance = 0.02
    assert guard.admissible(x, clearance=lambda q: clearance)
    evaluations = guard.invariant_evaluations
    nudge = np.zeros_like(x)
    nudge[5, 0] = 0.4 * clearance  # 2 * 0.4 < 1: no pair can have crossed
    assert guard.admissible(x + nudge)
    assert guard.invariant_evaluations == evaluations
    nudge[5, 0] = 0.6 * clearance
    assert guard.admissible(x + nudge)
    assert guard.invariant_evaluations == evaluations + 1
