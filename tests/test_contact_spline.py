"""B-spline piece distance (supercoil.contact.spline_distance, spline_pieces): oracles.

Finite differences against the gradient and Hessian (every distance type,
near-parallel pieces), dense sampling against the value, the chord reduction
against the segment distance, and the observed order of the sampling-phase
ripple (4 for the spline, 2 for the chords).
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_toys import assert_derivatives_match_differences

from supercoil.contact.distance import segment_distance_derivatives
from supercoil.contact.distance_kernels import DistanceKind
from supercoil.contact.spline_distance import piece_distance, piece_distance_derivatives
from supercoil.contact.spline_pieces import CurvePieces, bspline_pieces, chord_pieces, sag_bound


def _two_strands(p_nodes: np.ndarray, q_nodes: np.ndarray):
    """Points and the B-spline pieces of two open strands; pair (1 of p, 1 of q)."""
    n = len(p_nodes)
    pts = np.concatenate([p_nodes, q_nodes])
    seg_p = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    seg_q = seg_p + n
    a, b = bspline_pieces(seg_p, False), bspline_pieces(seg_q, False)
    pieces = CurvePieces(np.concatenate([a.stencil, b.stencil]),
                         np.concatenate([a.control, b.control]))
    return pts, pieces, np.array([[1, n - 1 + 1]])


def _arc(center, radius, start, step, count, axis=2, lift=0.0):
    ang = start + step * np.arange(count)
    c = np.cos(ang) * radius
    s = np.sin(ang) * radius
    pts = np.zeros((count, 3))
    others = [k for k in range(3) if k != axis]
    pts[:, others[0]] = c
    pts[:, others[1]] = s
    pts[:, axis] = lift * np.arange(count)
    return pts + np.asarray(center, dtype=float)


def _random_case(rng, kind: str):
    """A pair of curved pieces whose closest points are of the given type."""
    p = _arc([0, 0, 0], 1.0, rng.uniform(-0.3, 0.3), 0.2, 4, lift=0.02)
    p += 0.01 * rng.normal(size=p.shape)
    if kind == "interior":  # q crosses above the middle of piece 1 of p, curving away
        mid = p[1:3].mean(0)
        phi = 0.2 * (np.arange(4) - 1.5) + rng.uniform(-0.05, 0.05)
        q = np.stack([mid[0] + np.sin(phi), np.full(4, mid[1]), 1.3 - np.cos(phi)], 1)
        q += 0.01 * rng.normal(size=q.shape)
    elif kind == "side":  # an end of q against the interior of p
        mid = p[1:3].mean(0)
        direction = np.cross(p[2] - p[1], [0, 0, 1.0])
        direction /= np.linalg.norm(direction)
        q = mid + np.outer(0.3 + 0.2 * np.arange(4), direction) + 0.02 * rng.normal(size=(4, 3))
        q = q[::-1]
    else:  # corner: beyond the end of p, pointing away
        end = p[2]
        tangent = (p[2] - p[1]) / np.linalg.norm(p[2] - p[1])
        side = np.cross(tangent, [0, 0, 1.0])
        q = end + np.outer(0.3 + 0.2 * np.arange(4), tangent + 0.5 * side) \
            + 0.02 * rng.normal(size=(4, 3))
        q = np.concatenate([q[:1] - (q[1] - q[0]), q[:3]])
    return p, q


def _check_derivatives(pts, pieces, pairs, tolerance=1e-6, eps=1e-6):
    _d, _s, _t, grad, hess, kind, nodes = piece_distance_derivatives(pts, pieces, pairs, tolerance)
    flat = pts.ravel().copy()
    dofs = (3 * nodes[0][:, None] + np.arange(3)).ravel()
    G = np.zeros(flat.size)
    H = np.zeros((flat.size, flat.size))
    np.add.at(G, dofs, grad[0])
    np.add.at(H, (dofs[:, None], dofs[None, :]), hess[0])
    num_g = np.zeros(flat.size)
    num_h = np.zeros((flat.size, flat.size))
    for k in np.unique(dofs):
        for sign in (1, -1):
            x = flat.copy()
            x[k] += sign * eps
            dd, _, _, gg, _, kk, _ = piece_distance_derivatives(x.reshape(-1, 3), pieces, pairs,
                                                                tolerance)
            assert kk[0] == kind[0], "the finite difference crossed a type boundary"
            Gk = np.zeros(flat.size)
            np.add.at(Gk, dofs, gg[0])
            num_g[k] += sign * dd[0] / (2 * eps)
            num_h[k] += sign * Gk / (2 * eps)
    scale_g = max(1.0, np.abs(G).max())
    scale_h = max(1.0, np.abs(H).max())
    np.testing.assert_allclose(G, num_g, atol=1e-7 * scale_g)
    np.testing.assert_allclose(H, num_h, atol=1e-5 * scale_h)
    return kind[0]


@pytest.mark.parametrize("case", ["interior", "side", "corner"])
def test_derivatives_match_finite_differences(case):
    rng = np.random.default_rng({"interior": 1, "side": 2, "corner": 3}[case])
    kinds = set()
    for _ in range(4):
        p, q = _random_case(rng, case)
        pts, pieces, pairs = _two_strands(p, q)
        kinds.add(DistanceKind(_check_derivatives(pts, pieces, pairs)).name)
    expected = {"interior": {"EDGE_EDGE"}, "side": {"Q0_EDGE_P", "Q1_EDGE_P"},
                "corner": {"P1_Q0", "P1_Q1", "P0_Q0", "P0_Q1"}}[case]
    assert kinds <= expected and kinds


def test_near_parallel_pieces_use_a_side_with_bounded_derivatives():
    """Two nearly concentric arcs (a line contact): the valley of |r|^2 is
    nearly flat, the interior type is dropped, the side type's derivatives are
    exact and its value within the stated bound of the distance."""
    p = _arc([0, 0, 0], 1.0, 0.0, 0.1, 4)
    # q about 0.3 from p; the small shift of its centre picks its closer end
    q = _arc([0, 3e-4, 0], 1.3, 0.03, 0.1 / 1.3, 4)
    pts, pieces, pairs = _two_strands(p, q)
    d, *_rest, kind, _nodes = piece_distance_derivatives(pts, pieces, pairs)
    assert kind[0] != DistanceKind.EDGE_EDGE
    exact, _, _ = piece_distance(pts, pieces, pairs)
    assert 0.0 <= d[0] - exact[0] <= 1e-6
    _check_derivatives(pts, pieces, pairs)


def test_value_matches_dense_sampling():
    rng = np.random.default_rng(7)
    for case in ("interior", "side", "corner", "interior", "side"):
        p, q = _random_case(rng, case)
        pts, pieces, pairs = _two_strands(p, q)
        d, s, t = piece_distance(pts, pieces, pairs)
        u = np.linspace(0.0, 1.0, 801)
        cp = pieces.evaluate(pts, np.full(u.size, pairs[0, 0]), u)
        cq = pieces.evaluate(pts, np.full(u.size, pairs[0, 1]), u)
        brute = np.sqrt(((cp[:, None] - cq[None]) ** 2).sum(-1)).min()
        attained = np.linalg.norm(pieces.evaluate(pts, pairs[0, 0], s[0])
                                  - pieces.evaluate(pts, pairs[0, 1], t[0]))
        assert attained == pytest.approx(d[0], abs=1e-13)
        assert d[0] <= brute + 1e-13
        assert brute - d[0] <= 1e-5 * d[0]


def test_nonconvex_pair_finds_the_global_minimum():
    """The end of q near the centre of p's osculating circle: |r| has a local
    maximum along p; the global minimum is still found (dense sampling)."""
    p = _arc([0, 0, 0], 0.3, -0.6, 0.4, 4)
    q = np.array([[-0.3, 0.0, 0.02], [-0.2, 0.0, 0.01], [-0.1, 0.0, 0.0], [0.02, 0.0, 0.0]])
    pts, pieces, pairs = _two_strands(p, q)
    d, _, _ = piece_distance(pts, pieces, pairs)
    u = np.linspace(0.0, 1.0, 2001)
    cp = pieces.evaluate(pts, np.full(u.size, 1), u)
    cq = pieces.evaluate(pts, np.full(u.size, 4), u)
    brute = np.sqrt(((cp[:, None] - cq[None]) ** 2).sum(-1)).min()
    assert d[0] <= brute + 1e-13 and brute - d[0] <= 1e-6


def test_chord_pieces_reduce_to_the_segment_distance():
    rng = np.random.default_rng(11)
    m = 300
    pts = rng.normal(size=(4 * m, 3))
    seg = np.arange(4 * m).reshape(-1, 2)
    pairs = np.stack([np.arange(0, 2 * m, 2), np.arange(1, 2 * m, 2)], 1)
    d, _s, _t, grad, hess, kind, _nodes = piece_distance_derivatives(pts, chord_pieces(seg),
                                                                     pairs)
    a, b = seg[pairs[:, 0]], seg[pairs[:, 1]]
    d2, g2, h2, k2 = segment_distance_derivatives(pts[a[:, 0]], pts[a[:, 1]], pts[b[:, 0]],
                                                  pts[b[:, 1]])
    np.testing.assert_allclose(d, d2, rtol=1e-13, atol=1e-14)
    assert np.array_equal(kind, k2)
    # the chord's stencil is (a, b, a, b) for each piece: sum the repeated nodes
    fold = np.zeros((8, 4))
    fold[[0, 2], 0] = fold[[1, 3], 1] = fold[[4, 6], 2] = fold[[5, 7], 3] = 1.0
    P = np.kron(fold, np.eye(3))
    np.testing.assert_allclose(grad @ P, g2, atol=1e-12)
    np.testing.assert_allclose(P.T @ hess @ P, h2, atol=1e-9 * np.abs(h2).max())


def test_collinear_control_points_give_a_straight_piece():
    """Equally spaced collinear nodes: the B-spline piece is the chord itself."""
    line = np.outer(np.arange(5), [0.3, 0.1, -0.2])
    other = line[:, [1, 2, 0]] + [0.5, -0.4, 0.7]
    pts, pieces, pairs = _two_strands(line, other)
    u = np.linspace(0, 1, 7)
    np.testing.assert_allclose(pieces.evaluate(pts, np.full(7, 1), u),
                               line[1] + np.outer(u, line[2] - line[1]), atol=1e-15)
    assert np.allclose(sag_bound(pts, pieces), 0.0)
    d, _, _ = piece_distance(pts, pieces, pairs)
    d2, *_ = segment_distance_derivatives(pts[1], pts[2], pts[6], pts[7])
    assert d[0] == pytest.approx(float(d2), rel=1e-13)


def test_open_ends_interpolate_the_end_node_and_sag_bound_holds():
    pts = _arc([0, 0, 0], 1.0, 0.0, 0.3, 6)
    seg = np.stack([np.arange(5), np.arange(1, 6)], 1)
    pieces = bspline_pieces(seg, closed=False)
    np.testing.assert_allclose(pieces.evaluate(pts, 0, 0.0), pts[0], atol=1e-15)
    np.testing.assert_allclose(pieces.evaluate(pts, 4, 1.0), pts[5], atol=1e-15)
    u = np.linspace(0, 1, 101)
    bound = sag_bound(pts, pieces)
    for i in range(5):
        chord = pts[seg[i, 0]] + np.outer(u, pts[seg[i, 1]] - pts[seg[i, 0]])
        gap = np.linalg.norm(pieces.evaluate(pts, np.full(u.size, i), u) - chord, axis=1)
        assert gap.max() <= bound[i] * (1 + 1e-12)


def _phase_ripple(n: int, curve: str, spline: bool) -> float:
    """Max - min over the sampling phase of the distance between a sampled
    closed curve and a straight line (exactly represented) near contact."""
    R, D, m = 1.0, 0.3, 41
    h = 2 * np.pi * R / n
    seg_c = np.stack([np.arange(n), (np.arange(n) + 1) % n], 1)
    seg_l = np.stack([np.arange(m - 1), np.arange(1, m)], 1) + n
    values = []
    for phase in np.linspace(0.0, 1.0, 12, endpoint=False):
        th = (np.arange(n) + phase) * 2 * np.pi / n
        z = 0.3 * np.sin(2 * th) + 0.1 * np.cos(th) if curve == "wobble" else 0 * th
        ring = np.stack([R * np.cos(th), R * np.sin(th), z], 1)
        y = (np.arange(m) - m // 2) * h
        line = np.stack([np.full(m, R + D), y, 0 * y], 1)
        pts = np.concatenate([ring, line])
        if spline:
            a, b = bspline_pieces(seg_c, True), bspline_pieces(seg_l, False)
        else:
            a, b = chord_pieces(seg_c), chord_pieces(seg_l)
        pieces = CurvePieces(np.concatenate([a.stencil, b.stencil]),
                             np.concatenate([a.control, b.control]))
        near = np.flatnonzero(np.cos(th) > np.cos(5 * h))
        pairs = np.array([(i, n + j) for i in near for j in range(m - 1)])
        d, _, _ = piece_distance(pts, pieces, pairs)
        values.append(d.min())
    return float(np.ptp(values))


@pytest.mark.parametrize("curve", ["circle", "wobble"])
def test_phase_ripple_order(curve):
    """The B-spline's contact distance depends on the sampling phase only at
    O(h^4); the chords' at O(h^2) (module docstring of spline_pieces)."""
    ns = np.array([32, 64, 128])
    h = 2 * np.pi / ns
    spline = [_phase_ripple(n, curve, True) for n in ns]
    chord = [_phase_ripple(n, curve, False) for n in ns]
    order_spline = np.polyfit(np.log(h), np.log(spline), 1)[0]
    order_chord = np.polyfit(np.log(h), np.log(chord), 1)[0]
    assert 3.8 < order_spline < 4.2
    assert 1.9 < order_chord < 2.1
    assert spline[-1] < 1e-4 * chord[-1]


