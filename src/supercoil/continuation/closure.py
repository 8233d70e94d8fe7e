"""Closed branches: whether the last step of a branch passed through an earlier point.

A branch that is a closed curve (a loop of equilibria) comes back to where it
started; continuation stops there (``ContinuationOptions.detect_closed_loops``)
rather than going round again. The last chord must pass within
``closed_loop_tolerance`` of its length of an earlier point of the same
direction and unstable count, and a correction from the nearest point of the
chord on that point's normal hyperplane must land on it (:func:`returned_to`).

A corrected point that lies on the branch's own earlier path with its tangent the
other way is no point of the branch ahead but a jump back onto the part already
followed (:func:`retraced`): a solution curve through a regular point is unique, and
a smooth branch cannot run back along itself. Past a sharp fold the two sheets run
side by side, and a step long against their distance converges onto the sheet
already followed. Measured on the tweezers' contact branch held on its symmetry (L/D =
500, lambda = 10, C/A = 1.5, N = 1004): folded at 1.8042 turns, the branch followed
the second sheet down to 1.8026 turns (0.2 D from the first) with steps growing to
0.36 D, then converged within 1e-3 D of the first sheet and followed it back down to
the contact-free branch, its count falling from 1 to 0 with no fold, a "count change"
whose location failed. The tracer refuses such a point and shortens the step where
its unstable count is the earlier chord's and not the step start's (the two sheets of a
fold differ by one): close to a sharp fold the sheet ahead runs within the step's
tolerance of the one followed, with the count of the step's start (measured on the same
branch at 1.838 turns, where without the count the steps fell to the minimum).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from supercoil.continuation.corrector import correct
from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.system import ExtendedSystem

CLOSURE_TOLERANCE = 1e-6  # a closed branch passes through its earlier point to this (relative)


def returned_to(system: ExtendedSystem, opts: ContinuationOptions, xs: Sequence[np.ndarray],
                ts: Sequence[np.ndarray], unstable_counts: Sequence[int],
                parameters: np.ndarray | None = None) -> int | None:
    """Index of an earlier point of the branch ``xs`` (tangents ``ts``) that its last
    step passed through (see ``ContinuationOptions.detect_closed_loops``), or None.
    ``parameters``: the points' parameter values (``x[-1]``) if kept by the caller."""
    k = len(xs) - 1
    if k < 4:
        return None
    a, b = xs[-2], xs[-1]
    chord = b - a
    length = system.norm(chord)
    if length == 0.0:
        return None
    reach = opts.closed_loop_tolerance * length
    # The metric weighs the parameter by w (its last weight is w^2), so a point whose
    # parameter lies farther than reach / w from the chord's is not within reach:
    # only the others are stacked (this runs at every point).
    lam = (np.array([x[-1] for x in xs[:k - 2]]) if parameters is None
           else parameters[:k - 2])
    low, high = sorted((a[-1], b[-1]))
    off = np.maximum(np.maximum(low - lam, lam - high), 0.0)
    near = np.flatnonzero(off * np.sqrt(system.weights[-1]) <= reach)
    if near.size == 0:
        return None
    earlier = np.array([xs[j] for j in near])
    w = system.weights
    u = np.clip(((earlier - a) * w) @ chord / length**2, 0.0, 1.0)
    gaps = np.sqrt(np.einsum("ij,ij->i", (a + u[:, None] * chord - earlier) ** 2,
                             np.broadcast_to(w, earlier.shape)))
    cos_limit = math.cos(math.radians(15.0))
    close = np.flatnonzero(gaps <= reach)
    if close.size == 0:
        return None
    count = unstable_counts[-1]
    for i in close:
        j = int(near[i])
        if (ts[j] @ (w * ts[-1]) >= cos_limit and unstable_counts[j] == count
                and _closes_at(system, opts, a + u[i] * chord, xs[j], ts[j])):
            return j
    return None


def _closes_at(system: ExtendedSystem, opts: ContinuationOptions, start: np.ndarray,
               x_j: np.ndarray, t_j: np.ndarray) -> bool:
    """Whether the branch really passes through the point ``x_j`` (tangent ``t_j``): the
    point ``start`` of the last chord nearest to it, corrected on the hyperplane through
    it orthogonal to its tangent, must land on it (a branch that only passes near it,
    e.g. a helix of small pitch, lands elsewhere on that hyperplane)."""
    corr = correct(system, start, system.weights * t_j, x_j, 0.0,
                   opts.tolerance, opts.max_corrector_iterations)
    if not corr.ok:
        return False
    scale = max(1.0, system.norm(x_j))
    return system.norm(corr.x - x_j) <= CLOSURE_TOLERANCE * scale


def retraced(system: ExtendedSystem, opts: ContinuationOptions, xs: Sequence[np.ndarray],
             ts: Sequence[np.ndarray], x_new: np.ndarray, t_new: np.ndarray,
             parameters: np.ndarray | None = None) -> int | None:
    """Index ``j`` of the earlier chord ``xs[j] -> xs[j + 1]`` (the nearest) of the branch ``xs``
    (tangents ``ts``) on which the corrected point ``x_new`` of the step from ``xs[-1]``
    lies, traversed the other way (module doc), or None: within ``closed_loop_tolerance``
    times the step's length of the chord, and its tangent ``t_new`` within 15 degrees of
    the reverse of the chord's end tangents. The chord that ends at the step's start is
    not asked (every step back along the branch lies on it); on the others a fold's turn
    is told from a jump by the unstable counts (the tracer's ``_back_on_sheet``).
    ``parameters``: the points' parameter values (``x[-1]``) if kept by the caller."""
    k = len(xs) - 1
    if k < 2:
        return None
    length = system.norm(x_new - xs[-1])
    if length == 0.0:
        return None
    reach = opts.closed_loop_tolerance * length
    w = system.weights
    # chords j -> j + 1 for j < k - 1
    lam = np.array([x[-1] for x in xs[:k]]) if parameters is None else parameters[:k]
    low, high = np.minimum(lam[:-1], lam[1:]), np.maximum(lam[:-1], lam[1:])
    off = np.maximum(np.maximum(low - x_new[-1], x_new[-1] - high), 0.0)
    near = np.flatnonzero(off * np.sqrt(w[-1]) <= reach)
    if near.size == 0:
        return None
    a = np.array([xs[j] for j in near])
    chord = np.array([xs[j + 1] for j in near]) - a
    sq = np.einsum("ij,ij->i", chord * w, chord)
    u = np.clip(np.einsum("ij,ij->i", (x_new - a) * w, chord) / np.where(sq > 0, sq, 1.0),
                0.0, 1.0)
    gap = x_new - (a + u[:, None] * chord)
    gaps = np.sqrt(np.einsum("ij,ij->i", gap * w, gap))
    cos_limit = math.cos(math.radians(15.0))
    close = np.flatnonzero(gaps <= reach)
    for i in close[np.argsort(gaps[close])]:  # the nearest chord first
        j = int(near[i])
        if max(ts[j] @ (w * t_new), ts[j + 1] @ (w * t_new)) <= -cos_limit:
            return j
    return None
