"""The twisted circle of a continuous Cosserat rod: exact equilibrium and mode stability.

An isotropic, intrinsically straight Cosserat rod of length ``L`` (bending A, twist C,
shear GA, stretch EA, intrinsic twist ``tau0``) closed into a ring whose material line
``d1`` turns ``n`` times about the centreline (its ribbon's linking number; the excess
link is ``dLk = n - tau0 L / 2 pi``). The uniformly twisted circle is an equilibrium for
every ``dLk``, but not the Kirchhoff rod's: the twist moment ``C tau`` turning around
the circle needs a shear force ``n`` along the circle's axis (``m' + x' x n = 0``), so
the directors tilt out of the tangent and the ring stretches.

Equilibrium. With ``kappa = 2 pi / L`` (the frame turns once about the axis ``e_z``),
``d3 = cos(delta) t + sin(delta) e_z`` tilted by ``delta`` toward the axis, stretch
``1 + eps = |x'|`` and the excess twist rate ``tau_e = 2 pi dLk / L``, the strains are
``K = kappa (0, cos delta, sin delta)`` (plus the twist, in a frame co-rotating with
the twist; isotropy), ``Gamma = (1 + eps) (0, -sin delta, cos delta) - e_3``, and the
balance of forces (``n`` parallel to the axis) and of moments gives

    (1 + eps) (GA sin^2 delta + EA cos^2 delta) = EA cos delta,
    kappa cos delta ((A - C) kappa sin delta - C tau_e) = GA (1 + eps)^2 sin delta / cos delta,

so ``delta = -C tau_e kappa / GA + O(GA^-2)``. The energy is ``L`` times
``A kappa^2 cos^2 delta / 2 + C (kappa sin delta + tau_e)^2 / 2 + GA (1 + eps)^2 sin^2
delta / 2 + EA ((1 + eps) cos delta - 1)^2 / 2``, ``2 pi^2 (A + C dLk^2) / L`` in the
Kirchhoff limit.

Stability. Perturb the frame ``R_f exp(hat(phi))`` and the centreline ``x + R_f v``
(``phi``, ``v`` in the co-rotating frame ``R_f`` of the circle, in which every
coefficient is constant). To second order
``K = K_f + (phi' + K_f x phi) + (phi x (phi x K_f) - phi x phi') / 2`` and
``Gamma = Gamma_0 + (v' + K_f x v + g x phi) + (phi x (phi x g) / 2 - phi x (v' + K_f x v))``
(``g = Gamma_0 + e_3``), so the second variation is
``integral dK.C_K dK / 2 + d2K.mu + dGamma.C_G dGamma / 2 + d2Gamma.n`` with the
circle's stresses ``mu = C_K (K - K0)``, ``n = C_G Gamma_0``. Fourier modes
``(phi, v) exp(i m kappa s)`` decouple: a Hermitian 6 x 6 matrix ``H(m)`` per mode
(:func:`mode_matrix`). The rigid motions and the rotation of the section about ``d3``
(isotropy) are its null vectors at ``m = 0`` (three) and ``m = 1`` (two complex); mode
``m >= 2`` loses stability where ``H(m)`` becomes singular (:func:`michell_threshold`),
Michell's ``dLk_m = (A / C) sqrt(m^2 - 1)`` (Michell 1889; Goriely 2006) in the
Kirchhoff limit. The shift of the threshold by shear and extension follows from
this matrix; to first order in ``1 / GA`` and ``1 / EA`` it is
``dLk_m (1 + (C - 3 A / 2) kappa^2 / GA - A kappa^2 / (2 EA))`` for every mode
(:func:`first_order_threshold`: coefficients measured on the matrix): shear lowers the
threshold when ``C < 3 A / 2`` and raises it above, extension always lowers it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from supercoil.cosserat.rotations import hat
from supercoil.errors import InputError


@dataclass(frozen=True)
class CircleState:
    """The continuous twisted circle: tilt ``delta``, stretch ``eps`` and its energy."""

    tilt: float
    stretch: float
    energy: float
    curvature: np.ndarray  # K in the co-rotating frame
    shear: np.ndarray  # Gamma
    moment: np.ndarray  # mu = C_K (K - K0)
    force: np.ndarray  # n = C_G Gamma


def _check(twist_ratio, stretch_stiffness, shear_stiffness):
    for name, value in (("twist_ratio", twist_ratio), ("stretch_stiffness", stretch_stiffness),
                        ("shear_stiffness", shear_stiffness)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive finite number, got {value!r}")


def circle_state(twist_ratio: float, excess_link: float, stretch_stiffness: float,
                 shear_stiffness: float) -> CircleState:
    """The continuous twisted circle at ``dLk`` (module doc), nondimensional ``A = L = 1``:
    ``twist_ratio = C / A``, ``stretch_stiffness = EA L^2 / A``,
    ``shear_stiffness = GA L^2 / A``."""
    _check(twist_ratio, stretch_stiffness, shear_stiffness)
    A, C, GA, EA = 1.0, float(twist_ratio), float(shear_stiffness), float(stretch_stiffness)
    kappa, tau_e = 2 * np.pi, 2 * np.pi * float(excess_link)

    def stretch(delta):
        return EA * np.cos(delta) / (GA * np.sin(delta) ** 2 + EA * np.cos(delta) ** 2) - 1

    def balance(delta):
        c, s = np.cos(delta), np.sin(delta)
        return kappa * c * c * ((A - C) * kappa * s - C * tau_e) - GA * (1 + stretch(delta)) ** 2 * s

    if tau_e == 0.0:
        delta = 0.0
    else:
        guess = -C * tau_e * kappa / GA
        width = 2 * abs(guess)
        while balance(np.sign(guess) * width) * balance(0.0) > 0:
            width *= 2
            if width > 1.5:
                raise InputError("no tilted twisted circle: the shear stiffness is too small "
                                 "for this excess link")
        lo, hi = sorted((0.0, np.sign(guess) * width))
        delta = brentq(balance, lo, hi, xtol=1e-16, rtol=4 * np.finfo(float).eps)
    eps = stretch(delta)
    c, s = np.cos(delta), np.sin(delta)
    K = kappa * np.array([0.0, c, s])
    gamma = (1 + eps) * np.array([0.0, -s, c]) - np.array([0.0, 0.0, 1.0])
    mu = np.array([A, A, C]) * (K + np.array([0.0, 0.0, tau_e]))
    n = np.array([GA, GA, EA]) * gamma
    energy = 0.5 * (A * (kappa * c) ** 2 + C * (kappa * s + tau_e) ** 2
                    + GA * ((1 + eps) * s) ** 2 + EA * ((1 + eps) * c - 1) ** 2)
    return CircleState(float(delta), float(eps), float(energy), K, gamma, mu, n)


def mode_matrix(twist_ratio: float, excess_link: float, mode: int, stretch_stiffness: float,
                shear_stiffness: float) -> np.ndarray:
    """``H(m)`` ``(6, 6)`` Hermitian: the second variation of the continuous circle on the
    Fourier mode ``(phi, v) exp(2 pi i m s / L)`` (module doc)."""
    state = circle_state(twist_ratio, excess_link, stretch_stiffness, shear_stiffness)
    CK = np.diag([1.0, 1.0, float(twist_ratio)])
    CG = np.diag([float(shear_stiffness), float(shear_stiffness), float(stretch_stiffness)])
    K, mu, n = state.curvature, state.moment, state.force
    g = state.shear + np.array([0.0, 0.0, 1.0])
    eye, zero = np.eye(3), np.zeros((3, 3))
    # y = (phi, phi', v, v')
    DK = np.hstack([hat(K), eye, zero, zero])
    DG = np.hstack([hat(g), zero, hat(K), eye])
    M = DK.T @ CK @ DK + DG.T @ CG @ DG

    def add(i, j, X):
        M[3 * i:3 * i + 3, 3 * j:3 * j + 3] += X
        M[3 * j:3 * j + 3, 3 * i:3 * i + 3] += X.T

    def curl(a, b):  # phi.(phi x (phi x a)).b / 2 as the block of y^T M y / 2
        return 0.5 * (np.outer(a, b) + np.outer(b, a)) - np.dot(a, b) * eye

    M[:3, :3] += curl(K, mu) + curl(g, n)
    add(0, 1, 0.5 * hat(mu))  # -(phi x phi').mu / 2 = phi^T hat(mu) phi' / 2
    add(0, 3, hat(n))  # -(phi x v').n
    add(0, 2, hat(n) @ hat(K))  # -(phi x (K x v)).n
    k = 2 * np.pi * mode
    P = np.zeros((12, 6), dtype=complex)
    P[0:3, 0:3] = eye
    P[3:6, 0:3] = 1j * k * eye
    P[6:9, 3:6] = eye
    P[9:12, 3:6] = 1j * k * eye
    H = P.conj().T @ M @ P
    return 0.5 * (H + H.conj().T)


def lowest_mode_eigenvalue(twist_ratio: float, excess_link: float, mode: int,
                           stretch_stiffness: float, shear_stiffness: float) -> float:
    """The smallest eigenvalue of ``H(m)``: zero at the threshold of mode ``m``."""
    H = mode_matrix(twist_ratio, excess_link, mode, stretch_stiffness, shear_stiffness)
    return float(np.linalg.eigvalsh(H)[0])


def michell_threshold(twist_ratio: float, mode: int, stretch_stiffness: float,
                      shear_stiffness: float) -> float:
    """Excess link where mode ``m >= 2`` of the continuous Cosserat circle loses stability:
    the root of :func:`lowest_mode_eigenvalue` near Michell's ``sqrt(m^2 - 1) A / C``."""
    if not (isinstance(mode, (int, np.integer)) and mode >= 2):
        raise InputError(f"mode must be an integer >= 2, got {mode!r}")
    _check(twist_ratio, stretch_stiffness, shear_stiffness)
    michell = np.sqrt(mode**2 - 1) / twist_ratio

    def f(dlk):
        return lowest_mode_eigenvalue(twist_ratio, dlk, mode, stretch_stiffness, shear_stiffness)

    lo, hi = 0.5 * michell, 1.5 * michell
    if not f(lo) > 0 > f(hi):
        raise InputError("the threshold is not within half of Michell's value: the shear "
                         "and stretch stiffnesses are too small")
    return float(brentq(f, lo, hi, xtol=1e-14 * michell, rtol=4 * np.finfo(float).eps))