# ------------------------------------------------- ContactProblem(curve="spline")
def _crossed_spline(treatment, **kw):
    from contact_toys import CrossedRods

    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem

    toy = CrossedRods(load=2.0)
    options = ContactOptions(diameter=0.05, treatment=treatment, curve="spline", **kw)
    return toy, ContactProblem(toy, options)


def test_contact_curve_option_is_validated():
    from supercoil.contact.options import ContactOptions

    assert ContactOptions(diameter=0.1).curve == "polygon"
    with pytest.raises(ValueError, match="curve .* must be one of polygon, spline"):
        ContactOptions(diameter=0.1, curve="bezier")


@pytest.mark.parametrize("treatment", ["exact", "penalty", "barrier"])
def test_spline_contact_force_equals_load(treatment):
    """Oracle: rod B rests on rod A, the contact carries the whole load."""
    from supercoil.contact.report import contact_summary
    from supercoil.contact.solve import solve_contact
    from supercoil.solvers.newton import NewtonOptions

    toy, problem = _crossed_spline(treatment)
    res = solve_contact(problem, toy.points.ravel(), NewtonOptions(max_iterations=200))
    assert res.converged, res.message
    summary = contact_summary(problem, res.q, res.multipliers)
    force_scale = toy.rod.length**2 / toy.rod.bending_stiffness
    total = sum(c["force"] for c in summary["contacts"])
    np.testing.assert_allclose(total / force_scale, toy.load, rtol=1e-6)
    d_min = summary["min_gap_over_diameter"]
    if treatment == "barrier":
        assert 1.0 < d_min < 1.0 + problem.options.barrier_activation
    elif treatment == "exact":
        assert abs(d_min - 1.0) <= problem.options.penetration_tolerance


