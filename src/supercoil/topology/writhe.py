"""Writhe of polygonal curves: the exact Gauss double integral as signed solid angles.

The writhe of a curve ``r(s)`` is Gauss's double integral

    Wr = (1/4π) ∮∮ (t1 × t2)·(r1 − r2) / |r1 − r2|³ ds1 ds2,

with ``t = dr/ds``. For a polygon the integral over a pair of straight edges
``A→B`` and ``C→D`` is exact (Banchoff 1976; Klenin & Langowski 2000):
the map ``(s1, s2) ↦ (r2 − r1)/|r2 − r1|`` sends the parameter square onto the
spherical quadrilateral with vertices

    v1 = C − A,   v2 = C − B,   v3 = D − B,   v4 = D − A   (projected on S²),

and the Gauss integral of the pair equals its signed area ``Ω`` (a solid angle,
``|Ω| < 2π``), evaluated as two Van Oosterom & Strackee (1983) triangles combined into
one ``atan2`` (:mod:`supercoil.topology.solid_angles` derives it and sums the pairs).
The pair integral is symmetric, so

    Wr = (1/4π) Σ_{i≠j} Ω_ij = (1/2π) Σ_{i<j} Ω_ij.

Sign convention: a right-handed helix has positive writhe.

References
----------
- C. F. Gauss (1833), the linking integral.
- T. Banchoff, Indiana Univ. Math. J. 25 (1976) 1171–1188: self-linking of
  space polygons (the Gauss map of two edges is a spherical quadrilateral).
- G. Călugăreanu (1959); J. H. White (1969); F. B. Fuller (1971, 1978):
  ``Lk = Tw + Wr`` and Fuller's single-integral formula for the writhe.
- A. van Oosterom & J. Strackee, IEEE Trans. Biomed. Eng. 30 (1983) 125–126:
  the solid angle of a plane triangle.
- K. Klenin & J. Langowski, Biopolymers 54 (2000) 307–317: exact writhe of a
  polygon (arcsin form).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from supercoil._numba import njit
from supercoil.errors import InputError
from supercoil.topology.polygon import (
    Closure,
    coordinate_columns,
    extended_vertices,
    prepare_polygon,
)
from supercoil.topology.solid_angles import self_half_angle_rows, self_half_angle_rows_serial

__all__ = ["writhe"]

# Polygons of at most this many edges are summed on one thread. Waking numba's
# OpenMP workers costs more than the work there: measured at N = 100 on the
# shared 2-core machine, with other work between calls (as in a continuation's
# records), 12 ms per writhe on two threads against 0.4 ms on one.
_SERIAL_BELOW = 1000


@njit()
def _tail_half_angles(vertices: np.ndarray, axis: np.ndarray) -> float:
    """Σ over edges of the Gauss integrals with the two axial tails, halved.

    Upper tail (ray ``P + s·axis``, ``s ≥ 0``, ``P`` the last vertex), edge ``A→B``:
    ``Ω = 2 atan2(u·(w × a), |u||w| + u·w + (u·a)|w| + (w·a)|u|)``, ``u = P − A``,
    ``w = P − B``. Lower tail (``Q + s·axis``, ``s ≤ 0``, ``Q`` the first vertex):
    the same with ``u = Q − A``, ``w = Q − B`` and the two ``a`` terms of the
    denominator negated. Edges touching the tail's vertex contribute 0.
    """
    n_vertices = vertices.shape[0]
    axx, axy, axz = axis[0], axis[1], axis[2]
    total = 0.0
    for which in range(2):
        if which == 0:
            anchor = n_vertices - 1
            sign = 1.0
            first, stop = 0, n_vertices - 2
        else:
            anchor = 0
            sign = -1.0
            first, stop = 1, n_vertices - 1
        px, py, pz = vertices[anchor, 0], vertices[anchor, 1], vertices[anchor, 2]
        for k in range(first, stop):
            ux = px - vertices[k, 0]
            uy = py - vertices[k, 1]
            uz = pz - vertices[k, 2]
            wx = px - vertices[k + 1, 0]
            wy = py - vertices[k + 1, 1]
            wz = pz - vertices[k + 1, 2]
            lu = math.sqrt(ux * ux + uy * uy + uz * uz)
            lw = math.sqrt(wx * wx + wy * wy + wz * wz)
            triple = (
                ux * (wy * axz - wz * axy) + uy * (wz * axx - wx * axz) + uz * (wx * axy - wy * axx)
            )
            ua = ux * axx + uy * axy + uz * axz
            wa = wx * axx + wy * axy + wz * axz
            denominator = lu * lw + (ux * wx + uy * wy + uz * wz) + sign * (ua * lw + wa * lu)
            total += math.atan2(triple, denominator)
    return total


def writhe(
    points: npt.ArrayLike,
    closure: Closure = "closed",
    axis: npt.ArrayLike = (0.0, 0.0, 1.0),
    *,
    self_crossing: str = "error",
) -> float:
    """Writhe of a polygonal curve, exact for the polygon (Gauss integral as solid angles).

    Parameters
    ----------
    points
        ``(n_vertices, 3)`` polygon vertices, each vertex once (a closed polygon
        must not repeat its first vertex at the end).
    closure
        How the curve is closed before the Gauss integral is taken:

        - ``"closed"``: a closed polygon; the edge from the last vertex back to
          the first is part of the curve (at least 3 vertices).
        - ``"chord"``: an open curve closed by the straight chord from its last
          vertex to its first. Numerically identical to ``"closed"``; kept as a
          separate name so that callers state which convention they report.
        - ``"none"``: the open polygon alone, ``(1/4π) Σ_{i≠j}`` over its own
          ``n_vertices − 1`` edges (not a topological quantity).
        - ``"axis"``: an open curve closed by two straight semi-infinite tails
          parallel to ``axis``: the first vertex continues to −∞ along
          ``−axis``, the last to +∞ along ``+axis``, the tails joined at
          infinity (the convention of magnetic-tweezers experiments).
    axis
        Direction ``(3,)`` of the tails for ``closure="axis"`` (normalised here).
    self_crossing
        What a polygon that meets itself gives, where the writhe is undefined (it
        jumps by 2 across a crossing): ``"error"`` (an InputError) or ``"nan"``
        (for the records of a rod allowed to pass through itself).

    Returns
    -------
    float
        ``Wr = (1/4π) ∮∮ (t1 × t2)·(r1 − r2)/|r1 − r2|³ ds1 ds2``; a right-handed
        helix has positive writhe.

    Notes
    -----
    Edge pairs: see the module docstring (Van Oosterom & Strackee 1983 triangles
    combined into one ``atan2``).

    Tails (``closure="axis"``). Take an edge ``A→B`` and the upper tail
    ``r2(s) = P + s a``, ``s ∈ [0, ∞)``, ``|a| = 1``. The Gauss integrand is the
    pull-back of the area form of S² by ``(s1, s2) ↦ (r2 − r1)/|r2 − r1|``; the
    corners of the parameter strip map to ``P − A``, ``P − B`` and, for every
    ``s1``, ``s2 → ∞`` maps to the single point ``a`` (the vertex at infinity).
    The sides are arcs of great circles, so the integral is the signed solid
    angle of the spherical triangle ``(P − A, P − B, a)``:

        Ω_+ = 2 atan2(u·(w × a), |u||w| + u·w + (u·a)|w| + (w·a)|u|),
        u = P − A, w = P − B.

    The lower tail ``r2(s) = Q + s a``, ``s ∈ (−∞, 0]``, traversed towards
    ``Q``, maps its end at infinity to ``−a`` and the boundary is run the other
    way: ``Ω_− = −Ω(Q − A, Q − B, −a)``, i.e. the formula above with
    ``u = Q − A``, ``w = Q − B`` and the ``(u·a)``, ``(w·a)`` terms negated. The
    tails are parallel, so tail–tail integrands vanish (``t1 × t2 = 0``); an
    edge touching a tail's vertex is coplanar with it and contributes 0; the
    arc at infinity contributes nothing. Hence

        Wr = (1/2π) [Σ_{i<j} Ω_ij + Σ_i (Ω_{i,+} + Ω_{i,−})].

    The result is meaningful only if neither tail meets the curve.

    Cost: ``O(N²)`` pairs, on all cores (numba ``prange``, rows paired for load
    balance), the pair loop vectorised (SIMD) through a branch-free ``atan2``;
    ``N = 5000`` takes 0.1–0.2 s on two cores (``benchmarks/bench_writhe.py``).
    The points are centred and scaled to unit size first (the writhe is
    invariant under both), which keeps intermediate products in range.

    Raises
    ------
    InputError
        Unknown ``closure``; ``points`` not ``(n_vertices, 3)``, non-finite,
        too few vertices (3 closed, 2 open) or with a zero-length edge; a
        polygon that meets itself (two edges within ``1e-15`` of its extent, or
        two consecutive edges folding back), where the writhe is undefined; a
        zero or non-finite ``axis``.
    """
    if self_crossing not in ("error", "nan"):
        raise InputError(f"self_crossing: got {self_crossing!r}; valid: 'error' or 'nan'",
                         name="self_crossing")
    vertices, closed, unit_axis = prepare_polygon(points, closure, axis, self_crossing == "error")
    if vertices is None:
        return math.nan
    centred = vertices - vertices.mean(axis=0)
    scale = float(np.max(np.abs(centred)))
    if scale > 0.0:
        centred = centred / scale
    nx, ny, nz = coordinate_columns(extended_vertices(centred, closed))
    rows = (self_half_angle_rows_serial if nx.size <= _SERIAL_BELOW else self_half_angle_rows)
    half_angles = math.fsum(rows(nx, ny, nz, closed))
    if unit_axis is not None:
        half_angles += _tail_half_angles(np.ascontiguousarray(centred), unit_axis)
    return half_angles / math.pi
