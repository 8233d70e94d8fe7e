"""Localisation of special points on a segment (supercoil.continuation.events): exact answers
and the number of evaluations against scipy's brentq (the previous root finder) on the
same functions."""

import numpy as np
import pytest
from scipy.optimize import brentq
from test_continuation_toys import Bratu, DiagonalQuartic

from supercoil.continuation import ContinuationOptions, continuation, events
from supercoil.continuation.events import (
    Segment,
    UserEvent,
    locate_count_change,
    locate_fold,
    locate_user_event,
)
from supercoil.continuation.system import ExtendedSystem
from supercoil.continuation.zeroin import RTOL, LocationFailed, brentq_reference, zeroin


class Counted:
    def __init__(self, f):
        self.f, self.points = f, []

    def __call__(self, u):
        self.points.append(float(u))
        return self.f(u)


SMOOTH = [  # (function, exact root in (0, 1))
    (lambda u: np.tan(u - 0.3), 0.3),
    (lambda u: np.exp(u) - 1.5, np.log(1.5)),
    (lambda u: (u - 0.77) ** 3 + 0.01 * (u - 0.77), 0.77),
    (lambda u: np.sin(2 * u) - 0.3, np.arcsin(0.3) / 2),
    (lambda u: 1.0 / (u + 0.1) - 2.5, 0.3),
]


def _bracket_closes(f, points, x, xtol):
    """brentq's guarantee: an evaluated point within xtol (+ round-off) of x with the
    other sign of f (or f(x) = 0)."""
    fx = f(x)
    return fx == 0 or any(abs(p - x) <= xtol * (1 + 1e-9) + 1e-15 and f(p) * fx < 0
                          for p in points)


@pytest.mark.parametrize("xtol", [1e-2, 1e-6, 1e-10])
def test_zeroin_without_a_guess_is_brentq(xtol):
    """Oracle: scipy's brentq (the same steps: the same points evaluated, the same
    result) and the exact roots; known end values are not evaluated again."""
    for f, root in SMOOTH:
        reference, counted = Counted(f), Counted(f)
        x_ref = brentq(reference, 0.0, 1.0, xtol=xtol, rtol=RTOL)
        x = zeroin(counted, 0.0, 1.0, xtol)
        assert x == x_ref and counted.points == reference.points
        assert abs(x - root) <= xtol and _bracket_closes(f, counted.points, x, xtol)
        known = Counted(f)
        assert zeroin(known, 0.0, 1.0, xtol, f(0.0), f(1.0)) == x_ref
        assert known.points == reference.points[2:]


def test_zeroin_from_a_guess_within_the_tolerance_needs_two_evaluations():
    xtol = 1e-8
    for f, root in SMOOTH:
        for offset in (-0.4, 0.3):
            counted = Counted(f)
            x = zeroin(counted, 0.0, 1.0, xtol, f(0.0), f(1.0), root + offset * xtol)
            assert len(counted.points) == 2
            assert abs(x - root) <= xtol and _bracket_closes(f, counted.points, x, xtol)
        # a poor guess still ends with the guarantee
        counted = Counted(f)
        x = zeroin(counted, 0.0, 1.0, xtol, f(0.0), f(1.0), 0.5 * (root + 1.0))
        assert abs(x - root) <= xtol and _bracket_closes(f, counted.points, x, xtol)
    # a step function: bisection, as brentq
    step = Counted(lambda u: 0.5 if u > 0.4321 else -0.5)
    reference = Counted(step.f)
    x = zeroin(step, 0.0, 1.0, 1e-6)
    brentq(reference, 0.0, 1.0, xtol=1e-6, rtol=RTOL)
    assert abs(x - 0.4321) <= 1e-6 and len(step.points) == len(reference.points)


def _fold_segment(n, max_step):
    p = Bratu(n, 3.0)
    b = continuation(p, np.zeros(n + 1), parameter="lam", options=ContinuationOptions(
        parameter_bounds=(3.0, 4.0), initial_step=0.05, max_step=max_step))
    t = b.tangents[:, -1]
    k = int(np.flatnonzero(t[:-1] * t[1:] < 0)[0])
    system = ExtendedSystem(p, "lam", b.states[k])
    x_a = system.pack(b.states[k], b.multipliers[k], b.parameter_values[k])
    x_b = system.pack(b.states[k + 1], b.multipliers[k + 1], b.parameter_values[k + 1])
    return system, x_a, x_b


