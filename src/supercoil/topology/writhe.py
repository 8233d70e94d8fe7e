"""Writhe of polygonal curves: the exact Gauss double integral as signed solid angles.

The writhe of a curve ``r(s)`` is Gauss's double integral

    Wr = (1/4π) ∮∮ (t1 × t2)·(r1 − r2) / |r1 − r2|³ ds1 ds2,

with ``t = dr/ds``. For a polygon the integral over a pair of straight edges
``A→B`` and ``C→D`` is exact (Banchoff 1976; Klenin & Langowski 2000):
the map ``(s1, s2) ↦ (r2 − r1)/|r2 − r1|`` sends the parameter square onto the
spherical quadrilateral with vertices

    v1 = C − A,   v2 = C − B,   v3 = D − B,   v4 = D − A   (projected on S²),

and the Gauss integral of the pair equals its signed area ``Ω`` (a solid angle,
``|Ω| < 2π``). We split the quadrilateral along ``v1–v3`` into two triangles and
use the Van Oosterom & Strackee (1983) formula for a signed triangle,

    tan(Ω_abc / 2) = a·(b × c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|),

which stays accurate for nearly planar configurations. The arcsin form of
Klenin & Langowski (2000) takes ``arcsin`` of dot products of unit normals that are
then close to ±1, where ``arcsin`` amplifies rounding to about ``√ε ≈ 1e-8``. Both triangles share the
numerator ``a·(b × c) = (e_i × e_j)·(A − C)`` (``e_i = B − A``, ``e_j = D − C``),
so with denominators ``D1``, ``D2`` the two half angles add as the argument of a
product of complex numbers:

    Ω_ij = 2 arg((D1 + iN)(D2 + iN)) = 2 atan2(N (D1 + D2), D1 D2 − N²),

a single ``atan2`` whose principal value is the right branch because
``|Ω_ij| < 2π``. In floating point that branch is not safe near ``|Ω_ij| = 2π``
(two edges nearly crossing): there ``D1 + D2 → 0`` and a rounding error in its
sign would return ``Ω ∓ 4π``, an error of ±2 in the writhe. Both half angles
``atan2(N, D_k)`` have the sign of ``N``, so ``Ω_ij`` has it too; the kernel
takes ``atan2(|N (D1 + D2)|, D1 D2 − N²) ∈ [0, π]`` and gives it the sign of
``N``, which is correct on both sides of ``|Ω| = 2π`` and costs one select.
Edges that share a vertex are coplanar and contribute exactly 0
and are skipped. The fast kernel evaluates that ``atan2`` with a branch-free
rational approximation (Cephes) so that the pair loop vectorises; the numpy
reference adds the two triangles' ``arctan2`` separately.
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
from typing import Literal

import numba
import numpy as np
import numpy.typing as npt

from supercoil._numba import njit
from supercoil.errors import InputError
from supercoil.topology.crossings import first_self_crossing

Closure = Literal["closed", "chord", "none", "axis"]

_CLOSURES: tuple[str, ...] = ("closed", "chord", "none", "axis")

__all__ = ["Closure", "writhe"]

# Polygons of at most this many edges are summed on one thread. Waking numba's
# OpenMP workers costs more than the work there: measured at N = 100 on the
# shared 2-core machine, with other work between calls (as in a continuation's
# records), 12 ms per writhe on two threads against 0.4 ms on one.
_SERIAL_BELOW = 1000




# --------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------


def _as_polygon(points: npt.ArrayLike, name: str, closed: bool) -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 ``(n_vertices, 3)`` array, or raise.

    Checks the shape, finiteness, the number of vertices (3 for a closed
    polygon, 2 for an open one) and that no edge (including the closing edge
    of a closed polygon) has zero length.
    """
    try:
        array = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(
            f"{name}: cannot be read as a float array ({error}); "
            "expected an (n_vertices, 3) array of coordinates", name=name
        ) from None
    if array.ndim != 2 or array.shape[1] != 3:
        raise InputError(
            f"{name} has shape {array.shape}; expected an (n_vertices, 3) array of coordinates",
            name=name)
    minimum = 3 if closed else 2
    if array.shape[0] < minimum:
        count = "1 vertex" if array.shape[0] == 1 else f"{array.shape[0]} vertices"
        kind = "a closed" if closed else "an open"
        raise InputError(f"{name} has {count}; {kind} polygon needs at least {minimum} vertices",
                         name=name)
    if not np.all(np.isfinite(array)):
        bad = int(np.argwhere(~np.isfinite(array))[0, 0])
        raise InputError(f"{name} has a non-finite coordinate at vertex {bad}; all must be finite",
                         name=name)
    following = np.roll(array, -1, axis=0) if closed else array[1:]
    lengths = np.linalg.norm(following - array[: following.shape[0]], axis=1)
    zero = np.flatnonzero(lengths == 0.0)
    if zero.size:
        k = int(zero[0])
        k_next = (k + 1) % array.shape[0]
        hint = (
            " (do not repeat the first vertex at the end of a closed polygon)"
            if closed and k == array.shape[0] - 1
            else ""
        )
        raise InputError(
            f"{name} has a zero-length edge between vertices {k} and {k_next}; "
            f"consecutive vertices must be distinct{hint}", name=name
        )
    return np.ascontiguousarray(array)


