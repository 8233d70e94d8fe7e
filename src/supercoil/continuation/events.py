"""Detection and localisation of special points between two branch points.

Between accepted points ``x_a`` and ``x_b`` the branch is parametrised by
``u`` in ``[0, 1]``: the point at ``u`` solves ``F(x) = 0`` with
``W d . (x - x_a) = u |d|_W^2``, ``d = x_b - x_a`` (re-corrected from
``x_a + u d`` at every trial, never accepted by the problem). Then

* a **fold** is a sign change of ``dlambda/ds`` (the tangent's last
  component, oriented along ``d``), located by Brent's method (secant steps
  safeguarded by bisection) on ``u`` to ``event_tolerance`` in arclength,
  started from the extremum of the cubic Hermite interpolant of ``lambda``
  through the ends (:func:`_fold_guess`);
* a **bifurcation** is a change of the unstable count that a fold does not
  explain (a fold changes it by exactly one). Bisection on the exact inertia
  count (Chamekh, Mani-Aouadi & Moakher 2014; pairs of eigenvalues crossing
  together are seen, unlike with the determinant's sign) down to ``switch_below``, then Brent's method
  on the signed eigenvalue nearest zero to ``event_tolerance``; each change
  on a segment in turn, a split double eigenvalue as one event
  (:func:`locate_count_change`). A change that no eigenvalue crossing zero makes
  (the stiff sliding's eigenvalue counted on one side of it and left out on the
  other) is a ``count_change`` labelled ``sliding``;
* a **user event** is a sign change of one of the named scalars returned by a
  :class:`UserEvent`'s function, located by Brent's method (bisection
  safeguarded: discontinuous indicators are bracketed as well).
"""

from __future__ import annotations

import inspect
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.stability import eigenpairs, inertia_with_factor
from supercoil.continuation.system import ExtendedSystem
from supercoil.continuation.zeroin import LocationFailed, zeroin
from supercoil.solvers.errors import InertiaError, SingularMatrixError


@dataclass(frozen=True)
class UserEvent:
    """An event defined by the caller.

    ``function(q, multipliers, parameter)`` returns named scalars (a mapping
    ``name -> float``); a sign change of any of them between two branch
    points is an event of kind ``kind`` (e.g. ``"contact_onset"``), labelled
    by the name. The problem passed to the continuation is never changed: a
    function that needs it takes the keyword ``problem`` and is called with the
    problem at the point (its parameter value and its carried frames).
    """

    kind: str
    function: Callable[[np.ndarray, np.ndarray, float], Mapping[str, float]]


