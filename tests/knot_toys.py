"""Crossing changes of knotted polygons, constructed exactly (for the knot guards' tests)."""

from __future__ import annotations

import numpy as np


def over_crossing(x: np.ndarray) -> tuple[int, float]:
    """``(i, dz)``: an edge ``i`` that crosses over another in the xy projection, and
    the height by which it passes above it there (brute force over all edge pairs)."""
    n = len(x)
    e = np.roll(x, -1, 0) - x
    for i in range(n):
        for j in range(i + 2, n):
            if (j + 1) % n == i:
                continue
            m = np.array([e[i, :2], -e[j, :2]]).T
            if abs(np.linalg.det(m)) < 1e-12:
                continue
            s, t = np.linalg.solve(m, x[j, :2] - x[i, :2])
            if 0 < s < 1 and 0 < t < 1:
                zi, zj = x[i, 2] + s * e[i, 2], x[j, 2] + t * e[j, 2]
                return (i, zi - zj) if zi > zj else (j, zj - zi)
    raise AssertionError("no crossing")


def pushed_down(x: np.ndarray, fraction: float, margin: float = 0.02) -> np.ndarray:
    """``x`` with the over-strand of its first crossing lowered by ``fraction`` of what
    takes it ``margin`` below the under-strand (a smooth bump over 10 nodes, z only)."""
    i, dz = over_crossing(x)
    w = 4
    idx = (i + np.arange(-w, w + 2)) % len(x)
    bump = np.cos(np.linspace(-np.pi / 2, np.pi / 2, len(idx) + 2)[1:-1])
    y = x.copy()
    y[idx, 2] -= fraction * (dz + margin) * bump / bump[w:w + 2].min()
    return y


SHORT_RUN = 3  # points per run of a knotted branch in the tests of resume and switching


def short_knot_diagram(case: dict, out):
    """``supercoil.knot_diagram(**case, out=out)`` with its branches' runs of
    :data:`SHORT_RUN` points (so that interruptions fall within and between runs)."""
    import pytest

    import supercoil as sc
    from supercoil.problems import knot_branch

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(knot_branch, "SEGMENT_POINTS", SHORT_RUN)
        return sc.knot_diagram(**case, out=out)