def test_bratu_fold_is_located_as_by_brentq_with_fewer_corrections():
    """Oracle: brentq on the same segment's dlambda/ds (the previous algorithm) and the
    Moore-Spence fold of the discrete problem (tests/test_continuation.py). The Hermite
    guess and the end-game probe never cost more trial corrections here, and fewer in
    all (measured: 104 -> 83 over N = 16, 32, 64 and four step sizes)."""
    from test_continuation import moore_spence_fold

    total_reference = total = 0
    for n, max_step in ((16, 0.5), (32, 0.05), (32, 0.2)):
        system, x_a, x_b = _fold_segment(n, max_step)
        exact = moore_spence_fold(n)
        for tolerance in (1e-6, 1e-10):
            reference = Segment(system, x_a, x_b, 1e-10, 10, 1e-6)
            segment = Segment(system, x_a, x_b, 1e-10, 10, 1e-6)
            xtol = tolerance / segment.length
            u_ref = brentq_reference(lambda u, r=reference: r.tangent(u)[-1], 0.0, 1.0, xtol)
            located = locate_fold(segment, xtol)
            assert located.located
            # both within xtol of the zero of dlambda/ds
            assert abs(located.u - u_ref) * segment.length <= 2 * tolerance
            assert abs(located.x[-1] - exact) < 1e-11
            n_reference = len(reference.corrected) - 2
            n_new = len(segment.corrected) - 2
            assert n_new <= n_reference
            total_reference += n_reference
            total += n_new
    assert total < total_reference


def test_pitchfork_of_the_diagonal_problem_at_its_exact_parameter():
    """Oracle: lambda = d_0 exactly (the trivial branch x = 0, eigenvalue d_0 - lambda);
    the localisation with brentq in place of zeroin (the previous algorithm) uses at
    least as many eigenproblems."""
    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0])
    p = DiagonalQuartic(d)
    system = ExtendedSystem(p, "lam", np.zeros(6))
    calls = {}
    for name, finder in (("new", None), ("brentq", lambda f, lo, hi, xtol, *a:
                                         brentq_reference(f, lo, hi, xtol))):
        for lam_a, lam_b in ((0.8, 1.3), (0.55, 1.7)):
            x_a = system.pack(np.zeros(6), np.zeros(0), lam_a)
            x_b = system.pack(np.zeros(6), np.zeros(0), lam_b)
            segment = Segment(system, x_a, x_b, 1e-10, 10, 1e-8)
            original = events.zeroin
            if finder is not None:
                events.zeroin = finder
            try:
                located = locate_count_change(segment, 1e-10 / segment.length, 1e-3)
            finally:
                events.zeroin = original
            assert located.located and (located.count_before, located.count_after) == (0, 1)
            assert abs(located.x[-1] - 1.0) <= 1e-10 * (1 + 1e-6)
            calls[name, lam_a] = len(segment._nearest)
    for lam_a in (0.8, 0.55):
        assert calls["new", lam_a] <= calls["brentq", lam_a]


