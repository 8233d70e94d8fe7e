"""Switching off the circle at its bifurcation points, shared by the Kirchhoff and the
Cosserat ring diagrams.

The requested modes' points (:func:`mode_points`), the attempts in turn
(:data:`SWITCH_AMPLITUDES` on either side of the critical mode), the test that a
run left the circle (:func:`leaves_circle`: its first :data:`SWITCH_TRIAL_POINTS`
points show the writhe growing away from zero) and the notes on the attempts
(:func:`switch_notes`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence

import numpy as np

from supercoil.continuation import Branch, SpecialPoint
from supercoil.problems.ring_branches import mode_bifurcation

SWITCH_AMPLITUDE = 2e-3  # first point of a primary branch from its bifurcation (arclength)
SWITCH_AMPLITUDES = (SWITCH_AMPLITUDE, 5e-3, 1.5e-2)  # tried in turn, both sides each
SWITCH_TRIAL_POINTS = 4


def switch_attempts() -> list[tuple[float, int]]:
    """``(amplitude, side)`` in the order tried: each amplitude on both sides."""
    return [(a, side) for a in SWITCH_AMPLITUDES for side in (1, -1)]


def mode_points(circle: Branch, modes: Sequence[int], notes: list[str],
                say: Callable[[str], None]) -> Iterator[tuple[str, SpecialPoint]]:
    """``(name, point)`` of each mode's bifurcation point on the ``circle``, announced
    through ``say`` as its switch begins; a mode without one gets its note
    (:func:`~supercoil.problems.ring_branches.mode_bifurcation`) and is skipped."""
    for mode in modes:
        name, point = mode_bifurcation(circle, mode, notes)
        if point is None:
            continue
        say(f"{name}: switched from the circle at dLk = {point.parameter:.4g}, no contact")
        yield name, point


def leaves_circle(branch: Branch) -> bool:
    """Whether the first :data:`SWITCH_TRIAL_POINTS` points of a switched branch show its
    writhe growing (else it fell back onto the circle)."""
    wr = np.abs(branch.records.get("writhe", np.zeros(0)))[:SWITCH_TRIAL_POINTS]
    return bool(wr.size >= 2 and wr[-1] > 1e-4 and wr[-1] > 2 * wr[0])


def switch_notes(notes: list[str], name: str, number: int, amplitude: float, side: int,
                 leaves: bool) -> None:
    """Append the notes on the switch that ended with attempt ``number`` (from 0) of
    :func:`switch_attempts`: the attempts that fell back before it, and a failure when
    this one fell back too."""
    if number:
        notes.append(f"{name}: switched with amplitude {amplitude:g}, side {side:+d} "
                     f"({number} earlier attempt(s) fell back onto the circle)")
    if not leaves:
        notes.append(f"failed: {name}: every switching attempt fell back onto the circle")
