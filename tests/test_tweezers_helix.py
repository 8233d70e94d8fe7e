"""Kirchhoff's helix: the discrete rod's equilibrium equations on an exact helix.

A helix of radius R whose tangent makes the angle alpha with its axis, with a
uniform twisting moment m3 = C Omega, is an equilibrium of the Kirchhoff rod
under an axial force T and axial moment M (Love, Treatise, sec. 270-271;
derived here from n' = 0, m' + t x n = 0 with m = A t x t' + m3 t):

    T = (sin(alpha) / R) (m3 - A sin(alpha) cos(alpha) / R),
    M = A sin(alpha)^3 / R + m3 cos(alpha).

The internal force is T e_z everywhere, so each edge's tension (the
multiplier of its inextensibility constraint) is T cos(alpha). The discrete
gradient of the clamped rod's energy plus those constraint forces must then
vanish at the interior nodes of a polygon inscribed in the helix, to O(h^2);
with another force it does not. (The axial moment M is stated for reference:
the interior equilibrium equations do not see it, so it is not checked here.)
"""

import numpy as np
import pytest

from supercoil.geometry.curves import parallel_transport
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod


def helix_residual(n, radius=0.15, alpha=0.6, twist_ratio=1.3, twist=0.8, force_offset=0.0):
    """max |KKT residual| per unit length at interior nodes, and the force T used."""
    step = np.sin(alpha) / radius / (n - 2)  # arc step 1/(n-2) on the continuum helix
    phi = step * np.arange(n)
    pts = np.stack([radius * np.cos(phi), radius * np.sin(phi),
                    radius * phi / np.tan(alpha)], axis=1)
    chord = np.linalg.norm(pts[1] - pts[0])
    rod = Rod(n, twist_stiffness=twist_ratio, closed=False, length=chord * (n - 2))
    problem = ClampedRodEnergy(rod, straight_rod(n, rod.length), 0.0)
    # reference frames of the helix: parallel transport from a director normal to t_0
    # (set directly: the helix's ends are not clamped on the axis)
    t = np.diff(pts, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    u = np.empty_like(t)
    u[0] = np.cross(t[0], [0.0, 0.0, 1.0])
    u[0] /= np.linalg.norm(u[0])
    for i in range(1, len(t)):
        u[i] = parallel_transport(u[i - 1:i], t[i - 1:i], t[i:i + 1])[0]
    problem._set_frames(t, u)
    q = pts.ravel()
    problem.turns = 0.0
    problem.turns = twist - problem.twist(q)  # the uniform excess twist Tw = twist
    m3 = 2 * np.pi * twist_ratio * twist / rod.length
    force = np.sin(alpha) / radius * (m3 - np.sin(alpha) * np.cos(alpha) / radius)
    force += force_offset
    mu = np.full(problem.n_constraints, force * np.cos(alpha))
    residual = (problem.gradient(q) + problem.constraint_jacobian(q).T @ mu).reshape(-1, 3)
    return float(np.max(np.abs(residual[3:n - 3]))) / rod.edge_length, force


@pytest.mark.parametrize("alpha, twist", [(0.6, 0.8), (1.1, -0.5), (0.3, 2.0)])
def test_helix_is_an_equilibrium_with_kirchhoffs_force(alpha, twist):
    ns = (25, 50, 100, 200)
    errors = np.array([helix_residual(n, alpha=alpha, twist=twist)[0] for n in ns])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.15), (errors, orders)
    # another force is not an equilibrium: the residual stays O(1)
    wrong = helix_residual(200, alpha=alpha, twist=twist, force_offset=1.0)[0]
    assert wrong > 100 * errors[-1]
