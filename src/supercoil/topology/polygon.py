"""Polygonal curves as the topology functions take them: validated vertex arrays, the
closures of an open curve, and the layouts the compiled sums read.

:func:`as_polygon` checks one polygon (shape, finiteness, number of vertices, no
zero-length edge) and names the input in its :class:`~supercoil.errors.InputError`;
:func:`prepare_polygon` adds the closure, the axis of the tails and the test that the
polygon does not meet itself (where its writhe is undefined,
:mod:`supercoil.topology.crossings`).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import numpy.typing as npt

from supercoil.errors import InputError
from supercoil.topology.crossings import first_self_crossing

__all__ = ["CLOSURES", "Closure", "as_axis", "as_polygon", "check_closure",
           "coordinate_columns", "extended_vertices", "prepare_polygon"]

Closure = Literal["closed", "chord", "none", "axis"]

CLOSURES: tuple[str, ...] = ("closed", "chord", "none", "axis")


def as_polygon(points: npt.ArrayLike, name: str, closed: bool) -> np.ndarray:
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


def as_axis(axis: npt.ArrayLike) -> np.ndarray:
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


def check_closure(closure: str) -> None:
    """Raise an InputError unless ``closure`` is one of :data:`CLOSURES`."""
    if closure not in CLOSURES:
        raise InputError(f"closure {closure!r} is unknown; expected one of {', '.join(CLOSURES)}",
                         name="closure")


def prepare_polygon(
    points: npt.ArrayLike, closure: str, axis: npt.ArrayLike, crossing_is_error: bool = True
) -> tuple[np.ndarray, bool, np.ndarray | None]:
    """Validate; return (vertices, closed polygon?, unit axis or None). A polygon that
    meets itself is an InputError, or with ``crossing_is_error=False`` gives vertices None
    (the writhe is undefined there)."""
    check_closure(closure)
    closed = closure in ("closed", "chord")
    vertices = as_polygon(points, "points", closed)
    unit_axis = as_axis(axis) if closure == "axis" else None
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


def coordinate_columns(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The x, y, z columns of ``(n, 3)`` ``vertices`` as three contiguous ``(n,)`` arrays."""
    columns = np.ascontiguousarray(vertices.T)
    return columns[0], columns[1], columns[2]
