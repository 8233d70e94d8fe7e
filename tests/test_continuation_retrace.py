"""A corrected point on the branch's own earlier path, followed the other way, is a jump.

Oracle: geometry of a computed branch (Bratu's, through its fold): a point on one of
its earlier chords with the chord's tangent reversed is found on that chord; the same
point with the tangent along the chord, the next point of the branch past its fold, and
a step back along the last chord are not.
"""

import numpy as np
from test_continuation_toys import Bratu

from supercoil.continuation import ContinuationOptions, ContinuationStatus, continuation
from supercoil.continuation.closure import retraced
from supercoil.continuation.system import ExtendedSystem


def bratu_through_its_fold():
    """Points ``X`` (free DOFs and lambda) of Bratu's branch from lambda 3 round its fold
    back to 3, unit tangents ``T`` along it (central differences, the metric's), the
    system and the fold's index."""
    p = Bratu(16, 3.0)
    opts = ContinuationOptions(parameter_bounds=(3.0, 4.0), initial_step=0.05, max_step=0.2)
    b = continuation(p, np.zeros(17), parameter="lam", options=opts)
    assert b.status is ContinuationStatus.PARAMETER_BOUND, b.message
    system = ExtendedSystem(p, "lam", np.zeros(17))
    X = np.array([np.append(q[system.free], lam)
                  for q, lam in zip(b.states, b.parameter_values, strict=True)])
    d = np.gradient(X, axis=0)
    T = d / np.sqrt(np.einsum("ij,ij->i", d * system.weights, d))[:, None]
    (fold,) = b.points_of_kind("fold")
    return system, opts, X, T, fold.index


def test_a_point_on_an_earlier_chord_followed_back_is_retraced():
    system, opts, X, T, i = bratu_through_its_fold()
    assert i >= 4 and len(X) >= i + 6
    xs, ts = list(X[:i + 4]), list(T[:i + 4])  # the lower branch, the fold, 3 points past it
    for j in range(i - 3):
        back = 0.5 * (X[j] + X[j + 1])
        assert retraced(system, opts, xs, ts, back, -T[j]) == j
        assert retraced(system, opts, xs, ts, back, T[j]) is None  # along: not followed back


def test_the_branch_ahead_and_the_folds_turn_are_not_retraced():
    system, opts, X, T, i = bratu_through_its_fold()
    for k in range(i + 2, len(X) - 1):  # each next point past the fold, from the run before it
        assert retraced(system, opts, list(X[:k]), list(T[:k]), X[k], T[k]) is None
    # back along the last chord (every step back lies on it): not asked
    xs, ts = list(X[:i + 2]), list(T[:i + 2])
    assert retraced(system, opts, xs, ts, 0.5 * (X[i] + X[i + 1]), -T[i]) is None
