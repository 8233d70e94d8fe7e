"""The straight twisted rod under load control, its buckling located all at once.

The straight rod is the same state at every number of turns: its branch only
brackets the count changes, which :func:`straight_bifurcations` locates from
one definite eigenproblem and compares with Greenhill's exact clamped
condition (:mod:`supercoil.problems.greenhill`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, continuation
from supercoil.problems.tweezers.options import TweezersOptions, segment_length
from supercoil.problems.tweezers.problem import clamped_problem
from supercoil.rod.open import ClampedRodEnergy

STRAIGHT_MAX_STEP = 1.0  # arclength step of the straight branch (see straight_branch)
# relative departure from linearity in turns of the straight rod's Hessian above which
# the pencil is not trusted (measured: 1e-17 of its largest entry at N = 100)
PENCIL_LINEARITY = 1e-10
# the located buckling above Greenhill's clamped condition by more than this relative
# gap: the mesh under-resolves the buckling helix (resolution_note)
GREENHILL_GAP = 0.05


def straight_branch(options: TweezersOptions, problem: ClampedRodEnergy, q0: np.ndarray,
                    records, on_point=None) -> Branch:
    """The straight rod in turns (load control), with its bifurcations located.

    The straight twisted rod is the same state at every ``turns``: its points
    only bracket the count changes. Steps up to one turn (``STRAIGHT_MAX_STEP``)
    halve the points against a quarter turn (N = 100, 0-5 turns: 12 points
    instead of 24, the five bifurcations within 3e-9 turns of those found with
    quarter turns). The points are followed without bifurcation detection and
    the count changes are located all at once by :func:`straight_bifurcations`
    (the Hessian is linear in turns there); where that does not certify them,
    the branch is computed again with the continuation's own localisation
    (bisection on the count, then Brent's method on the eigenvalue nearest zero).
    """
    opts = options
    cont = ContinuationOptions(initial_step=0.05, max_step=STRAIGHT_MAX_STEP,
                               parameter_bounds=opts.turns, max_points=opts.max_points,
                               event_tolerance=opts.event_tolerance, detect_bifurcations=False)
    branch = continuation(problem, q0, parameter="turns", options=cont, name="straight",
                          records=records, on_point=on_point)
    specials = straight_bifurcations(problem, branch, cont, records)
    if specials is not None:
        return dataclasses.replace(branch, special_points=specials)
    problem.accept(q0)
    return continuation(problem, q0, parameter="turns", options=dataclasses.replace(
        cont, detect_bifurcations=True), name="straight", records=records, on_point=on_point)


def straight_bifurcations(problem: ClampedRodEnergy, branch: Branch,
                          options: ContinuationOptions, records=None
                          ) -> tuple[SpecialPoint, ...] | None:
    """The count changes of the straight branch from one symmetric-definite eigenproblem;
    None where they are not certified (the caller then locates them by continuation).

    Every point of ``branch`` is the one state ``(q, mu)`` (checked), so the Hessian
    of the Lagrangian on the free DOFs is a function of ``turns`` alone, and it is
    linear there, ``H(t) = H_0 + (t - t_0) B``: the twist energy is ``(C/2L)(2 pi Tw)^2``
    with ``Tw = turns + f(q)`` and ``grad f = 0`` on the straight rod (by its symmetry
    under the half turn about the axis), so its Hessian is ``(C/L)(2 pi)^2 Tw hess f``.
    Linearity is checked at a third point (departure at most ``PENCIL_LINEARITY``
    of the largest entry). With ``Z`` an orthonormal basis of the constraints' kernel
    (``J Z = 0``, the same ``J`` at every point) and ``A = Z^T H_0 Z`` positive definite
    (the count is 0 at the first point), Sylvester's law of inertia gives the count at
    ``t > t_0`` as the number of eigenvalues ``theta > 1 / (t - t_0)`` of the definite
    pencil ``(-Z^T B Z) v = theta A v``: the constrained Hessian is singular exactly at
    ``t_0 + 1 / theta``, the axisymmetric rod's pairs giving double roots. These roots
    are the bifurcations (roots within ``event_tolerance`` of each other one event, its
    count jump their number).

    Certified by inertia counts: the pencil's count must equal the branch's stored
    count at every point, and the continuation's
    :func:`~supercoil.continuation.stability.inertia` halfway between consecutive
    roots (and between the first root and ``t_0``, the last and the branch's end) must
    give the counts the pencil predicts there, so every count change lies between two
    such checks and at the pencil's root, a backward-stable eigenvalue. (Counts taken
    ``event_tolerance`` from each root would not do: at N = 1000 the constrained
    eigenvalues there are 1e-17 of the Hessian's largest, below what an inertia
    resolves, so they would never certify.) For
    ``t < t_0`` (turns decreasing) the count is the number of ``theta (t - t_0) > 1``,
    the same rule. Each special point is then filled as the continuation's
    localisation fills it (its stability, ``point_stability``, with the critical modes
    that the branch switch follows; its records), at the state of the branch, except
    its ``unstable_count``: the count of the eigenvalues below zero there, i.e. the
    count before (certified; the pair is at zero). ``point_stability`` at a point this
    close to singular counts from an inertia that round-off decides and undercounts
    (measured: 0, 2, 2, 5, 8 at the continuation's five points, whose counts before
    are 0, 2, 4, 6, 8).

    Measured (N = 100, C/A = 4/3, F L^2/A = 75, 0-5 turns): the five bifurcations agree
    with the continuation's bisection-then-Brent localisation to 1e-9 turns (its
    tolerance 1e-8); the straight branch took 75 inertia counts and 48 eigenproblems
    with that localisation, 23 and 17 with this one (12 points, 6 certifying counts
    halfway between the roots and the ends, 5 special points) plus the 192 x 192
    definite eigenproblem.
    """
    from scipy.linalg import LinAlgError, eigh, null_space

    from supercoil.continuation.stability import count_rows, inertia, point_stability
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.solvers.errors import InertiaError, SingularMatrixError

    n_points = len(branch)
    if n_points < 2 or branch.unstable_count[0] != 0 or branch.zero_modes[0] != 0:
        return None
    q, mu = branch.states[0], branch.multipliers[0]
    if not (np.array_equal(branch.states, np.broadcast_to(q, branch.states.shape))
            and np.array_equal(branch.multipliers,
                               np.broadcast_to(mu, branch.multipliers.shape))):
        return None
    turns = branch.parameter_values
    t0 = float(turns[0])
    system = ExtendedSystem(problem, "turns", q, None, q, options.parameter_weight,
                            options.finite_difference_step)

    def x_at(t: float) -> np.ndarray:
        return system.pack(q, mu, t)

    last = float(turns[-1])
    if last == t0:
        return None
    sense = 1.0 if last > t0 else -1.0  # the direction of travel in turns
    try:
        if count_rows(system, x_at(t0)).size:
            return None
        h0 = system.hessian(x_at(t0)).dense()
        slope = (system.hessian(x_at(last)).dense() - h0) / (last - t0)
        middle = 0.5 * (t0 + last)  # not a stored point: a two-point branch has none
        departure = np.abs(system.hessian(x_at(middle)).dense() - (h0 + (middle - t0) * slope))
        if departure.max() > PENCIL_LINEARITY * np.abs(h0).max():
            return None
        J = system.jacobian(x_at(t0))
        Z = null_space(J.toarray()) if J.shape[0] else np.eye(system.n)
        theta = eigh(-(Z.T @ slope @ Z), Z.T @ h0 @ Z, eigvals_only=True)
    except LinAlgError:
        return None

    def pencil_count(t: float) -> int:
        return int(np.sum(theta * (t - t0) > 1.0))

    counts = np.array([0] + [pencil_count(t) for t in turns[1:]])
    if not np.array_equal(counts, branch.unstable_count) or np.any(branch.zero_modes):
        return None
    ahead = theta[theta * sense > 0]
    roots = t0 + 1.0 / ahead[np.argsort(-np.abs(ahead))]  # nearest t0 first
    roots = roots[sense * (roots - last) <= 0]
    delta = options.event_tolerance / options.parameter_weight  # in turns
    clusters: list[list[float]] = []
    for root in roots:
        if clusters and abs(root - clusters[-1][-1]) <= delta:
            clusters[-1].append(float(root))
        else:
            clusters.append([float(root)])
    centres = [float(np.mean(c)) for c in clusters]
    # the count halfway between consecutive roots (and the ends) must be the pencil's
    stops = [t0, *centres, last]
    for k in range(len(stops) - 1):
        if abs(stops[k + 1] - stops[k]) <= 4 * delta:
            return None
        check = 0.5 * (stops[k] + stops[k + 1])
        try:
            if inertia(system, x_at(check), options.zero_tolerance)[0] != pencil_count(check):
                return None
        except (SingularMatrixError, InertiaError):
            return None
    order = turns if sense > 0 else -turns  # increasing, for the segment of a root
    specials = []
    before = 0
    for cluster, at in zip(clusters, centres, strict=True):
        after = before + len(cluster)
        index = int(np.searchsorted(order, sense * at)) - 1
        x = x_at(at)
        stab = point_stability(system, x, options.zero_tolerance, options.n_modes)
        values, modes = stab.critical_modes(len(cluster))
        u = (at - turns[index]) / (turns[index + 1] - turns[index])
        arclength = float(branch.arclength[index]
                          + u * (branch.arclength[index + 1] - branch.arclength[index]))
        tangent = np.zeros(branch.tangents.shape[1])
        tangent[-1] = 1.0  # the branch's secant: the state does not move
        specials.append(SpecialPoint(
            kind="bifurcation", label="bifurcation", branch=branch.name, index=index,
            parameter=at, arclength=arclength, q=q.copy(), multipliers=mu.copy(),
            tangent=tangent, unstable_count=before, count_before=before,
            count_after=after, critical_eigenvalues=values, critical_modes=modes,
            located=True, tolerance=options.event_tolerance,
            records=dict(records(q, mu, at)) if records is not None else {}))
        before = after
    return tuple(specials)


def resolution_note(options: TweezersOptions, buckling: float) -> str | None:
    """A note when the straight rod's located buckling ``buckling`` (turns) lies more than
    ``GREENHILL_GAP`` above Greenhill's clamped condition: the mesh under-resolves the
    buckling helix, and the note names the ``--nodes`` that bring it within that gap.
    None otherwise (or without tension).

    The critical mode of a rod under the tension ``F`` is a helix of wavenumber close to
    ``k = sqrt(F/A)`` (:mod:`supercoil.problems.greenhill`: ``M -> 2 sqrt(A F)`` for
    long rods); on segments of length ``h`` the discrete rod buckles late by about
    ``(k h)^2 / 8`` (measured at L/D = 100 and 200, ``lambda = L k = 150``, C/A = 1.5:
    25 %, 6.8 % and 1.7 % at ``k h`` = 1.5, 0.74 and 0.37, against 28 %, 6.9 % and 1.7 %
    from the estimate). Beyond ``k h`` of about 1 the localised loop into which the
    branch grows (its core is ``sqrt(A/F)`` long) spans a segment or two and is pinned
    by the mesh."""
    if not options.load_control or not options.tension:
        return None
    from supercoil.problems.greenhill import critical_turns

    exact = critical_turns(options.twist_ratio, options.tension)
    gap = buckling / exact - 1.0
    if not gap > GREENHILL_GAP:
        return None
    return (f"the straight rod buckles at {buckling:.6g} turns, {100 * gap:.3g} % above "
            f"Greenhill's clamped condition ({exact:.6g}): "
            + _under_resolved(options, GREENHILL_GAP,
                              f"brings the buckling within {100 * GREENHILL_GAP:g} %"))


def unreached_note(options: TweezersOptions) -> str | None:
    """A note when the straight rod does not buckle up to the last turn although
    Greenhill's clamped condition lies below it, by less than the segments' estimate
    ``(k h)^2 / 8`` of the discrete rod's late buckling (:func:`resolution_note`): the
    note names the ``--nodes`` whose estimate is half the margin between the condition
    and the last turn (at most ``GREENHILL_GAP``). None otherwise (or without tension)."""
    if not options.load_control or not options.tension:
        return None
    from supercoil.problems.greenhill import critical_turns

    exact = critical_turns(options.twist_ratio, options.tension)
    margin = options.turns[1] / exact - 1.0
    late = options.core_segments ** 2 / 8.0
    if not 0.0 < margin < late:
        return None
    return (f"Greenhill's clamped condition ({exact:.6g} turns) lies {100 * margin:.2g} % "
            f"below the last turn, and the discrete rod buckles later by about "
            f"(k h)^2/8 = {100 * late:.2g} %: "
            + _under_resolved(options, min(GREENHILL_GAP, 0.5 * margin),
                              "brings the buckling below the last turn"))


def _under_resolved(options: TweezersOptions, gap: float, goal: str) -> str:
    """The segments against ``sqrt(A/F)``, and the ``--nodes`` whose estimated late
    buckling ``(k h)^2 / 8`` is ``gap`` (what they achieve: ``goal``)."""
    k = math.sqrt(options.tension)  # sqrt(F/A) in units of 1/L
    h = segment_length(options.n_nodes)
    nodes = 2 + math.ceil(k / math.sqrt(8.0 * gap))
    return (f"its segments ({h:.3g} L) are {k * h:.2g} times the length sqrt(A/F) = "
            f"{1 / k:.3g} L of the buckling helix and the localised loop, which this mesh "
            f"under-resolves; --nodes >= {nodes} {goal}")


def straight_force_branch(options: TweezersOptions, turns: float,
                          force_range: tuple[float, float], records=None) -> Branch:
    """The straight rod at fixed ``turns`` followed in the force (``tension``), high to low.

    Continuation in the load parameter ``tension`` (F L^2/A) from ``force_range[1]``
    down to ``force_range[0]``: the straight rod loses stability where the force
    falls below the one at which ``turns`` is critical (located as a
    ``bifurcation``; exact: ``critical_moment(F) = 2 pi (C/A) turns``).
    """
    low, high = (float(v) for v in force_range)
    if not (math.isfinite(low) and math.isfinite(high) and 0 <= low < high):
        raise ValueError(f"force_range must be (low, high) with 0 <= low < high, got "
                         f"{force_range!r}")
    opts = dataclasses.replace(options, tension=high, end_distance=None, turns=(0.0, 1.0))
    problem, q0 = clamped_problem(opts)
    problem = problem.at(turns=float(turns))
    cont = ContinuationOptions(initial_step=0.05, max_step=max(1.0, 0.05 * (high - low)),
                               parameter_bounds=(low, high), max_points=options.max_points,
                               direction=-1, event_tolerance=options.event_tolerance)
    return continuation(problem, q0, parameter="tension", options=cont,
                        name="straight_in_force", records=records)
