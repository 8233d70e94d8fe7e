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
"""

from __future__ import annotations

import numpy as np


def mirror_image(q: np.ndarray) -> np.ndarray:
    """The image ``(n_nodes * 3,)`` of the centreline ``q`` under the half-turn about the
    horizontal axis through the midpoint of its end nodes that brings it closest to
    ``q`` (module doc); ``q`` itself when the rod is straight (every axis does)."""
    x = np.asarray(q, dtype=float).reshape(-1, 3)
    c = np.array([0.0, 0.0, 0.5 * (x[0, 2] + x[-1, 2])])
    a = x - c
    b = a[::-1]
    form = a[:, :2].T @ b[:, :2]
    form = 0.5 * (form + form.T)
    values, vectors = np.linalg.eigh(form)
    if values[-1] <= 0.0:
        return x.ravel().copy()
    n = np.array([vectors[0, -1], vectors[1, -1], 0.0])
    image = 2.0 * np.outer(b @ n, n) - b + c
    return image.ravel()


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
