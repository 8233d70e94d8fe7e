"""Local stencil kernels of the discrete Kirchhoff rod, with exact derivatives.

Each kernel is a scalar function of the three vertices ``x_{i-1}, x_i, x_{i+1}``
around one interior vertex (a flat vector of 9 numbers) plus per-vertex data.
The kernels return local values, gradients ``(9,)`` and Hessians ``(9, 9)``,
which :mod:`supercoil.rod.assembly` scatters into the global sparse pattern.

Curvature. With ``e = x_i - x_{i-1}``, ``f = x_{i+1} - x_i`` and turning angle
``phi``, the curvature binormal of Bergou et al. (2008, eq. 1) is
``kb = 2 e x f / (|e||f| + e.f)`` with ``|kb| = 2 tan(phi/2)``. The bending
energy of vertex ``i`` is ``A * k^2 / (l_{i-1} + l_i)`` (rest lengths), i.e.
``int A/2 kappa^2 ds`` with ``kappa = k / lbar``, where ``k`` is one of

* ``"angle"``: ``k = phi`` (the exact turning angle; a regular polygon then has
  exactly the bending energy of its circle),
* ``"tan"``:   ``k = 2 tan(phi/2)`` (Bergou et al. 2008),
* ``"sin"``:   ``k = 2 sin(phi/2)``.

All three converge as O(h^2); their error constants differ (see
``tests/test_ring.py`` and docs/model.md).

Twist. ``reference_twist`` is the signed angle at vertex ``i`` between the
reference director of edge ``i-1`` parallel-transported onto edge ``i`` and the
reference director of edge ``i`` (Bergou et al. 2010, sec. 6). The reference
directors are carried along by *time-parallel transport* from the previous
state (``u_old``, ``t_old``), so the kernel is a smooth function of the
vertices. Summed around a closed rod it is the holonomy of discrete parallel
transport, which does not depend on the reference directors (mod 2 pi) and
whose variation is minus 2 pi times the variation of the writhe
(Călugăreanu–White–Fuller). Its Hessian is therefore the banded Hessian of the
writhe, obtained from a local expression, never from the double sum.

Derivatives (hand-derived, numba). Both energies depend on the vertices only
through ``e`` and ``f``; derivatives are taken in ``(e, f)`` and mapped to the
vertices (``d/dx_{i-1} = -d/de``, ``d/dx_i = d/de - d/df``, ``d/dx_{i+1} = d/df``).

* Bending: ``k^2 = K(s)`` with ``s = tan^2(phi/2) = |e x f|^2 / D^2``,
  ``D = |e||f| + e.f``, so ``grad = K' grad s`` and
  ``hess = K' hess s + K'' grad s grad s^T``, with the derivatives of
  ``N = |e x f|^2`` and ``D`` in closed form. ``K = 4 s`` (tan),
  ``4 s / (1 + s)`` (sin), ``4 s m(s)^2`` with ``m = atan(sqrt s) / sqrt s``
  (angle; ``K' = 4 m / (1 + s)``, and ``m``, ``m'`` from their Taylor series
  for ``s < 1e-3``, which keeps ``phi = 0`` regular and avoids cancellation).
* Twist: minimal-rotation transport around a geodesic triangle ``(p, q, r)``
  of unit vectors rotates by its signed solid angle
  ``Omega(p, q, r) = 2 atan2(p.(q x r), 1 + p.q + q.r + r.p)``
  (Van Oosterom & Strackee 1983), hence, with ``A = t_old`` of edge ``i-1``,
  ``B = t_old`` of edge ``i``, ``q = e/|e|`` and ``r = f/|f|``,

      m = m_0 + Omega(A, B, r) - Omega(A, q, r)   (mod 2 pi),

  ``m_0`` the reference twist of the old state (a constant). The derivatives
  of ``atan2`` of the triple product and the dot products are elementary; the
  chain rule through ``q = e/|e|`` uses ``dq/de = (I - q q^T)/|e|`` and
  ``sum_k g_k d^2 q_k/de^2 = -(q g^T + g q^T + (q.g)(I - 3 q q^T))/|e|^2``.

:func:`supercoil.rod.reference_kernels.reference_kernels` differentiates the formulas above
(``kb`` and the transport of the directors) with JAX autodiff: an independent
route, used as the oracle for the hand-derived kernels (and imported only
then: the runtime path does not need JAX).
"""

