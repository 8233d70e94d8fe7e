"""The half-turn symmetry of the clamped rod (``supercoil.rod.mirror``) and the contact
branch held on it (``supercoil.problems.tweezers.mirrored``).

Oracles: curves symmetric by construction under the rotation by pi about a known axis
across the middle (with the node order reversed), turned about the rod's axis; for the
held branch, the nodes' distances to the axis (``r_i = r_{N-1-i}`` on a symmetric state,
whatever the axis), the KKT residual without the phase row (the force it holds) and the
freely followed contact branch, which passes through the same states where it is
symmetric too.
"""

from __future__ import annotations

import dataclasses
from itertools import pairwise

import numpy as np
import pytest

from supercoil.continuation import ContinuationStatus
from supercoil.continuation import tracer as tracing
from supercoil.problems.contact_events import first_onset
from supercoil.problems.tweezers import TweezersOptions, compute, tweezers_branches
from supercoil.problems.tweezers.contact import MIRROR_TOLERANCE
from supercoil.problems.tweezers.mirrored import SUFFIX, mirrored_contact
from supercoil.problems.tweezers.returned import axis_distance
from supercoil.rod.mirror import mirror_asymmetry, mirror_image, mirror_offset
from supercoil.stability.analysis import analyse, eigen_system, sliding_phase_modes
from supercoil.stability.eigen import dense_constrained_eigenpairs

# a short rod whose contact branch starts from its centred loop (L/D = 100, lambda = 10)
SMALL = TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=100, n_nodes=102,
                        turns=(0.0, 3.34), max_points=400, loop_sliding=True)


def held_after_free():
    """The run of ``SMALL``, its last two branches the free contact branch and the held one."""
    result = tweezers_branches(SMALL)
    assert [b.name for b in result.branches][-2:] == ["buckled_contact",
                                                       "buckled_contact" + SUFFIX]
    return result


def symmetric_curve(n: int, angle: float) -> np.ndarray:
    """A loop-like curve on the clamped rod's nodes, mapped onto itself by the half-turn
    about the x axis through ``z = 1/2`` (``x(s) -> (x, -y, 1 - z)(1 - s)``), then turned
    by ``angle`` about the rod's axis; ends on the axis."""
    s = (np.arange(n) - 0.5) / (n - 2)
    u = s - 0.5
    bump = np.exp(-(u / 0.08) ** 2)
    x = np.stack([0.05 * bump, 0.3 * u * bump, s + 0.02 * u * bump], axis=1)
    c, d = np.cos(angle), np.sin(angle)
    return (x @ np.array([[c, -d, 0.0], [d, c, 0.0], [0.0, 0.0, 1.0]]).T).ravel()


def odd_field(n: int) -> np.ndarray:
    """A displacement that the same half-turn maps to its opposite (``C w = -w``), along
    the axis (so that the best axis of the moved curve stays the same)."""
    s = (np.arange(n) - 0.5) / (n - 2)
    w = np.zeros((n, 3))
    w[:, 2] = np.exp(-((s - 0.5) / 0.08) ** 2)
    w[[0, 1, -2, -1]] = 0.0
    return w.ravel()


@pytest.mark.parametrize("angle", [0.0, 0.7, 2.9])
def test_symmetric_curve_is_its_own_image_and_an_odd_part_is_taken_out(angle):
    n = 81
    q = symmetric_curve(n, angle)
    assert mirror_asymmetry(q) < 1e-14
    np.testing.assert_allclose(mirror_image(q), q, atol=1e-14)
    w = odd_field(n)
    for delta in (1e-6, 1e-4):
        moved = q + delta * w
        # to first order the image is q - delta w: the asymmetry is 2 delta |w|
        biggest = np.max(np.linalg.norm(w.reshape(-1, 3), axis=1))
        assert mirror_asymmetry(moved) == pytest.approx(2 * delta * biggest, rel=1e-2)
        # the symmetric part is symmetric, and the image an involution
        assert mirror_asymmetry(moved + mirror_offset(moved)) < 1e-12
        np.testing.assert_allclose(mirror_image(mirror_image(moved)), moved, atol=1e-12)
        np.testing.assert_allclose(mirror_offset(moved), -delta * w, atol=1e-14)


