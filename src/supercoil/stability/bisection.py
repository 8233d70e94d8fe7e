"""Locate where an integer stability count changes, by bisection.

Chamekh, Mani-Aouadi & Moakher 2014, sec. 6.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def locate_count_change(count: Callable[[float], int], lo: float, hi: float, target: int,
                        rtol: float = 1e-10, max_steps: int = 200,
                        eigenvalue: Callable[[float], float] | None = None,
                        switch_below: float = 1e-3) -> float:
    """Parameter where ``count`` first reaches ``target`` between ``lo`` and ``hi``.

    ``count(lo) < target <= count(hi)`` is required (checked; ``ValueError``
    otherwise). Bisection on the exact count, so pair crossings (the count
    jumps by two, the determinant keeps its sign) are found as well.

    The count is exact only while the crossing eigenvalue is larger than the
    round-off of the inertia computation. If ``eigenvalue`` (the signed
    eigenvalue nearest zero, a smooth function of the parameter) is given, the
    bisection stops at relative width ``switch_below`` and the root of the
    eigenvalue inside the bracket is found by Brent's method to ``rtol``
    (secant-type localisation). Returns the threshold.
    """
    c_lo, c_hi = count(lo), count(hi)
    if not (c_lo < target <= c_hi):
        raise ValueError(f"no bracket: count is {c_lo} at {lo:.6g} and {c_hi} at {hi:.6g}, "
                         f"target {target}")
    scale = max(abs(lo), abs(hi))
    width = rtol if eigenvalue is None else max(rtol, switch_below)
    for _ in range(max_steps):
        if hi - lo <= width * scale:
            break
        mid = 0.5 * (lo + hi)
        if count(mid) >= target:
            hi = mid
        else:
            lo = mid
    if eigenvalue is not None:
        f_lo, f_hi = eigenvalue(lo), eigenvalue(hi)
        if f_lo > 0 > f_hi:
            from scipy.optimize import brentq  # here: scipy.optimize takes ~0.1 s to import

            return float(brentq(eigenvalue, lo, hi, xtol=rtol * scale, rtol=4 * np.finfo(float).eps))
        # no clean sign change of the nearest eigenvalue: keep bisecting on the count
        while hi - lo > rtol * scale:
            mid = 0.5 * (lo + hi)
            if count(mid) >= target:
                hi = mid
            else:
                lo = mid
    return 0.5 * (lo + hi)
