"""The double-integral contact energy (supercoil.contact.integral): oracles.

Finite differences against the kernel's gradient and Hessian (polygon and
B-spline samples); an independent numpy double loop against the kernel's
value; the exact integral for two crossing straight lines; the sampling-phase
ripple of the force against the pair formulation's; the exact sample
collision time against a dense scan; the crossed-rods force balance through
:class:`ContactProblem`.
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_toys import CrossedRods
from scipy.integrate import quad
from test_contact_stiffness import crossing_energy

from supercoil.contact import potentials
from supercoil.contact.integral import barrier, integral_terms
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import contact_summary
from supercoil.contact.sample_ccd import first_time_of_approach_samples
from supercoil.contact.sample_weights import (
    default_samples,
    polygon_weights,
    quintic_samples,
    sample_parameters,
    spline_weights,
)
from supercoil.contact.solve import solve_contact
from supercoil.contact.spline_distance import piece_distance
from supercoil.contact.spline_pieces import CurvePieces, bspline_pieces
from supercoil.solvers.newton import NewtonOptions

D = 1.0
G_HAT = 0.01


def _psi(gap):
    """The formulation's barrier written out (kappa = 1): ``-(g - g_hat)^4 / g_hat^2 log(g / g_hat)``."""
    g = np.asarray(gap, dtype=float)
    inside = (g > 0) & (g < G_HAT)
    gs = np.where(inside, g, G_HAT)
    return np.where(inside, -((gs - G_HAT) ** 4) / G_HAT**2 * np.log(gs / G_HAT), 0.0)


def _two_strands(a: np.ndarray, b: np.ndarray, spline: bool):
    """Nodes, stencil, piece sets and the pairs (interior segments) of two open strands."""
    n = len(a)
    x = np.concatenate([a, b])
    seg = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    segments = np.concatenate([seg, seg + n])
    pairs = np.array([[i, n - 1 + j] for i in range(1, n - 2) for j in range(1, n - 2)])
    if spline:
        pa, pb = bspline_pieces(seg, False), bspline_pieces(seg + n, False)
        pieces = CurvePieces(np.concatenate([pa.stencil, pb.stencil]),
                             np.concatenate([pa.control, pb.control]))
        return x, pieces.stencil, pieces, pairs
    return x, segments, None, pairs


def _weights(stencil, pieces, q):
    return (spline_weights(pieces.coefficients, q) if pieces is not None
            else polygon_weights(len(stencil), q))


def _arcs(phase: float, theta: float, gap: float, radius: float = 40.0, n: int = 12,
          h: float = 1.0, spline: bool = False):
    """Two arcs bending away from each other, crossing at angle ``theta`` with the
    given gap (of the B-spline when ``spline``: it lies ``h^2 / 6R`` inside each arc's
    chords); strand a sampled with its nodes shifted by ``phase`` edge lengths."""
    s = (np.arange(n) - n / 2 + phase) * h
    a = np.stack([radius * np.sin(s / radius), np.zeros(n), radius * (1 - np.cos(s / radius))], 1)
    t = (np.arange(n) - n / 2 + 0.37) * h
    b = np.stack([radius * np.sin(t / radius), np.zeros(n), -radius * (1 - np.cos(t / radius))],
                 1)
    c, sn = np.cos(theta), np.sin(theta)
    b = b @ np.array([[c, sn, 0], [-sn, c, 0], [0, 0, 1]]).T
    b[:, 2] -= D + gap - (2 * h * h / (6 * radius) if spline else 0.0)
    return a, b


