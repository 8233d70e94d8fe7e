"""Cubic B-spline pieces of a polygon: the curve whose distance is the spline contact distance.

Why a spline. A polygon's chord sags inside the smooth curve through its
nodes by up to ``h^2 kappa / 8``, and by nothing at the nodes, so a contact
distance measured between chords depends on where the nodes sit relative to
the contact: a ripple of period ``h`` that locks contacts to the mesh and
breaks the material-sliding symmetry of a closed homogeneous rod
(docs/continuation.md, "Closed rods: the sliding gauge and the pins"). The uniform
cubic B-spline whose control points are the nodes has discrete moments that
are shift invariant up to degree 3: for nodes ``x_k = x(s_0 + k h)`` sampled
from a smooth curve, ``c(s) = x(s) + (h^2 / 6) x''(s) + O(h^4)`` whatever the
sampling phase ``s_0``, so the ripple falls to ``O(h^4)`` (measured in
``tests/test_contact_spline.py``: observed orders about 4 for the spline and 2
for the chords). An interpolating (Catmull–Rom) spline has no phase-independent
leading error and is not used.

Pieces. Piece ``i`` (the segment from node ``a_i`` to node ``b_i``) is

    c_i(u) = sum_{k=0..3} B_k(u) P_{i,k},  u in [0, 1],

``B_0 = (1-u)^3/6``, ``B_1 = (3u^3 - 6u^2 + 4)/6``, ``B_2 = (-3u^3 + 3u^2 +
3u + 1)/6``, ``B_3 = u^3/6``, with control points ``P_i = (x_{i-1}, x_i,
x_{i+1}, x_{i+2})`` on a closed rod (indices wrap). Each control point is a
fixed linear combination of at most four *stencil nodes*: :class:`CurvePieces`
holds the stencil ``(k, 4)`` and the matrix ``control`` ``(k, 4, 4)`` with
``P_{i,j} = sum_l control[i, j, l] x[stencil[i, l]]``. Open (clamped) rods
have ghost control points by reflection, ``x_{-1} = 2 x_0 - x_1`` and
``x_n = 2 x_{n-1} - x_{n-2}``: the end piece then starts exactly at the end
node with the chord's direction and zero curvature (``c(0) = x_0``,
``c'(0) = x_1 - x_0``, ``c''(0) = 0``). A chord is the same form with
collinear, equally spaced control points ``(2a - b, a, b, 2b - a)``
(:func:`chord_pieces`), which the B-spline reproduces exactly: the tests use
it to reduce to :mod:`supercoil.contact.distance`.

Sag. ``c_i(u) - ((1-u) x_i + u x_{i+1}) = B_0(u) Δ_i + B_3(u) Δ_{i+1}`` with the
second differences ``Δ_i = P_{i,0} - 2 P_{i,1} + P_{i,2}``, ``Δ_{i+1} =
P_{i,1} - 2 P_{i,2} + P_{i,3}`` (linear reproduction fixes the form), and
``B_0 + B_3 <= 1/6``; so a piece lies within ``max(|Δ_i|, |Δ_{i+1}|) / 6``
(:func:`sag_bound`, about ``h^2 kappa / 6``) of its chord, and a broad phase on
the chords with the cutoff widened by twice that bound misses no pair.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

# B_j(u) = sum_p BSPLINE_BASIS[j, p] u^p (uniform cubic B-spline, module docstring)
BSPLINE_BASIS = np.array([[1.0, -3.0, 3.0, -1.0],
                          [4.0, 0.0, -6.0, 3.0],
                          [1.0, 3.0, 3.0, -3.0],
                          [0.0, 0.0, 0.0, 1.0]]) / 6.0


@dataclass(frozen=True)
class CurvePieces:
    """Cubic B-spline pieces of a polygon: ``stencil`` ``(k, 4)`` node indices and
    ``control`` ``(k, 4, 4)``, control point ``j`` of piece ``i`` being
    ``sum_l control[i, j, l] x[stencil[i, l]]`` (module docstring)."""

    stencil: np.ndarray
    control: np.ndarray
    # (k, 2): whether the piece continues into a neighbour at u = 0 and at u = 1
    joined: np.ndarray | None = None

    def joined_ends(self) -> np.ndarray:
        return (np.zeros((len(self.stencil), 2), dtype=bool) if self.joined is None
                else np.asarray(self.joined, dtype=bool))

    @cached_property
    def coefficients(self) -> np.ndarray:
        """``(k, 4, 4)``: weight of stencil node ``l`` on ``u^p`` is ``[i, l, p]``."""
        return np.einsum("ijl,jp->ilp", self.control, BSPLINE_BASIS)

    def control_points(self, points: np.ndarray) -> np.ndarray:
        """``(k, 4, 3)`` control points of the pieces for nodes ``points`` ``(n, 3)``."""
        x = np.asarray(points, dtype=float)[self.stencil]  # (k, 4, 3)
        return np.einsum("ijl,ilx->ijx", self.control, x)

    def evaluate(self, points: np.ndarray, piece: npt.ArrayLike, u: npt.ArrayLike) -> np.ndarray:
        """Points ``c_piece(u)`` ``(..., 3)`` of the curve."""
        piece = np.asarray(piece)
        u = np.asarray(u, dtype=float)
        basis = np.stack([u**p for p in range(4)], axis=-1) @ BSPLINE_BASIS.T  # (..., 4)
        return np.einsum("...j,...jx->...x", basis, self.control_points(points)[piece])


def bspline_pieces(segments: np.ndarray, closed: bool) -> CurvePieces:
    """The uniform cubic B-spline pieces of the segments ``(k, 2)`` (node indices).

    Segment ``i`` runs from ``segments[i, 0]`` to ``segments[i, 1]``; it is
    joined to segment ``i + 1`` when ``segments[i + 1, 0] == segments[i, 1]``
    (and the last to the first when ``closed``). The control points of piece
    ``i`` are the nodes ``(a_{i-1}, a_i, b_i, b_{i+1})``; at a free end (no
    joined neighbour: the ends of an open rod, or of each strand of a set of
    strands) the missing one is a ghost by reflection (module docstring).
    """
    seg = np.asarray(segments, dtype=np.int64)
    k = len(seg)
    if seg.ndim != 2 or seg.shape[1] != 2 or k < 1:
        raise ValueError(f"segments must have shape (k, 2) with k >= 1, got {seg.shape}")
    stencil = np.empty((k, 4), dtype=np.int64)
    control = np.zeros((k, 4, 4))
    joined = np.zeros((k, 2), dtype=bool)
    eye = np.eye(4)
    for i in range(k):
        a, b = seg[i]
        prev = (i - 1) % k if (closed or i > 0) else None
        succ = (i + 1) % k if (closed or i < k - 1) else None
        before = seg[prev, 0] if prev is not None and seg[prev, 1] == a and prev != i else None
        after = seg[succ, 1] if succ is not None and seg[succ, 0] == b and succ != i else None
        stencil[i] = (a, b, before if before is not None else a,
                      after if after is not None else b)
        # control points in terms of the stencil (a, b, before, after)
        control[i, 0] = eye[2] if before is not None else 2 * eye[0] - eye[1]
        control[i, 1] = eye[0]
        control[i, 2] = eye[1]
        control[i, 3] = eye[3] if after is not None else 2 * eye[1] - eye[0]
        joined[i] = (before is not None, after is not None)
    return CurvePieces(stencil, control, joined)


def chord_pieces(segments: np.ndarray) -> CurvePieces:
    """The segments themselves as B-spline pieces (control points ``2a - b, a, b, 2b - a``)."""
    seg = np.asarray(segments, dtype=np.int64)
    stencil = np.concatenate([seg, seg], axis=1)
    rows = np.array([[2.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0],
                     [0.0, 1.0, 0.0, 0.0], [-1.0, 2.0, 0.0, 0.0]])
    return CurvePieces(stencil, np.broadcast_to(rows, (len(seg), 4, 4)).copy())


def sag_bound(points: np.ndarray, pieces: CurvePieces) -> np.ndarray:
    """``(k,)`` bound on the distance of each piece from its chord (module docstring)."""
    ctrl = pieces.control_points(points)
    second = ctrl[:, :2] - 2 * ctrl[:, 1:3] + ctrl[:, 2:]  # (k, 2, 3)
    return np.linalg.norm(second, axis=-1).max(axis=1) / 6.0
