"""A step along the branch's chord past a point where its tangent is lost.

The tracer refuses a corrected point whose tangent turned by more than
``max_turn_degrees`` from the last point's (the guard against jumping between
branches). Where every step from the last point is refused so, down to the minimum
step, the tangents computed there are not the branch's: near a branch point the
bordered matrix is nearly singular and its solve loses the tangent in round-off
(measured on a long rod's contact branch with 25 unstable modes: over its last 30
points, 1e-9 turns apart, the tangent's parameter component varied by 20 %). No
step along such a tangent goes, however short.

The chord of the branch's recent path still points along it. As a last resort before
stopping, the run steps along the chord instead (Allgower & Georg 1990, ch. 8: the
secant predictor, and steps over singular points): from the last point, the
pseudo-arclength step with the unit chord ``d = (x_k - x_j) / |x_k - x_j|`` as
predictor and row, ``x_j`` the latest point at least the largest recent step back.
The step lengths tried grow by :data:`GROWTH` from four times the last step up to
four times the largest recent step, the shortest that goes taken: its corrected
point must pass the usual tests, its tangent turned by at most ``max_turn_degrees``
from the chord (not from the lost tangent), and it must not lie on the branch's own
path followed the other way. The run's message counts the steps so taken.

Measured on that branch, continued from its stop at 41.21 turns: four steps along the
chord (1e-11 to 1e-10 long) passed four points where the tangent was lost, and after
a fifth the branch came back within a step of a point five points before (a lap of
1e-10 in arclength), which the tweezers' driver reports as a closure and follows
again from before it; the rejoined branch reached 41.86 turns. Trying the longest
length first (four times the largest recent step down), the branch closed so two
points after its first step along the chord.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.step import Step, take_step
from supercoil.continuation.system import ExtendedSystem

# the recent points whose steps and chords the jump is made from
SECANT_POINTS = 50
# the growth of the step lengths tried
GROWTH = 4.0


def chord_direction(system: ExtendedSystem, xs: list[np.ndarray],
                    s: list[float]) -> tuple[np.ndarray, float] | None:
    """``(d, big)``: the unit chord (in the continuation's metric) from the latest point at
    least ``big`` back to the last, ``big`` the largest step among the last
    :data:`SECANT_POINTS` points (the oldest of them if none is that far); None before
    three points or where the chord has no length."""
    k = len(xs) - 1
    if k < 2:
        return None
    first = max(0, k - SECANT_POINTS)
    big = max(s[i + 1] - s[i] for i in range(first, k))
    chord, length = xs[k] - xs[first], 0.0
    for j in range(k - 1, first - 1, -1):
        chord = xs[k] - xs[j]
        length = system.norm(chord)
        if length >= big:
            break
    if not length > 0:
        return None
    return chord / length, big


def jump_lengths(last_step: float, big: float, min_step: float) -> list[float]:
    """The step lengths tried, shortest first: from ``4 last_step`` (at least
    ``min_step``) by :data:`GROWTH` while at most ``4 big``."""
    lengths, ds = [], max(4.0 * last_step, min_step)
    while ds <= 4.0 * big:
        lengths.append(ds)
        ds *= GROWTH
    return lengths


def chord_step(system: ExtendedSystem, opts: ContinuationOptions, xs: list[np.ndarray],
               s: list[float], admissible: Callable[[np.ndarray], bool] | None,
               stop: Callable[[np.ndarray], str | None] | None,
               retraced: Callable[[Step], str | None]) -> tuple[Step, float] | str:
    """``(taken, ds)``: the first length of :func:`jump_lengths` (shortest first) whose
    step along :func:`chord_direction` from the last point ``xs[-1]`` goes (``admissible``
    and ``stop`` vet its state as for any step; ``retraced(taken)`` says why it lies on
    the branch's own path followed the other way, or None); else the text to add to the
    stop's message (empty where none was tried)."""
    found = chord_direction(system, xs, s)
    if found is None:
        return ""
    d, big = found
    lengths = jump_lengths(s[-1] - s[-2], big, opts.min_step)
    for ds in lengths:
        taken = take_step(system, opts, xs[-1], d, None, None, ds, admissible, stop)
        if taken.refusal or taken.leaves_bound or taken.failure is not None:
            continue
        if opts.detect_closed_loops and retraced(taken) is not None:
            continue
        return taken, ds
    if not lengths:
        return ""
    return (f"; steps along the chord of the last points ({lengths[0]:.2g} to "
            f"{lengths[-1]:.2g}) failed too")