def _check_kernel_derivatives(x, stencil, weights, pairs, every=1):
    """Finite differences of the kernel's energy and gradient against its gradient and
    Hessian (assembled from the per-pair blocks) at the nodes ``x``."""
    def terms(flat, order):
        return integral_terms(flat.reshape(-1, 3), stencil, weights, pairs, D, "barrier", 1.0,
                              G_HAT, 1.0, order=order)

    def gradient(flat):
        _e, g, _h, _f, _p, dofs = terms(flat, 1)
        out = np.zeros(flat.size)
        np.add.at(out, dofs.ravel(), g.ravel())
        return out

    flat = x.ravel()
    energy, _g, hess, _f, _p, dofs = terms(flat, 2)
    assert energy.sum() > 0
    H = np.zeros((flat.size, flat.size))
    for p in range(len(pairs)):
        np.add.at(H, (dofs[p][:, None], dofs[p][None, :]), hess[p])
    g = gradient(flat)
    eps = 1e-7
    for k in range(0, flat.size, every):
        e = np.zeros(flat.size)
        e[k] = eps
        fd = (terms(flat + e, 0)[0].sum() - terms(flat - e, 0)[0].sum()) / (2 * eps)
        assert abs(fd - g[k]) <= 1e-6 * max(1.0, np.abs(g).max())
        fd_h = (gradient(flat + e) - gradient(flat - e)) / (2 * eps)
        np.testing.assert_allclose(H[:, k], fd_h, rtol=1e-5, atol=1e-5 * np.abs(H).max())


@pytest.mark.parametrize("spline", [False, True])
def test_kernel_derivatives_match_finite_differences(spline):
    rng = np.random.default_rng(7)
    # the chords lie up to h^2 / 8R = 0.003 outside the arcs
    a, b = _arcs(0.5, 1.1, 0.001 if spline else -0.003, radius=40.0, n=6, spline=spline)
    x, stencil, pieces, _ = _two_strands(a, b, spline)
    x = x + 1e-4 * rng.standard_normal(x.shape)
    pairs = np.array([[i, 5 + j] for i in range(1, 4) for j in range(1, 4)])
    _check_kernel_derivatives(x, stencil, _weights(stencil, pieces, 8), pairs)


def test_kernel_equals_a_plain_double_loop():
    a, b = _arcs(0.1, 0.7, 0.003, radius=6.0, n=8, spline=True)
    x, stencil, pieces, pairs = _two_strands(a, b, True)
    q = 5
    weights = _weights(stencil, pieces, q)
    energy = integral_terms(x, stencil, weights, pairs, D, "barrier", 2.0, G_HAT, 1.0,
                            order=0)[0].sum()
    # oracle: evaluate the B-spline pieces at the midpoint parameters, all pairs
    u = sample_parameters(q)
    total = 0.0
    for i, j in pairs:
        pi = pieces.evaluate(x, np.full(q, i), u)
        pj = pieces.evaluate(x, np.full(q, j), u)
        d = np.linalg.norm(pi[:, None, :] - pj[None, :, :], axis=-1)
        total += 2.0 * _psi(d - D).sum()
    total *= (1.0 / q) ** 2 / (2 * D * G_HAT)
    assert total > 0
    np.testing.assert_allclose(energy, total, rtol=1e-12)


@pytest.mark.parametrize("theta", [np.pi / 2, 0.6])
def test_crossing_lines_give_the_exact_integral(theta):
    # two straight lines crossing at angle theta, distance h0 apart:
    # int int psi(|r(s) - r(t)| - D) ds dt
    #     = (2 pi / sin theta) int_h0^{D + g_hat} psi(d - D) d dd
    h0 = D + 0.004
    exact = 2 * np.pi / np.sin(theta) * quad(
        lambda d: float(_psi(d - D)) * d, h0, D + G_HAT,
        epsabs=0, epsrel=1e-12, limit=200)[0] / (2 * D * G_HAT)
    errors = [abs(crossing_energy(theta, h0, 1.0, D, G_HAT, q) / exact - 1)
              for q in (4, 8, 16, 32)]
    assert errors[-1] < 2e-3
    assert errors[-1] < errors[0] / 20  # converges under refinement of the quadrature


def _force(x, stencil, pieces, pairs, q):
    weights = _weights(stencil, pieces, q)
    return integral_terms(x, stencil, weights, pairs, D, "barrier", 1.0, G_HAT, 1.0,
                          order=1)[3].sum()