def first_order_threshold(twist_ratio: float, mode: int, stretch_stiffness: float,
                          shear_stiffness: float) -> float:
    """Michell's threshold with its first-order shift by shear and extension,
    ``(A/C) sqrt(m^2 - 1) (1 + (C - 3 A / 2) kappa^2 / GA - A kappa^2 / (2 EA))``,
    ``kappa = 2 pi / L`` (nondimensional, ``A = L = 1``).

    The coefficients are those of :func:`michell_threshold` (the singular mode matrix)
    as ``GA, EA -> infinity``: measured by Richardson extrapolation in ``1 / GA`` and
    ``1 / EA`` for ``m = 2, 3, 4`` and ``C / A`` from 0.5 to 2, they are
    ``C / A - 3 / 2`` and ``-1 / 2`` to within 1e-3, independent of the mode.
    """
    if not (isinstance(mode, (int, np.integer)) and mode >= 2):
        raise InputError(f"mode must be an integer >= 2, got {mode!r}")
    _check(twist_ratio, stretch_stiffness, shear_stiffness)
    k2 = (2 * np.pi) ** 2
    return float(np.sqrt(mode**2 - 1) / twist_ratio
                 * (1 + (twist_ratio - 1.5) * k2 / shear_stiffness - 0.5 * k2 / stretch_stiffness))