def test_spline_contact_energy_derivatives_match_finite_differences():
    toy, problem = _crossed_spline("penalty", stiffness=50.0)
    q = toy.points.ravel().copy()
    rng = np.random.default_rng(3)
    q[3 * toy.n:] += 1e-3 * rng.standard_normal(3 * toy.n)
    q[3 * toy.n + 2 :: 3] -= 0.25 - 0.045  # B into A: pairs penetrate
    q[3 * toy.n + 2 :: 3] += 0.02 * np.linspace(-1, 1, toy.n) ** 2  # and B curved
    assert problem.contact_energy(q) > 0
    assert_derivatives_match_differences(problem, q, range(0, 6 * toy.n, 5))


def test_spline_barrier_step_guard_keeps_the_spline_gap():
    toy, problem = _crossed_spline("barrier")
    q = toy.points.ravel().copy()
    q[3 * toy.n + 2 :: 3] += 0.03 * np.linspace(-1, 1, toy.n) ** 2
    dq = np.zeros_like(q)
    dq[3 * toy.n + 2 :: 3] = -0.5  # straight through A
    bound = problem.step_bound(q, dq)
    assert 0.0 < bound < 1.0
    assert problem.min_distance(q + bound * dq) > problem.diameter
    assert problem.min_distance(q + bound * dq, polygon=True) > 0.5 * problem.diameter


