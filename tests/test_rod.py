"""The discrete closed rod: derivatives against finite differences, invariances, convergence."""

import numpy as np
import pytest
from conftest import smooth_closed_curve
from scipy.integrate import quad
from scipy.optimize import brentq

from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.topology import writhe


def make(points, excess_link=0.7, twist_ratio=1.3, form="angle"):
    rod = Rod(len(points), twist_stiffness=twist_ratio, curvature=form)
    return ClosedRodEnergy(rod, points, excess_link)


def central_difference(f, q, d, eps=1e-6):
    return (f(q + eps * d) - f(q - eps * d)) / (2 * eps)


TERMS = {
    "bending": lambda p: (p.bending_energy, lambda q: p._pattern.scatter_vector(
        p._bending[1](p._pattern.gather(q), p._bend_weight))),
    "twist": lambda p: (p.twist_energy, lambda q: p._twist_coefficient * p.twist(q)
                        * p._twist_gradient(q)),
    "total": lambda p: (p.energy, p.gradient),
}


@pytest.mark.parametrize("form", ["angle", "tan", "sin"])
@pytest.mark.parametrize("term", list(TERMS))
def test_gradient_matches_finite_differences(form, term, rng):
    p = make(smooth_closed_curve(24), form=form)
    q = smooth_closed_curve(24).ravel()
    # Move away from the point where the reference frames were adapted, without
    # accepting: the kernels must be exact for the frames as carried.
    q = q + 1e-3 * rng.standard_normal(q.size)
    energy, gradient = TERMS[term](p)
    for _ in range(3):
        d = rng.standard_normal(q.size)
        fd = central_difference(energy, q, d)
        assert gradient(q) @ d == pytest.approx(fd, rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("form", ["angle", "tan", "sin"])
def test_hessian_matches_finite_differences_per_term(form, rng):
    p = make(smooth_closed_curve(20), form=form)
    q = smooth_closed_curve(20).ravel() + 1e-3 * rng.standard_normal(60)
    H = p.hessian(q)
    for _ in range(3):
        d = rng.standard_normal(q.size)
        fd = central_difference(p.gradient, q, d, eps=1e-6)
        assert np.max(np.abs(H.matvec(d) - fd)) <= 1e-6 * np.max(np.abs(fd))
    # the sparse part is symmetric and the rank-one part is the twist (k g g^T)
    assert abs(H.sparse - H.sparse.T).max() <= 1e-10 * abs(H.sparse).max()
    assert H.coefficients[0] == pytest.approx(4 * np.pi**2 * 1.3)


def test_constraint_derivatives(rng):
    p = make(smooth_closed_curve(16))
    q = smooth_closed_curve(16).ravel() + 1e-2 * rng.standard_normal(48)
    lam = rng.standard_normal(16)
    d = rng.standard_normal(48)
    J = p.constraint_jacobian(q)
    assert np.allclose(J @ d, central_difference(p.constraints, q, d), atol=1e-8)
    fd = central_difference(lambda x: p.constraint_jacobian(x).T @ lam, q, d)
    assert np.allclose(p.constraint_hessian(q, lam) @ d, fd, atol=1e-7)


def test_energy_invariant_under_rigid_motion(rng):
    pts = smooth_closed_curve(30)
    a = rng.standard_normal((3, 3))
    rot, _ = np.linalg.qr(a)
    if np.linalg.det(rot) < 0:
        rot[:, 0] *= -1
    moved = pts @ rot.T + rng.standard_normal(3)
    assert make(moved).energy(moved.ravel()) == pytest.approx(make(pts).energy(pts.ravel()),
                                                              rel=1e-12)


def test_rigid_modes_are_null_vectors_of_the_hessian_at_equilibrium():
    from supercoil.solvers.newton import least_squares_multipliers

    p = make(circle(40), excess_link=1.0, twist_ratio=0.8)
    q = circle(40).ravel()
    lam = least_squares_multipliers(p, q, np.arange(q.size))
    H = p.hessian(q).plus_sparse(p.constraint_hessian(q, lam))
    scale = abs(H.sparse).max()
    for mode in p.symmetry_modes(q):
        assert np.max(np.abs(H.matvec(mode))) <= 1e-9 * scale * np.max(np.abs(mode))
    # translations are null at every state (the energy depends on differences only)
    q2 = smooth_closed_curve(40).ravel()
    p2 = make(q2.reshape(-1, 3))
    H2 = p2.hessian(q2)
    for k in range(3):
        t = np.zeros((40, 3))
        t[:, k] = 1.0
        assert np.max(np.abs(H2.matvec(t.ravel()))) <= 1e-9 * abs(H2.sparse).max()


def test_local_writhe_equals_double_sum_along_a_deformation_path(rng):
    """Wr from the tracked reference twist equals the Gauss double sum at every step."""
    start = smooth_closed_curve(60, wobble=0.05)
    end = smooth_closed_curve(60, wobble=0.6)
    p = make(start)
    for t in np.linspace(0, 1, 41):
        q = ((1 - t) * start + t * end).ravel()
        p.accept(q)
        assert p.writhe_local(q) == pytest.approx(writhe(q.reshape(-1, 3)), abs=1e-10)


def test_link_equals_twist_from_material_frames_plus_double_sum_writhe():
    """Lk = Tw + Wr at non-planar states: Tw from explicit material directors, Wr double sum."""
    from supercoil.topology import twist_from_frames

    start = smooth_closed_curve(50, wobble=0.05)
    end = smooth_closed_curve(50, wobble=0.7)
    p = make(start, excess_link=2.3)
    for t in np.linspace(0, 1, 15):
        pts = (1 - t) * start + t * end
        q = pts.ravel()
        p.accept(q)
        d1 = p.material_directors(q)
        # excess twist = twist of the material ribbon - its intrinsic link (Lk_u - dLk)
        tw = twist_from_frames(pts, d1, closed=True) - p.reference_link + p.excess_link
        wr = writhe(pts)
        assert abs(tw + wr - p.excess_link) < 1e-9
        assert tw == pytest.approx(p.twist(q), abs=1e-9)  # the twist the energy uses


def test_writhe_tracking_survives_passing_the_half_turn():
    """Wr crossing +-1/2 (where the holonomy wraps) keeps being tracked continuously."""
    n = 80
    s = 2 * np.pi * np.arange(n) / n
    p = None
    values = []
    for amp in np.linspace(0.05, 3.0, 80):
        # a figure-eight opened out of plane: its writhe falls from ~1 through 1/2
        pts = np.stack([np.sin(s), np.sin(2 * s) * 0.5, amp * 0.3 * np.cos(s)], axis=1)
        if p is None:
            p = make(pts)
        q = pts.ravel()
        p.accept(q)
        values.append((p.writhe_local(q), writhe(pts)))
    local, exact = np.array(values).T
    assert np.max(np.abs(local - exact)) < 1e-9
    assert exact.max() > 0.9 and exact.min() < 0.4


def _arclength_curve(n_nodes):
    """A smooth closed curve sampled at equal arc length (to ~1e-13)."""
    def r(t):
        return np.array([np.cos(t) + 0.1 * np.cos(2 * t), np.sin(t) - 0.08 * np.sin(2 * t),
                         0.3 * np.sin(t)])

    def dr(t):
        return np.array([-np.sin(t) - 0.2 * np.sin(2 * t), np.cos(t) - 0.16 * np.cos(2 * t),
                         0.3 * np.cos(t)])

    def ddr(t):
        return np.array([-np.cos(t) - 0.4 * np.cos(2 * t), -np.sin(t) + 0.32 * np.sin(2 * t),
                         -0.3 * np.sin(t)])

    speed = lambda t: np.linalg.norm(dr(t))
    total = quad(speed, 0, 2 * np.pi, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
    cum = lambda t: quad(speed, 0, t, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
    ts = [0.0] + [brentq(lambda t, s=s: cum(t) - s, 0, 2 * np.pi, xtol=1e-14)
                  for s in total * np.arange(1, n_nodes) / n_nodes]
    pts = np.array([r(t) for t in ts])

    def kappa2(t):
        v, a = dr(t), ddr(t)
        return np.linalg.norm(np.cross(v, a)) ** 2 / np.linalg.norm(v) ** 6 * speed(t)

    bending = 0.5 * quad(kappa2, 0, 2 * np.pi, epsabs=1e-12, epsrel=1e-12, limit=400)[0]
    return pts, total, bending


def test_bending_energy_converges_with_second_order():
    """Polygon bending energy -> int A/2 kappa^2 ds as O(h^2) (observed order)."""
    errors = []
    for n in (40, 80, 160, 320):
        pts, total, exact = _arclength_curve(n)
        rod = Rod(n, length=total)
        p = ClosedRodEnergy(rod, pts, 0.0, reference_link=0)
        errors.append(abs(p.bending_energy(pts.ravel()) - exact) / exact)
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2) < 0.2), (errors, orders)


@pytest.mark.parametrize("bad", [{"n_nodes": 4}, {"n_nodes": 10, "twist_stiffness": 0.0},
                                 {"n_nodes": 10, "length": -1.0},
                                 {"n_nodes": 10, "bending_stiffness": np.nan},
                                 {"n_nodes": 10, "curvature": "cubic"}])
def test_bad_rod_parameters_raise(bad):
    with pytest.raises(ValueError):
        Rod(**bad)


def test_non_finite_points_raise():
    pts = circle(10)
    pts[3, 1] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        ClosedRodEnergy(Rod(10), pts, 0.0)


@pytest.mark.parametrize("form", ["angle", "tan", "sin"])
def test_hand_derived_kernels_equal_jax_autodiff(form, rng):
    """The numba kernels (hand-derived derivatives) against JAX autodiff of the
    formulas as first written, on random strongly curved stencils."""
    pytest.importorskip("jax")
    from supercoil.rod import kernels
    from supercoil.rod.closed import initial_reference_frames
    from supercoil.rod.reference_kernels import reference_kernels

    ref = reference_kernels(form)
    fast = kernels.bending_kernels(form)
    stencils = rng.normal(size=(64, 9))
    weights = rng.uniform(0.5, 2.0, size=64)
    for k, name in enumerate(("bending_value", "bending_gradient", "bending_hessian")):
        a = np.asarray(fast[k](stencils, weights))
        b = np.asarray(ref[name](stencils, weights))
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10 * np.abs(b).max())
    # twist: frames carried from slightly different tangents (as after a step)
    x = smooth_closed_curve(40)
    frames_u = initial_reference_frames(x)
    t = np.diff(np.vstack([x, x[:1]]), axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    idx = np.arange(40)
    stencils = np.concatenate([x[idx - 1], x[idx], x[(idx + 1) % 40]], axis=1)
    stencils = stencils + 1e-2 * rng.normal(size=stencils.shape)
    frames = np.stack([frames_u[idx - 1], t[idx - 1], frames_u[idx], t[idx]], axis=1)
    for fast_k, name in ((kernels.twist_value, "twist_value"),
                         (kernels.twist_gradient, "twist_gradient"),
                         (kernels.twist_hessian, "twist_hessian")):
        a = np.asarray(fast_k(stencils, frames))
        b = np.asarray(ref[name](stencils, frames))
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * np.abs(b).max())
