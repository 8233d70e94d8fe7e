"""Finite rotations: the exponential map of SO(3), its logarithm and its tangent map.

Batched over a leading axis: vectors ``(..., 3)``, matrices ``(..., 3, 3)``.
Spatial (left) convention throughout: a variation of ``R`` is ``dR = hat(w) R``
with ``w`` the spatial spin, and ``exp(phi + dphi) = exp(hat(T(phi) dphi)) exp(phi)``
with ``T(phi) = I + a(theta) hat(phi) + b(theta) hat(phi)^2``,
``a = (1 - cos theta) / theta^2``, ``b = (theta - sin theta) / theta^3``,
``theta = |phi|`` (Simo & Vu-Quoc 1986, eq. 2.11; Ibrahimbegovic, Frey & Kozar 1995).

Every coefficient with a removable singularity at ``theta = 0`` switches to its
Taylor series below :data:`SERIES_BELOW` (0.25 or 0.5 for the derivatives,
whose closed forms cancel more), where the series' truncation error is below
round-off.
"""

from __future__ import annotations

import numpy as np

from supercoil._numba import njit

SERIES_BELOW = 0.05


def hat(v: np.ndarray) -> np.ndarray:
    """Skew matrices ``hat(v) u = v x u``, ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


# the closed forms of the coefficients, by kind (see _series)
SINC, A, B, A_PRIME, B_PRIME, F, F_PRIME, T, T_PRIME = range(9)


@njit()
def _closed_form(kind: int, t: float) -> float:
    if kind == SINC:
        return np.sin(t) / t
    if kind == A:
        return (1 - np.cos(t)) / t**2
    if kind == B:
        return (t - np.sin(t)) / t**3
    if kind == A_PRIME:
        return (t * np.sin(t) - 2 * (1 - np.cos(t))) / t**4
    if kind == B_PRIME:
        return (3 * np.sin(t) - t * np.cos(t) - 2 * t) / t**5
    if kind == F:
        return (1 - (t / 2) / np.sin(t / 2)) / t**2
    if kind == F_PRIME:
        x = t / 2
        sigma = x / np.sin(x)
        dsigma = (0.5 * np.sin(x) - 0.5 * x * np.cos(x)) / np.sin(x) ** 2
        return -dsigma / t**3 - 2 * (1 - sigma) / t**4
    if kind == T:
        return np.tan(t / 4) / t
    return (t / (4 * np.cos(t / 4) ** 2) - np.tan(t / 4)) / t**3  # T_PRIME


@njit()
def _series_kernel(theta: np.ndarray, kind: int, coefficients: np.ndarray,
                   below: float) -> np.ndarray:
    out = np.empty(theta.size)
    for k in range(theta.size):
        t = theta[k]
        if t < below:
            t2 = t * t
            poly = 0.0
            for c in coefficients[::-1]:
                poly = poly * t2 + c
            out[k] = poly
        else:
            out[k] = _closed_form(kind, t)
    return out


def _series(theta: np.ndarray, kind: int, coefficients, below: float = SERIES_BELOW
            ) -> np.ndarray:
    """The closed form of ``kind`` where ``theta >= below``, else
    ``sum_k c_k theta^(2k)``."""
    theta = np.asarray(theta, dtype=float)
    flat = np.ascontiguousarray(theta.reshape(-1))
    return _series_kernel(flat, kind, np.asarray(coefficients, dtype=float),
                          float(below)).reshape(theta.shape)


def sinc(theta):
    """``sin(theta) / theta``."""
    return _series(theta, SINC, [1.0, -1 / 6, 1 / 120, -1 / 5040])


def coefficient_a(theta):
    """``a = (1 - cos theta) / theta^2``."""
    return _series(theta, A, [0.5, -1 / 24, 1 / 720, -1 / 40320])


def coefficient_b(theta):
    """``b = (theta - sin theta) / theta^3``."""
    return _series(theta, B,
                   [1 / 6, -1 / 120, 1 / 5040, -1 / 362880])


def coefficient_a_prime(theta):
    """``a'(theta) / theta``."""
    return _series(theta, A_PRIME,
                   [-1 / 12, 1 / 180, -1 / 6720, 1 / 453600, -1 / 47900160], below=0.5)


