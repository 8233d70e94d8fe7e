"""An independent reversal-axis search, the oracle of ``reversal_axes``' fast scan."""

from __future__ import annotations

import numpy as np

from supercoil.geometry.symmetry import refined_axes, reversal_residuals


def reversal_axes_reference(points: np.ndarray, tolerance: float) -> list[tuple[float, float]]:
    """:func:`~supercoil.geometry.symmetry.reversal_axes` by a half-node trigonometric
    scan with every local minimum that can hide a zero refined (slower: the oracle)."""
    x = np.asarray(points, dtype=float)
    n = x.shape[0]
    grid = np.arange(2 * n) * 0.5
    values = reversal_residuals(x, grid)
    left, right = np.roll(values, 1), np.roll(values, -1)
    # A local minimum on the half-node grid is refined (an axis rarely falls on it)
    # when it can hide a zero: near an axis the residual is a V, k |c - c*|, and the
    # grid point nearest c* (within 1/4) has at most half the value of its farther
    # neighbour (at least 1/2 away); 3/4 leaves room for the V's curvature.
    candidates = np.flatnonzero((values <= left) & (values <= right) &
                                (values <= 0.75 * np.maximum(left, right) + tolerance))
    return refined_axes(x, grid[candidates], 0.5, tolerance)