class Segment:
    """The branch between two accepted points, re-corrected on demand (see module doc)."""

    def __init__(self, system: ExtendedSystem, x_a: np.ndarray, x_b: np.ndarray,
                 tolerance: float, max_iterations: int, zero_tolerance: float,
                 tangents: tuple[np.ndarray, np.ndarray] | None = None):
        self.system = system
        self.x_a, self.x_b = x_a, x_b
        self.d = x_b - x_a
        self.length = system.norm(self.d)
        # the ends' tangents (unit in the arclength metric), for the cubic start of
        # start(); oriented along the segment
        self.tangents = None
        if tangents is not None:
            self.tangents = tuple(t if (system.weights * t) @ self.d >= 0 else -t
                                  for t in (np.asarray(t, float) for t in tangents))
        self.row = system.weights * self.d / self.length**2
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self.zero_tolerance = zero_tolerance
        self._points: dict[float, np.ndarray] = {0.0: x_a, 1.0: x_b}
        # Hessians at the re-corrected trial points (never accepted, so they stay
        # valid): their tangents and counts need no new one
        self._hessians: dict[float, object] = {}
        # counts, nearest eigenvalues and tangents already computed, by fraction: the
        # points are never accepted, so a second evaluation would repeat the first
        # (Brent's method re-evaluates the bracket's ends the bisection left, and a
        # further count change is searched from the bisection's last bracket)
        self._counts: dict[float, int] = {}
        # of each count, the eigenvalues the count left out as the stiff sliding's
        # (stability.stiff_sliding: 0 or 1, more only as the contact's ripple)
        self._left_out: dict[float, int] = {}
        self._nearest: dict[float, float] = {}
        self._tangents: dict[float, np.ndarray] = {}
        # user events' values at trial points, by id(event) and fraction (all of an
        # event's labels come from one evaluation)
        self.user_values: dict[int, dict[float, dict[str, float]]] = {}

    @property
    def corrected(self) -> list[float]:
        """Fractions ``u`` of the points corrected so far (the ends included)."""
        return list(self._points)

    def start(self, u: float) -> np.ndarray:
        """Warm corrector start at ``u``: the quadratic (Lagrange, in ``u``) through the
        corrected points nearest to ``u`` on either side and the next nearest one, or
        the chord between the two while there are only the segment's ends. It lies on
        the hyperplane of ``u``: the Lagrange weights ``w_i`` sum to one and
        ``sum w_i u_i = u``, and the hyperplane's condition is linear. With the ends'
        tangents (``tangents``) and only the ends corrected, the cubic Hermite curve
        through them instead, within ``O(width^4)`` of the branch: on a stiff rod in
        rotation coordinates (a Cosserat rod) the chord leaves the nearly unshearable,
        inextensible states by a force of order ``GA |w ds|^2 / 8`` at its middle, as a
        straight predictor does (:mod:`supercoil.problems.cosserat_ring`), and the
        damped corrector's merit, ``max |F|``, dominated by those forces, rose once on
        the way down and was taken for divergence (measured: alpha at N = 200, EA = GA
        = 1e5, a trial start with residual 67 reached 4.5e-4, then 4.7e-4 after the
        halvings, where Newton undamped converged with its ``max |F|`` rising twice);
        the contact onset was then reported at the step's end.

        As a bracket shrinks, the chord is within ``O(width^2)`` of the branch, so
        the corrector needs one or two iterations instead of the four or five from
        the segment's own chord (measured on the tweezers' contact branch, where
        Brent's method on a contact count's indicator bisects 10-14 times); the
        quadratic, within ``O(width^3)`` where the branch is smooth, saves a third
        of what remains (measured, user events of the tweezers benchmark at N = 100
        and of the ring diagram at N = 200: 97 -> 65 and 103 -> 81 corrector
        iterations; ``python benchmarks/bench_events.py tweezers``, ``... ring``). Used
        for user events
        (:func:`locate_user_event`); folds and bifurcations keep the segment's
        chord: a bifurcation point moved within the tolerance turns the critical
        mode of a double eigenvalue (the circle's), and the switched branch with it
        (measured: the ring's beta branch then lost a bifurcation point at a contact
        release 1e-4 away), and a fold's point corrected from a warm start stops at
        the corrector's tolerance where the cold one lands at round-off (measured
        on Bratu, N = 16: the fold's parameter moved by 9e-11).
        """
        known = np.array(sorted(self._points))
        if self.tangents is not None and known.size == 2:
            return self._hermite(u)
        above = min(max(int(np.searchsorted(known, u)), 1), known.size - 1)
        nodes = [known[above - 1], known[above]]
        others = np.delete(known, [above - 1, above])
        if others.size:
            nodes.append(others[np.argmin(np.abs(others - u))])
        x = np.zeros_like(self.x_a)
        for i, u_i in enumerate(nodes):
            weight = np.prod([(u - u_j) / (u_i - u_j) for j, u_j in enumerate(nodes) if j != i])
            x += weight * self._points[u_i]
        return x

    def _hermite(self, u: float) -> np.ndarray:
        """The cubic Hermite curve at ``u`` through the ends with their tangents, scaled
        by the segment's length (the arclength between them, to second order)."""
        t_a, t_b = self.tangents
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        return h00 * self.x_a + h01 * self.x_b + self.length * (h10 * t_a + h11 * t_b)

    def point(self, u: float, warm: bool = False) -> np.ndarray:
        """The branch's point at ``u``, corrected from the segment's chord or, with
        ``warm``, from :meth:`start`; where that is the cubic through the ends and its
        correction fails, from the chord again. Neither start is the better one for
        every stiff rod: the damped corrector's merit, ``max |F|``, is ruled by its
        stiff forces (measured, alpha of the Cosserat ring: at N = 200, EA = GA = 1e5,
        the chord's start failed and the cubic's converged; at N = 40, EA = 1e5, GA =
        1e6, the cubic's start, residual 4.3, was still at 1e-4 after 10 iterations,
        and the chord's, residual 236, converged in 9)."""
        u = float(u)
        if u not in self._points:
            chord = self.x_a + u * self.d
            starts = [self.start(u) if warm else chord]
            if warm and self.tangents is not None and len(self._points) == 2:
                starts.append(chord)
            for start in starts:
                corr = correct(self.system, start, self.row, self.x_a, u,
                               self.tolerance, self.max_iterations)
                if corr.ok:
                    break
            if not corr.ok:
                raise LocationFailed(f"trial correction at u = {u:.6g} failed: {corr.message}")
            self._points[u] = corr.x
            self._hessians[u] = corr.hessian
        return self._points[u]

    def tangent(self, u: float) -> np.ndarray:
        u = float(u)
        if u not in self._tangents:
            try:
                x = self.point(u)
                self._tangents[u] = tangent(self.system, x, self.row, self._hessians.get(u))
            except SingularMatrixError as exc:
                raise LocationFailed(str(exc)) from None
        return self._tangents[u].copy()

    def count(self, u: float) -> int:
        u = float(u)
        if u not in self._counts:
            try:
                x = self.point(u)
                negative, _sign, _factor, _dofs, left_out = inertia_with_factor(
                    self.system, x, self.zero_tolerance, self._hessians.get(u))
            except (SingularMatrixError, InertiaError) as exc:
                raise LocationFailed(str(exc)) from None
            self._counts[u], self._left_out[u] = negative, left_out
        return self._counts[u]

    def factor_count(self, u: float) -> int:
        """``count(u)`` with the stiff sliding's eigenvalue it left out added back
        (:func:`~supercoil.continuation.stability.stiff_sliding`): the negative
        eigenvalues of the count's pencil at ``u``."""
        count = self.count(u)
        return count + self._left_out[float(u)]

    def system_eigenpairs(self, u: float, n_wanted: int) -> tuple[np.ndarray, np.ndarray]:
        """Eigenpairs of the constrained Hessian nearest zero at ``u`` (``eigenpairs``)."""
        return eigenpairs(self.system, self.point(u), n_wanted)

    def nearest_eigenvalue(self, u: float) -> float:
        u = float(u)
        if u not in self._nearest:
            values, _ = self.system_eigenpairs(u, 4)
            self._nearest[u] = (float(values[np.argmin(np.abs(values))]) if values.size
                                else float("nan"))
        return self._nearest[u]


