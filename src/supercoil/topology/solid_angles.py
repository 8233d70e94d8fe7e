"""The Gauss integral of two polygon edges: a signed solid angle, summed by compiled rows.

For two straight edges ``A→B`` and ``C→D`` the Gauss integral
``(1/4π) ∫∫ (t1 × t2)·(r1 − r2) / |r1 − r2|³ ds1 ds2`` is exact (Banchoff 1976;
Klenin & Langowski 2000): the map ``(s1, s2) ↦ (r2 − r1)/|r2 − r1|`` sends the
parameter square onto the spherical quadrilateral with vertices

    v1 = C − A,   v2 = C − B,   v3 = D − B,   v4 = D − A   (projected on S²),

and the integral of the pair is its signed area ``Ω`` over 4π (a solid angle,
``|Ω| < 2π``). We split the quadrilateral along ``v1–v3`` into two triangles and
use the Van Oosterom & Strackee (1983) formula for a signed triangle,

    tan(Ω_abc / 2) = a·(b × c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|),

which stays accurate for nearly planar configurations. The arcsin form of
Klenin & Langowski (2000) takes ``arcsin`` of dot products of unit normals that are
then close to ±1, where ``arcsin`` amplifies rounding to about ``√ε ≈ 1e-8``. Both
triangles share the numerator ``a·(b × c) = (e_i × e_j)·(A − C)`` (``e_i = B − A``,
``e_j = D − C``), so with denominators ``D1``, ``D2`` the two half angles add as the
argument of a product of complex numbers:

    Ω_ij = 2 arg((D1 + iN)(D2 + iN)) = 2 atan2(N (D1 + D2), D1 D2 − N²),

a single ``atan2`` whose principal value is the right branch because
``|Ω_ij| < 2π``. In floating point that branch is not safe near ``|Ω_ij| = 2π``
(two edges nearly crossing): there ``D1 + D2 → 0`` and a rounding error in its
sign would return ``Ω ∓ 4π``, an error of ±2 in the writhe. Both half angles
``atan2(N, D_k)`` have the sign of ``N``, so ``Ω_ij`` has it too; the kernel
takes ``atan2(|N (D1 + D2)|, D1 D2 − N²) ∈ [0, π]`` and gives it the sign of
``N``, which is correct on both sides of ``|Ω| = 2π`` and costs one select.
Edges that share a vertex are coplanar and contribute exactly 0
and are skipped. The kernel evaluates that ``atan2`` with a branch-free
rational approximation (Cephes, :func:`branch_free_atan2`) so that the pair loop
vectorises; the numpy reference (:mod:`supercoil.topology.writhe_reference`) adds the
two triangles' ``arctan2`` separately.

:func:`row_half_angles` sums one edge against a run of edges of a curve (the
writhe's rows, and the linking number's in :mod:`supercoil.topology.linking`);
:func:`self_half_angle_rows` gives the rows of one polygon with itself, on all cores,
and :func:`self_half_angle_rows_serial` the same rows on the calling thread.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from supercoil._numba import njit

__all__ = ["branch_free_atan2", "row_half_angles", "self_half_angle_rows",
           "self_half_angle_rows_serial"]

# Cephes ``atan`` coefficients (S. L. Moshier): atan(t) = t + t z P(z)/Q(z), z = t²,
# |t| ≤ tan(π/8); relative error about 1e-16.
_P0, _P1, _P2, _P3, _P4 = (
    -8.750608600031904122785e-1,
    -1.615753718733365076637e1,
    -7.500855792314704667340e1,
    -1.228866684490136173410e2,
    -6.485021904942025371773e1,
)
_Q0, _Q1, _Q2, _Q3, _Q4 = (
    2.485846490142306297962e1,
    1.650270098316988542046e2,
    4.328810604912902668951e2,
    4.853903996359136964868e2,
    1.945506571482613964425e2,
)
_TAN_PI_8 = 0.41421356237309504880


@njit(inline="always", error_model="numpy")
def branch_free_atan2(y: float, x: float) -> float:
    """``atan2(y, x)`` in ``[−π, π]`` without branches, so that loops calling it vectorise.

    ``libm``'s ``atan2`` is an opaque call that keeps the pair loop scalar and
    takes two thirds of its time. Here: ``t = min(|x|,|y|)/max(|x|,|y|) ∈ [0, 1]``,
    reduced to ``|t'| ≤ tan(π/8)`` by ``t' = (t − 1)/(t + 1)`` (adding π/4),
    the Cephes rational approximation, then the octant is restored by selects.
    Agrees with ``math.atan2`` to a few units in the last place; ``atan2(0, 0) = 0``;
    the sign of a zero ``y`` is ignored (only reached for ``x < 0``, i.e. a
    pair subtending a solid angle of exactly 2π, which non-touching edges never do).
    """
    ax = abs(x)
    ay = abs(y)
    swap = ay > ax
    hi = ay if swap else ax
    lo = ax if swap else ay
    reduce = lo > _TAN_PI_8 * hi
    numerator = lo - hi if reduce else lo
    denominator = lo + hi if reduce else hi
    t = numerator / denominator if denominator > 0.0 else 0.0
    z = t * t
    p = (((_P0 * z + _P1) * z + _P2) * z + _P3) * z + _P4
    q = ((((z + _Q0) * z + _Q1) * z + _Q2) * z + _Q3) * z + _Q4
    angle = t + t * z * p / q
    angle = angle + 0.25 * math.pi if reduce else angle
    angle = 0.5 * math.pi - angle if swap else angle
    angle = math.pi - angle if x < 0.0 else angle
    return -angle if y < 0.0 else angle


@njit(error_model="numpy")
def row_half_angles(
    sx: np.ndarray,
    sy: np.ndarray,
    sz: np.ndarray,
    i: int,
    cx: np.ndarray,
    cy: np.ndarray,
    cz: np.ndarray,
    j_start: int,
    j_stop: int,
    to_start: np.ndarray,
    to_end: np.ndarray,
    half_angle: np.ndarray,
) -> float:
    """Σ_j Ω_ij / 2 of edge ``i`` of curve ``s`` with edges ``j ∈ [j_start, j_stop)`` of ``c``.

    Coordinates are split by component (``sx``, ``sy``, ``sz`` of shape
    ``(n_s,)``; ``cx``, ``cy``, ``cz`` of shape ``(n_c,)``; edge ``k`` runs from
    entry ``k`` to ``k+1``). ``to_start``, ``to_end``, ``half_angle`` are
    ``(n_c,)`` scratch arrays. The distances from the two ends of edge ``i`` to
    every column vertex are computed once (each serves two pairs); the pair
    loop then has no loop-carried state and, with :func:`branch_free_atan2`, vectorises.
    """
    if j_stop <= j_start:
        return 0.0
    ax, ay, az = sx[i], sy[i], sz[i]
    bx, by, bz = sx[i + 1], sy[i + 1], sz[i + 1]
    eix, eiy, eiz = bx - ax, by - ay, bz - az
    for j in range(j_start, j_stop + 1):
        ux, uy, uz = cx[j] - ax, cy[j] - ay, cz[j] - az
        wx, wy, wz = cx[j] - bx, cy[j] - by, cz[j] - bz
        to_start[j] = math.sqrt(ux * ux + uy * uy + uz * uz)
        to_end[j] = math.sqrt(wx * wx + wy * wy + wz * wz)
    for j in range(j_start, j_stop):
        # v1 = C − A, v2 = C − B, v3 = D − B, v4 = D − A for the edge pair (A→B, C→D)
        v1x, v1y, v1z = cx[j] - ax, cy[j] - ay, cz[j] - az
        v2x, v2y, v2z = cx[j] - bx, cy[j] - by, cz[j] - bz
        v3x, v3y, v3z = cx[j + 1] - bx, cy[j + 1] - by, cz[j + 1] - bz
        v4x, v4y, v4z = cx[j + 1] - ax, cy[j + 1] - ay, cz[j + 1] - az
        ejx, ejy, ejz = cx[j + 1] - cx[j], cy[j + 1] - cy[j], cz[j + 1] - cz[j]
        l1, l2, l3, l4 = to_start[j], to_end[j], to_end[j + 1], to_start[j + 1]
        # N = v1·(v2 × v3) = v1·(v3 × v4) = −v1·(e_i × e_j)
        numerator = -(
            v1x * (eiy * ejz - eiz * ejy)
            + v1y * (eiz * ejx - eix * ejz)
            + v1z * (eix * ejy - eiy * ejx)
        )
        d12 = v1x * v2x + v1y * v2y + v1z * v2z
        d13 = v1x * v3x + v1y * v3y + v1z * v3z
        d23 = v2x * v3x + v2y * v3y + v2z * v3z
        d14 = v1x * v4x + v1y * v4y + v1z * v4z
        d34 = v3x * v4x + v3y * v4y + v3z * v4z
        den1 = l1 * l2 * l3 + d12 * l3 + d13 * l2 + d23 * l1
        den2 = l1 * l3 * l4 + d13 * l4 + d14 * l3 + d34 * l1
        # Ω/2 = atan2(N, D1) + atan2(N, D2) has the sign of N and |Ω/2| < π, so the
        # combined atan2 is taken with |imaginary part| and the sign of N restored:
        # near |Ω| = 2π (nearly crossing edges) D1 + D2 → 0 and its rounded sign
        # would otherwise pick the wrong branch (an error of ±2 in the writhe).
        magnitude = branch_free_atan2(abs(numerator * (den1 + den2)), den1 * den2 - numerator * numerator)
        half_angle[j] = -magnitude if numerator < 0.0 else magnitude
    # four partial sums: a fixed order (reproducible) that does not serialise on one adder
    s0 = s1 = s2 = s3 = 0.0
    j = j_start
    while j + 3 < j_stop:
        s0 += half_angle[j]
        s1 += half_angle[j + 1]
        s2 += half_angle[j + 2]
        s3 += half_angle[j + 3]
        j += 4
    while j < j_stop:
        s0 += half_angle[j]
        j += 1
    return (s0 + s1) + (s2 + s3)


@njit(error_model="numpy")
def _mirrored_rows(nx, ny, nz, closed, k, rows):
    """Rows ``k`` and ``n_edges − 1 − k`` of :func:`self_half_angle_rows` (written into ``rows``)."""
    n_edges = nx.shape[0] - 1
    to_start = np.empty(n_edges + 1)
    to_end = np.empty(n_edges + 1)
    half_angle = np.empty(n_edges + 1)
    # in a closed polygon edges 0 and n_edges − 1 are adjacent
    stop = n_edges - 1 if closed and k == 0 else n_edges
    rows[k] = row_half_angles(nx, ny, nz, k, nx, ny, nz, k + 2, stop, to_start, to_end, half_angle)
    mirror = n_edges - 1 - k
    if mirror != k:
        rows[mirror] = row_half_angles(
            nx, ny, nz, mirror, nx, ny, nz, mirror + 2, n_edges, to_start, to_end, half_angle
        )


@njit(parallel=True, error_model="numpy")
def self_half_angle_rows(
    nx: np.ndarray, ny: np.ndarray, nz: np.ndarray, closed: bool
) -> np.ndarray:
    """Row sums ``(n_edges,)`` of Ω_ij/2 over non-adjacent pairs ``i < j`` of one polygon.

    ``nx``, ``ny``, ``nz`` are ``(n_edges + 1,)``: edge k runs from entry k to
    k+1. Rows ``k`` and ``n_edges − 1 − k`` are handled by the same loop
    iteration so that every iteration has about the same number of pairs
    (numba's ``prange`` splits iterations statically).
    """
    n_edges = nx.shape[0] - 1
    rows = np.zeros(n_edges)
    for k in numba.prange((n_edges + 1) // 2):
        _mirrored_rows(nx, ny, nz, closed, k, rows)
    return rows


@njit(error_model="numpy")
def self_half_angle_rows_serial(
    nx: np.ndarray, ny: np.ndarray, nz: np.ndarray, closed: bool
) -> np.ndarray:
    """:func:`self_half_angle_rows` on the calling thread (the same rows, bit for bit)."""
    n_edges = nx.shape[0] - 1
    rows = np.zeros(n_edges)
    for k in range((n_edges + 1) // 2):
        _mirrored_rows(nx, ny, nz, closed, k, rows)
    return rows
