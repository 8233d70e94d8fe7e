"""Gauss linking number of two closed polygons, exact, as a sum of signed solid angles.

    Lk(C1, C2) = (1/4π) ∮_{C1} ∮_{C2} (t1 × t2)·(r1 − r2) / |r1 − r2|³ ds1 ds2
               = (1/4π) Σ_{i ∈ C1} Σ_{j ∈ C2} Ω_ij,

where ``Ω_ij`` is the Gauss integral of edge ``i`` of ``C1`` with edge ``j`` of
``C2``: the signed solid angle of the spherical quadrilateral of the four
vertex differences (Banchoff 1976; Klenin & Langowski 2000), evaluated with the
Van Oosterom & Strackee (1983) ``atan2`` form exactly as for the writhe (see
:mod:`supercoil.topology.solid_angles`). With this sign convention ``Lk = +1`` when
``C2`` passes through a disc bounded by ``C1`` along the disc's right-hand
normal (Ampère's law), and ``Lk(C, C') = Tw + Wr`` for a push-off ``C'`` of ``C``
along a ribbon (Călugăreanu 1959, White 1969).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

from supercoil._numba import njit
from supercoil.errors import InputError
from supercoil.topology.crossings import first_crossing
from supercoil.topology.polygon import as_polygon, coordinate_columns, extended_vertices
from supercoil.topology.solid_angles import row_half_angles

__all__ = ["linking_number"]


@njit(parallel=True, error_model="numpy")
def _linking_half_angle_rows(
    ax: np.ndarray, ay: np.ndarray, az: np.ndarray, bx: np.ndarray, by: np.ndarray, bz: np.ndarray
) -> np.ndarray:
    """Row sums ``(n1,)`` of Ω_ij/2 over all edges ``j`` of curve 2, for each edge ``i`` of curve 1.

    Inputs are the coordinates, split by component, of the two closed polygons
    with their first vertex repeated at the end (shapes ``(n1 + 1,)`` and
    ``(n2 + 1,)``).
    """
    n1 = ax.shape[0] - 1
    n2 = bx.shape[0] - 1
    rows = np.zeros(n1)
    for i in numba.prange(n1):
        to_start = np.empty(n2 + 1)
        to_end = np.empty(n2 + 1)
        half_angle = np.empty(n2 + 1)
        rows[i] = row_half_angles(ax, ay, az, i, bx, by, bz, 0, n2, to_start, to_end, half_angle)
    return rows


def linking_number(curve1: npt.ArrayLike, curve2: npt.ArrayLike) -> float:
    """Gauss linking number of two closed polygons (exact for the polygons).

    Parameters
    ----------
    curve1, curve2
        ``(n1, 3)`` and ``(n2, 3)`` vertices of two closed polygons, each
        vertex once (the edge from the last vertex back to the first is
        implied); at least 3 vertices each.

    Returns
    -------
    float
        ``Lk = (1/4π) Σ_{i,j} Ω_ij``, an integer up to rounding (about 1e-12)
        when the polygons are disjoint; returned unrounded so that callers can
        check it.

    Raises
    ------
    InputError
        A curve that is not ``(n, 3)``, non-finite, has fewer than 3 vertices
        or a zero-length edge; the same curve twice; curves that meet (an edge
        of one within ``1e-15`` of their extent of an edge of the other), where
        the linking number is undefined (a jump by ±1).
    """
    first = as_polygon(curve1, "curve1", closed=True)
    second = as_polygon(curve2, "curve2", closed=True)
    if first.shape == second.shape and np.array_equal(first, second):
        raise InputError("curve2 is curve1 (the same vertices): the linking number of a "
                         "curve with itself is undefined (its self-linking needs a framing, "
                         "Lk = Tw + Wr); give two disjoint closed curves", name="curve2")
    crossing = first_crossing(first, second)
    if crossing is not None:
        i, j = crossing
        raise InputError(f"curve2: edge {j} meets edge {i} of curve1, where the linking "
                         "number is undefined (it jumps by 1 across a crossing); give two "
                         "disjoint closed curves", name="curve2")
    # a common translation and scale leave Lk unchanged and keep products in range
    centre = np.vstack([first, second]).mean(axis=0)
    scale = float(max(np.max(np.abs(first - centre)), np.max(np.abs(second - centre))))
    first = (first - centre) / scale
    second = (second - centre) / scale
    ax, ay, az = coordinate_columns(extended_vertices(first, closed=True))
    bx, by, bz = coordinate_columns(extended_vertices(second, closed=True))
    return math.fsum(_linking_half_angle_rows(ax, ay, az, bx, by, bz)) / (2.0 * math.pi)
