"""The compiled loops of the rod's stencil kernels: bending and reference twist, with
exact derivatives (numba).

Each kernel is a scalar function of the three vertices ``x_{i-1}, x_i, x_{i+1}``
around one interior vertex (a flat vector of 9 numbers) plus per-vertex data.
The loops write local values, gradients ``(9,)`` and Hessians ``(9, 9)`` into
arrays that :mod:`supercoil.rod.kernels` (the array interface) allocates and checks;
:mod:`supercoil.rod.assembly` scatters them into the global sparse pattern. The loops
and their building blocks share this module, so that numba's cache, which checks only
the file of the function it caches, sees every edit of a loop's callees.

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

# the codes of the curvature forms "tan", "sin" and "angle" in the loops
TAN, SIN, ANGLE = 0, 1, 2

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
    if form == TAN:
        return 4.0 * s, 4.0, 0.0
    u = 1.0 / (1.0 + s)
    if form == SIN:
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
def bending_loop(stencils, weights, form, order, scale, values, gradients, hessians):
    """Bending energies ``w k^2`` of the stencils ``(n, 9)`` into ``values``, up to
    ``order``: gradients into ``gradients`` ``(n, 9)``, ``scale`` times the Hessians
    added to ``hessians`` ``(n, 9, 9)``; ``form`` one of the codes TAN, SIN, ANGLE."""
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
def twist_loop(stencils, frames, order, scale, values, gradients, hessians):
    """Reference twists of the stencils ``(n, 9)`` with the transported frames ``(n, 4,
    3)`` into ``values``, and their derivatives up to ``order`` as :func:`bending_loop`."""
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


@njit()
def gradient_loop(q, dofs, bend_weights, form, frames, bend_out, twist_out, twist_values):
    """Bending and twist gradients at order 1 on ``q[dofs]``, summed by DOF into
    ``bend_out`` and ``twist_out``; the reference twists into ``twist_values``."""
    n = dofs.shape[0]
    stencils = np.empty((n, 9))
    for i in range(n):
        for k in range(9):
            stencils[i, k] = q[dofs[i, k]]
    values = np.empty(n)
    local = np.empty((n, 9))
    no_hessians = np.zeros((0, 9, 9))
    bending_loop(stencils, bend_weights, form, 1, 1.0, values, local, no_hessians)
    for i in range(n):  # np.bincount's sums: in the order of the stencils
        for k in range(9):
            bend_out[dofs[i, k]] += local[i, k]
    twist_loop(stencils, frames, 1, 1.0, twist_values, local, no_hessians)
    for i in range(n):
        for k in range(9):
            twist_out[dofs[i, k]] += local[i, k]
