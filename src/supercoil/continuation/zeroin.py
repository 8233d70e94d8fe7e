"""Brent's method for the zeros that locate events, with known end values and a guess.

:func:`zeroin` takes the steps of scipy's ``brentq`` (Brent 1973: secant and
inverse quadratic interpolation safeguarded by bisection), and also the values at the ends when
they are known and a first iterate (e.g. the zero of a Hermite interpolant), so that
an event costs fewer corrections; :func:`brentq_reference` is scipy's ``brentq`` with
the same tolerances.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np


class LocationFailed(RuntimeError):
    """A trial correction inside a bracket did not converge, or a zero was not located."""


RTOL = 4 * np.finfo(float).eps  # brentq's rtol here: the root's relative round-off


def brentq_reference(f, lo: float, hi: float, xtol: float) -> float:
    """scipy's ``brentq`` with this module's tolerances (the reference for :func:`zeroin`)."""
    from scipy.optimize import brentq  # not at the top: scipy.optimize takes ~0.1 s to import

    return float(brentq(f, lo, hi, xtol=xtol, rtol=RTOL, maxiter=200))


def zeroin(f: Callable[[float], float], lo: float, hi: float, xtol: float,
           f_lo: float | None = None, f_hi: float | None = None,
           guess: float | None = None, maxiter: int = 200) -> float:
    """A zero of ``f`` in ``[lo, hi]`` by Brent's method, as scipy's ``brentq`` (the same
    steps, the same result without ``guess``, and the same stopping rule: the returned
    point ``x`` is the end with the smaller ``|f|`` of a bracket ``[x, x_other]`` with a
    sign change and ``|x_other - x| < xtol + RTOL |x|``, or an exact zero), with two
    differences.

    * ``f_lo``, ``f_hi``: the values at the ends when they are known (accepted
      points' user values, tangents), so that they are not evaluated.
    * ``guess``: a first iterate inside the bracket (e.g. the zero of a Hermite
      interpolant, :func:`~supercoil.continuation.events._fold_guess`), evaluated
      before any other point. The method then continues with inverse quadratic interpolation through the
      guess and both ends (the guess being the current iterate, the end of its
      sign the previous one, the other end the contrapoint), so a good guess
      saves the first secant steps.

    Raises ValueError when the end values have the same sign (as ``brentq``), and
    :class:`LocationFailed` when ``maxiter`` steps did not close the bracket (``brentq``
    raised RuntimeError).
    """
    f_lo = f(lo) if f_lo is None else f_lo
    f_hi = f(hi) if f_hi is None else f_hi
    if f_lo == 0:
        return lo
    if f_hi == 0:
        return hi
    if f_lo * f_hi > 0:
        raise ValueError("f(lo) and f(hi) must have different signs")
    x_pre, f_pre, x_cur, f_cur = lo, f_lo, hi, f_hi
    x_blk, f_blk, s_pre, s_cur = 0.0, 0.0, 0.0, 0.0
    if guess is not None and min(lo, hi) < guess < max(lo, hi):
        f_g = f(guess)
        if f_g == 0:
            return guess
        # the end of the guess's sign is the previous iterate, the other the contrapoint
        same, other = ((lo, f_lo), (hi, f_hi)) if np.signbit(f_g) == np.signbit(f_lo) \
            else ((hi, f_hi), (lo, f_lo))
        x_pre, f_pre = same
        x_blk, f_blk = other
        x_cur, f_cur = guess, f_g
        s_pre = s_cur = hi - lo  # as brentq's start: interpolation allowed at once
    for _ in range(maxiter):
        if f_pre != 0 and f_cur != 0 and np.signbit(f_pre) != np.signbit(f_cur):
            x_blk, f_blk = x_pre, f_pre
            s_pre = s_cur = x_cur - x_pre
        if abs(f_blk) < abs(f_cur):
            x_pre, x_cur, x_blk = x_cur, x_blk, x_cur
            f_pre, f_cur, f_blk = f_cur, f_blk, f_cur
        delta = 0.5 * (xtol + RTOL * abs(x_cur))
        s_bis = 0.5 * (x_blk - x_cur)
        if f_cur == 0 or abs(s_bis) < delta:
            return x_cur
        if abs(s_pre) > delta and abs(f_cur) < abs(f_pre):
            try:
                if x_pre == x_blk:  # secant
                    s_try = -f_cur * (x_cur - x_pre) / (f_cur - f_pre)
                else:  # inverse quadratic interpolation
                    d_pre = (f_pre - f_cur) / (x_pre - x_cur)
                    d_blk = (f_blk - f_cur) / (x_blk - x_cur)
                    s_try = -f_cur * (f_blk * d_blk - f_pre * d_pre) / (
                        d_blk * d_pre * (f_blk - f_pre))
            except ZeroDivisionError:
                # brentq's C arithmetic gives inf or nan here and bisects (measured: tiny
                # values, |f| ~ 1e-110, underflow the differences to zero)
                s_try = math.inf
            if not math.isfinite(s_try):
                s_try = math.inf
            if 2 * abs(s_try) < min(abs(s_pre), 3 * abs(s_bis) - delta):
                s_pre, s_cur = s_cur, s_try
            else:
                s_pre = s_cur = s_bis
        else:
            s_pre = s_cur = s_bis
        x_pre, f_pre = x_cur, f_cur
        x_cur += s_cur if abs(s_cur) > delta else (delta if s_bis > 0 else -delta)
        f_cur = f(x_cur)
    raise LocationFailed(f"no zero located to {xtol:.1e} in {maxiter} iterations "
                         f"(bracket [{min(x_cur, x_blk):.10g}, {max(x_cur, x_blk):.10g}])")