def _as_axis(axis: npt.ArrayLike) -> np.ndarray:
    """Return ``axis`` as a unit float64 vector of shape ``(3,)``, or raise."""
    try:
        vector = np.asarray(axis, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"axis {axis!r} is not a vector; expected 3 finite numbers",
                         name="axis") from None
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise InputError(f"axis {axis!r} is not a finite 3-vector; expected 3 finite numbers",
                         name="axis")
    norm = float(np.linalg.norm(vector))
    if norm == 0.0:
        raise InputError("axis is the zero vector; expected a non-zero direction", name="axis")
    return vector / norm


def _check_closure(closure: str) -> None:
    if closure not in _CLOSURES:
        raise InputError(f"closure {closure!r} is unknown; expected one of {', '.join(_CLOSURES)}",
                         name="closure")


def prepare_polygon(
    points: npt.ArrayLike, closure: str, axis: npt.ArrayLike, crossing_is_error: bool = True
) -> tuple[np.ndarray, bool, np.ndarray | None]:
    """Validate; return (vertices, closed polygon?, unit axis or None). A polygon that
    meets itself is an InputError, or with ``crossing_is_error=False`` gives vertices None
    (the writhe is undefined there)."""
    _check_closure(closure)
    closed = closure in ("closed", "chord")
    vertices = _as_polygon(points, "points", closed)
    unit_axis = _as_axis(axis) if closure == "axis" else None
    crossing = first_self_crossing(vertices, closed)
    if crossing is not None and not crossing_is_error:
        return None, closed, unit_axis
    if crossing is not None:
        i, j = crossing
        raise InputError(
            f"points: edges {i} and {j} of the polygon meet (it intersects itself), where its "
            "writhe is undefined (it jumps by 2 across a crossing); a polygon whose "
            "non-neighbouring edges are apart is valid", name="points")
    return vertices, closed, unit_axis


def extended_vertices(vertices: np.ndarray, closed: bool) -> np.ndarray:
    """Vertices with the first appended for a closed polygon: edge k is row k → row k+1."""
    if closed:
        return np.ascontiguousarray(np.vstack([vertices, vertices[:1]]))
    return vertices


def _components(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The x, y, z columns of ``(n, 3)`` ``vertices`` as three contiguous ``(n,)`` arrays."""
    columns = np.ascontiguousarray(vertices.T)
    return columns[0], columns[1], columns[2]


# --------------------------------------------------------------------------
# numpy reference
# --------------------------------------------------------------------------


# --------------------------------------------------------------------------
# numba fast path
# --------------------------------------------------------------------------


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
def _atan2(y: float, x: float) -> float:
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
def _row_half_angles(
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
    loop then has no loop-carried state and, with :func:`_atan2`, vectorises.
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
        magnitude = _atan2(abs(numerator * (den1 + den2)), den1 * den2 - numerator * numerator)
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
    """Rows ``k`` and ``n_edges − 1 − k`` of :func:`_self_half_angle_rows` (written into ``rows``)."""
    n_edges = nx.shape[0] - 1
    to_start = np.empty(n_edges + 1)
    to_end = np.empty(n_edges + 1)
    half_angle = np.empty(n_edges + 1)
    # in a closed polygon edges 0 and n_edges − 1 are adjacent
    stop = n_edges - 1 if closed and k == 0 else n_edges
    rows[k] = _row_half_angles(nx, ny, nz, k, nx, ny, nz, k + 2, stop, to_start, to_end, half_angle)
    mirror = n_edges - 1 - k
    if mirror != k:
        rows[mirror] = _row_half_angles(
            nx, ny, nz, mirror, nx, ny, nz, mirror + 2, n_edges, to_start, to_end, half_angle
        )


@njit(parallel=True, error_model="numpy")
def _self_half_angle_rows(
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
def _self_half_angle_rows_serial(
    nx: np.ndarray, ny: np.ndarray, nz: np.ndarray, closed: bool
) -> np.ndarray:
    """:func:`_self_half_angle_rows` on the calling thread (the same rows, bit for bit)."""
    n_edges = nx.shape[0] - 1
    rows = np.zeros(n_edges)
    for k in range((n_edges + 1) // 2):
        _mirrored_rows(nx, ny, nz, closed, k, rows)
    return rows


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
    nx, ny, nz = _components(extended_vertices(centred, closed))
    rows = (_self_half_angle_rows_serial if nx.size <= _SERIAL_BELOW else _self_half_angle_rows)
    half_angles = math.fsum(rows(nx, ny, nz, closed))
    if unit_axis is not None:
        half_angles += _tail_half_angles(np.ascontiguousarray(centred), unit_axis)
    return half_angles / math.pi