@pytest.mark.parametrize("theta", [np.pi / 2, 0.05])
def test_force_does_not_ripple_with_the_sampling_phase(theta):
    # A contact between two B-splines slid along by a fraction of a segment: the
    # pair formulation counts it once or up to four times (a ripple of the order
    # of the force itself); the integral counts it once, up to the quadrature.
    pair_force, integral_force = [], []
    for phase in np.linspace(0, 1, 12, endpoint=False):
        a, b = _arcs(phase, theta, 0.005, spline=True)
        x, stencil, pieces, pairs = _two_strands(a, b, True)
        d, _s, _t = piece_distance(x, pieces, pairs)
        pair_force.append(-potentials.barrier(d - D, 1.0, G_HAT)[1].sum())
        integral_force.append(_force(x, stencil, pieces, pairs, 32))
    ripple = [np.ptp(f) / np.mean(f) for f in (pair_force, integral_force)]
    assert ripple[0] > 0.5  # measured 0.67-0.91
    assert ripple[1] < 2e-3  # measured 5e-5 - 6e-4


def test_default_samples_resolve_the_barrier_width():
    q = default_samples(1.0, 1.0, 0.01)
    assert (1.0 / q) <= 0.25 * np.sqrt(2 * 0.01) < 1.0 / (q - 1)


def test_sample_collision_time_is_exact():
    rng = np.random.default_rng(11)
    a, b = _arcs(0.2, 0.9, 0.3, radius=5.0, n=6)
    x, stencil, _, _ = _two_strands(a, b, False)
    pairs = np.array([[i, 5 + j] for i in range(5) for j in range(5)])
    weights = polygon_weights(len(stencil), 4)
    dx = np.zeros_like(x)
    dx[6:] = [0, 0, 0.8] + 0.05 * rng.standard_normal((6, 3))  # strand b rises into a
    threshold = D + 0.01
    tau = first_time_of_approach_samples(x, dx, stencil, weights, pairs, threshold)
    assert 0 < tau < 1

    def closest(t):
        pts = np.einsum("kal,klx->kax", weights, (x + t * dx)[stencil])
        return min(np.linalg.norm(pts[i][:, None] - pts[j][None], axis=-1).min()
                   for i, j in pairs)

    assert closest(tau) == pytest.approx(threshold, abs=1e-10)
    scan = np.linspace(0, tau, 400)
    assert min(closest(t) for t in scan) >= threshold - 1e-10


def test_crossed_rods_force_balance_through_the_problem():
    toy = CrossedRods(load=2.0)
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, formulation="integral",
                                                 curve="spline"))
    res = solve_contact(problem, toy.points.ravel(), NewtonOptions(max_iterations=200))
    assert res.converged, res.message
    summary = contact_summary(problem, res.q, res.multipliers)
    force_scale = toy.rod.length**2 / toy.rod.bending_stiffness
    total = sum(c["force"] for c in summary["contacts"]) / force_scale
    # oracle: rod B's vertical equilibrium; the pairs' resultants are vertical up to
    # the tilt of the sample normals within the barrier's reach
    np.testing.assert_allclose(total, toy.load, rtol=2e-3)
    assert summary["n_contact_points"] == 1 and summary["n_contact_intervals"] == 0
    assert summary["min_gap_over_diameter"] > 1.0 - 1e-3


def test_problem_derivatives_match_finite_differences():
    toy = CrossedRods(load=2.0)
    problem = ContactProblem(toy, ContactOptions(diameter=0.05, formulation="integral"))
    q = toy.points.ravel().copy()
    q[3 * toy.n + 2:: 3] -= 0.25 - 0.0502  # B just above A, inside the barrier's reach
    assert problem.contact_energy(q) > 0
    g = problem.gradient(q)
    H = problem.hessian(q).dense()
    eps = 1e-9
    for k in range(3 * toy.n + 2, 6 * toy.n, 3):
        e = np.zeros_like(q)
        e[k] = eps
        fd = (problem.energy(q + e) - problem.energy(q - e)) / (2 * eps)
        assert abs(fd - g[k]) <= 1e-5 * max(1.0, abs(g[k]))
        fd_h = (problem.gradient(q + e) - problem.gradient(q - e)) / (2 * eps)
        np.testing.assert_allclose(H[:, k], fd_h, rtol=1e-4, atol=1e-4 * np.abs(H).max())


