"""The ring's contact-free bifurcation diagram: the circle, Michell's points, alpha and beta.

Oracles: Michell's thresholds (A/C) sqrt(m^2 - 1); Coleman & Swigon's shapes
(subcritical alpha at C/A = 2/3 tending to the planar figure-eight,
supercritical at C/A = 2; D_m symmetry of the primary branch of mode m);
Lk = Tw + Wr with Tw from the material frames and Wr from the double sum;
dense eigenvalues of the constrained Hessian (rigid motions and material
sliding projected out) for the unstable count.
"""

from itertools import pairwise

import numpy as np
import pytest
from scipy.linalg import eigh, null_space

from supercoil.continuation import consistency_check
from supercoil.problems.ring import circle_energy, michell_excess_link, richardson
from supercoil.problems.ring_branches import circle_branch, radial_harmonics, ring_branches
from supercoil.solvers.newton import lagrangian_hessian
from supercoil.stability.analysis import analyse, goldstone_modes, near_symmetry_gauge
from supercoil.topology import writhe


@pytest.fixture(scope="module")
def dna():
    """C/A = 2/3 (Coleman & Swigon's DNA), N = 48 (a lattice with D_2 and D_3 symmetry)."""
    return ring_branches(2 / 3, 48, modes=(2, 3), max_points=30,
                         excess_link_bounds={2: (1.05, 3.0), 3: (0.5, 5.0)})


def dense_count(problem, q, multipliers, excess_link, tolerance=1e-6):
    """Negative eigenvalues of H v = mu M v on ker J, rigid motions and sliding projected out."""
    problem.excess_link = excess_link
    problem.accept(q)
    dofs = np.arange(problem.n_dofs)
    H = lagrangian_hessian(problem, q, multipliers).restrict(dofs).dense()
    J = problem.constraint_jacobian(q).toarray()
    M = problem.mass
    S = np.vstack([problem.symmetry_modes(q), problem.near_symmetry_modes(q)])
    Z = null_space(np.vstack([J, S * M]))
    values = eigh(Z.T @ H @ Z, Z.T @ (M[:, None] * Z), eigvals_only=True)
    return int(np.sum(values < -tolerance)), values


def test_circle_bifurcations_converge_at_order_two():
    """Michell's points m = 2, 3, 4 at C/A = 1: order 2 in N, Richardson within 1e-4."""
    exact = [michell_excess_link(1.0, m) for m in (2, 3, 4)]
    found = {}
    for n in (64, 128):
        circle, _ = circle_branch(1.0, n, 1.1 * exact[-1])
        points = circle.points_of_kind("bifurcation")
        assert [(p.count_before, p.count_after) for p in points] == [(0, 2), (2, 4), (4, 6)]
        # pairs cross: the determinant never changes sign along the circle
        assert np.all(circle.determinant_sign == circle.determinant_sign[0])
        found[n] = np.array([p.parameter for p in points])
    errors = {n: found[n] / exact - 1 for n in found}
    order = np.log2(errors[64] / errors[128])
    assert np.all(np.abs(order - 2) < 0.1), order
    extrapolated = richardson(found[64], found[128]) / exact - 1
    assert np.all(np.abs(extrapolated) < 1e-4), extrapolated
    assert np.all(np.abs(errors[128]) < 3e-3)


def test_alpha_is_subcritical_at_dna_stiffness_and_tends_to_the_figure_eight(dna):
    alpha = dna.primary[2]
    assert alpha.name == "alpha" and alpha.parent == "circle"
    assert alpha.origin.kind == "bifurcation"
    lk, wr, tw = (alpha.records[k] for k in ("excess_link", "writhe", "twist"))
    start = dna.bifurcation(2).parameter
    assert start == pytest.approx(np.sqrt(3) * 1.5, rel=3e-3)  # 2.2e-3 at N = 48
    # subcritical: dLk decreases away from the bifurcation, all the way down
    assert np.all(np.diff(lk) < 0) and lk[0] < start
    # towards the planar figure-eight: Wr -> 1, dLk -> 1, Tw -> 0
    assert lk[-1] == pytest.approx(1.05) and alpha.ok
    assert 0.95 < wr[-1] < 1.0 and 0 < tw[-1] < 0.1
    assert np.all(np.diff(wr) > 0)
    # energy: the circle's at the bifurcation, then dE/dLk = 4 pi^2 (C/A) Tw along
    # the branch (the twisting moment; trapezoidal rule, error O(step^3) per step)
    energy = alpha.records["energy"]
    assert energy[0] == pytest.approx(circle_energy(2 / 3, lk[0]), rel=1e-6)
    predicted = 4 * np.pi**2 * (2 / 3) * 0.5 * (tw[1:] + tw[:-1]) * np.diff(lk)
    assert np.max(np.abs(np.diff(energy) - predicted)) < 1e-3 * np.max(np.abs(predicted))