from __future__ import annotations

import math

import numpy as np

from supercoil._numba import njit

CURVATURE_FORMS = ("angle", "tan", "sin")
FORM_CODE = {"tan": 0, "sin": 1, "angle": 2}
_TAN, _SIN = 0, 1

# Below this value of s = tan^2(phi/2) the angle form uses the Taylor series of
# m(s) = atan(sqrt s)/sqrt s and of m'(s); _SERIES_TERMS terms of the
# alternating series leave an error below s^7 / 15 < 1e-21.
_SERIES_BELOW = 1e-3
_SERIES_TERMS = 7




# --------------------------------------------------------------------------
# small building blocks (3-vectors as tuples: no allocation inside the loops)
# --------------------------------------------------------------------------


@njit()
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit()
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit()
def _edges(x):
    """``e = x_i - x_{i-1}`` and ``f = x_{i+1} - x_i`` of a stencil ``(9,)``."""
    return ((x[3] - x[0], x[4] - x[1], x[5] - x[2]), (x[6] - x[3], x[7] - x[4], x[8] - x[5]))


@njit()
def _transport(v, a, b):
    """Parallel transport of ``v`` from unit ``a`` to unit ``b`` (rotation about ``a x b``)."""
    n = _cross(a, b)
    c = _dot(a, b)
    nv = _cross(n, v)
    k = _dot(n, v) / (1.0 + c)
    return (c * v[0] + nv[0] + k * n[0], c * v[1] + nv[1] + k * n[1], c * v[2] + nv[2] + k * n[2])


@njit()
def _measure(s, form):
    """``K(s)``, ``K'(s)``, ``K''(s)`` with ``k^2 = K(s)``, ``s = tan^2(phi/2)``."""
    if form == _TAN:
        return 4.0 * s, 4.0, 0.0
    u = 1.0 / (1.0 + s)
    if form == _SIN:
        return 4.0 * s * u, 4.0 * u * u, -8.0 * u * u * u
    if s < _SERIES_BELOW:  # m = sum (-s)^k / (2k + 1)
        m = 0.0
        dm = 0.0
        power = 1.0
        for k in range(_SERIES_TERMS):
            m += power / (2 * k + 1)
            dm -= (k + 1) * power / (2 * k + 3)
            power *= -s
    else:
        root = math.sqrt(s)
        m = math.atan(root) / root
        dm = (u - m) / (2.0 * s)
    return 4.0 * s * m * m, 4.0 * m * u, 4.0 * u * (dm - m * u)


@njit()
def _set_gradient(g6, out):
    """``out (9,) = P^T g6``: the ``(e, f)`` gradient ``g6`` on the three vertices."""
    for k in range(3):
        out[k] = -g6[k]
        out[3 + k] = g6[k] - g6[3 + k]
        out[6 + k] = g6[3 + k]


@njit()
def _add_hessian(h6, scale, out):
    """``out (9, 9) += scale P^T h6 P`` for a symmetric ``(e, f)`` Hessian ``h6``."""
    for i in range(3):
        for j in range(3):
            ee = scale * h6[i, j]
            ef = scale * h6[i, 3 + j]
            fe = scale * h6[3 + i, j]
            ff = scale * h6[3 + i, 3 + j]
            out[i, j] += ee
            out[i, 3 + j] += ef - ee
            out[i, 6 + j] -= ef
            out[3 + i, j] += fe - ee
            out[3 + i, 3 + j] += ee + ff - (ef + fe)  # same rounding as its mirror
            out[3 + i, 6 + j] += ef - ff
            out[6 + i, j] -= fe
            out[6 + i, 3 + j] += fe - ff
            out[6 + i, 6 + j] += ff


# --------------------------------------------------------------------------
# bending
# --------------------------------------------------------------------------


