"""A knotted branch started at a singular point: the fold of the trefoil's ring.

The trefoil at C/A = 1.4, L/D = 40, N = 36, relaxed at dLk = 4.3 and followed up, turns
back at a fold near dLk 4.574 (the unstable count 0 -> 3: D3 symmetry, the contacts
released). Started at the located fold (a singular point: the plain start's tangent
does not move dLk, and ``knot_up`` would leave its range at once), each half of the
diagram starts there on the hyperplane orthogonal to the critical mode and follows
one side of the fold. Oracles: the parent branch on either side of the fold (writhe
against dLk), Lk = Tw + Wr and the knot type at every point.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.problems.knot_branch import follow_knot, relaxed_knot


@pytest.fixture(scope="module")
def parent():
    cp, q0, _knot, _message = relaxed_knot("3_1", 1.4, 40.0, 4.3, 36)
    branch = follow_knot(cp, q0, 4.3, 6.0, 30, 1e-8, "parent")
    (fold, *_rest) = [p for p in branch.special_points if p.kind == "fold"]
    assert fold.located and fold.count_after == 3
    assert np.all(branch.unstable_count[:fold.index] == 0)
    return cp, branch, fold


def _writhe_on(branch, lo, hi, at):
    """The writhe of ``branch`` interpolated at dLk ``at`` on its points ``lo .. hi - 1``
    (dLk monotone there), by a cubic spline."""
    from scipy.interpolate import CubicSpline

    lam = np.asarray(branch.parameter_values[lo:hi], float)
    wr = np.asarray(branch.records["writhe"][lo:hi], float)
    order = np.argsort(lam)
    keep = np.concatenate([[True], np.diff(lam[order]) > 1e-9])  # repeated points once
    return CubicSpline(lam[order][keep], wr[order][keep])(at)


def test_the_located_fold_is_singular(parent):
    """At the located fold the constrained Hessian's eigenvalue nearest zero vanishes (to
    the location's accuracy) while it is of order 1000 at the relaxed start."""
    from supercoil.continuation import ContinuationOptions
    from supercoil.continuation.singular_start import critical_mode

    cp, branch, fold = parent
    opts = ContinuationOptions(parameter_bounds=(3.0, 6.0), parameter_weight=cp.diameter)
    at_fold, _mode = critical_mode(cp, np.asarray(fold.q), "excess_link",
                                   float(fold.parameter), opts)
    at_start, _mode = critical_mode(cp, branch.states[0], "excess_link",
                                    float(branch.parameter_values[0]), opts)
    assert abs(at_fold) < 1e-3 and abs(at_start) > 100.0  # measured 1.3e-5 and 2.3e3


@pytest.mark.parametrize("stop", [6.0, 3.0])
def test_a_start_at_a_fold_follows_one_side_of_it_and_says_so(parent, stop):
    cp, branch, fold = parent
    notes = []
    half = follow_knot(cp, np.asarray(fold.q).copy(), float(fold.parameter), stop, 8, 1e-8,
                       "half", notes=notes, singular_bounds=(3.0, 6.0))
    assert len(half) == 8, half.message
    (note,) = notes
    assert "singular point" in note and "fold" in note
    D = cp.diameter
    assert np.max(np.abs(half.states[0] - fold.q)) < 1e-10 * D
    lam = np.asarray(half.parameter_values)
    assert np.all(lam <= fold.parameter + 1e-9)  # both sides lie below the fold
    # up: side + of the critical mode, the stable side; down: side -, the unstable one
    k = fold.index + 1  # the parent's first point past the fold
    if stop > fold.parameter:
        assert np.all(half.unstable_count[1:] == 0)
        lo, hi = 0, fold.index
    else:
        assert np.all(half.unstable_count[1:] == 3)
        lo, hi = k, len(branch)
    inside = (lam >= min(branch.parameter_values[lo:hi])) & (lam <= max(
        branch.parameter_values[lo:hi]))
    assert inside.sum() >= 4
    wr = np.asarray(half.records["writhe"])
    # the parent's writhe interpolated (measured within 1.2e-5; the other side of the
    # fold differs by up to 0.4 at these dLk)
    np.testing.assert_allclose(wr[inside], _writhe_on(branch, lo, hi, lam[inside]),
                               atol=1e-4)
    # Lk = Tw + Wr and the knot type at every point
    assert np.max(np.abs(half.records["link_error"])) < 1e-10
    assert np.all(half.records["knot_determinant"] == 3)
