"""The unstable count along a branch survives refinement: the same counts at N and 1.5 N
away from the branch's genuine events, along a tweezers branch with self-contact and a
ring's branch with self-contact.

Oracle: the continuum's count is a property of the branch, not of the mesh; between two
events that change it (folds, verified bifurcations) it is constant, so the two meshes'
counts at the same parameter on the same stretch between folds must agree, the events
themselves at the same parameter to the discretisation's error. Each reported
bifurcation is verified (:mod:`supercoil.problems.tweezers.verify`; its tests in
``test_tweezers_long.py``); these branches have none, and no unverified change either.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.continuation import Branch
from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

COUNT_EVENTS = ("fold", "bifurcation", "count_change")


def stretches(branch: Branch) -> list[np.ndarray]:
    """The indices of ``branch``'s points on each stretch between its folds (a fold at
    ``index`` lies between the points ``index`` and ``index + 1``)."""
    cuts = sorted({p.index + 1 for p in branch.special_points if p.kind == "fold"})
    return np.split(np.arange(len(branch)), cuts)


def compare_counts(coarse: Branch, fine: Branch, window: float) -> np.ndarray:
    """Each point of ``fine`` against the point of ``coarse`` nearest in the parameter on
    the same stretch between folds, within that stretch's range, with no count event of
    either branch between them or within ``window`` of either; returns the
    parameter values compared, after asserting that the counts agree there."""
    folds = [[p.parameter for p in b.special_points if p.kind == "fold"]
             for b in (coarse, fine)]
    assert len(folds[0]) == len(folds[1])
    np.testing.assert_allclose(folds[1], folds[0], rtol=0.01)
    events = np.array([p.parameter for b in (coarse, fine) for p in b.special_points
                       if p.kind in COUNT_EVENTS])
    compared = []
    for pc, pf in zip(stretches(coarse), stretches(fine), strict=True):
        lc = coarse.parameter_values[pc]
        for i in pf:
            lam = fine.parameter_values[i]
            j = pc[np.argmin(np.abs(lc - lam))]
            near = coarse.parameter_values[j]
            low, high = min(lam, near) - window, max(lam, near) + window
            if not lc.min() <= lam <= lc.max() or np.any((events > low) & (events < high)):
                continue
            assert fine.unstable_count[i] == coarse.unstable_count[j], (
                fine.name, lam, fine.unstable_count[i], near, coarse.unstable_count[j])
            compared.append(lam)
    return np.array(compared)


@pytest.fixture(scope="module")
def plectonemes():
    """C/A = 1.5, L/D = 40, F L^2/A = 320 (lambda = 18; the hard-core ply test's) from 0 to
    6.5 turns at N = 82 and 123, default options."""
    return {n: tweezers_branches(TweezersOptions(
        twist_ratio=1.5, length_over_diameter=40, tension=320.0, n_nodes=n,
        turns=(0.0, 6.5))) for n in (82, 123)}


def test_tweezers_counts_agree_at_n_and_one_and_a_half_n(plectonemes):
    """Along the contact branch (the localised loop's contact, three folds, the
    plectoneme's growth) the counts agree point by point. With the plectoneme's sliding
    counted (its eigenvalue the contact's ripple, -1900 to +900) or removed by pinning
    one coordinate instead of the M-orthogonal projection of the eigenvalues, N = 82
    counted 0 from 3.8 to 6.5 turns while N = 123 counted 1 on 3.97-4.45 and 4.8-5.4
    turns, with three "bifurcations" there; at N = 82 alone the count changed 25 times
    between 1.6 and 3.8 turns."""
    coarse, fine = (plectonemes[n] for n in (82, 123))
    assert coarse.ok and fine.ok
    a, b = coarse.branches[-1], fine.branches[-1]
    assert a.name == b.name == "buckled_contact"
    compared = compare_counts(a, b, window=0.01)
    assert compared.size >= 0.8 * len(b)
    assert np.any((compared > 3.9) & (compared < 5.5))  # where the counts differed
    for branch in (a, b):
        changes = np.flatnonzero(np.diff(branch.unstable_count))
        folds = {p.index for p in branch.special_points if p.kind == "fold"}
        assert set(changes) <= folds  # the count changes only at the folds
        assert not [p for p in branch.special_points if p.kind in ("bifurcation",
                                                                    "count_change")]
    # the contact-free branch: the localised loop's one unstable mode at both meshes
    for result in (coarse, fine):
        assert np.all(result.branch("buckled").unstable_count == 1)


def test_ring_counts_agree_at_n_and_one_and_a_half_n():
    """The ring's alpha branch and its contact branch (C/A = 2/3, L/D = 40, dLk up to 4:
    the contact onset, three folds, contact intervals and their splits) at N = 48 and
    72: the same counts at the same excess link between the folds."""
    diagrams = {n: ring_diagram(DiagramOptions(
        2 / 3, 40.0, n_nodes=n, modes=(2,), max_excess_link=4.0, free_max_points=60,
        contact_max_points=150)) for n in (48, 72)}
    for name in ("alpha", "alpha_contact"):
        coarse, fine = (diagrams[n].branch(name) for n in (48, 72))
        compared = compare_counts(coarse, fine, window=0.01)
        assert compared.size >= 0.7 * len(fine), (name, compared.size, len(fine))
        for branch in (coarse, fine):
            assert not [p for p in branch.special_points if p.kind == "count_change"]
    assert diagrams[72].branch("alpha_contact").parameter_values[-1] == pytest.approx(4.0)


@pytest.mark.parametrize(("m", "n", "r"), [(5, 12, 1), (30, 80, 2), (0, 7, 1)])
def test_dense_rows_stacked_from_arrays_equal_scipys_vstack(m, n, r):
    """Oracle: ``scipy.sparse.vstack`` of ``J`` and the rows' CSR matrix, entry for entry
    and array for array (the rows' zeros left out, as scipy leaves them)."""
    import scipy.sparse as sp

    from supercoil.continuation.stability import with_dense_rows

    J = sp.random(m, n, density=0.2, random_state=1, format="csr")
    rows = np.random.default_rng(m).standard_normal((r, n))
    rows[:, ::3] = 0.0
    stacked = with_dense_rows(J, rows)
    expected = sp.vstack([J, sp.csr_matrix(rows)], format="csr")
    assert stacked.shape == expected.shape
    for name in ("indptr", "indices", "data"):
        np.testing.assert_array_equal(getattr(stacked, name), getattr(expected, name))