@njit()
def _bending_loop(stencils, weights, form, order, scale, values, gradients, hessians):
    g6 = np.empty(6)
    h6 = np.empty((6, 6))
    dn = np.empty(6)  # grad N, N = |e x f|^2
    dd = np.empty(6)  # grad D, D = |e||f| + e.f
    ds = np.empty(6)  # grad s, s = N / D^2
    for i in range(stencils.shape[0]):
        e, f = _edges(stencils[i])
        a = math.sqrt(_dot(e, e))
        b = math.sqrt(_dot(f, f))
        d = _dot(e, f)
        c = _cross(e, f)
        den = a * b + d
        s = _dot(c, c) / (den * den)
        k0, k1, k2 = _measure(s, form)
        w = weights[i]
        values[i] = w * k0
        if order == 0:
            continue
        ne = _cross(f, c)  # grad_e N = 2 f x (e x f), grad_f N = 2 (e x f) x e
        nf = _cross(c, e)
        for k in range(3):
            dn[k] = 2.0 * ne[k]
            dn[3 + k] = 2.0 * nf[k]
            dd[k] = (b / a) * e[k] + f[k]
            dd[3 + k] = (a / b) * f[k] + e[k]
        for k in range(6):
            ds[k] = dn[k] / (den * den) - 2.0 * s * dd[k] / den
            g6[k] = w * k1 * ds[k]
        _set_gradient(g6, gradients[i])
        if order == 1:
            continue
        # hess s = (hess N - 2 (dN dD^T + dD dN^T) / D - 2 s D hess D + 6 s dD dD^T) / D^2;
        # first the blocks ee, ff, ef of hess N - 2 s D hess D
        for p in range(3):
            for r in range(3):
                delta = 1.0 if p == r else 0.0
                n_ee = 2.0 * (b * b * delta - f[p] * f[r])
                n_ff = 2.0 * (a * a * delta - e[p] * e[r])
                n_ef = 2.0 * (2.0 * e[p] * f[r] - f[p] * e[r] - d * delta)
                d_ee = (b / a) * (delta - e[p] * e[r] / (a * a))
                d_ff = (a / b) * (delta - f[p] * f[r] / (b * b))
                d_ef = e[p] * f[r] / (a * b) + delta
                h6[p, r] = n_ee - 2.0 * s * den * d_ee
                h6[3 + p, 3 + r] = n_ff - 2.0 * s * den * d_ff
                h6[p, 3 + r] = n_ef - 2.0 * s * den * d_ef
        for p in range(6):
            for r in range(p, 6):
                hs = (
                    h6[p, r] - 2.0 * (dn[p] * dd[r] + dd[p] * dn[r]) / den + 6.0 * s * dd[p] * dd[r]
                ) / (den * den)
                h6[p, r] = w * (k1 * hs + k2 * ds[p] * ds[r])
                h6[r, p] = h6[p, r]
        _add_hessian(h6, scale, hessians[i])


# --------------------------------------------------------------------------
# reference twist
# --------------------------------------------------------------------------


@njit()
def _atan2_derivatives(y, x):
    """First and second derivatives of ``atan2(y, x)``: t_y, t_x, t_yy, t_xx, t_xy."""
    rho = x * x + y * y
    rho2 = rho * rho
    return x / rho, -y / rho, -2.0 * x * y / rho2, 2.0 * x * y / rho2, (y * y - x * x) / rho2


@njit()
def _add_atan2_outer(out, row, col, coefficient, y_row, x_row, y_col, x_col, tyy, txx, txy):
    """``out[row + i, col + j] += coefficient (t_yy y y^T + t_xx x x^T + t_xy (y x^T + x y^T))``."""
    for i in range(3):
        for j in range(3):
            out[row + i, col + j] += coefficient * (
                tyy * y_row[i] * y_col[j]
                + txx * x_row[i] * x_col[j]
                + txy * (y_row[i] * x_col[j] + x_row[i] * y_col[j])
            )


