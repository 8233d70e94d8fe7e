"""Linear stability of a straight rod clamped at both ends under tension and twist.

Greenhill's problem with tension (Greenhill 1883; Love, *Treatise*, sec.
270-272; van der Heijden, Neukirch, Goss & Thompson 2003, Int. J. Mech.
Sci. 45:161, sec. 3). A straight, twisted rod along ``z`` carries the
tension ``T`` and the axial moment ``M``. A small transverse deflection
``w = x + i y`` of the linearised Kirchhoff equations obeys

    A w'''' + i M w''' - T w'' = 0,

whose characteristic roots are ``r = 0`` (double) and ``r = i k`` with
``A k^2 + M k + T = 0``. Clamped ends, ``w = w' = 0`` at ``s = 0`` and at
``s = L`` (the tangents along the axis, the pulled end free to slide
axially only), leave a non-zero solution ``w = c1 + c2 s + c3 exp(i k1 s)
+ c4 exp(i k2 s)`` when the 4 x 4 determinant vanishes. With

    m = M L / (2 A),    t = T L^2 / A,    p = sqrt(m^2 - t)

(``k_{1,2} L = -m +- p``) the determinant reduces, after factoring out
``exp(-i m)`` and ``t``, to the condition

    g(m, t) = 2 p (cos p - cos m) - t sin p = 0.                       (*)

For ``t -> 0`` (*) vanishes to second order in ``t``; its limit is
Greenhill's clamped condition ``tan m = m``, i.e. ``M L / A = 2 x 4.4934 =
8.9868``. The straight rod is stable below the smallest root ``m_c(t) >
sqrt(t)`` (a tensioned rod needs ``M^2 > 4 A T`` at least, the infinite-rod
threshold) and loses stability there through a double eigenvalue (the
rotation about the axis turns one critical mode into a circle of them).
Twisting the rod by ``turns`` gives ``M = 2 pi C turns / L``, so the critical
number of turns is ``m_c / (pi C / A)``.
"""

from __future__ import annotations

import math

import numpy as np

GREENHILL_ZERO_TENSION = 8.986818916  # M L / A, 2 x the first positive root of tan x = x


def stability_function(m: float, t: float) -> float:
    """``g(m, t)`` of (*) (module doc) for ``m^2 > t``, ``t = F L^2 / A``, ``m = M L / 2A``."""
    p = math.sqrt(m * m - t)
    return 2.0 * p * (math.cos(p) - math.cos(m)) - t * math.sin(p)


def critical_moment(tension: float) -> float:
    """Smallest buckling moment ``M L / A`` of the clamped straight rod under ``F L^2 / A``.

    ``tension`` >= 0. At zero tension Greenhill's ``2 x 4.4934``; otherwise the
    first root of (*) above ``m = sqrt(t)`` (bracketed on a fine grid, then
    bisection, :func:`_bisect`). Raises ValueError for a negative tension (a compressed
    rod buckles without twist; not this problem).
    """
    t = float(tension)
    if not math.isfinite(t) or t < 0:
        raise ValueError(f"tension must be a finite number >= 0, got {tension!r}")
    if t < 1e-3:
        # (*) is O(t^2) small here: use its limit tan m = m (first root in (pi, 3pi/2))
        m = _bisect(lambda x: math.sin(x) - x * math.cos(x), math.pi, 1.5 * math.pi, 1e-15)
        return 2.0 * m
    start = math.sqrt(t) * (1.0 + 1e-12) + 1e-12
    grid = np.linspace(start, start + 4.0 * math.pi + 10.0, 4000)
    values = np.array([stability_function(m, t) for m in grid])
    # skip the spurious root at m = sqrt(t) (p = 0 makes g vanish)
    signs = np.sign(values[1:])
    change = np.flatnonzero(signs[:-1] * signs[1:] < 0)
    if change.size == 0:
        raise ValueError(f"no buckling moment found for tension {t}")
    i = change[0] + 1
    m = _bisect(lambda x: stability_function(x, t), float(grid[i]), float(grid[i + 1]), 1e-14)
    return 2.0 * m


def _bisect(f, lo: float, hi: float, xtol: float) -> float:
    """The zero of ``f`` in ``[lo, hi]`` (``f(lo)``, ``f(hi)`` of opposite signs) to within
    ``xtol``, or to the spacing of the floats there, by bisection.

    About 40-50 evaluations of a cheap ``f`` here (a bracket of 5e-3 or pi/2 halved down
    to 1e-14 or 1e-15), a few tens of microseconds; scipy's ``brentq`` finds the same
    zero to the same tolerance, but importing ``scipy.optimize`` brings
    ``scipy.spatial``, ``scipy.special`` and ``scipy.fft`` into every command's start.
    """
    f_lo = f(lo)
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):  # adjacent floats
            break
        f_mid = f(mid)
        if f_mid == 0.0:
            return mid
        if (f_mid < 0.0) == (f_lo < 0.0):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def critical_turns(twist_ratio: float, tension: float) -> float:
    """Turns at which the clamped straight rod buckles: ``(M L / A) / (2 pi C / A)``."""
    if not (math.isfinite(twist_ratio) and twist_ratio > 0):
        raise ValueError(f"twist_ratio must be positive, got {twist_ratio!r}")
    return critical_moment(tension) / (2.0 * math.pi * twist_ratio)