def coefficient_b_prime(theta):
    """``b'(theta) / theta``."""
    return _series(theta, B_PRIME,
                   [-1 / 60, 1 / 1260, -1 / 60480, 1 / 4989600, -1 / 622702080],
                   below=0.5)


@njit()
def _exp_kernel(phi: np.ndarray) -> np.ndarray:
    """Rodrigues' formula on ``(n, 3)`` rotation vectors (the coefficients as
    :func:`sinc` and :func:`coefficient_a`, their series below ``SERIES_BELOW``)."""
    n = phi.shape[0]
    out = np.empty((n, 3, 3))
    for k in range(n):
        x, y, z = phi[k, 0], phi[k, 1], phi[k, 2]
        t2 = x * x + y * y + z * z
        theta = np.sqrt(t2)
        if theta < SERIES_BELOW:
            s = ((-1 / 5040 * t2 + 1 / 120) * t2 - 1 / 6) * t2 + 1.0
            a = ((-1 / 40320 * t2 + 1 / 720) * t2 - 1 / 24) * t2 + 0.5
        else:
            s = np.sin(theta) / theta
            a = (1 - np.cos(theta)) / theta**2
        # I + s hat(phi) + a hat(phi)^2, hat(phi)^2 = phi phi^T - theta^2 I
        out[k, 0, 0] = 1.0 + a * (x * x - t2)
        out[k, 1, 1] = 1.0 + a * (y * y - t2)
        out[k, 2, 2] = 1.0 + a * (z * z - t2)
        out[k, 0, 1] = -s * z + a * x * y
        out[k, 1, 0] = s * z + a * x * y
        out[k, 0, 2] = s * y + a * x * z
        out[k, 2, 0] = -s * y + a * x * z
        out[k, 1, 2] = -s * x + a * y * z
        out[k, 2, 1] = s * x + a * y * z
    return out


def exp_so3(phi: np.ndarray) -> np.ndarray:
    """Rodrigues' formula ``exp(hat(phi)) = I + sinc(theta) hat + a(theta) hat^2``."""
    phi = np.asarray(phi, dtype=float)
    flat = np.ascontiguousarray(phi.reshape(-1, 3))
    return _exp_kernel(flat).reshape(phi.shape[:-1] + (3, 3))


