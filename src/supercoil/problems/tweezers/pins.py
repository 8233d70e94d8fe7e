"""The azimuth pin of the clamped rod: the rotation about its axis held by one coordinate.

The rotation about the axis is an exact symmetry of every state; the rod
pins the azimuth of one node (:meth:`~supercoil.rod.open.ClampedRodEnergy.repin`).
Along a branch a continuation run ends at the point before one where the
pinned node no longer sees the rotation well (:func:`pin_stop`, checked at
every point), and :func:`~supercoil.problems.segments.follow` picks the pin
again there. At an equilibrium the pin carries no reaction (the energy is
invariant under the rotation, and the pinned coordinate moves under it), so
every stored state is an equilibrium of the unpinned problem and the count
does not depend on the pin.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from supercoil.rod.open import ClampedRodEnergy

PIN_QUALITY = 0.5  # re-pick the azimuth pin below this (ClampedRodEnergy.pin_quality)
# a run ends where the sliding's tail ratio (ClampedRodEnergy.sliding) crosses the
# rod's sliding_tail by this factor, so that the next run starts on the far side of the
# threshold, with (or without) the sliding's phase row: without the margin a run ended
# where the ratio barely crossed, and the next started from the point before, on the
# near side, and was refused at once. The ratio changes by about 10 % a step; a factor
# of 4 kept a run without the row going where the ratio levelled off between the
# threshold and a quarter of it (L/D = 200, lambda = 20, N = 404: at 2.9e-4), until
# the corrector diverged
SLIDING_HYSTERESIS = 1.5


def rotated_mode(mode: np.ndarray) -> tuple[np.ndarray, int]:
    """The critical mode turned about the axis so the node it moves most moves along +x,
    and that node.

    The first such node within a relative ``1e-6`` of the largest move: the clamped
    rod's modes are symmetric about its middle, so two nodes tie exactly and round-off
    picks either (nodes 49 and 50 of 100); see :func:`pin_node`."""
    v = mode.reshape(-1, 3).copy()
    r = np.linalg.norm(v[:, :2], axis=1)
    k = int(np.flatnonzero(r >= (1.0 - 1e-6) * r.max())[0])
    a = -math.atan2(v[k, 1], v[k, 0])
    c, s = math.cos(a), math.sin(a)
    x, y = v[:, 0].copy(), v[:, 1].copy()
    v[:, 0], v[:, 1] = c * x - s * y, s * x + c * y
    return v.ravel(), k


def pin_node(rod: ClampedRodEnergy, node: int) -> None:
    """Pin the azimuth of the straight rod's buckling at ``node``: its ``y`` coordinate,
    along which the mode of :func:`rotated_mode` does not move it.

    What ``rod.repin(q* + 1e-3 mode)`` picks when ``node`` is the one farthest from the
    axis; with two nodes tied (the mode's symmetry about the rod's middle) the rotation's
    round-off decided, and a pin on the other node, which the mode moves across it,
    drops that component of the switch's direction: the switch then left the straight
    rod for another branch (measured at N = 100, F L^2/A = 75: its first point at 2.59
    turns, beyond the second bifurcation, instead of the subcritical branch at 2.20).
    """
    hold_azimuth(rod, (3 * node + 1,))


def hold_azimuth(rod: ClampedRodEnergy, dofs, problem=None) -> None:
    """Pin the rod's azimuth by the coordinates ``dofs`` (none: not pinned), the clamps
    kept; on its contact wrapper ``problem`` (whose ``fixed`` copies the rod's) too."""
    clamps = np.setdiff1d(rod.fixed, rod.gauge_dofs)
    rod.gauge_dofs = np.array(dofs, dtype=np.int64)
    rod.fixed = np.array(sorted(set(clamps.tolist()) | {int(d) for d in dofs}),
                         dtype=np.int64)
    if problem is not None and problem is not rod:
        problem.fixed = rod.fixed


def pin_stop(rod: ClampedRodEnergy) -> Callable[[np.ndarray], str | None]:
    """A ``continuation`` ``stop`` that refuses a state where the azimuth pin's quality
    (``rod.pin_quality``) is below ``PIN_QUALITY``: the run ends at the point before,
    where :func:`~supercoil.problems.segments.follow` picks the pin again.

    Checked at every point (about 20 us), so that the pin cannot degrade within a run
    and runs need not be kept short for its sake: each new run starts without the step
    growth and the quadratic predictor's history of the last, and recomputes its first
    point's stability.
    """

    def refuse(q: np.ndarray) -> str | None:
        quality = rod.pin_quality(q)
        if quality < PIN_QUALITY:
            return f"the azimuth pin's quality fell to {quality:.2g} (below {PIN_QUALITY:g})"
        return None

    return refuse


def sliding_stop(rod: ClampedRodEnergy, q_start: np.ndarray
                 ) -> Callable[[np.ndarray], str | None]:
    """A ``continuation`` ``stop`` for a run started at ``q_start``: it refuses a state
    where the sliding of a localised structure (``rod.near_symmetry_modes``) is an
    approximate symmetry and was not at the start, or the reverse, each with the margin
    ``SLIDING_HYSTERESIS`` on the threshold (``rod.sliding_tail``).

    A run carries the phase row of that sliding from its start or not at all
    (``ContinuationOptions.near_symmetry_gauge``); the run ends at the point before
    the change and the next one starts there with the rows the state needs
    (:func:`~supercoil.problems.segments.follow`). Without the row, Newton moves
    along the nearly null sliding by the residual's round-off over its eigenvalue
    (measured at L/D = 100, F L^2/A = 1200, N = 160: steps of 0.3 L from residuals
    of 2e-8, the eigenvalue 6e-8 unweighted), and the corrector diverged."""
    had = rod.near_symmetry_modes(q_start).shape[0] > 0

    def refuse(q: np.ndarray) -> str | None:
        threshold = rod.sliding_tail
        if threshold is None:
            return None
        tail = rod.sliding(q)[1]
        if not had and tail <= threshold / SLIDING_HYSTERESIS:
            return "the sliding of the localised structure became an approximate symmetry"
        if had and tail > threshold * SLIDING_HYSTERESIS:
            return "the sliding of the structure stopped being an approximate symmetry"
        return None

    return refuse