def test_user_event_labels_share_evaluations_and_locate_an_exact_threshold():
    """Oracle: the branch's parameter crosses lambda* = the mean of the ends' at a point
    found by brentq to 1e-14 on a reference segment; the event's two labels (the
    threshold and its negative) are located within the tolerance of it, the user
    function evaluated once per trial point for both, never at the ends (known)."""
    p = Bratu(16, 3.0)
    b = continuation(p, np.zeros(17), parameter="lam", options=ContinuationOptions(
        parameter_bounds=(3.0, 4.0), initial_step=0.05, max_step=0.5))
    system = ExtendedSystem(p, "lam", b.states[1])
    # a segment before the fold: lambda increases along it
    x_a = system.pack(b.states[1], b.multipliers[1], b.parameter_values[1])
    x_b = system.pack(b.states[2], b.multipliers[2], b.parameter_values[2])
    lam_a, lam_b = x_a[-1], x_b[-1]
    assert lam_b > lam_a
    star = 0.5 * (lam_a + lam_b)
    calls = []

    def function(q, mu, lam):
        calls.append(lam)
        return {"up": lam - star, "down": star - lam}

    event = UserEvent("threshold", function)
    tolerance = 1e-10
    reference = Segment(system, x_a, x_b, 1e-12, 10, 1e-6)
    exact = brentq(lambda u: reference.point(u)[-1] - star, 0.0, 1.0, xtol=1e-14)
    segment = Segment(system, x_a, x_b, 1e-12, 10, 1e-6)
    xtol = tolerance / segment.length
    ends = ({"up": lam_a - star, "down": star - lam_a}, {"up": lam_b - star, "down": star - lam_b})
    up = locate_user_event(segment, event, "up", xtol, ends)
    n_up = len(calls)
    down = locate_user_event(segment, event, "down", xtol, ends)
    assert up.located and down.located
    for located in (up, down):
        assert abs(located.u - exact) * segment.length <= tolerance * (1 + 1e-6)
        assert abs(located.x[-1] - star) < 1e-9
    assert lam_a not in calls and lam_b not in calls
    assert len(calls) == n_up == len(segment.corrected) - 2  # "down": no new evaluation
    # brentq on the same function (the previous algorithm, one label) evaluated more
    counted = Counted(lambda u: reference.point(u)[-1] - star)
    brentq(counted, 0.0, 1.0, xtol=xtol, rtol=RTOL)
    assert n_up <= len(counted.points) - 2


def test_warm_start_is_the_quadratic_through_the_nearest_corrected_points():
    """Oracle: on points x(u) = a + b u + c u^2 (a parabola in u) the start at any u is
    x(u) itself (Lagrange interpolation is exact for quadratics), and it lies on the
    hyperplane of u; with only the segment's ends it is the chord."""
    p = Bratu(8, 3.0)
    system = ExtendedSystem(p, "lam", np.zeros(9))
    rng = np.random.default_rng(0)
    a, b, c = (rng.standard_normal(system.size) for _ in range(3))
    segment = Segment(system, a, a + b + c, 1e-10, 10, 1e-6)

    def parabola(u):
        return a + b * u + c * u**2

    assert np.allclose(segment.start(0.3), a + 0.3 * (b + c), rtol=0, atol=1e-14)
    for u in (0.1, 0.37, 0.52, 0.9):
        segment._points[u] = parabola(u)
    # points on the segment's hyperplanes (row . (x_v - a) = v): so is the start
    on_planes = Segment(system, a, a + b, 1e-10, 10, 1e-6)
    across = c - (on_planes.row @ c) * b  # row . b = 1: across . row = 0
    for v in (0.1, 0.37, 0.52, 0.9):
        on_planes._points[v] = a + v * b + np.sin(3 * v) * across
    for u in (0.05, 0.2, 0.4, 0.45, 0.7, 0.95):
        assert np.allclose(segment.start(u), parabola(u), rtol=0, atol=1e-12)
        assert abs(on_planes.row @ (on_planes.start(u) - a) - u) < 1e-12


def test_zeroin_bisects_where_interpolation_divides_by_zero():
    """Found by review: values of order 1e-110 underflow the interpolation's differences
    to zero; brentq (C arithmetic) bisects there, and so must zeroin (it raised
    ZeroDivisionError). Oracle: brentq's zero."""
    for scale in (1e-110, 1e-150, 1e-200):
        def f(x, s=scale):
            return s * ((x - 0.3) ** 3 + 0.1 * (x - 0.3))

        x_ref = brentq(f, 0.0, 1.0, xtol=1e-12, rtol=RTOL)
        assert abs(zeroin(f, 0.0, 1.0, 1e-12) - x_ref) <= 2e-12


def test_zeroin_that_does_not_converge_says_so():
    """After maxiter steps without a bracket within xtol: LocationFailed (the callers'
    'not located'), not an unconverged point reported as located."""
    with pytest.raises(LocationFailed, match="no zero located"):
        zeroin(lambda x: np.exp(x) - 1.5, 0.0, 1.0, 1e-14, maxiter=2)