@njit()
def _project_block(gz, row, col, u, v, lu, lv, out):
    """``out`` block at (row, col) = ``(I - u u^T) G (I - v v^T) / (lu lv)``, ``G`` that of ``gz``."""
    for k in range(3):
        gv = gz[row + k, col] * v[0] + gz[row + k, col + 1] * v[1] + gz[row + k, col + 2] * v[2]
        for j in range(3):
            out[row + k, col + j] = gz[row + k, col + j] - gv * v[j]
    for j in range(3):
        ug = u[0] * out[row, col + j] + u[1] * out[row + 1, col + j] + u[2] * out[row + 2, col + j]
        for k in range(3):
            out[row + k, col + j] = (out[row + k, col + j] - u[k] * ug) / (lu * lv)


@njit()
def _add_unit_curvature(h6, row, u, g, length):
    """``h6`` block += ``sum_k g_k d^2 u_k / de^2 = -(u g^T + g u^T + (u.g)(I - 3 u u^T)) / |e|^2``."""
    ug = _dot(u, g)
    for k in range(3):
        for j in range(3):
            delta = 1.0 if k == j else 0.0
            h6[row + k, row + j] -= (
                u[k] * g[j] + g[k] * u[j] + ug * (delta - 3.0 * u[k] * u[j])
            ) / (length * length)


@njit()
def _twist_loop(stencils, frames, order, scale, values, gradients, hessians):
    g6 = np.empty(6)
    h6 = np.empty((6, 6))
    gz = np.empty((6, 6))  # Hessian in (q, r), q = e/|e|, r = f/|f|
    for i in range(stencils.shape[0]):
        e, f = _edges(stencils[i])
        a = math.sqrt(_dot(e, e))
        b = math.sqrt(_dot(f, f))
        q = (e[0] / a, e[1] / a, e[2] / a)
        r = (f[0] / b, f[1] / b, f[2] / b)
        fr = frames[i]
        u_a = (fr[0, 0], fr[0, 1], fr[0, 2])
        t_a = (fr[1, 0], fr[1, 1], fr[1, 2])
        u_b = (fr[2, 0], fr[2, 1], fr[2, 2])
        t_b = (fr[3, 0], fr[3, 1], fr[3, 2])
        carried = _transport(u_a, t_a, t_b)
        m0 = math.atan2(_dot(_cross(carried, u_b), t_b), _dot(carried, u_b))
        axb = _cross(t_a, t_b)
        # Omega(A, B, r) = 2 atan2(y1, x1), Omega(A, q, r) = 2 atan2(y2, x2)
        y1 = _dot(r, axb)
        x1 = 1.0 + _dot(t_a, t_b) + _dot(t_b, r) + _dot(r, t_a)
        y2 = _dot(t_a, _cross(q, r))
        x2 = 1.0 + _dot(t_a, q) + _dot(q, r) + _dot(r, t_a)
        m = m0 + 2.0 * math.atan2(y1, x1) - 2.0 * math.atan2(y2, x2)
        values[i] = m - 2.0 * math.pi * math.floor((m + math.pi) / (2.0 * math.pi))
        if order == 0:
            continue
        t1y, t1x, t1yy, t1xx, t1xy = _atan2_derivatives(y1, x1)
        t2y, t2x, t2yy, t2xx, t2xy = _atan2_derivatives(y2, x2)
        y1r = axb
        x1r = (t_a[0] + t_b[0], t_a[1] + t_b[1], t_a[2] + t_b[2])
        y2q = _cross(r, t_a)
        x2q = (t_a[0] + r[0], t_a[1] + r[1], t_a[2] + r[2])
        y2r = _cross(t_a, q)
        x2r = (t_a[0] + q[0], t_a[1] + q[1], t_a[2] + q[2])
        gq = (
            -2.0 * (t2y * y2q[0] + t2x * x2q[0]),
            -2.0 * (t2y * y2q[1] + t2x * x2q[1]),
            -2.0 * (t2y * y2q[2] + t2x * x2q[2]),
        )
        gr = (
            2.0 * (t1y * y1r[0] + t1x * x1r[0] - t2y * y2r[0] - t2x * x2r[0]),
            2.0 * (t1y * y1r[1] + t1x * x1r[1] - t2y * y2r[1] - t2x * x2r[1]),
            2.0 * (t1y * y1r[2] + t1x * x1r[2] - t2y * y2r[2] - t2x * x2r[2]),
        )
        qg = _dot(q, gq)
        rg = _dot(r, gr)
        for k in range(3):
            g6[k] = (gq[k] - qg * q[k]) / a
            g6[3 + k] = (gr[k] - rg * r[k]) / b
        _set_gradient(g6, gradients[i])
        if order == 1:
            continue
        gz[:, :] = 0.0
        _add_atan2_outer(gz, 0, 0, -2.0, y2q, x2q, y2q, x2q, t2yy, t2xx, t2xy)
        _add_atan2_outer(gz, 3, 3, 2.0, y1r, x1r, y1r, x1r, t1yy, t1xx, t1xy)
        _add_atan2_outer(gz, 3, 3, -2.0, y2r, x2r, y2r, x2r, t2yy, t2xx, t2xy)
        _add_atan2_outer(gz, 0, 3, -2.0, y2q, x2q, y2r, x2r, t2yy, t2xx, t2xy)
        # d^2 y2 / dq dr = -[A]x (A = t_a), d^2 x2 / dq dr = I; the other blocks vanish
        gz[0, 4] -= 2.0 * t2y * t_a[2]
        gz[0, 5] += 2.0 * t2y * t_a[1]
        gz[1, 3] += 2.0 * t2y * t_a[2]
        gz[1, 5] -= 2.0 * t2y * t_a[0]
        gz[2, 3] -= 2.0 * t2y * t_a[1]
        gz[2, 4] += 2.0 * t2y * t_a[0]
        for k in range(3):
            gz[k, 3 + k] -= 2.0 * t2x
        _project_block(gz, 0, 0, q, q, a, a, h6)
        _project_block(gz, 3, 3, r, r, b, b, h6)
        _project_block(gz, 0, 3, q, r, a, b, h6)
        _add_unit_curvature(h6, 0, q, gq, a)
        _add_unit_curvature(h6, 3, r, gr, b)
        for k in range(6):  # exact symmetry: mirror the upper triangle
            for j in range(k):
                h6[k, j] = h6[j, k]
        _add_hessian(h6, scale, hessians[i])