@dataclass(frozen=True)
class Located:
    """A located event before it becomes a SpecialPoint: fraction ``u`` of the segment."""

    kind: str
    label: str
    u: float
    x: np.ndarray
    tangent: np.ndarray | None  # None when localisation failed
    located: bool
    count_before: int = -1
    count_after: int = -1
    accuracy: float | None = None  # arclength; None: the run's event_tolerance
    resume: float | None = None  # where to search for a further count change


def _fold_guess(segment: Segment, t_a: np.ndarray, t_b: np.ndarray) -> float | None:
    """Zero in ``(0, 1)`` of ``dlambda/du`` of the cubic Hermite interpolant of
    ``lambda(u)`` through the segment's ends (None if there is none).

    With ``x(s)`` on the branch, ``du/ds = row . t`` (the hyperplane's row), so the
    ends' slopes are ``m = t_lambda / (row . t)``. The interpolant's derivative is
    ``p(u) = 6 u (u - 1) (lambda_a - lambda_b) + m_a (3u^2 - 4u + 1) + m_b (3u^2 - 2u)``,
    a quadratic with ``p(0) = m_a`` and ``p(1) = m_b`` of opposite signs: one zero in
    ``(0, 1)``. It is exact for a parabola ``lambda(u)`` (a fold's leading term), so
    its error is of the order of the branch's cubic term, where the secant of
    ``t_lambda`` (Brent's first step) errs by the quadratic one.
    """
    r_a, r_b = float(segment.row @ t_a), float(segment.row @ t_b)
    if not (r_a > 0 and r_b > 0):
        return None
    m_a, m_b = t_a[-1] / r_a, t_b[-1] / r_b
    jump = segment.x_a[-1] - segment.x_b[-1]
    coefficients = (6 * jump + 3 * (m_a + m_b), -6 * jump - 4 * m_a - 2 * m_b, m_a)
    roots = np.roots(coefficients) if coefficients[0] != 0 else np.roots(coefficients[1:])
    inside = [float(r.real) for r in np.atleast_1d(roots)
              if abs(r.imag) <= 1e-12 * max(1.0, abs(r)) and 0.0 < r.real < 1.0]
    return inside[0] if len(inside) == 1 else None