def radii_asymmetry(states: np.ndarray) -> np.ndarray:
    radii = np.linalg.norm(states.reshape(len(states), -1, 3)[:, :, :2], axis=2)
    return np.abs(radii - radii[:, ::-1]).max(axis=1) / radii.max(axis=1)


def test_contact_branch_held_on_its_symmetry_is_the_symmetric_one_and_holds_no_force():
    """At L/D = 100, lambda = 10, C/A = 1.5, N = 102 (loop_sliding) the contact branch held
    on its half-turn symmetry reaches the last turn; its states are symmetric (the radii
    to 1e-6 of the largest, where the freely followed branch leaves the symmetry by
    more), equilibria without the phase row to the contact tolerance (the row holds no
    force on the symmetric family), and the freely followed branch, where it is
    symmetric, passes through them."""
    kept = {}
    options = SMALL
    result = tweezers_branches(options, on_branch=lambda b, contact: kept.update({b.name: b}))
    free, contact = kept["buckled"], kept["buckled_contact"]
    onset = first_onset(free) or free.points_of_kind("contact_onset")[0]
    held, _pins = mirrored_contact(options, result.rod_problem, result.contact_problem, free,
                                   onset, "buckled_contact", {})
    assert held.name == "buckled_contact" + SUFFIX
    assert held.status is ContinuationStatus.PARAMETER_BOUND, held.message
    assert held.parameter_values[-1] == pytest.approx(options.turns[1])
    assert np.all(radii_asymmetry(held.states) < 1e-6)
    # the corrector projects onto the symmetric states: exact past the (free) start
    assert mirror_asymmetry(held.states[0]) <= MIRROR_TOLERANCE * options.diameter
    assert all(mirror_asymmetry(q) <= 1e-12 * options.diameter for q in held.states[1:])
    # the force the row holds: the KKT residual without it (3e-6 at most, where the
    # contact forces reach 1e2)
    assert np.max(held.records["sliding_residual"]) < 1e-5
    assert np.all(held.records["min_gap_over_diameter"] > 1.0)
    # the free branch where it is symmetric: its states on the held branch, read by
    # quadratic interpolation in arclength through three of its points (the branches
    # that left the symmetry were slid by 0.04 to 0.7 D; measured 1.6e-3 to 2.5e-3 D
    # with one or two BLAS threads, whose round-off gives the runs different steps, where
    # the chords alone are off by up to 0.012 D), the first ones exactly (the same steps)
    symmetric = np.flatnonzero(radii_asymmetry(contact.states) < 1e-6)
    assert symmetric.size >= 10
    distances = [curve_distance(contact.states[k], held) for k in symmetric]
    assert np.max(distances) < 5e-3 * options.diameter
    assert np.count_nonzero(np.array(distances) < 1e-6 * options.diameter) >= 10


def curve_distance(q: np.ndarray, branch) -> float:
    """The smallest largest-node distance (after the best turn about the axis) from ``q``
    to ``branch`` read between its points by the quadratic in arclength through three
    consecutive points, on either side of the chord nearest ``q`` (201 samples each)."""
    states, s = branch.states, branch.arclength
    k = int(np.argmin([chord_distance(q, states[[i, i + 1]]) for i in range(len(s) - 1)]))
    best = chord_distance(q, states[[k, k + 1]])
    for first in (k - 1, k):
        if first < 0 or first + 2 >= len(s):
            continue
        nodes = s[first:first + 3]
        for t in np.linspace(s[k], s[k + 1], 201):
            weights = [np.prod([(t - nodes[j]) / (nodes[i] - nodes[j]) for j in range(3)
                                if j != i]) for i in range(3)]
            best = min(best, axis_distance(q, np.tensordot(weights, states[first:first + 3],
                                                           axes=1)))
    return best


