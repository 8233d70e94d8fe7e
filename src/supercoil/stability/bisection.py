"""Locate where an integer stability count changes, by bisection (seed 000, sec. 6)."""

from __future__ import annotations

from collections.abc import Callable


def locate_count_change(count: Callable[[float], int], lo: float, hi: float, target: int,
                        rtol: float = 1e-10, max_steps: int = 200) -> float:
    """Parameter where ``count`` first reaches ``target`` between ``lo`` and ``hi``.

    ``count(lo) < target <= count(hi)`` is required (checked; ``ValueError``
    otherwise). Bisection on the exact count, so pair crossings (the count
    jumps by two, the determinant keeps its sign) are found as well. Returns
    the midpoint of the final bracket, of relative width ``rtol``.
    """
    c_lo, c_hi = count(lo), count(hi)
    if not (c_lo < target <= c_hi):
        raise ValueError(f"no bracket: count is {c_lo} at {lo:.6g} and {c_hi} at {hi:.6g}, "
                         f"target {target}")
    scale = max(abs(lo), abs(hi))
    for _ in range(max_steps):
        if hi - lo <= rtol * scale:
            break
        mid = 0.5 * (lo + hi)
        if count(mid) >= target:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)
