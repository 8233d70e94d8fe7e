"""Distance between two pieces of a uniform cubic B-spline, with exact derivatives.

The pieces are those of :mod:`supercoil.contact.spline_pieces` (the B-spline whose
control points are the nodes, and why); their closest points are found by the
global search of :mod:`supercoil.contact.spline_kernels`.

Derivatives. ``r = C(s, t) X`` is linear in the 24 coordinates ``X`` of the
8 stencil nodes, ``C = c ⊗ I_3`` with ``c = (w_p(s), -w_q(t))``, ``w`` the
nodes' weights ``w_l(u) = sum_j B_j(u) control[j, l]``. By the envelope and
implicit function theorems, over the free parameters ``u``,

    grad h = C^T r,      hess h = C^T C - h_xu h_uu^{-1} h_ux,

with ``h_ss = |r_s|^2 + r.r_ss``, ``h_tt = |r_t|^2 + r.r_tt``, ``h_st =
r_s.r_t`` (``r_s = c_p'``, ``r_t = -c_q'``, ``r_ss = c_p''``, ``r_tt = -c_q''``)
and ``d h_s / dX = C_s^T r + C^T r_s`` (``C_s = (w_p', 0) ⊗ I``), likewise for
``t``; then ``grad d = c ⊗ r̂`` and ``hess d = (hess h - grad d grad d^T) / d``
as in :mod:`supercoil.contact.distance` (checked against finite differences
in ``tests/test_contact_spline.py``).

Near-parallel pieces (line contacts). The interior type's ``h_uu^{-1}`` blows
up where the valley of ``h`` is flat, i.e. where two pieces run parallel at a
constant distance (two strands of a plectoneme). As for the chords, when
``det h_uu <= parallel_tolerance h_ss h_tt`` (``sin^2`` of the angle between
the pieces for chords) :func:`piece_distance_derivatives` drops the interior
candidate and uses the best side or corner instead: exact when the valley is
flat, bounded derivatives, and above the interior minimum by at most about
``lambda_min / (2 d)`` with ``lambda_min <= parallel_tolerance h_ss h_tt /
(h_ss + h_tt)`` the valley's curvature (the valley leaves the square within a
unit parameter step): ``5e-7 ℓ^2 / d`` for ``ℓ`` the piece length at the
default tolerance. :func:`piece_distance` never drops it.

Degenerate cases. When ``d <= 1e-12`` times the larger piece length the
gradient and Hessian are returned as zeros (crossing pieces), as in
:mod:`supercoil.contact.distance`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from supercoil.contact.spline_kernels import derivative_kernel, distance_kernel, shadow_kernel
from supercoil.contact.spline_pieces import CurvePieces


def _pair_arrays(points, pieces: CurvePieces, pairs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = np.asarray(points, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or not np.isfinite(x).all():
        raise ValueError(f"points must be a finite array of shape (n, 3), got {x.shape}")
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    stencil = pieces.stencil[pairs].reshape(len(pairs), 8)  # (m, 8) node indices
    coef = pieces.coefficients[pairs]  # (m, 2, 4, 4)
    return np.ascontiguousarray(x[stencil]), np.ascontiguousarray(coef), stencil


def piece_distance(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distances ``d``, ``s``, ``t`` ``(m,)`` of the piece pairs ``pairs`` ``(m, 2)``.

    ``d = |c_i(s) - c_j(t)|`` is attained by the returned parameters; the
    interior candidate is never dropped (module docstring).
    """
    nodes, coef, _ = _pair_arrays(points, pieces, pairs)
    return piece_distance_of_nodes(nodes, coef)


def local_minimum_pairs(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike,
                        s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(m,)`` bool: whether pair ``(i, j)``'s minimiser ``(s, t)`` is a local minimum of
    the distance between the whole curves, not a *shadow* of a neighbouring pair.

    A minimiser on a side of the square where the piece continues into its
    neighbour (``u = 1`` with the distance still falling into the next piece,
    or ``u = 0`` with it falling into the previous one) is the end of a piece
    that a neighbouring pair sees closer: the same contact counted twice.
    Keeping only the other pairs counts each local minimum of the curve
    distance once (a minimum exactly at a junction belongs to the piece that
    starts there, up to a relative tolerance of 1e-10 on the slope).
    """
    nodes, coef, _ = _pair_arrays(points, pieces, pairs)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    joined = np.ascontiguousarray(pieces.joined_ends()[pairs])  # (m, 2, 2)
    shadow = np.empty(len(pairs), dtype=np.bool_)
    shadow_kernel(nodes, coef, joined, np.ascontiguousarray(s, dtype=np.float64),
                   np.ascontiguousarray(t, dtype=np.float64), shadow)
    return ~shadow


def piece_distance_of_nodes(nodes: np.ndarray, coef: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`piece_distance` of gathered stencils ``(m, 8, 3)`` with coefficients
    ``(m, 2, 4, 4)`` (``CurvePieces.coefficients`` of the two pieces)."""
    m = nodes.shape[0]
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    kinds = np.empty(m, dtype=np.int64)
    distance_kernel(np.ascontiguousarray(nodes, dtype=np.float64),
                     np.ascontiguousarray(coef, dtype=np.float64), d, s, t, kinds)
    return d, s, t


def piece_distance_derivatives(points: npt.ArrayLike, pieces: CurvePieces, pairs: npt.ArrayLike,
                               parallel_tolerance: float = 1e-6):
    """Distance, parameters, gradient, Hessian and type of piece pairs.

    Returns ``d, s, t`` ``(m,)``, ``gradient`` ``(m, 24)`` and ``hessian``
    ``(m, 24, 24)`` with respect to the coordinates of the 8 stencil nodes
    (index ``3 k + xyz``; nodes ``0..3`` those of ``pairs[:, 0]``, ``4..7``
    those of ``pairs[:, 1]``, given by ``nodes`` ``(m, 8)``), ``kind`` ``(m,)``
    (:class:`~supercoil.contact.distance_kernels.DistanceKind`) and ``nodes``. A
    stencil that repeats a node (ghost ends) has its entries summed by the
    caller's scatter. Near-parallel pieces use the sides (module docstring).
    """
    if not (np.isfinite(parallel_tolerance) and 0.0 <= parallel_tolerance < 1.0):
        raise ValueError(f"parallel_tolerance must be in [0, 1), got {parallel_tolerance!r}")
    x_nodes, coef, stencil = _pair_arrays(points, pieces, pairs)
    m = x_nodes.shape[0]
    d = np.empty(m)
    s = np.empty(m)
    t = np.empty(m)
    gradient = np.empty((m, 24))
    hessian = np.empty((m, 24, 24))
    kind = np.empty(m, dtype=np.int64)
    derivative_kernel(x_nodes, coef, float(parallel_tolerance), d, s, t, gradient, hessian,
                       kind)
    return d, s, t, gradient, hessian, kind, stencil