def chord_distance(q: np.ndarray, states: np.ndarray) -> float:
    """The smallest largest-node distance (after the best turn about the axis) from ``q``
    to the chords between consecutive ``states``."""
    best = float("inf")
    for a, b in pairwise(states):
        d = b - a
        u = float(np.clip((q - a) @ d / (d @ d), 0.0, 1.0)) if d @ d > 0 else 0.0
        best = min(best, axis_distance(q, a + u * d))
    return best


def test_a_closed_contact_branch_is_followed_again_held_on_its_symmetry(monkeypatch):
    """The driver's path: where the contact branch closes (here made to, at its 40th
    point, by the closure test) the held branch is computed, reported as a contact
    branch after it, and reaches the last turn; the result is complete, and the closed
    branch keeps its status."""
    real = compute.close_on_return

    def closing(branch, other, diameter, reach=1.0):
        if branch.name == "buckled_contact":
            assert len(branch) == 40
            return dataclasses.replace(branch, status=ContinuationStatus.CLOSED_LOOP,
                                       message="made to close")
        return real(branch, other, diameter, reach)

    computed_up_to(monkeypatch, compute, "buckled_contact", 40)  # the points kept
    monkeypatch.setattr(compute, "close_on_return", closing)
    options = SMALL
    result = held_after_free()
    assert result.branches[-2].status is ContinuationStatus.CLOSED_LOOP
    held = result.branches[-1]
    assert held.name in result.contact_branches
    assert held.parameter_values[-1] == pytest.approx(options.turns[1])
    assert result.ok, result.notes
    assert any("followed again held on its half-turn symmetry" in n for n in result.notes)


def computed_up_to(monkeypatch, module, name: str, points: int, status=None,
                   message: str = "made to stop"):
    """Make ``module.contact_branch`` compute branch ``name`` only up to ``points`` points
    (its ``max_points``: the same points as the first ones of the branch given more,
    to the bit), and, with ``status``, return it as ended so (``STEP_TOO_SMALL``: as
    the free contact branch of a loop whose sliding the turns drive stops at the
    minimum step, benchmarks/results/long_dna_grid.md)."""
    real = module.contact_branch

    def cut(opts, rod, cp, free, onset, branch_name, *args, **kwargs):
        if branch_name != name:
            return real(opts, rod, cp, free, onset, branch_name, *args, **kwargs)
        branch, pins = real(dataclasses.replace(opts, max_points=points), rod, cp, free,
                            onset, branch_name, *args, **kwargs)
        assert len(branch) == points
        if status is not None:
            branch = dataclasses.replace(branch, status=status, message=message)
        return branch, pins
    monkeypatch.setattr(module, "contact_branch", cut)


def stopping(monkeypatch, module, name: str, points: int):
    """Make ``module.contact_branch`` return branch ``name`` after ``points`` points as
    stopped at the minimum step (:func:`computed_up_to`)."""
    computed_up_to(monkeypatch, module, name, points, ContinuationStatus.STEP_TOO_SMALL)


