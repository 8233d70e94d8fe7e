"""The half-turn symmetry of a rod clamped at both ends on the ``z`` axis.

The rotation by pi about an axis across the rod's middle (perpendicular to ``z``,
through the midpoint of its end nodes) with the reversal of the node order,
``x_i -> c + R (x_{n-1-i} - c)``, ``R = 2 n n^T - I``, maps the clamped rod onto
itself at any turns (the axis lies at half the angle between the two clamps'
directors) and leaves its energy unchanged: the straight rod's symmetric critical
mode, the localised loop off it, its first contact (at the crossing, on the axis) and
the plectoneme that grows from that crossing (its ply along the axis, the two strands
exchanged) are mapped onto themselves. The sliding of such a structure along the rod
(:meth:`~supercoil.rod.open.ClampedRodEnergy.sliding`) is odd under it.

:func:`mirror_image` gives the image with the axis that brings it closest to the state
(the horizontal ``n`` that maximises ``sum (a_i . n)(b_i . n)``, ``a_i = x_i - c``,
``b_i = x_{n-1-i} - c``: the leading eigenvector of that 2 x 2 form), so that a
state turned about ``z`` is symmetric about a turned axis.

:func:`symmetric_state` and :func:`symmetric_direction` project a state and a
direction onto the family of symmetric states, in the gauge that pins one azimuthal
coordinate: a Newton iteration projected so stays on the family, where the
antisymmetric modes (odd under the half-turn) drop out of its steps, and follows a
symmetric branch through the pitchforks where one of them crosses zero
(:mod:`supercoil.problems.tweezers.mirrored`). The multipliers of the edges' lengths
go with them (:func:`mirror_pairs`).
"""

from __future__ import annotations

import numpy as np


def mirror_axis(q: np.ndarray) -> np.ndarray | None:
    """The horizontal unit axis ``(3,)`` of the half-turn that brings the centreline
    ``q`` closest to itself (module doc); None when the rod is straight (every axis
    does)."""
    x = np.asarray(q, dtype=float).reshape(-1, 3)
    c = np.array([0.0, 0.0, 0.5 * (x[0, 2] + x[-1, 2])])
    a = x - c
    b = a[::-1]
    form = a[:, :2].T @ b[:, :2]
    form = 0.5 * (form + form.T)
    values, vectors = np.linalg.eigh(form)
    if values[-1] <= 0.0:
        return None
    return np.array([vectors[0, -1], vectors[1, -1], 0.0])


def mirror_image(q: np.ndarray, axis: np.ndarray | None = None) -> np.ndarray:
    """The image ``(n_nodes * 3,)`` of the centreline ``q`` under the half-turn about
    ``axis`` (default :func:`mirror_axis`) through the midpoint of its end nodes;
    ``q`` itself when the rod is straight."""
    x = np.asarray(q, dtype=float).reshape(-1, 3)
    n = mirror_axis(x) if axis is None else np.asarray(axis, dtype=float)
    if n is None:
        return x.ravel().copy()
    c = np.array([0.0, 0.0, 0.5 * (x[0, 2] + x[-1, 2])])
    b = x[::-1] - c
    image = 2.0 * np.outer(b @ n, n) - b + c
    return image.ravel()


