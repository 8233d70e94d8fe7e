"""The two-node Simo-Reissner element: strains, energy, gradient and tangents.

Element ``e`` joins nodes ``a = e`` and ``b = e + 1`` (rest length ``h``). The rotation
is interpolated along the geodesic ``R(s) = R_a exp(s psi / h)``,
``psi = log(R_a^T R_b)`` (the relative rotation vector, in ``a``'s frame), and the
position linearly. The strains of Simo (1985) are then

* curvature ``K = axial(R^T R') = psi / h``: constant, exact for this interpolation;
* shear and extension ``Gamma = R_m^T (x_b - x_a) / h - e_3`` at the element's
  midpoint rotation ``R_m = R_a exp(psi / 2)`` (one-point, reduced integration);

and the energy is ``sum_e h ((K - K0).C_K (K - K0) + Gamma.C_G Gamma) / 2`` with
``C_K = diag(A, A, C)``, ``C_G = diag(GA, GA, EA)`` and ``K0 = (0, 0, tau0)`` the
intrinsic twist (zero for the intrinsically straight, untwisted rod; for an isotropic
section it only shifts the twist at rest, the rod stays straight at rest).

Why this element. For two nodes the objective interpolation of Crisfield & Jelenic
(1999) (the relative rotation interpolated from a reference rotation) is this
geodesic, and with the midpoint as reference it is symmetric in ``a`` and ``b``.
Both strains depend only on ``R_a^T R_b`` and on ``R_m^T (x_b - x_a)``, which a rigid
motion ``(x, R) -> (Q x + c, Q R)`` leaves unchanged, so the discrete energy is
objective, and it depends on the current nodal values only, so it has no path
dependence (the additive interpolation of incremental rotations has both defects,
Crisfield & Jelenic 1999). Reduced integration of the shear strain is the classical
cure of shear locking for linear elements: a pure bending state (constant ``K``,
``Gamma = 0``) is represented exactly by chords of length ``h`` along ``R_m e_3``,
so a stiff ``GA`` adds no spurious energy to bending (the element is exact for
the roll-up of a cantilever by an end moment, whatever GA and EA).

Derivatives. With spatial spins ``dR_i = hat(w_i) R_i`` and, in the midpoint frame,
``Sigma = R_m^T (w_a + w_b) / 2``, ``Delta = R_m^T (w_b - w_a)``:

* ``d psi = S(psi) Delta``, ``S = (ad/2) / sinh(ad/2) = I + f hat(psi)^2``;
* the midpoint's body spin ``omega = Sigma - (t/2) psi x Delta``, ``t = tan(|psi|/4) / |psi|``;
* ``d Gamma = R_m^T dc / h + g x omega``, ``g = Gamma + e_3``, ``c = x_b - x_a``.

So ``dW = F.dc + M_S.Sigma + M_D.Delta`` with ``F = R_m n``, ``n = C_G Gamma``,
``M_S = h n x g``, ``M_D = S mu + (h t / 2) psi x (n x g)``, ``mu = C_K (K - K0)``.
The second variation along one-parameter subgroups ``exp(eps hat(w)) R`` (spins held
fixed) is the Hessian ``H0`` of the energy in exponential coordinates centred at
the state: it is symmetric, and it is the symmetric part of the consistent tangent
``K_c = H0 - blockdiag(hat(m_i)) / 2`` (``m_i`` the nodal spatial moments of the
gradient), the linearisation of the gradient under ``R -> exp(hat(w)) R``
(Simo & Vu-Quoc 1986: its skew part is proportional to the moments, hence zero at an
equilibrium of conservative loads).
"""

from __future__ import annotations

import numpy as np

from supercoil.cosserat.rotations import (
    coefficient_f,
    coefficient_f_prime,
    coefficient_t,
    coefficient_t_prime,
    exp_so3,
    hat,
    log_so3,
)

E3 = np.array([0.0, 0.0, 1.0])


def _transpose(R: np.ndarray) -> np.ndarray:
    return np.swapaxes(R, -1, -2)


def _outer(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., :, None] * v[..., None, :]