def locate_fold(segment: Segment, xtol: float) -> Located:
    """Root of ``dlambda/ds`` on the segment: Brent's method
    (:func:`~supercoil.continuation.zeroin.zeroin`) started from the zero of the Hermite interpolant of ``lambda`` (:func:`_fold_guess`)."""
    try:
        t_a, t_b = segment.tangent(0.0), segment.tangent(1.0)
        u = zeroin(lambda u: segment.tangent(u)[-1], 0.0, 1.0, xtol, t_a[-1], t_b[-1],
                   _fold_guess(segment, t_a, t_b))
        return Located("fold", "fold", u, segment.point(u), segment.tangent(u), True)
    except (LocationFailed, ValueError):
        return Located("fold", "fold", 1.0, segment.x_b, None, False)


# where a bisection tries its trial point in the bracket, in order: a trial correction
# can fail (the corrector stagnating at the contact barrier's round-off, measured at a
# contact onset) while a neighbouring one succeeds
_TRIAL_FRACTIONS = (0.5, 0.3, 0.7)


def _bisect_count(segment: Segment, lo: float, hi: float, c_lo: int, c_hi: int,
                  width: float) -> tuple[float, float, int]:
    """Narrow ``[lo, hi]`` (counts ``c_lo != c_hi``) to ``width`` by bisection on the count."""
    while hi - lo > width:
        for fraction in _TRIAL_FRACTIONS:
            mid = lo + fraction * (hi - lo)
            try:
                c_mid = segment.count(mid)
                break
            except LocationFailed:
                if fraction == _TRIAL_FRACTIONS[-1]:
                    raise
        if c_mid == c_lo:
            lo = mid
        else:
            hi, c_hi = mid, c_mid
    return lo, hi, c_hi


# A count change by k > 1 over one segment is one event, a multiple eigenvalue
# crossing zero, when at both ends of the segment the k eigenvalues nearest zero have
# one sign each and differ from their mean by at most CLUSTER_SPREAD of it: a double
# eigenvalue of a symmetric state (an E mode of D_m), split a little by the
# discretisation's or the gauge's small asymmetry. A spread below EXACT_SPREAD is an
# exact multiple eigenvalue (a continuous symmetry, the circle's O(2)): its crossing is
# one point, which bisection locates.
CLUSTER_SPREAD = 0.1
EXACT_SPREAD = 1e-6