def test_a_stopped_contact_branch_is_followed_again_held_on_its_symmetry(monkeypatch):
    """The driver's path where the free contact branch stops (here made to, after its
    6th point, at the minimum step): from its symmetric start the held branch is computed
    after it and reaches the last turn, its states symmetric and equilibria without the
    row; the notes give the free branch's stop, then the held branch; the run is
    complete, the stopped branch handed over."""
    stopping(monkeypatch, compute, "buckled_contact", 6)
    options = SMALL
    result = held_after_free()
    free, held = result.branches[-2:]
    assert free.status is ContinuationStatus.STEP_TOO_SMALL and len(free) == 6
    assert held.name in result.contact_branches
    assert held.status is ContinuationStatus.PARAMETER_BOUND, held.message
    assert held.parameter_values[-1] == pytest.approx(options.turns[1])
    np.testing.assert_allclose(held.states[0], free.states[0], atol=1e-12)  # same start
    assert all(mirror_asymmetry(q) <= 1e-12 * options.diameter for q in held.states[1:])
    assert np.all(radii_asymmetry(held.states) < 1e-6)
    assert np.max(held.records["sliding_residual"]) < 1e-5
    assert result.ok, result.notes
    assert result.held_instead == {"buckled_contact"} and result.branch_ok(free)
    stop = f"{free.parameter_values[-1]:.6g}"
    assert (f"buckled_contact: stopped at {stop} turns (made to stop); followed again held "
            f"on its half-turn symmetry: buckled_contact{SUFFIX}") in result.notes


def test_a_held_branch_that_stops_too_says_why(monkeypatch):
    """Where the held branch stops as well (here made to), the run is not complete: the
    notes give the free branch's stop, then the held branch's failure."""
    from supercoil.problems.tweezers import mirrored

    stopping(monkeypatch, compute, "buckled_contact", 6)
    stopping(monkeypatch, mirrored, "buckled_contact" + SUFFIX, 12)
    result = held_after_free()
    assert not result.ok
    assert any(n.startswith("buckled_contact: stopped at") for n in result.notes)
    assert f"failed: buckled_contact{SUFFIX}: made to stop" in result.notes


def test_a_stopped_contact_branch_without_a_symmetric_start_fails(monkeypatch):
    """Without loop_sliding there is no symmetric start to hold: the stopped free branch
    is the last, and the run fails with its reason."""
    stopping(monkeypatch, compute, "buckled_contact", 6)
    result = tweezers_branches(dataclasses.replace(SMALL, loop_sliding=False))
    assert result.branches[-1].name == "buckled_contact"
    assert not result.ok and result.held_instead == frozenset()
    assert "failed: buckled_contact: made to stop" in result.notes


def test_held_plectoneme_counts_no_remnant_of_its_stiff_sliding(monkeypatch):
    """At L/D = 200, lambda = 10, C/A = 1, N = 202 (segments of D) the held plectoneme's
    count is one only between its two folds (the S's middle, as at N = 303, where the
    folds lie at 2.4961 and 2.2000 turns against 2.4964 and 2.1998), and zero beyond:
    from 3.27 turns the count on the complement of the sliding's generator ``g`` was
    one (a reported bifurcation at 3.274 turns, none at N = 303, whose own count of
    one came and went elsewhere). Oracle at the points beyond 3.3 turns, dense: the
    constrained Hessian has one negative eigenvalue, the sliding's (its eigenvector odd
    under the half-turn, overlap with ``g`` above 0.7), and on the complement of ``g``
    still one, the rest of that eigenvector; the count is the one with the sliding mode
    left out, and so are the eigenvalues reported with the point and by the state's own
    report (:func:`~supercoil.stability.analysis.analyse`)."""
    dense = []
    real = tracing.point_stability

    def checked(system, x, zero_tolerance, n_modes, full=None, factor=None):
        stability = real(system, x, zero_tolerance, n_modes, full, factor)
        problem = system.problem_at(x[-1])
        if getattr(problem, "base", None) is not None and problem.base.mirror_hold \
                and x[-1] > 3.3:
            q, multipliers = system.q(x), system.multipliers(x)
            report = analyse(problem, q, multipliers)
            dense.append((stability.unstable_count, float(np.min(stability.eigenvalues)),
                          report.unstable_count, float(np.min(report.lowest_eigenvalues)))
                         + dense_check(problem, q, multipliers))
        return stability

    monkeypatch.setattr(tracing, "point_stability", checked)
    kept = {}
    options = TweezersOptions(twist_ratio=1.0, length_over_diameter=200, tension=100,
                              n_nodes=202, turns=(0.0, 3.35), max_points=30,
                              loop_sliding=True)
    result = tweezers_branches(options, on_branch=lambda b, contact: kept.update({b.name: b}))
    free = kept["buckled"]
    onset = first_onset(free) or free.points_of_kind("contact_onset")[0]
    held, _pins = mirrored_contact(dataclasses.replace(options, max_points=400),
                                   result.rod_problem, result.contact_problem, free, onset,
                                   "buckled_contact", {})
    assert held.parameter_values[-1] == pytest.approx(options.turns[1])
    folds = [p for p in held.special_points if p.kind == "fold"]
    assert [round(p.parameter, 2) for p in folds] == [1.06, 2.5, 2.2]
    counts = np.asarray(held.unstable_count)
    assert set(np.flatnonzero(np.diff(counts))) <= {p.index for p in folds}
    assert np.all(counts[folds[1].index + 1:folds[2].index + 1] == 1)
    assert np.all(counts[folds[2].index + 1:] == 0)
    assert not [p for p in held.special_points if p.kind in ("bifurcation", "count_change")]
    assert len(dense) >= 3
    for count, lowest, analysed, analysed_lowest, negative, with_g, overlap, odd in dense:
        assert (count, negative, with_g) == (0, 1, 1)
        assert lowest > 0  # the eigenvalues reported: the sliding's pair left out
        # a state's own report (supercoil.stability(state)) counts as its branch does
        assert analysed == count and analysed_lowest == pytest.approx(lowest, rel=1e-6)
        assert overlap > 0.7 and odd > 0.95