class ElementState:
    """Kinematics and stresses of every element of a rod, all ``(n_elements, ...)``.

    ``positions`` ``(n_nodes, 3)``, ``rotations`` ``(n_nodes, 3, 3)`` (columns: the
    directors ``d_1, d_2, d_3``), ``h`` the rest length of an element,
    ``bending_moduli`` ``(3,) = (A, A, C)``, ``shear_moduli`` ``(3,) = (GA, GA, EA)`` and
    ``intrinsic_twist`` ``tau0`` (the curvature at rest is ``K0 = (0, 0, tau0)``).
    """

    def __init__(self, positions: np.ndarray, rotations: np.ndarray, h: float,
                 bending_moduli: np.ndarray, shear_moduli: np.ndarray,
                 intrinsic_twist: float = 0.0):
        x = np.asarray(positions, dtype=float)
        R = np.asarray(rotations, dtype=float)
        self.h = float(h)
        self.ck = np.asarray(bending_moduli, dtype=float)
        self.cg = np.asarray(shear_moduli, dtype=float)
        Ra = R[:-1]
        self.psi = log_so3(_transpose(Ra) @ R[1:])  # (ne, 3)
        self.Rm = Ra @ exp_so3(0.5 * self.psi)  # (ne, 3, 3)
        self.chord = x[1:] - x[:-1]
        self.g = np.einsum("nji,nj->ni", self.Rm, self.chord) / self.h
        self.curvature = self.psi / self.h  # K
        self.shear = self.g - E3  # Gamma (shear 1, 2; extension 3)
        self.rest_curvature = np.array([0.0, 0.0, float(intrinsic_twist)])
        self.mu = self.ck * (self.curvature - self.rest_curvature)
        self.n = self.cg * self.shear
        self.theta = np.linalg.norm(self.psi, axis=1)

    def energy_density(self) -> np.ndarray:
        """``h ((K - K0).C_K (K - K0) + Gamma.C_G Gamma) / 2`` per element, ``(n_elements,)``."""
        return 0.5 * self.h * (np.sum((self.curvature - self.rest_curvature) * self.mu, axis=1)
                               + np.sum(self.shear * self.n, axis=1))

    def _S(self) -> np.ndarray:
        P = hat(self.psi)
        return np.eye(3) + coefficient_f(self.theta)[:, None, None] * (P @ P)

    def local_gradient(self) -> np.ndarray:
        """``(n_elements, 12)``: ``[force_a, moment_a, force_b, moment_b]``, spatial.

        ``dW = sum force.dx + moment.w`` for ``dR = hat(w) R``.
        """
        h, Rm = self.h, self.Rm
        F = np.einsum("nij,nj->ni", Rm, self.n)
        N = np.cross(self.n, self.g)
        MS = h * N
        t = coefficient_t(self.theta)
        MD = np.einsum("nij,nj->ni", self._S(), self.mu) \
            + 0.5 * h * t[:, None] * np.cross(self.psi, N)
        out = np.empty((len(F), 12))
        out[:, 0:3] = -F
        out[:, 3:6] = np.einsum("nij,nj->ni", Rm, 0.5 * MS - MD)
        out[:, 6:9] = F
        out[:, 9:12] = np.einsum("nij,nj->ni", Rm, 0.5 * MS + MD)
        return out

    def intrinsic_twist_derivative(self) -> np.ndarray:
        """``d local_gradient / d tau0`` ``(n_elements, 12)``: ``d mu = -C e_3``, so
        ``d M_D = -C S e_3`` and the moments change by ``+-R_m S C e_3`` (exact: the
        gradient is affine in ``tau0``)."""
        dMD = -self.ck[2] * self._S()[:, :, 2]
        out = np.zeros((len(dMD), 12))
        out[:, 3:6] = -np.einsum("nij,nj->ni", self.Rm, dMD)
        out[:, 9:12] = np.einsum("nij,nj->ni", self.Rm, dMD)
        return out

    def local_hessian(self) -> np.ndarray:
        """``H0`` ``(n_elements, 12, 12)``: the symmetrised tangent (see module doc).

        The second variation is a sum of bilinear terms ``(A v).(X (B v))`` in the
        12 nodal variations ``v = (dx_a, w_a, dx_b, w_b)``; each is assembled as
        ``A^T X B`` (those with one ``A`` summed first) and the sum symmetrised (the
        quadratic form fixes only that).
        """
        h, Rm, psi, g, n, mu = self.h, self.Rm, self.psi, self.g, self.n, self.mu
        ne = len(psi)
        RT = _transpose(Rm)
        zero = np.zeros((ne, 3, 3))
        Pu = np.concatenate([-RT, zero, RT, zero], axis=2)  # R_m^T dc
        PS = np.concatenate([zero, 0.5 * RT, zero, 0.5 * RT], axis=2)  # Sigma
        PD = np.concatenate([zero, -RT, zero, RT], axis=2)  # Delta
        th = self.theta
        t, tp = coefficient_t(th), coefficient_t_prime(th)
        f, fp = coefficient_f(th), coefficient_f_prime(th)
        hp = hat(psi)
        S = np.eye(3) + f[:, None, None] * (hp @ hp)
        Pw = PS - 0.5 * t[:, None, None] * (hp @ PD)  # omega
        G = hat(g)
        PG = Pu / h + G @ Pw  # d Gamma
        Pp = S @ PD  # d psi
        nh = hat(n)
        CG = self.cg[None, :, None] * np.eye(3)
        CK = self.ck[None, :, None] * np.eye(3)
        N = np.cross(n, g)
        MS = h * N
        MD = np.einsum("nij,nj->ni", S, mu) + 0.5 * h * t[:, None] * np.cross(psi, N)
        dN = nh - G @ CG  # d(n x g) per d Gamma
        pm = np.sum(psi * mu, axis=1)
        along = psi * pm[:, None] - (th**2)[:, None] * mu
        DSmu = (fp[:, None, None] * _outer(along, psi)
                + f[:, None, None] * (pm[:, None, None] * np.eye(3) + _outer(psi, mu)
                                      - 2 * _outer(mu, psi)))
        dtpsi = t[:, None, None] * np.eye(3) + tp[:, None, None] * _outer(psi, psi)

        # the terms grouped by their left factor: A^T (X B + Y C + ...)
        H = (_transpose(Pu) @ (-nh @ Pw + CG @ PG)
             + _transpose(PS) @ (h * dN @ PG - hat(MS) @ Pw)
             + _transpose(PD) @ ((DSmu + S @ CK / h - 0.5 * h * hat(N) @ dtpsi) @ Pp
                                 + 0.5 * h * t[:, None, None] * hp @ dN @ PG
                                 - hat(MD) @ Pw))
        return 0.5 * (H + _transpose(H))