def _crossing_cluster(segment: Segment, k: int) -> tuple[float, float] | None:
    """Means of the ``k`` eigenvalues nearest zero at both ends if they cross as a split
    cluster (above), else None."""
    means, spreads = [], []
    for u in (0.0, 1.0):
        values, _ = segment.system_eigenpairs(u, k + 2)
        if values.size < k:
            return None
        cluster = values[np.argsort(np.abs(values))[:k]]
        mean = float(np.mean(cluster))
        spread = float(np.max(np.abs(cluster - mean))) / abs(mean) if mean else np.inf
        if np.any(np.sign(cluster) != np.sign(mean)) or spread > CLUSTER_SPREAD:
            return None
        means.append(mean)
        spreads.append(spread)
    if means[0] * means[1] >= 0 or max(spreads) <= EXACT_SPREAD:
        return None
    return means[0], means[1]


def locate_count_change(segment: Segment, xtol: float, switch_below: float,
                        start: float = 0.0) -> Located | None:
    """Where the unstable count first changes on the segment after ``start`` (a fraction;
    None if the raw inertia does not change from there to the end).

    Bisection on the count to ``switch_below``, then Brent's method on the eigenvalue
    nearest zero (or bisection to ``xtol`` when it does not change sign there). A trial
    point whose correction fails is replaced by one at 0.3 or 0.7 of the bracket.

    When the count changes by ``k > 1`` over the segment and the ``k``
    eigenvalues cross as a split cluster (:data:`CLUSTER_SPREAD`), the crossing
    is one event and is not bisected: near it the branches that bifurcate there
    pass within the segment's length of the parent, and a trial point
    re-corrected on the segment's hyperplane can land on one of them (measured
    on the ring's beta branch at its three-point contact onset: trial points of
    C_2 symmetry between D_3 ends, with the count of neither). The event is put
    at the end of the segment nearer the zero of the linear interpolant of the
    cluster's mean eigenvalue, an accepted point of the parent branch, with
    ``accuracy`` the arclength to that zero; its special point carries the
    ``k`` critical modes.

    Where the count's pencil has as many negative eigenvalues at both ends of the last
    bracket (:meth:`Segment.factor_count`), no eigenvalue crossed zero: the stiff
    sliding's was left out on one side only (:mod:`~supercoil.stability.sliding_count`),
    and a ``count_change`` labelled ``sliding`` is returned at the bracket's far end.

    ``Located.resume`` is the first corrected point past the change (with the new
    count): a further change on the segment is searched from there.
    """
    try:
        lo, hi = float(start), 1.0
        c_lo, c_hi = segment.count(lo), segment.count(hi)
        if c_lo == c_hi:
            return None
        if abs(c_hi - c_lo) > 1 and start == 0.0:
            means = _crossing_cluster(segment, abs(c_hi - c_lo))
            if means is not None:
                u_zero = means[0] / (means[0] - means[1])
                u = 0.0 if u_zero <= 0.5 else 1.0
                return Located("bifurcation", "bifurcation", u, segment.point(u),
                               segment.tangent(u), True, c_lo, c_hi,
                               accuracy=abs(u_zero - u) * segment.length)
        lo, hi, c_hi = _bisect_count(segment, lo, hi, c_lo, c_hi, max(switch_below, xtol))
        if segment.factor_count(lo) == segment.factor_count(hi):
            # no eigenvalue crossed zero: the sliding's eigenvalue was counted on one side
            # and left out on the other
            return Located("count_change", "sliding", hi, segment.point(hi),
                           _tangent_or_secant(segment, hi), True, c_lo, c_hi,
                           accuracy=(hi - lo) * segment.length, resume=hi)
        f_lo, f_hi = segment.nearest_eigenvalue(lo), segment.nearest_eigenvalue(hi)
        if np.isfinite(f_lo) and np.isfinite(f_hi) and f_lo * f_hi < 0:
            u = zeroin(segment.nearest_eigenvalue, lo, hi, xtol, f_lo, f_hi)
        else:
            lo, hi, c_hi = _bisect_count(segment, lo, hi, c_lo, c_hi, xtol)
            u = hi  # the first point found with the new count (already corrected)
        resume = hi
        return Located("bifurcation", "bifurcation", u, segment.point(u),
                       _tangent_or_secant(segment, u), True, c_lo, c_hi, resume=resume)
    except LocationFailed:
        return Located("bifurcation", "bifurcation", 1.0, segment.x_b, None, False)