def test_start_with_the_ends_tangents_is_the_cubic_through_them():
    """Oracle: on a cubic x(u) = a + b u + c u^2 + e u^3, given the ends' tangents (as the
    continuation keeps them, scaled by the segment's length) the start at any u is x(u)
    itself (Hermite interpolation is exact for cubics), where the chord misses it by the
    curvature; once a point inside is corrected, the quadratic through the nearest ones."""
    p = Bratu(8, 3.0)
    system = ExtendedSystem(p, "lam", np.zeros(9))
    rng = np.random.default_rng(1)
    a, c, e = (rng.standard_normal(system.size) for _ in range(3))
    b = 4.0 * (c + e) + rng.standard_normal(system.size)  # along the chord at both ends

    def cubic(u):
        return a + b * u + c * u**2 + e * u**3

    chord = Segment(system, a, cubic(1.0), 1e-10, 10, 1e-6)
    length = chord.length
    slopes = (b / length, (b + 2 * c + 3 * e) / length)
    assert all((system.weights * t) @ chord.d > 0 for t in slopes)
    segment = Segment(system, a, cubic(1.0), 1e-10, 10, 1e-6, tangents=slopes)
    for u in (0.1, 0.37, 0.52, 0.9):
        assert np.allclose(segment.start(u), cubic(u), rtol=0, atol=1e-12)
        assert np.max(np.abs(chord.start(u) - cubic(u))) > 1e-3
    # tangents given against the segment's direction are turned along it
    flipped = Segment(system, a, cubic(1.0), 1e-10, 10, 1e-6,
                      tangents=(-slopes[0], -slopes[1]))
    assert np.allclose(flipped.start(0.37), cubic(0.37), rtol=0, atol=1e-12)
    segment._points[0.5] = cubic(0.5)
    quadratic = Segment(system, a, cubic(1.0), 1e-10, 10, 1e-6)
    quadratic._points[0.5] = cubic(0.5)
    assert np.allclose(segment.start(0.3), quadratic.start(0.3), rtol=0, atol=1e-14)


def test_takes_problem_reads_each_function_once_and_keeps_none_alive():
    """takes_problem answers as inspect.signature does (the oracle) for functions, bound
    methods, callable objects, partials and builtins, also when asked again (the answer
    remembered per function); the memo holds its functions weakly."""
    import functools
    import gc
    import inspect
    import weakref

    class Records:
        def with_problem(self, q, multipliers, parameter, problem=None):
            return {}

        def without(self, q, multipliers, parameter):
            return {}

        def __call__(self, q, multipliers, parameter, *, problem):
            return {}

    def plain(q, multipliers, parameter):
        return {}

    records = Records()
    callables = [records.with_problem, records.without, records, plain, Records().without,
                 lambda q, m, p, problem: {}, functools.partial(plain, 1.0), print]
    for function in callables * 2:
        try:
            expected = "problem" in inspect.signature(function).parameters
        except (TypeError, ValueError):
            expected = False
        assert events.takes_problem(function) is expected
    held = weakref.ref(records)
    del records, callables
    gc.collect()
    assert held() is None


def _sliding_left_out_below(threshold, monkeypatch):
    """Make the count leave one negative eigenvalue out below ``lambda = threshold`` (as
    the stiff sliding's, whose share of ``g`` passes one half there), the factor's
    count untouched: the count then changes at the threshold with no eigenvalue
    crossing zero."""
    original = events.inertia_with_factor

    def patched(system, x, zero_tolerance, hessian, factor=None):
        negative, sign, f, dofs, _ = original(system, x, zero_tolerance, hessian, factor)
        left_out = int(negative >= 1 and x[-1] < threshold)
        return negative - left_out, sign, f, dofs, left_out

    monkeypatch.setattr(events, "inertia_with_factor", patched)


def _sliding_segment(lam_b, monkeypatch) -> Segment:
    """The diagonal problem's trivial branch from lambda = 1.3 to ``lam_b``, its count
    leaving one negative eigenvalue out below 1.6."""
    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0])
    system = ExtendedSystem(DiagonalQuartic(d), "lam", np.zeros(6))
    _sliding_left_out_below(1.6, monkeypatch)
    x_a = system.pack(np.zeros(6), np.zeros(0), 1.3)
    x_b = system.pack(np.zeros(6), np.zeros(0), lam_b)
    return Segment(system, x_a, x_b, 1e-10, 10, 1e-8)