@njit()
def _log_kernel(R: np.ndarray) -> np.ndarray:
    """:func:`log_so3` on ``(n, 3, 3)`` rotations."""
    n = R.shape[0]
    out = np.empty((n, 3))
    q = np.empty(4)
    for k in range(n):
        r = R[k]
        tr = r[0, 0] + r[1, 1] + r[2, 2]
        case = 0
        best = tr
        for i in range(3):
            if r[i, i] > best:
                best = r[i, i]
                case = i + 1
        if case == 0:
            s = np.sqrt(1.0 + tr) * 2
            q[0] = 0.25 * s
            q[1] = (r[2, 1] - r[1, 2]) / s
            q[2] = (r[0, 2] - r[2, 0]) / s
            q[3] = (r[1, 0] - r[0, 1]) / s
        else:
            i = case - 1
            j, m = (i + 1) % 3, (i + 2) % 3
            s = np.sqrt(1.0 + 2 * r[i, i] - tr) * 2
            q[0] = (r[m, j] - r[j, m]) / s
            q[1 + i] = 0.25 * s
            q[1 + j] = (r[j, i] + r[i, j]) / s
            q[1 + m] = (r[m, i] + r[i, m]) / s
        if q[0] < 0:
            for c in range(4):
                q[c] = -q[c]
        w = q[0]
        v = np.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        if v > 1e-12:
            factor = 2 * np.arctan2(v, w) / v
        else:
            factor = 2.0 / max(w, 1e-300)
        for c in range(3):
            out[k, c] = factor * q[1 + c]
    return out


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of ``R`` with angle in ``[0, pi]``, ``(..., 3, 3) -> (..., 3)``.

    Through the unit quaternion (Shepperd's choice of the largest pivot, accurate at
    every angle: the trace or the largest diagonal entry, the first of equals), then
    ``phi = 2 atan2(|v|, w) v / |v|`` with ``w >= 0``.
    """
    R = np.asarray(R, dtype=float)
    flat = np.ascontiguousarray(R.reshape(-1, 3, 3))
    return _log_kernel(flat).reshape(R.shape[:-2] + (3,))


def dexp(phi: np.ndarray) -> np.ndarray:
    """Tangent map ``T(phi) = I + a hat(phi) + b hat(phi)^2`` (spatial spin per ``dphi``)."""
    phi = np.asarray(phi, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)
    P = hat(phi)
    return (np.eye(3) + coefficient_a(theta)[..., None, None] * P
            + coefficient_b(theta)[..., None, None] * (P @ P))


def dexp_transpose_derivative(phi: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``d/dphi [T(phi)^T m]`` at fixed ``m``, ``(..., 3, 3)``.

    ``T^T m = m - a phi x m + b (phi (phi.m) - theta^2 m)``; the derivative is
    ``-(a'/theta)(phi x m) phi^T + a hat(m) + (b'/theta)(phi (phi.m) - theta^2 m) phi^T
    + b ((phi.m) I + phi m^T - 2 m phi^T)``; at ``phi = 0`` it is ``hat(m) / 2``.
    """
    phi = np.asarray(phi, dtype=float)
    m = np.asarray(m, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)
    a, b = coefficient_a(theta), coefficient_b(theta)
    ap, bp = coefficient_a_prime(theta), coefficient_b_prime(theta)
    pm = np.sum(phi * m, axis=-1)
    cross = np.cross(phi, m)
    along = phi * pm[..., None] - (theta**2)[..., None] * m
    outer = lambda u, v: u[..., :, None] * v[..., None, :]
    return (-ap[..., None, None] * outer(cross, phi) + a[..., None, None] * hat(m)
            + bp[..., None, None] * outer(along, phi)
            + b[..., None, None] * (pm[..., None, None] * np.eye(3) + outer(phi, m)
                                    - 2 * outer(m, phi)))


def coefficient_f(theta):
    """``f = (1 - sigma) / theta^2``, ``sigma = (theta/2) / sin(theta/2)``.

    ``S(psi) = I + f hat(psi)^2 = (ad/2) / sinh(ad/2)``, ``ad = hat(psi)``, maps the
    difference of two nodal spins (in the midpoint frame) to the variation of
    their relative rotation vector ``psi`` (see :mod:`supercoil.cosserat.element`).
    """
    return _series(theta, F,
                   [-1 / 24, -7 / 5760, -31 / 967680, -127 / 154828800,
                    -73 / 3503554560])


def coefficient_f_prime(theta):
    """``f'(theta) / theta``."""
    return _series(theta, F_PRIME, [-7 / 2880, -31 / 241920, -127 / 25804800, -73 / 437944320],
                   below=0.25)


def coefficient_t(theta):
    """``t = tan(theta/4) / theta``: the midpoint spin is ``Sigma - (t/2) psi x Delta``."""
    return _series(theta, T,
                   [1 / 4, 1 / 192, 1 / 7680, 17 / 5160960, 62 / 743178240])


def coefficient_t_prime(theta):
    """``t'(theta) / theta``."""
    return _series(theta, T_PRIME,
                   [1 / 96, 1 / 1920, 17 / 860160, 31 / 46448640], below=0.25)