def test_drivers_accept_and_validate_the_contact_curve():
    from supercoil.problems.ring_diagram import DiagramOptions
    from supercoil.problems.tweezers import TweezersOptions

    ring = DiagramOptions(2 / 3, 122.0)
    assert (ring.contact_curve, ring.contact_formulation) == ("spline", "integral")
    with pytest.raises(ValueError, match="contact_predictor"):
        DiagramOptions(2 / 3, 122.0, contact_predictor="cubic")
    tweezers = TweezersOptions(4 / 3, 33.0, tension=75.0)
    assert (tweezers.contact_curve, tweezers.contact_formulation) == ("spline", "integral")
    with pytest.raises(ValueError, match="contact_formulation"):
        TweezersOptions(4 / 3, 33.0, tension=75.0, contact_formulation="sum")
    with pytest.raises(ValueError, match="contact_curve"):
        DiagramOptions(2 / 3, 122.0, contact_curve="bezier")
    with pytest.raises(ValueError, match="contact_curve"):
        TweezersOptions(4 / 3, 33.0, tension=75.0, contact_curve="bezier")


def test_local_minimum_pairs_count_a_contact_once():
    """A strand crossing another near a piece junction: every pair of pieces
    around the crossing sees the same closest point (the neighbours through the
    shared end of their pieces); exactly one pair, the closest, is not a shadow."""
    from supercoil.contact.spline_distance import local_minimum_pairs

    n = 12
    u = np.arange(n) * 0.1
    p = np.stack([u, np.zeros(n), 0.02 * u**2], 1)  # strand along x, curved
    x0 = 0.1 * 5 + 0.1 * 0.03  # just past the start of piece 5
    q = np.stack([np.full(n, x0), u - 0.55, 0.3 - 0.03 * (u - 0.55) ** 2], 1)
    pts = np.concatenate([p, q])
    seg = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    a, b = bspline_pieces(seg, False), bspline_pieces(seg + n, False)
    pieces = CurvePieces(np.concatenate([a.stencil, b.stencil]),
                         np.concatenate([a.control, b.control]),
                         np.concatenate([a.joined_ends(), b.joined_ends()]))
    pairs = np.array([(i, n - 1 + j) for i in range(3, 8) for j in range(3, 8)])
    d, s, t = piece_distance(pts, pieces, pairs)
    kept = local_minimum_pairs(pts, pieces, pairs, s, t)
    assert kept.sum() == 1
    assert d[kept][0] == d.min()
    assert 0.0 < s[kept][0] < 1.0 and 0.0 < t[kept][0] < 1.0