def test_alpha_is_supercritical_for_stiff_twist():
    branches = ring_branches(2.0, 40, modes=(2,), max_points=8)
    alpha = branches.primary[2]
    lk = alpha.records["excess_link"]
    assert lk[0] > branches.bifurcation(2).parameter and np.all(np.diff(lk) > 0)
    assert np.all(alpha.unstable_count == 0)  # it inherits the circle's stability
    assert np.all(alpha.records["link_error"] < 1e-9)


@pytest.mark.parametrize("mode", [2, 3])
def test_primary_branches_have_dihedral_symmetry(dna, mode):
    """Distance to the centroid along the rod: only harmonics that are multiples of m."""
    branch = dna.primary[mode]
    checked = 0
    for q, wr in zip(branch.states, branch.records["writhe"]):
        if not 0.01 < wr < 1.2:
            continue
        harmonics = radial_harmonics(q, 12)
        others = np.delete(harmonics[1:], np.arange(mode - 1, 12, mode))
        assert harmonics[mode] > 1e-3
        assert np.max(others) < 1e-6 * harmonics[mode]
        checked += 1
    assert checked >= 5


def test_branches_are_consistent_and_keep_lk_equal_tw_plus_wr(dna):
    assert [b.name for b in dna.branches] == ["circle", "alpha", "beta"]
    for branch in dna.branches:
        assert branch.ok, branch.message
        report = consistency_check(branch, dna.problem)
        assert report.ok, (branch.name, report.problems)
        assert np.max(branch.records["link_error"]) < 1e-9
        lk = branch.records["twist"] + branch.records["writhe"]
        assert np.allclose(lk, branch.parameter_values, atol=1e-9)


def test_unstable_count_is_constant_between_special_points_and_matches_dense(dna):
    for branch in dna.branches:
        cuts = [0] + [p.index + 1 for p in branch.special_points] + [len(branch)]
        for a, b in pairwise(cuts):
            assert np.unique(branch.unstable_count[a:b]).size == 1, (
                branch.name, branch.unstable_count)
        assert np.all(branch.zero_modes == 0)
    # circle 0 -> 2 -> 4; alpha one unstable mode, beta three (subcritical, no contact)
    assert list(dna.circle.unstable_count[[0, -1]]) == [0, 4]
    assert np.all(dna.primary[2].unstable_count == 1)
    assert np.all(dna.primary[3].unstable_count == 3)
    problem = dna.problem
    for branch in dna.primary.values():
        for i in (0, len(branch) // 2, len(branch) - 1):
            q, mu, lk = branch.states[i], branch.multipliers[i], branch.parameter_values[i]
            count, values = dense_count(problem, q, mu, lk)
            assert count == branch.unstable_count[i]
            assert np.min(np.abs(values)) > 1e-3  # no eigenvalue near the sign threshold
        # analyse (the state alone, its own gauge) agrees at every point, certified:
        # with the sliding counted through a Schur complement of the nearly singular
        # pinned KKT matrix it flickered (1, 1, 2, 1, ...) and was not certified
        for q, mu, lk, count in zip(branch.states, branch.multipliers,
                                    branch.parameter_values, branch.unstable_count):
            problem.excess_link = lk
            problem.accept(q)
            report = analyse(problem, q, mu)
            assert report.certified, report.message
            assert (report.unstable_count, report.zero_modes) == (count, 0)
            assert report.determinant_sign == (-1) ** count


def test_sliding_is_gauged_off_the_circle_only(dna):
    """One unit phase row (a pinned DOF) against the sliding on alpha and beta, none on the circle."""
    problem = dna.problem
    assert dna.circle.phase_modes.shape[0] == 0
    q = dna.circle.states[-1]
    assert goldstone_modes(problem, q).shape[0] == 0
    assert near_symmetry_gauge(problem, q).size == 0
    for branch in dna.primary.values():
        (row,) = branch.phase_modes
        assert np.count_nonzero(row) == 1
        assert int(np.flatnonzero(row)[0]) not in set(problem.fixed.tolist())


def test_going_back_to_a_stored_state_keeps_the_tracked_writhe(dna):
    """Regression: frames carried in one jump between stored states (the end of beta, the
    circle, the end of alpha) slipped the tracked writhe by one or two (measured at N = 48
    with plain time-parallel transport): the beta branch switched after alpha was wrong."""
    problem = dna.problem
    alpha, beta = dna.primary[2].states, dna.primary[3].states
    walks = [(beta[-1], alpha), (alpha[-1], alpha), (alpha[-1], [*dna.circle.states, *beta])]
    for start, walk in walks:
        problem.accept(start)
        for q in walk:
            problem.accept(q)
            assert problem.writhe_local(q) == pytest.approx(writhe(q.reshape(-1, 3)), abs=1e-10)