def _tangent_or_secant(segment: Segment, u: float) -> np.ndarray:
    try:
        return segment.tangent(u)
    except LocationFailed:
        # [K, F_lambda] has a two-dimensional kernel at a bifurcation point: the
        # bordered matrix may be exactly singular there; use the secant instead
        return segment.d / segment.length


def takes_problem(function) -> bool:
    """Whether a record or event function takes the keyword ``problem`` (module doc).

    Read once per function (a bound method: per underlying function, held weakly), not
    at every point: ``inspect.signature`` costs tens of microseconds a call, and the
    records and user events are evaluated at every point and localisation trial."""
    bound = getattr(function, "__func__", None)
    key = function if bound is None else bound
    try:
        return _TAKES_PROBLEM[key, bound is not None]
    except KeyError:
        pass
    except TypeError:  # neither hashable nor weakly referable: read it now
        return _reads_problem(function)
    answer = _reads_problem(function)
    try:
        _TAKES_PROBLEM[key, bound is not None] = answer
    except TypeError:
        pass
    return answer


class _ByFunction:
    """A map from ``(function, bound)`` to a value that does not keep the functions."""

    def __init__(self):
        self._maps = (weakref.WeakKeyDictionary(), weakref.WeakKeyDictionary())

    def __getitem__(self, key):
        return self._maps[key[1]][key[0]]

    def __setitem__(self, key, value):
        self._maps[key[1]][key[0]] = value


_TAKES_PROBLEM = _ByFunction()


def _reads_problem(function) -> bool:
    try:
        return "problem" in inspect.signature(function).parameters
    except (TypeError, ValueError):
        return False


def point_values(function, system: ExtendedSystem, x) -> Mapping:
    """``function(q, multipliers, parameter)`` at ``x``, with ``problem=`` the problem at
    the point (``system.problem`` carried there, at ``x``'s parameter) if it takes it."""
    args = (system.q(x), system.multipliers(x), float(x[-1]))
    if takes_problem(function):
        return function(*args, problem=system.problem_at(x[-1]))
    return function(*args)


def user_values(event: UserEvent, system: ExtendedSystem, x: np.ndarray) -> dict[str, float]:
    return {k: float(v) for k, v in point_values(event.function, system, x).items()}


def locate_user_event(segment: Segment, event: UserEvent, label: str, xtol: float,
                      ends: tuple[Mapping[str, float], Mapping[str, float]] | None = None
                      ) -> Located:
    """Root of the event's value ``label`` on the segment (Brent's method, :func:`zeroin`).

    The bracket is first narrowed to the tightest pair of points already
    corrected on the segment (by earlier localisations) between which the
    value changes sign: two indicators of one transition (a contact point
    turning into an interval changes two counts) then cost one localisation
    and a few evaluations, not two. The event's values at each trial point are
    kept on the segment for the other labels (one evaluation of all of them per
    point); ``ends``: its values at the accepted ends, when known.
    """
    known_values = segment.user_values.setdefault(id(event), {})
    if ends is not None:
        known_values.setdefault(0.0, dict(ends[0]))
        known_values.setdefault(1.0, dict(ends[1]))

    def value(u):
        u = float(u)
        if u not in known_values:
            known_values[u] = user_values(event, segment.system,
                                          segment.point(u, warm=True))
        return known_values[u][label]

    try:
        lo, hi = 0.0, 1.0
        known = sorted(segment.corrected)
        signs = [value(u) for u in known]
        for (a, f_a), (b, f_b) in zip(zip(known, signs), zip(known[1:], signs[1:])):
            if f_a * f_b < 0:
                lo, hi = a, b
                break
        u = zeroin(value, lo, hi, xtol)
        return Located(event.kind, label, u, segment.point(u), segment.tangent(u), True)
    except (LocationFailed, ValueError):
        return Located(event.kind, label, 1.0, segment.x_b, None, False)