def mirrored_direction(dq: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The image of a displacement ``dq`` ``(n_nodes * 3,)`` under the linearised
    half-turn about the fixed ``axis``: ``R dx_{n-1-i} + (dz_0 + dz_{n-1}) e_z``
    (the midpoint of the end nodes moves with them)."""
    d = np.asarray(dq, dtype=float).reshape(-1, 3)
    n = np.asarray(axis, dtype=float)
    b = d[::-1]
    image = 2.0 * np.outer(b @ n, n) - b
    image[:, 2] += d[0, 2] + d[-1, 2]
    return image.ravel()


def mirror_pairs(edges: np.ndarray, n_nodes: int) -> np.ndarray:
    """Pairs ``(k, k')`` ``(p, 2)`` of positions in ``edges`` (the indices of the
    constrained edges, edge ``e`` joining nodes ``e`` and ``e + 1``) whose edges the
    half-turn exchanges (``e' = n_nodes - 2 - e``), each pair once (``k < k'``); an
    edge whose image is not constrained (a clamped edge, fixed whole) has none."""
    edges = np.asarray(edges, dtype=np.int64)
    where = {int(e): k for k, e in enumerate(edges)}
    pairs = [(k, where[n_nodes - 2 - int(e)]) for k, e in enumerate(edges)
             if where.get(n_nodes - 2 - int(e), -1) > k]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def _turned_to_pin(s: np.ndarray, pin: int, value: float) -> np.ndarray:
    """``s`` ``(n_nodes * 3,)`` turned about ``z`` by the smallest angle that gives its
    coordinate ``pin`` (an ``x`` or ``y``) the ``value``; ``s`` where none does."""
    x = s.reshape(-1, 3)
    node, axis = divmod(int(pin), 3)
    px, py = x[node, 0], x[node, 1]
    radius = float(np.hypot(px, py))
    if axis == 2 or radius == 0.0 or abs(value) > radius:
        return s
    # x cos(phi) - y sin(phi) = r cos(phi + beta); x sin(phi) + y cos(phi) = r sin(phi + beta)
    beta = float(np.arctan2(py, px))
    base = np.arccos(value / radius) if axis == 0 else np.arcsin(value / radius)
    targets = (base, -base) if axis == 0 else (base, np.pi - base)
    phis = [np.angle(np.exp(1j * (t - beta))) for t in targets]
    phi = min(phis, key=abs)
    c, sn = np.cos(phi), np.sin(phi)
    turned = x.copy()
    turned[:, 0] = c * x[:, 0] - sn * x[:, 1]
    turned[:, 1] = sn * x[:, 0] + c * x[:, 1]
    turned[node, axis] = value
    return turned.ravel()


def symmetric_state(q: np.ndarray, pin: int | None = None) -> np.ndarray:
    """The symmetric part ``(q + image) / 2`` of the centreline ``q`` (axis
    :func:`mirror_axis`), turned about ``z`` so that the pinned azimuthal coordinate
    ``pin`` keeps its value in ``q`` (a turn about the axis maps a symmetric state
    onto one symmetric about the turned axis): a projection onto the symmetric
    states in that gauge, the identity on them."""
    q = np.asarray(q, dtype=float).ravel()
    s = 0.5 * (q + mirror_image(q))
    return s if pin is None else _turned_to_pin(s, pin, float(q[pin]))


def symmetric_direction(q: np.ndarray, dq: np.ndarray, pin: int | None = None) -> np.ndarray:
    """The part of the displacement ``dq`` at the symmetric state ``q`` that keeps it
    symmetric: ``(dq + image) / 2`` about ``q``'s axis, plus the turn about ``z``
    that holds the pinned coordinate ``pin`` (the turn is odd about a fixed axis, so
    the first part drops it); ``dq`` where ``q`` is straight."""
    axis = mirror_axis(q)
    dq = np.asarray(dq, dtype=float).ravel()
    if axis is None:
        return dq.copy()
    even = 0.5 * (dq + mirrored_direction(dq, axis))
    if pin is None:
        return even
    turn = np.cross([0.0, 0.0, 1.0], np.asarray(q, dtype=float).reshape(-1, 3)).ravel()
    if turn[pin] == 0.0:
        return even
    return even + ((dq[pin] - even[pin]) / turn[pin]) * turn


def mirror_offset(q: np.ndarray) -> np.ndarray:
    """The displacement from ``q`` to its symmetric part ``(q + image) / 2``: zero on a
    symmetric state, minus the odd part of the state elsewhere."""
    q = np.asarray(q, dtype=float).ravel()
    return 0.5 * (mirror_image(q) - q)


def mirror_asymmetry(q: np.ndarray) -> float:
    """The largest node distance between ``q`` and its :func:`mirror_image` (length
    units): zero to round-off on a symmetric state."""
    x = np.asarray(q, dtype=float).reshape(-1, 3)
    return float(np.max(np.linalg.norm(mirror_image(q).reshape(-1, 3) - x, axis=1)))