def test_options_validate():
    with pytest.raises(ValueError, match="formulation"):
        ContactOptions(diameter=0.1, formulation="sum")
    with pytest.raises(ValueError, match="barrier or the penalty"):
        ContactOptions(diameter=0.1, formulation="integral", treatment="exact")
    with pytest.raises(ValueError, match="samples_per_segment"):
        ContactOptions(diameter=0.1, formulation="integral", samples_per_segment=0)


def test_barrier_derivatives_and_smoothness():
    g = np.linspace(0.02, 0.999, 60) * G_HAT
    value, first, second = barrier(g, 1.0, G_HAT)
    np.testing.assert_allclose(value, _psi(g), rtol=1e-12)
    eps = 1e-9
    fd1 = (barrier(g + eps, 1.0, G_HAT)[0] - barrier(g - eps, 1.0, G_HAT)[0]) / (2 * eps)
    fd2 = (barrier(g + eps, 1.0, G_HAT)[1] - barrier(g - eps, 1.0, G_HAT)[1]) / (2 * eps)
    np.testing.assert_allclose(first, fd1, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(second, fd2, rtol=1e-5, atol=1e-9)
    # like the IPC barrier near g = 0, and vanishing like (g_hat - g)^5 at g_hat
    assert barrier([1e-9 * G_HAT], 1.0, G_HAT)[0][0] == pytest.approx(
        potentials.barrier(np.array([1e-9 * G_HAT]), 1.0, G_HAT)[0][0], rel=1e-8)
    near = G_HAT * (1 - np.array([1e-2, 5e-3]))
    v = barrier(near, 1.0, G_HAT)[0]
    assert np.log(v[0] / v[1]) / np.log(2.0) == pytest.approx(5.0, abs=0.05)
    assert barrier([0.0], 1.0, G_HAT)[0][0] == np.inf


# ------------------------------------------------------------------ quintic B-spline
def _quintic(x_strands):
    """Stencil and weights of the quintic pieces of open strands (one per array)."""
    stencils, weights, offset = [], [], 0
    for x in x_strands:
        n = len(x)
        seg = np.stack([np.arange(n - 1), np.arange(1, n)], 1) + offset
        s, w = quintic_samples(seg, False, 32)
        stencils.append(s)
        weights.append(w)
        offset += n
    return np.concatenate(stencils), np.concatenate(weights)


def test_quintic_pieces_reproduce_lines_and_shift_circles_by_h2_over_4r():
    # a line, ends included (the ghosts reflect it onto itself): samples on the chords
    x = np.stack([np.linspace(0, 3, 7), 0.5 * np.linspace(0, 3, 7), np.zeros(7)], 1)
    stencil, weights = _quintic([x])
    u = sample_parameters(32)
    expected = x[:-1, None, :] + u[None, :, None] * (x[1:] - x[:-1])[:, None, :]
    np.testing.assert_allclose(np.einsum("kal,klx->kax", weights, x[stencil]), expected,
                               atol=1e-14)
    # a closed circle of radius R sampled at spacing h: the uniform B-spline of degree p
    # lies inside by (p + 1) h^2 / (24 R) + O(h^4) (1/6 for cubic pieces, 1/4 for quintic)
    radius = 1.0
    shifts = []
    for n in (40, 80):
        phi = 2 * np.pi * np.arange(n) / n
        ring = np.stack([np.cos(phi), np.sin(phi), np.zeros(n)], 1)
        seg = np.stack([np.arange(n), (np.arange(n) + 1) % n], 1)
        s, w = quintic_samples(seg, True, 8)
        assert np.allclose(w.sum(axis=2), 1.0)  # a partition of unity
        pts = np.einsum("kal,klx->kax", w, ring[s])
        h = 2 * np.sin(np.pi / n) * radius
        shifts.append((radius - np.linalg.norm(pts, axis=-1).mean()) / (h * h / (4 * radius)))
    assert abs(shifts[-1] - 1) < 0.01 and abs(shifts[-1] - 1) < abs(shifts[0] - 1)


def _phase_ripples(h: float, radius: float) -> list[float]:
    """The contact force's peak-to-peak ripple over its mean as strand a's nodes slide
    through one segment along the same arcs (radius ``radius``, segments ``h``, crossing
    at 3 degrees, gap 0.005 D): ``[cubic, quintic]``. The arcs' own contact does not
    depend on where the nodes lie on them (the material sliding), so the ripple is the
    curve's error alone."""
    cubic, quintic = [], []
    for phase in np.linspace(0, 1, 10, endpoint=False):
        a, b = _arcs(phase, 0.05, 0.005, radius=radius, n=16, h=h, spline=True)
        x, stencil, pieces, pairs = _two_strands(a, b, True)
        weights = spline_weights(pieces.coefficients, 32)
        cubic.append(integral_terms(x, stencil, weights, pairs, D, "barrier", 1.0, G_HAT, h,
                                    order=1)[3].sum())
        b[:, 2] += 2 * (h * h / (4 * radius) - h * h / (6 * radius))  # the quintic's shift
        x = np.concatenate([a, b])
        stencil, weights = _quintic([a, b])
        quintic.append(integral_terms(x, stencil, weights, pairs, D, "barrier", 1.0, G_HAT, h,
                                      order=1)[3].sum())
    return [float(np.ptp(f) / np.mean(f)) for f in (cubic, quintic)]


def test_quintic_removes_the_cubic_phase_ripple_of_tight_strands():
    # strands of radius 3 D, h = 0.6 D, crossing at 3 degrees: the cubic B-spline's shape
    # depends on the nodes' phase at O(h^4 kappa^3), which the barrier amplifies by 1/g
    # (force ripple 1.2e-2 whatever the samples); the quintic's at O(h^6 kappa^5)
    ripple = _phase_ripples(0.6, 3.0)
    assert ripple[0] > 5e-3  # measured 1.2e-2
    assert ripple[1] < 5e-4  # measured 5e-5


def test_the_dna_contact_curve_keeps_the_ply_from_rippling_at_n0():
    # a DNA run's default nodes n0 give segments of D, and its plectoneme's strands a
    # radius of curvature of about 4.6 D (3 kbp at 1 pN, 150 mM): the cubic's force
    # ripples by 2.7 % there as the ply slides (measured; 0.15 % at h = D / 2, the h^4 of
    # its shape error), which made the 3 kbp contact branch turn back and forth for
    # 1600 points at 9.1 turns; the DNA runs' curve (quintic) ripples by 5e-4
    from supercoil.units.tweezers import DNA_CONTACT_CURVE

    assert DNA_CONTACT_CURVE == "quintic"
    cubic, quintic = _phase_ripples(1.0, 4.6)
    assert cubic > 1.5e-2 and quintic < 1e-3 and quintic < cubic / 30
    half = _phase_ripples(0.5, 4.6)[0]
    assert 8 < cubic / half < 32  # about 2^4: the cubic's error is O(h^4)


def test_quintic_kernel_derivatives_match_finite_differences():
    # the quintic pieces lie h^2 / 4R = 0.00625 inside each arc: a gap of 0.0015 between them
    a, b = _arcs(0.5, 1.1, 0.0015 - 2 * 0.00625, radius=40.0, n=7)
    x = np.concatenate([a, b])
    n = len(a)
    seg = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    s1, w1 = quintic_samples(seg, False, 8)
    s2, w2 = quintic_samples(seg + n, False, 8)
    stencil, weights = np.concatenate([s1, s2]), np.concatenate([w1, w2])
    pairs = np.array([[i, n - 1 + j] for i in range(2, 4) for j in range(2, 4)])
    _check_kernel_derivatives(x, stencil, weights, pairs, every=2)


def test_quintic_needs_the_integral_formulation():
    with pytest.raises(ValueError, match="quintic"):
        ContactOptions(diameter=0.1, curve="quintic")
    ContactOptions(diameter=0.1, curve="quintic", formulation="integral")
