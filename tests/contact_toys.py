"""Toy problems for the contact tests (not rods: oracles with exact answers)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from test_continuation_toys import Unconstrained

from supercoil.contact.broadphase import candidate_pairs
from supercoil.contact.distance import segment_distance
from supercoil.solvers.problem import HessianParts


def assert_derivatives_match_differences(problem, q: np.ndarray, columns) -> None:
    """Oracle of a problem's gradient and Hessian at ``q``: central differences (step
    1e-7) of its energy and of its gradient along each DOF of ``columns``."""
    g = problem.gradient(q)
    H = problem.hessian(q).dense()
    eps = 1e-7
    for k in columns:
        e = np.zeros_like(q)
        e[k] = eps
        fd = (problem.energy(q + e) - problem.energy(q - e)) / (2 * eps)
        assert abs(fd - g[k]) <= 1e-5 * max(1.0, abs(g[k]))
        fd_h = (problem.gradient(q + e) - problem.gradient(q - e)) / (2 * eps)
        np.testing.assert_allclose(H[:, k], fd_h, rtol=1e-4, atol=1e-4)


def integral_pair_hessians_loop(x, stencil, weights, pairs, diameter, stiffness, activation, scale):
    """Oracle of the integral formulation's pair Hessians (barrier,
    :func:`supercoil.contact.integral.integral_terms`): a Python loop over the sample
    pairs in the kernel's order, the same terms in the same order (so equal to the bit):
    entry ``(3 l1 + r, 3 l2 + s)`` gains ``(c[l1] c[l2]) h3[r, s]``."""
    from supercoil.contact.integral import barrier

    q, w = weights.shape[1], weights.shape[2]
    points = np.zeros((len(stencil), q, 3))  # summed as the kernel sums them
    for i in range(len(stencil)):
        for a in range(q):
            for k in range(3):
                total = 0.0
                for m in range(w):
                    total += weights[i, a, m] * x[stencil[i, m], k]
                points[i, a, k] = total
    out = np.zeros((len(pairs), 6 * w, 6 * w))
    for p, (i, j) in enumerate(pairs):
        for a in range(q):
            for b in range(q):
                d0, d1, d2 = (float(points[i, a, k] - points[j, b, k]) for k in range(3))
                d = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                if d >= diameter + activation:
                    continue
                value, first, second = (v[0] for v in barrier(np.array([d - diameter]),
                                                               stiffness, activation))
                if value == np.inf:
                    continue
                first *= scale
                second *= scale
                tang = first / d
                nv = (d0 / d, d1 / d, d2 / d)
                h3 = [[(second - tang) * nv[r] * nv[s] for s in range(3)] for r in range(3)]
                for r in range(3):
                    h3[r][r] += tang
                c = [float(weights[i, a, m]) for m in range(w)] + \
                    [-float(weights[j, b, m]) for m in range(w)]
                for l1 in range(2 * w):
                    if c[l1] == 0.0:
                        continue
                    for l2 in range(2 * w):
                        cc = c[l1] * c[l2]
                        for r in range(3):
                            for s in range(3):
                                out[p, 3 * l1 + r, 3 * l2 + s] += cc * h3[r][s]
    return out


def assert_fresh_pair_state(problem, state: np.ndarray, cutoff: float, fast) -> None:
    """``fast`` (a ``problem.pair_state(state, cutoff, ...)`` on the segments) equals a
    fresh broad phase and segment distances at ``state``, bit for bit: the oracle of
    the remembered neighbour lists."""
    curve = problem.curve
    a, b = curve.endpoints(state)
    cand = candidate_pairs(a, b, curve.s_start, curve.s_end, cutoff, curve.exclusion,
                           period=curve.period)
    i, j = cand[:, 0], cand[:, 1]
    d, s, t = segment_distance(a[i], b[i], a[j], b[j])
    keep = d <= cutoff
    assert np.array_equal(fast.pairs, cand[keep])
    for mine, reference in ((fast.distance, d), (fast.s, s), (fast.t, t)):
        assert np.array_equal(mine, reference[keep])


@dataclass(frozen=True)
class _ToyRod:
    closed: bool
    edge_length: float
    length: float
    bending_stiffness: float = 1.0


class CrossedRods(Unconstrained):
    """Rod A (fixed, along x at z = 0) and rod B (along y, above A) pushed down by ``load``.

    B's nodes move only in z (x, y fixed), with a stiff bending spring
    ``K/2 sum (z_{i-1} - 2 z_i + z_{i+1})^2``, a spring ``K/2 (z_0 - z_last)^2``
    against tilting (internal: no net vertical force) and the dead load
    ``load * mean(z)``, symmetric about the crossing. At equilibrium B rests
    level on A with a total normal contact force equal to ``load``.
    """

    def __init__(self, n: int = 10, spacing: float = 0.1, height: float = 0.25,
                 load: float = 1.0, stiffness: float = 1e3, anchor: float = 0.0):
        self.n = n
        self.load = float(load)
        self.K = float(stiffness)
        # optional springs (anchor / n each) holding B's nodes at the start height
        self.anchor = float(anchor)
        self.height = float(height)
        u = (np.arange(n) - (n - 1) / 2) * spacing  # symmetric about 0
        a = np.stack([u + 0.013, np.zeros(n), np.zeros(n)], axis=1)  # crossing off A's nodes
        b = np.stack([np.full(n, 0.021), u, np.full(n, height)], axis=1)
        self.points = np.concatenate([a, b])
        self.rod = _ToyRod(closed=False, edge_length=spacing, length=spacing * (2 * n - 1))
        edges_a = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
        # a dummy edge (n-1, n) joins the rods so that the arc-length bookkeeping
        # is contiguous; it is far from the crossing and never near contact.
        edges_b = np.stack([np.arange(n - 1, 2 * n - 1), np.arange(n, 2 * n)], 1)
        self.edge_nodes = np.concatenate([edges_a, edges_b])
        self.n_dofs = 3 * 2 * n
        fixed = list(range(3 * n)) + [3 * k + c for k in range(n, 2 * n) for c in (0, 1)]
        self.fixed = np.array(sorted(fixed), dtype=np.int64)
        self.mass = np.full(self.n_dofs, spacing)
        self.n_constraints = 0
        z = 3 * np.arange(n, 2 * n) + 2
        rows = []
        for i in range(1, n - 1):
            row = np.zeros(self.n_dofs)
            row[z[i - 1]], row[z[i]], row[z[i + 1]] = 1.0, -2.0, 1.0
            rows.append(row)
        row = np.zeros(self.n_dofs)
        row[z[0]], row[z[-1]] = 1.0, -1.0
        rows.append(row)
        self._D2 = sp.csr_matrix(np.array(rows))
        self._load = np.zeros(self.n_dofs)
        self._load[z] = self.load / n

    def _anchor(self):
        z = np.zeros(self.n_dofs)
        z[3 * np.arange(self.n, 2 * self.n) + 2] = 1.0
        return z

    def energy(self, q):
        r = self._D2 @ q
        dz = self._anchor() * (q - self.height)
        return (0.5 * self.K * float(r @ r) + float(self._load @ q)
                + 0.5 * self.anchor / self.n * float(dz @ dz))

    def gradient(self, q):
        return (self.K * (self._D2.T @ (self._D2 @ q)) + self._load
                + self.anchor / self.n * self._anchor() * (q - self.height))

    def hessian(self, q):
        return HessianParts((self.K * (self._D2.T @ self._D2)
                             + sp.diags(self.anchor / self.n * self._anchor())).tocsr())


def stadium_ring(n: int, radius: float):
    """``(rod, x)``: a twisted ring problem of ``n`` nodes (C/A = 2/3) and a stadium of
    length 1 for its nodes, two straight sides ``2 radius`` apart joined by half circles
    of ``radius`` (in the plane z = 0)."""
    from supercoil.problems.ring import twisted_circle_problem

    rod, _q = twisted_circle_problem(2 / 3, 0.0, n)
    r = radius
    side = (1.0 - 2 * np.pi * r) / 2
    x = np.zeros((n, 3))
    for k, u in enumerate(np.arange(n) / n):
        if u < side:
            x[k] = (u - side / 2, -r, 0.0)
        elif u < side + np.pi * r:
            phi = (u - side) / r - np.pi / 2
            x[k] = (side / 2 + r * np.cos(phi), r * np.sin(phi), 0.0)
        elif u < 2 * side + np.pi * r:
            x[k] = (side / 2 - (u - side - np.pi * r), r, 0.0)
        else:
            phi = (u - 2 * side - np.pi * r) / r + np.pi / 2
            x[k] = (-side / 2 + r * np.cos(phi), r * np.sin(phi), 0.0)
    return rod, x
