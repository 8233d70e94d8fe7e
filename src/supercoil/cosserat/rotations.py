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

SERIES_BELOW = 0.05


def hat(v: np.ndarray) -> np.ndarray:
    """Skew matrices ``hat(v) u = v x u``, ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _series(theta: np.ndarray, exact, coefficients, below: float = SERIES_BELOW) -> np.ndarray:
    """``exact(theta)`` where ``theta >= below``, else ``sum_k c_k theta^(2k)``."""
    theta = np.asarray(theta, dtype=float)
    small = theta < below
    safe = np.where(small, 1.0, theta)
    out = exact(safe)
    t2 = theta * theta
    poly = np.zeros_like(theta)
    for c in reversed(coefficients):
        poly = poly * t2 + c
    return np.where(small, poly, out)


def sinc(theta):
    """``sin(theta) / theta``."""
    return _series(theta, lambda t: np.sin(t) / t, [1.0, -1 / 6, 1 / 120, -1 / 5040])


def coefficient_a(theta):
    """``a = (1 - cos theta) / theta^2``."""
    return _series(theta, lambda t: (1 - np.cos(t)) / t**2, [0.5, -1 / 24, 1 / 720, -1 / 40320])


def coefficient_b(theta):
    """``b = (theta - sin theta) / theta^3``."""
    return _series(theta, lambda t: (t - np.sin(t)) / t**3,
                   [1 / 6, -1 / 120, 1 / 5040, -1 / 362880])


def coefficient_a_prime(theta):
    """``a'(theta) / theta``."""
    return _series(theta, lambda t: (t * np.sin(t) - 2 * (1 - np.cos(t))) / t**4,
                   [-1 / 12, 1 / 180, -1 / 6720, 1 / 453600, -1 / 47900160], below=0.5)


def coefficient_b_prime(theta):
    """``b'(theta) / theta``."""
    return _series(theta, lambda t: (3 * np.sin(t) - t * np.cos(t) - 2 * t) / t**5,
                   [-1 / 60, 1 / 1260, -1 / 60480, 1 / 4989600, -1 / 622702080],
                   below=0.5)


def exp_so3(phi: np.ndarray) -> np.ndarray:
    """Rodrigues' formula ``exp(hat(phi)) = I + sinc(theta) hat + a(theta) hat^2``."""
    phi = np.asarray(phi, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)
    P = hat(phi)
    P2 = P @ P
    return (np.eye(3) + sinc(theta)[..., None, None] * P
            + coefficient_a(theta)[..., None, None] * P2)


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of ``R`` with angle in ``[0, pi]``, ``(..., 3, 3) -> (..., 3)``.

    Through the unit quaternion (Shepperd's choice of the largest pivot, accurate at
    every angle), then ``phi = 2 atan2(|v|, w) v / |v|`` with ``w >= 0``.
    """
    R = np.asarray(R, dtype=float)
    shape = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    tr = np.trace(R, axis1=1, axis2=2)
    diag = np.stack([R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    pivots = np.concatenate([tr[:, None], diag], axis=1)
    k = np.argmax(pivots, axis=1)
    quat = np.empty((R.shape[0], 4))  # (w, x, y, z)
    r21, r12 = R[:, 2, 1], R[:, 1, 2]
    r02, r20 = R[:, 0, 2], R[:, 2, 0]
    r10, r01 = R[:, 1, 0], R[:, 0, 1]
    for case in range(4):
        sel = k == case
        if not np.any(sel):
            continue
        if case == 0:
            s = np.sqrt(1.0 + tr[sel]) * 2
            quat[sel] = np.stack([0.25 * s, (r21 - r12)[sel] / s, (r02 - r20)[sel] / s,
                                  (r10 - r01)[sel] / s], axis=1)
        else:
            i = case - 1
            j, m = (i + 1) % 3, (i + 2) % 3
            s = np.sqrt(1.0 + 2 * diag[sel, i] - tr[sel]) * 2
            q = np.empty((int(sel.sum()), 4))
            q[:, 0] = (R[sel, m, j] - R[sel, j, m]) / s
            q[:, 1 + i] = 0.25 * s
            q[:, 1 + j] = (R[sel, j, i] + R[sel, i, j]) / s
            q[:, 1 + m] = (R[sel, m, i] + R[sel, i, m]) / s
            quat[sel] = q
    quat *= np.where(quat[:, :1] < 0, -1.0, 1.0)
    w, v = quat[:, 0], quat[:, 1:]
    s = np.linalg.norm(v, axis=1)
    angle = 2 * np.arctan2(s, w)
    factor = np.where(s > 1e-12, angle / np.where(s > 1e-12, s, 1.0), 2.0 / np.maximum(w, 1e-300))
    return (factor[:, None] * v).reshape(shape + (3,))


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
    return _series(theta, lambda t: (1 - (t / 2) / np.sin(t / 2)) / t**2,
                   [-1 / 24, -7 / 5760, -31 / 967680, -127 / 154828800,
                    -73 / 3503554560])


def coefficient_f_prime(theta):
    """``f'(theta) / theta``."""
    def exact(t):
        x = t / 2
        sigma = x / np.sin(x)
        dsigma = (0.5 * np.sin(x) - 0.5 * x * np.cos(x)) / np.sin(x) ** 2
        return -dsigma / t**3 - 2 * (1 - sigma) / t**4

    return _series(theta, exact, [-7 / 2880, -31 / 241920, -127 / 25804800, -73 / 437944320],
                   below=0.25)


def coefficient_t(theta):
    """``t = tan(theta/4) / theta``: the midpoint spin is ``Sigma - (t/2) psi x Delta``."""
    return _series(theta, lambda t: np.tan(t / 4) / t,
                   [1 / 4, 1 / 192, 1 / 7680, 17 / 5160960, 62 / 743178240])


def coefficient_t_prime(theta):
    """``t'(theta) / theta``."""
    return _series(theta, lambda t: (t / (4 * np.cos(t / 4) ** 2) - np.tan(t / 4)) / t**3,
                   [1 / 96, 1 / 1920, 17 / 860160, 31 / 46448640], below=0.25)
