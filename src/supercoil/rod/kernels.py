"""The rod's stencil kernels as array functions: bending and reference twist of each
interior vertex with exact derivatives, the fused gradient of both, and the edge-length
constraints.

A stencil is the three vertices ``x_{i-1}, x_i, x_{i+1}`` around one interior vertex (a
flat vector of 9 numbers); the functions here check the arrays and call the compiled
loops of :mod:`supercoil.rod.stencil_loops`, whose docstring derives the energies and
their derivatives (curvature forms ``"angle"``, ``"tan"``, ``"sin"``; the reference
twist by time-parallel transport, Bergou et al. 2008, 2010).
:func:`supercoil.rod.reference_kernels.reference_kernels` is the JAX oracle of both.
"""

from __future__ import annotations

import numpy as np

from supercoil._numba import njit
from supercoil.rod.stencil_loops import ANGLE, SIN, TAN, bending_loop, gradient_loop, twist_loop

__all__ = ["CURVATURE_FORMS", "FORM_CODE", "bending_kernels", "bending_terms",
           "edge_length_terms", "gradient_terms", "twist_gradient", "twist_hessian",
           "twist_terms", "twist_value"]

CURVATURE_FORMS = ("angle", "tan", "sin")
FORM_CODE = {"tan": TAN, "sin": SIN, "angle": ANGLE}

_NO_HESSIANS = np.zeros((0, 9, 9))


def _run(loop, stencils, data, data_shape, extra, order, hessians, scale):
    stencils = np.ascontiguousarray(stencils, dtype=np.float64)
    data = np.ascontiguousarray(data, dtype=np.float64)
    n = stencils.shape[0]
    if stencils.shape != (n, 9) or data.shape != (n, *data_shape):
        expected = "(n" + "".join(f", {d}" for d in data_shape) + ")"
        raise ValueError(f"stencils must have shape (n, 9) and the per-vertex data {expected}; "
                         f"got {stencils.shape} and {data.shape}")
    if order not in (0, 1, 2):
        raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
    values = np.empty(n)
    gradients = np.empty((n if order >= 1 else 0, 9))
    if order == 2:
        if hessians is None:
            hessians = np.zeros((n, 9, 9))
        elif (hessians.shape != (n, 9, 9) or hessians.dtype != np.float64
              or not hessians.flags.c_contiguous):
            raise ValueError(f"hessians must be a C-contiguous float64 array of shape ({n}, 9, 9)")
    else:
        hessians = _NO_HESSIANS
    loop(stencils, data, *extra, order, float(scale), values, gradients, hessians)
    return values, gradients, hessians


def bending_terms(stencils: np.ndarray, weights: np.ndarray, form: str, order: int,
                  hessians: np.ndarray | None = None, scale: float = 1.0):
    """Per-vertex bending energy and, up to ``order`` (0, 1, 2), its derivatives.

    ``stencils`` ``(n, 9)``, ``weights`` ``(n,)`` (``A / (l_{i-1} + l_i)``).
    Returns ``(values (n,), gradients (n, 9), hessians (n, 9, 9))``;
    ``gradients`` has no rows below order 1. At order 2, ``scale`` times the
    local Hessians is *added* to ``hessians`` when given (C-contiguous float64),
    so that several energies accumulate into one array.
    """
    if form not in FORM_CODE:
        raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")
    return _run(bending_loop, stencils, weights, (), (FORM_CODE[form],), order, hessians,
                scale)


def twist_terms(stencils: np.ndarray, frames: np.ndarray, order: int,
                hessians: np.ndarray | None = None, scale: float = 1.0):
    """Per-vertex reference twists (radians, in ``[-pi, pi)``) and their derivatives.

    ``frames`` ``(n, 4, 3)``: ``u_old, t_old`` of edge ``i-1`` and of edge ``i``.
    Returns and accumulates as :func:`bending_terms`.
    """
    return _run(twist_loop, stencils, frames, (4, 3), (), order, hessians, scale)


