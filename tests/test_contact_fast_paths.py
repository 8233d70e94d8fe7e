"""Fast paths of ContactProblem against the code they replaced.

* ``step_bound`` asks the segments' pair state at ``D/2 + 2.5 s`` (``s`` the step's
  largest node displacement) instead of ``D + 2.5 s`` when the threshold is
  ``min(0.9 d0, max(0.1 d0, D/2))``, and the sample points' state first; against
  the former code (copied below, on a fresh problem: a new broad phase for every
  pair state): the same bound, bit for bit, for steps from 0.03 to 3 edge lengths.
* ``ContactCurve._candidates`` serves cutoffs above ``2 D`` from the last wide broad phase
  (``_verlet_wide``) while no node has moved enough: against a new broad phase, the
  same pairs, distances and feet, bit for bit.
* the sample points of the integral formulation are remembered per state: pair
  states and integral terms equal those of a fresh problem.
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_toys import assert_fresh_pair_state, stadium_ring

from supercoil.contact.ccd import first_time_of_approach, first_time_of_approach_pieces
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.sample_ccd import first_time_of_approach_samples

D = 0.02
CHOICES = {
    "integral spline barrier": {"curve": "spline", "formulation": "integral"},
    "integral polygon barrier": {"formulation": "integral"},
    "pairs spline barrier": {"curve": "spline"},
    "pairs polygon barrier": {},
    "pairs polygon penalty": {"treatment": "penalty"},
}


def _flattened_ring(n=80):
    """A stadium of length 1: two straight sides 1.2 D apart joined by half circles of
    radius 0.6 D (a rod in contact's reach, nowhere within D)."""
    return stadium_ring(n, 0.6 * D)


def _smooth_move(x, amplitude, rng):
    """``x`` plus a random combination of the first Fourier modes along the ring, each
    node moving by at most about ``amplitude`` (no kinks: neighbours do not cross)."""
    theta = 2 * np.pi * np.arange(len(x)) / len(x)
    move = np.zeros_like(x)
    for k in (1, 2, 3):
        move += np.outer(np.sin(k * theta + rng.uniform(0, 2 * np.pi)), rng.normal(size=3))
    return x + amplitude * move / np.max(np.linalg.norm(move, axis=1))


def _former_step_bound(problem: ContactProblem, q, dq) -> float:
    """The former ContactProblem.step_bound (pair states at ``D + 2.5 s``, the segments'
    first), on a fresh problem (no remembered state or neighbour list)."""
    self = ContactProblem(problem.base, problem.options)
    x0 = np.asarray(q, dtype=float).reshape(-1, 3)
    dx = np.asarray(dq, dtype=float).reshape(-1, 3)
    largest = float(np.max(np.linalg.norm(dx, axis=1))) if dx.size else 0.0
    if largest == 0.0:
        return 1.0
    cap = min(1.0, self.edge_length / largest)
    reach = self.diameter + 2.5 * cap * largest
    D = self.diameter
    st = self.pair_state(q, reach, polygon=True)
    t_hit = 1.0
    if len(st.pairs):
        d0 = st.distance
        if self.treatment == "barrier" and not self.spline and not self.integral:
            threshold = D + 0.1 * np.maximum(d0 - D, 0.0)
        else:
            threshold = np.minimum(0.9 * d0, np.maximum(0.1 * d0, 0.5 * D))
        t_hit, _k = first_time_of_approach(x0, cap * dx, self.curve.pair_nodes(st.pairs), threshold)
    if self.integral and self.treatment == "barrier":
        st = self.pair_state(q, reach)
        if len(st.pairs):
            gap = float(np.min(st.distance)) - D
            t_hit = min(t_hit, first_time_of_approach_samples(
                x0, cap * dx, self.curve.sample_stencil, self.curve.sample_weights, st.pairs,
                D + 0.1 * max(gap, 0.0)))
    elif self.spline and self.treatment == "barrier":
        st = self.pair_state(q, reach, shadows=True)
        if len(st.pairs):
            nodes = self.curve.pieces.stencil[st.pairs].reshape(-1, 8)
            pieces = (self.curve.pieces.control[st.pairs], self.curve.pieces.coefficients[st.pairs])
            t_spline, _k = first_time_of_approach_pieces(
                x0[nodes], cap * dx[nodes], pieces, D + 0.1 * np.maximum(st.distance - D, 0.0))
            t_hit = min(t_hit, t_spline)
    return cap * float(t_hit)


@pytest.mark.parametrize("name", list(CHOICES))
def test_step_bound_equals_the_former_code_bit_for_bit(name):
    rod, x0 = _flattened_ring()
    problem = ContactProblem(rod, ContactOptions(diameter=D, **CHOICES[name]))
    h = problem.edge_length
    rng = np.random.default_rng(31)
    x = x0.copy()
    bounds = []
    for state in range(12):
        # small moves (lists reused), now and then a jump (lists rebuilt)
        x = _smooth_move(x0, D * (0.2 if state % 4 == 3 else 0.05), rng)
        q = x.ravel()
        problem.gradient(q)  # a residual at the iterate first, as Newton does
        for size in (0.03, 0.1, 0.3, 1.0, 3.0):
            dq = size * h * rng.standard_normal(q.size) / np.sqrt(3)
            if state % 2:  # a step that drives the two sides into each other
                dq.reshape(-1, 3)[:, 1] = -size * h * np.sign(x[:, 1])
            bound = problem.step_bound(q, dq)
            assert bound == _former_step_bound(problem, q, dq)
            bounds.append(bound)
    bounds = np.array(bounds)
    # the sequence meets free steps, shortened ones and (barrier) states already at
    # the threshold
    assert np.any(bounds == 1.0) and np.any((bounds > 0.0) & (bounds < 0.5))


@pytest.mark.parametrize("name", ["pairs polygon barrier", "integral spline barrier"])
def test_wide_cutoffs_from_the_last_wide_broad_phase_equal_a_new_one(name):
    rod, x0 = _flattened_ring()
    problem = ContactProblem(rod, ContactOptions(diameter=D, **CHOICES[name]))
    rng = np.random.default_rng(12)
    x = x0.copy()
    served = 0
    for state in range(30):
        x = _smooth_move(x if state % 6 else x0, D * (0.5 if state % 6 == 5 else 0.01), rng)
        q = x.ravel()
        for cutoff in (3.5 * D, 2.2 * D, 3.0 * D, 1.01 * D, 2.5 * D, 6.0 * D):
            before = problem.curve._verlet_wide
            fast = problem.pair_state(q, cutoff, polygon=True)
            served += problem.curve._verlet_wide is before and cutoff > 2 * D
            assert_fresh_pair_state(problem, q, cutoff, fast)
            if problem.integral:  # the sample points' state against a fresh problem
                fresh = ContactProblem(problem.base, problem.options)
                mine, reference = problem.pair_state(q, cutoff), fresh.pair_state(q, cutoff)
                assert np.array_equal(mine.pairs, reference.pairs)
                assert np.array_equal(mine.distance, reference.distance)
    assert served > 40  # the wide list did serve


def test_integral_terms_after_remembered_samples_equal_a_fresh_problem():
    rod, x0 = _flattened_ring()
    options = ContactOptions(diameter=D, **CHOICES["integral spline barrier"])
    problem = ContactProblem(rod, options)
    rng = np.random.default_rng(5)
    x = x0.copy()
    for state in range(8):
        x = _smooth_move(x, D * 0.02, rng)
        q = x.ravel()
        problem.step_bound(q, 0.1 * problem.edge_length * rng.standard_normal(q.size))
        fresh = ContactProblem(rod, options)
        assert np.array_equal(problem.gradient(q), fresh.gradient(q))
        mine, reference = problem.hessian(q), fresh.hessian(q)
        assert np.array_equal(mine.sparse.indices, reference.sparse.indices)
        assert np.array_equal(mine.sparse.data, reference.sparse.data)


def test_extended_residual_equals_the_scipy_transpose_product_bit_for_bit():
    """ExtendedSystem._kkt_residual forms J^T mu by csr_rmatvec on all DOFs and takes the
    free ones: against scipy's J[:, free].T @ mu (the former code) on the stadium's
    contact problem, bit for bit."""
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.solvers.csr import csr_columns

    rod, x0 = _flattened_ring()
    problem = ContactProblem(rod, ContactOptions(diameter=D, **CHOICES["integral spline barrier"]))
    system = ExtendedSystem(problem, "excess_link", x0.ravel())
    rng = np.random.default_rng(8)
    for _ in range(3):
        q = _smooth_move(x0, 0.05 * D, rng).ravel()
        mu = rng.standard_normal(system.m)
        J = csr_columns(problem.constraint_jacobian(q), system.free)
        former = np.concatenate([problem.gradient(q)[system.free] + J.T @ mu,
                                 problem.constraints(q)])
        assert np.array_equal(system._kkt_residual(q, mu), former)


@pytest.mark.parametrize("name", list(CHOICES))
def test_min_distance_from_remembered_states_equals_the_search(name):
    """min_distance answers from a remembered non-empty pair state at q when there is
    one: against a fresh problem's search (no remembered state), bit for bit, on the
    contact curve and between the segments, after the states a residual and a step
    bound leave."""
    rod, x0 = _flattened_ring()
    problem = ContactProblem(rod, ContactOptions(diameter=D, **CHOICES[name]))
    rng = np.random.default_rng(21)
    answered = 0
    for state in range(6):
        q = _smooth_move(x0, D * 0.05, rng).ravel()
        problem.gradient(q)
        problem.step_bound(q, 0.3 * problem.edge_length * rng.standard_normal(q.size))
        for polygon in (False, True):
            answered += problem.curve.remembered_min_distance(q, polygon) is not None
            fresh = ContactProblem(rod, problem.options)
            assert problem.min_distance(q, polygon) == fresh.min_distance(q, polygon)
    assert answered >= 6
