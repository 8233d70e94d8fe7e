"""Closed rods without contact keep their linking number and knot type at every step.

Oracles:

- ``closest_approach`` against dense sampling of every pair of non-neighbouring
  edges (an upper bound converging to it as the sampling is refined);
- an exactly constructed crossing change of the trefoil (its over-strand pushed
  below the under-strand: an unknot, unknotting number 1): refused by the link
  (the double-sum writhe jumps by 2) and, with the link check blind, by the knot type;
- Coleman & Swigon's contact-free alpha branch at C/A = 2/3 tends to the planar
  figure-eight (Wr -> 1, dLk -> 1); the same run without the guard passes the rod
  through itself there (Tw + Wr off dLk by 2, and still an unknot: the knot type
  alone cannot see it). Guarded, every point keeps Lk = Tw + Wr and the unknot,
  and the branch stops at the figure-eight with the refusal as its status;
- Newton minimising a trefoil without contact (it would unknot) stops with a status
  naming the passage, still a trefoil.
"""

from __future__ import annotations

import numpy as np
import pytest
from knot_toys import pushed_down

from supercoil.continuation import ContinuationStatus
from supercoil.problems.ring_branches import ring_branches
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions, Status, newton
from supercoil.topology import writhe
from supercoil.topology.crossings import closest_approach
from supercoil.topology.knots import StrandPassageGuard, identify, knot_curve


def sampled_approach(x: np.ndarray, samples: int) -> float:
    """Smallest distance over ``samples`` points per edge, every pair of edges sharing
    no vertex (brute force)."""
    n = len(x)
    s = np.linspace(0.0, 1.0, samples)[:, None]
    e = np.roll(x, -1, 0) - x
    best = np.inf
    for i in range(n):
        a = x[i] + s * e[i]
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            b = x[j] + s * e[j]
            best = min(best, float(np.min(np.linalg.norm(a[:, None] - b[None], axis=2))))
    return best


@pytest.mark.parametrize("seed", [0, 1])
def test_closest_approach_is_the_limit_of_dense_sampling(seed):
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((12, 3))
    exact = closest_approach(x)
    coarse, fine = sampled_approach(x, 41), sampled_approach(x, 401)
    assert exact <= fine <= coarse
    # at least first order in the spacing (a minimum on an edge's end), ten times finer
    assert fine - exact < 0.15 * (coarse - exact) + 1e-12


def test_a_crossing_change_is_refused_by_the_link_and_by_the_knot_type():
    x = knot_curve("3_1", 120)
    rod = ClosedRodEnergy(Rod(n_nodes=120, twist_stiffness=1.0), x, 0.0)
    assert rod.admissible(pushed_down(x, 0.4).ravel())
    crossed = pushed_down(x, 1.0)
    assert not rod.admissible(crossed.ravel())
    assert "linking number would change by" in rod.refusal
    # a guard whose link check cannot fail (the carried writhe is the double sum)
    guard = StrandPassageGuard(x)
    assert not guard.admissible(crossed, lambda q: writhe(q.reshape(-1, 3)))
    assert "3_1" in guard.refusal and "0_1" in guard.refusal


def alpha_to_the_figure_eight():
    branches = ring_branches(2 / 3, 24, modes=(2,), max_points=200, max_step=0.2,
                             excess_link_bounds={2: (0.3, 3.0)})
    return branches.primary[2], branches.problem


def test_the_contact_free_alpha_branch_stops_where_it_would_pass_through_itself(monkeypatch):
    alpha, problem = alpha_to_the_figure_eight()
    assert alpha.status is ContinuationStatus.STEP_TOO_SMALL
    assert "linking number would change by -2" in alpha.message
    assert np.max(alpha.records["link_error"]) < 1e-9
    assert {identify(q.reshape(-1, 3)).name for q in alpha.states} == {"0_1"}
    # it went all the way to the figure-eight, the touching state
    last = alpha.states[-1].reshape(-1, 3)
    assert alpha.records["writhe"][-1] == pytest.approx(1.0, abs=1e-3)
    assert alpha.parameter_values[-1] == pytest.approx(1.0, abs=1e-3)
    assert closest_approach(last) < 1e-2 * problem.rod.length
    # the pre-check spared most points the invariants
    assert problem.passage_guard.invariant_evaluations < len(alpha)

    monkeypatch.delattr(ClosedRodEnergy, "admissible")
    unguarded, _ = alpha_to_the_figure_eight()
    crossed = unguarded.records["link_error"] > 1.9
    assert np.any(crossed) and np.min(unguarded.parameter_values) < 0.99
    assert {identify(q.reshape(-1, 3)).name for q in unguarded.states} == {"0_1"}


def test_newton_does_not_unknot_a_trefoil_without_contact():
    x = knot_curve("3_1", 60)
    problem = ClosedRodEnergy(Rod(n_nodes=60, twist_stiffness=1.0), x, 0.0)
    result = newton(problem, x.ravel(), NewtonOptions(mode="minimize", max_iterations=300))
    assert result.status is Status.LINE_SEARCH_FAILED
    assert "a strand through another" in result.message
    final = result.q.reshape(-1, 3)
    assert identify(final).name == "3_1"
    assert writhe(final) == pytest.approx(problem.writhe_local(result.q), abs=1e-9)
