"""Twist of a framed polygon from its material frame, by discrete parallel transport.

A framed polygon carries one unit material vector ``d1_k`` per edge, normal to
the edge tangent ``t_k``. Following Bergou et al. (2008, §4.2, "discrete
elastic rods"), the frame of edge ``k−1`` is carried to edge ``k`` by the
discrete parallel transport ``P(t_{k−1} → t_k)`` (the rotation about
``t_{k−1} × t_k`` that takes ``t_{k−1}`` to ``t_k``), and the twist at vertex
``k`` is the signed angle ``m_k ∈ (−π, π]``, about ``t_k``, from
``P d1_{k−1}`` to ``d1_k``. The total twist in turns is

    Tw = (1/2π) Σ_k m_k,

summed over the interior vertices of an open polygon, and over all vertices of
a closed one (including the vertex joining the last edge to the first).

For a closed polygon with a closed frame, ``Tw + Wr`` is an integer (the
linking number of the ribbon, Călugăreanu 1959, White 1969): the holonomy of
discrete parallel transport around the polygon is the area enclosed by its
tangent indicatrix (a geodesic polygon), which by Fuller (1978) equals
``2π(1 + Wr)`` modulo ``4π``. This module does not import the rod model, so
that the identity can be used to check it.

References
----------
- M. Bergou, M. Wardetzky, S. Robinson, B. Audoly, E. Grinspun, "Discrete
  elastic rods", ACM Trans. Graph. 27 (2008) 63.
- G. Călugăreanu (1959); J. H. White, Amer. J. Math. 91 (1969) 693–728;
  F. B. Fuller, PNAS 75 (1978) 3557–3561.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from supercoil.topology.polygon import as_polygon

__all__ = ["parallel_transport", "twist_from_frames"]

# Tolerances on the material frame: d1 must be a unit normal of its edge.
_FRAME_TOLERANCE = 1e-6


def _unit_rows(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def parallel_transport(
    vectors: npt.ArrayLike, t_from: npt.ArrayLike, t_to: npt.ArrayLike
) -> np.ndarray:
    """Discrete parallel transport of ``vectors`` from tangents ``t_from`` to ``t_to``.

    ``P(a → b)`` is the rotation about ``a × b`` by the angle between the unit
    tangents ``a`` and ``b`` (the identity if they are parallel). In closed form
    (Rodrigues), with ``c = a × b``,

        P v = (a·b) v + c × v + c (c·v) / (1 + a·b),

    which maps ``a`` to ``b`` and is undefined only for ``b = −a``.

    Parameters
    ----------
    vectors
        ``(M, 3)`` vectors to transport (any length).
    t_from, t_to
        ``(M, 3)`` tangents (normalised here; they need not be unit).

    Returns
    -------
    numpy.ndarray
        ``(M, 3)`` transported vectors.

    Raises
    ------
    ValueError
        Mismatched shapes, non-finite values, zero tangents, or a pair of
        opposite tangents (the rotation axis is undefined).
    """
    v = np.asarray(vectors, dtype=np.float64)
    a = np.asarray(t_from, dtype=np.float64)
    b = np.asarray(t_to, dtype=np.float64)
    for name, array in (("vectors", v), ("t_from", a), ("t_to", b)):
        if array.ndim != 2 or array.shape[1] != 3 or array.shape != v.shape:
            raise ValueError(
                f"{name} has shape {array.shape}; expected (M, 3) like vectors {v.shape}"
            )
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name} has non-finite entries; all must be finite")
    for name, array in (("t_from", a), ("t_to", b)):
        if np.any(np.linalg.norm(array, axis=1) == 0.0):
            raise ValueError(f"{name} has a zero vector; tangents must be non-zero")
    a = _unit_rows(a)
    b = _unit_rows(b)
    cosine = np.einsum("ij,ij->i", a, b)
    if np.any(cosine <= -1.0 + 1e-12):
        k = int(np.flatnonzero(cosine <= -1.0 + 1e-12)[0])
        raise ValueError(
            f"t_from and t_to are opposite in row {k}; parallel transport needs tangents "
            "that are not antiparallel"
        )
    axis = np.cross(a, b)
    return (
        cosine[:, None] * v
        + np.cross(axis, v)
        + axis * (np.einsum("ij,ij->i", axis, v) / (1.0 + cosine))[:, None]
    )


def twist_from_frames(points: npt.ArrayLike, d1: npt.ArrayLike, closed: bool = True) -> float:
    """Total twist, in turns, of a polygon framed by one material vector per edge.

    ``Tw = (1/2π) Σ_k m_k`` with ``m_k`` the signed angle, about ``t_k`` and in
    ``(−π, π]``, from ``P(t_{k−1} → t_k) d1_{k−1}`` to ``d1_k`` (Bergou et al.
    2008); see the module docstring.

    Parameters
    ----------
    points
        ``(N, 3)`` polygon vertices, each once.
    d1
        ``(n_edges, 3)`` material vectors: ``n_edges = N`` if ``closed`` (edge
        ``k`` joins vertex ``k`` to ``k+1 mod N``), ``N − 1`` otherwise. Each
        must be a unit vector normal to its edge (to 1e-6); the small residual
        tangential component is projected out.
    closed
        Whether the polygon (and its frame) is closed: then the vertex joining
        the last edge to the first is included.

    Returns
    -------
    float
        Total twist in turns (positive for a right-handed rotation of ``d1``
        about the tangent). For a closed polygon ``twist + writhe`` is an
        integer, the linking number of the ribbon.

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, too few vertices, zero-length edges,
        ``d1`` not unit or not normal to its edge, or two consecutive edges that
        are antiparallel (a cusp, where transport is undefined).
    """
    vertices = as_polygon(points, "points", closed=closed)
    frame = np.asarray(d1, dtype=np.float64)
    n_edges = vertices.shape[0] if closed else vertices.shape[0] - 1
    if frame.shape != (n_edges, 3):
        raise ValueError(
            f"d1 has shape {frame.shape}; expected ({n_edges}, 3), one vector per edge of a "
            f"{'closed' if closed else 'open'} polygon with {vertices.shape[0]} vertices"
        )
    if not np.all(np.isfinite(frame)):
        raise ValueError("d1 has non-finite entries; all must be finite")
    following = np.roll(vertices, -1, axis=0)[:n_edges]
    tangents = _unit_rows(following - vertices[:n_edges])
    norms = np.linalg.norm(frame, axis=1)
    off_unit = np.abs(norms - 1.0) > _FRAME_TOLERANCE
    if np.any(off_unit):
        k = int(np.flatnonzero(off_unit)[0])
        raise ValueError(
            f"d1[{k}] has length {norms[k]:.9g}; material vectors must be unit vectors"
        )
    along = np.einsum("ij,ij->i", frame, tangents)
    not_normal = np.abs(along) > _FRAME_TOLERANCE
    if np.any(not_normal):
        k = int(np.flatnonzero(not_normal)[0])
        raise ValueError(
            f"d1[{k}] makes cosine {along[k]:.3g} with edge {k}; material vectors must be "
            "normal to their edge"
        )
    frame = frame - along[:, None] * tangents
    if closed:
        previous = np.arange(n_edges) - 1  # edge −1 is the last edge
        current = np.arange(n_edges)
    else:
        previous = np.arange(n_edges - 1)
        current = previous + 1
    if current.size == 0:
        return 0.0
    cusp = np.einsum("ij,ij->i", tangents[previous], tangents[current]) <= -1.0 + 1e-12
    if np.any(cusp):
        k = int(current[np.flatnonzero(cusp)[0]])
        raise ValueError(
            f"points: edges {(k - 1) % n_edges} and {k} are antiparallel (a cusp); "
            "twist needs consecutive edges that do not fold back"
        )
    transported = parallel_transport(frame[previous], tangents[previous], tangents[current])
    target = frame[current]
    sine = np.einsum("ij,ij->i", np.cross(transported, target), tangents[current])
    cosine = np.einsum("ij,ij->i", transported, target)
    return math.fsum(np.arctan2(sine, cosine)) / (2.0 * math.pi)