# --------------------------------------------------------------------------
# array interface
# --------------------------------------------------------------------------

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
    return _run(_bending_loop, stencils, weights, (), (FORM_CODE[form],), order, hessians,
                scale)


def twist_terms(stencils: np.ndarray, frames: np.ndarray, order: int,
                hessians: np.ndarray | None = None, scale: float = 1.0):
    """Per-vertex reference twists (radians, in ``[-pi, pi)``) and their derivatives.

    ``frames`` ``(n, 4, 3)``: ``u_old, t_old`` of edge ``i-1`` and of edge ``i``.
    Returns and accumulates as :func:`bending_terms`.
    """
    return _run(_twist_loop, stencils, frames, (4, 3), (), order, hessians, scale)


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


@njit()
def _gradient_kernel(q, dofs, bend_weights, form, frames, bend_out, twist_out, twist_values):
    n = dofs.shape[0]
    stencils = np.empty((n, 9))
    for i in range(n):
        for k in range(9):
            stencils[i, k] = q[dofs[i, k]]
    values = np.empty(n)
    local = np.empty((n, 9))
    no_hessians = np.zeros((0, 9, 9))
    _bending_loop(stencils, bend_weights, form, 1, 1.0, values, local, no_hessians)
    for i in range(n):  # np.bincount's sums: in the order of the stencils
        for k in range(9):
            bend_out[dofs[i, k]] += local[i, k]
    _twist_loop(stencils, frames, 1, 1.0, twist_values, local, no_hessians)
    for i in range(n):
        for k in range(9):
            twist_out[dofs[i, k]] += local[i, k]


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
    _gradient_kernel(np.ascontiguousarray(q, dtype=np.float64), dofs, bend_weights,
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