def test_a_count_change_with_no_eigenvalue_crossing_is_no_bifurcation(monkeypatch):
    """Oracle: the diagonal problem's trivial branch has the eigenvalues d_i - lambda;
    on lambda in [1.3, 1.9] exactly one is negative (d_0 = 1) and none crosses zero.
    The count, with one negative eigenvalue left out below 1.6, changes there: a
    ``count_change`` labelled ``sliding``, within switch_below of 1.6 on its far side."""
    segment = _sliding_segment(1.9, monkeypatch)
    switch_below = 1e-3
    located = locate_count_change(segment, 1e-10 / segment.length, switch_below)
    assert (located.kind, located.label) == ("count_change", "sliding")
    assert located.located and (located.count_before, located.count_after) == (0, 1)
    assert 1.6 <= located.x[-1] <= 1.6 + 0.6 * switch_below
    assert segment.factor_count(0.0) == segment.factor_count(1.0) == 1


def test_a_crossing_after_a_sliding_count_change_is_still_a_located_bifurcation(monkeypatch):
    """On lambda in [1.3, 2.3] the count goes 0 -> 1 at 1.6 (the left-out eigenvalue
    counted again, no crossing) and 1 -> 2 at lambda = d_1 = 2 (an eigenvalue crossing):
    a sliding ``count_change``, then, searched from its resume point, a ``bifurcation``
    at exactly 2."""
    segment = _sliding_segment(2.3, monkeypatch)
    xtol = 1e-10 / segment.length
    first = locate_count_change(segment, xtol, 1e-3)
    assert first.kind == "count_change" and (first.count_before, first.count_after) == (0, 1)
    second = locate_count_change(segment, xtol, 1e-3, first.resume)
    assert second.kind == "bifurcation" and (second.count_before, second.count_after) == (1, 2)
    assert abs(second.x[-1] - 2.0) <= 1e-10 * (1 + 1e-6)


def _trivial_segment_events(lam_a, lam_b, count_a, count_b):
    """``locate_events`` on the diagonal problem's trivial branch from ``lam_a`` to
    ``lam_b`` (tangent ``d lambda`` = 1 at both ends), given the ends' counts."""
    from supercoil.continuation.special_points import locate_events

    d = np.array([1.0, 2.0, 3.5, 5.0, 6.0, 7.0])
    system = ExtendedSystem(DiagonalQuartic(d), "lam", np.zeros(6))
    x_a = system.pack(np.zeros(6), np.zeros(0), lam_a)
    x_b = system.pack(np.zeros(6), np.zeros(0), lam_b)
    t = np.zeros(x_a.size)
    t[-1] = 1.0
    opts = ContinuationOptions(event_tolerance=1e-10, switch_below=1e-3)
    _segment, found = locate_events(system, opts, (), x_a, x_b, t, t, count_a, count_b,
                                    (), ())
    return found


def test_a_crossing_of_the_continued_system_stays_a_bifurcation():
    """Oracle: on the trivial branch the eigenvalue d_0 - lambda crosses zero at 1: a
    branch point (the pitchfork), the extended Jacobian's determinant changing sign."""
    found = _trivial_segment_events(0.8, 1.3, 0, 1)
    assert [(e.kind, e.label) for e in found] == [("bifurcation", "bifurcation")]
    assert abs(found[0].x[-1] - 1.0) <= 1e-9


def test_a_count_change_with_no_branch_point_of_the_continued_system(monkeypatch):
    """The count made to gain one at lambda = 1.6 (as a count on another subspace than
    the continued system's can), with no eigenvalue of the continued system crossing on
    [1.3, 1.9] (d_0 = 1 < 1.3 < 1.9 < d_1 = 2): the extended Jacobian's determinant keeps
    its sign, so the change is a ``count_change`` labelled ``determinant``."""
    original = events.inertia_with_factor

    def patched(system, x, zero_tolerance, hessian, factor=None):
        negative, sign, f, dofs, left_out = original(system, x, zero_tolerance, hessian,
                                                     factor)
        return negative + int(x[-1] >= 1.6), sign, f, dofs, left_out

    monkeypatch.setattr(events, "inertia_with_factor", patched)
    found = _trivial_segment_events(1.3, 1.9, 1, 2)
    assert [(e.kind, e.label) for e in found] == [("count_change", "determinant")]
    assert (found[0].count_before, found[0].count_after) == (1, 2)
    assert abs(found[0].x[-1] - 1.6) <= 1e-3