def dense_check(problem, q: np.ndarray, multipliers: np.ndarray):
    """``(negative, with_g, overlap, odd)``: the dense counts of the constrained Hessian
    with the sliding kept and on the complement of its generator ``g``, the M-overlap of
    the lowest eigenvector with ``g`` and the M-norm of its odd part under the half-turn
    (of 1)."""
    rod = problem.base
    g = sliding_phase_modes(problem, q)[0]
    dofs, H, J, mass, exact = eigen_system(problem, q, multipliers)
    assert exact.shape[1] == 2  # the rotation about the axis and the sliding
    with_g = int(np.sum(dense_constrained_eigenpairs(H, J, mass, exact)[0] < 0))
    tail, rod.sliding_tail = rod.sliding_tail, None  # the sliding kept
    try:
        dofs, H, J, mass, exact = eigen_system(problem, q, multipliers)
    finally:
        rod.sliding_tail = tail
    values, vectors = dense_constrained_eigenpairs(H, J, mass, exact)
    mode = np.zeros(problem.n_dofs)
    mode[dofs] = vectors[:, 0]
    m = np.asarray(problem.mass, dtype=float)
    overlap = abs(mode @ (m * g)) / np.sqrt(g @ (m * g))
    axis = mirror_axis(q)
    image = (mode.reshape(-1, 3)[::-1] @ (2 * np.outer(axis, axis) - np.eye(3)).T).ravel()
    odd = 0.5 * (mode - image)  # the displacement's odd part (mode M-normalised)
    return int(np.sum(values < 0)), with_g, overlap, np.sqrt(odd @ (m * odd))


def mirror_axis(q: np.ndarray) -> np.ndarray:
    """The horizontal axis ``n`` of the half-turn that maps ``q`` closest onto itself
    (``supercoil.rod.mirror``: the leading eigenvector of the symmetrised 2 x 2 form
    ``sum a_i b_i^T``, ``a_i = x_i - c``, ``b_i = x_{n-1-i} - c``)."""
    x = q.reshape(-1, 3)
    a = x - np.array([0.0, 0.0, 0.5 * (x[0, 2] + x[-1, 2])])
    form = a[:, :2].T @ a[::-1, :2]
    vectors = np.linalg.eigh(0.5 * (form + form.T))[1]
    return np.array([vectors[0, -1], vectors[1, -1], 0.0])