def bending_kernels(form: str):
    """``(value, gradient, hessian)`` of the per-vertex bending energy.

    Each takes ``stencils`` of shape ``(n_vertices, 9)`` and ``weights`` of shape
    ``(n_vertices,)`` (``A / (l_{i-1} + l_i)``) and returns shapes
    ``(n_vertices,)``, ``(n_vertices, 9)``, ``(n_vertices, 9, 9)``.
    """
    if form not in FORM_CODE:
        raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")

    def value(stencils: np.ndarray, weights: np.ndarray) -> np.ndarray:
        return bending_terms(stencils, weights, form, 0)[0]

    def gradient(stencils: np.ndarray, weights: np.ndarray) -> np.ndarray:
        return bending_terms(stencils, weights, form, 1)[1]

    def hessian(stencils: np.ndarray, weights: np.ndarray) -> np.ndarray:
        return bending_terms(stencils, weights, form, 2)[2]

    return value, gradient, hessian



def gradient_terms(q: np.ndarray, dofs: np.ndarray, bend_weights: np.ndarray, form: str,
                   frames: np.ndarray, n_dofs: int):
    """``(bending gradient (n_dofs,), reference twists (n,), gradient of their sum
    (n_dofs,))`` at ``q`` ``(n_dofs,)`` for the stencils of DOFs ``dofs`` ``(n, 9)``:
    :func:`bending_terms` and :func:`twist_terms` at order 1 on ``q[dofs]`` with the
    local gradients summed by DOF in the stencils' order (the values of
    ``np.bincount(dofs.ravel(), weights=local.ravel())``), in one compiled call (the
    gather, two kernels and two scatters cost 25 us at N = 100 as separate steps).
    """
    if form not in FORM_CODE:
        raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    n = dofs.shape[0]
    frames = np.ascontiguousarray(frames, dtype=np.float64)
    bend_weights = np.ascontiguousarray(bend_weights, dtype=np.float64)
    if dofs.shape != (n, 9) or frames.shape != (n, 4, 3) or bend_weights.shape != (n,):
        raise ValueError(f"dofs (n, 9), frames (n, 4, 3) and weights (n,) needed; got "
                         f"{dofs.shape}, {frames.shape}, {bend_weights.shape}")
    bend = np.zeros(n_dofs)
    twist = np.zeros(n_dofs)
    values = np.empty(n)
    gradient_loop(np.ascontiguousarray(q, dtype=np.float64), dofs, bend_weights,
                     FORM_CODE[form], frames, bend, twist, values)
    return bend, values, twist


@njit()
def _edge_length_kernel(x, edges, h, order, values, data):
    for k in range(edges.shape[0]):
        a = edges[k, 0]
        b = edges[k, 1]
        e0 = x[b, 0] - x[a, 0]
        e1 = x[b, 1] - x[a, 1]
        e2 = x[b, 2] - x[a, 2]
        values[k] = (e0 * e0 + e1 * e1 + e2 * e2 - h * h) / (2.0 * h)
        scaled = (e0 / h, e1 / h, e2 / h)
        for j in range(6):
            source = order[k, j]
            data[6 * k + j] = -scaled[source] if source < 3 else scaled[source - 3]


def edge_length_terms(x: np.ndarray, edges: np.ndarray, h: float, order: np.ndarray):
    """``(c (m,), data (6 m,))`` of the edges ``edges`` ``(m, 2)`` (node indices) at the
    nodes ``x`` ``(n, 3)``: the inextensibility constraints ``c_k = (|e_k|^2 - h^2) /
    (2 h)`` and their Jacobian's entries, row ``k`` the six values ``[-e_k / h, e_k /
    h]`` taken in the order ``order[k]`` ``(m, 6)`` (the same sums and quotients as
    the numpy expressions of :class:`~supercoil.rod.energy.RodEnergy`), in one call.
    """
    edges = np.ascontiguousarray(edges, dtype=np.int64)
    m = edges.shape[0]
    values = np.empty(m)
    data = np.empty(6 * m)
    _edge_length_kernel(np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3), edges,
                        float(h), np.ascontiguousarray(order, dtype=np.int64), values, data)
    return values, data


def twist_value(stencils: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Reference twists ``(n,)`` (see :func:`twist_terms`)."""
    return twist_terms(stencils, frames, 0)[0]


def twist_gradient(stencils: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Local gradients ``(n, 9)`` of the reference twists."""
    return twist_terms(stencils, frames, 1)[1]


def twist_hessian(stencils: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Local Hessians ``(n, 9, 9)`` of the reference twists."""
    return twist_terms(stencils, frames, 2)[2]
