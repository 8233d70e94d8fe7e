"""The projection onto states symmetric under the clamped rod's half-turn
(``supercoil.rod.mirror.symmetric_state``, ``symmetric_direction``) and the rod's
``held_part`` / ``held_direction`` that the continuation's corrector applies.

Oracles: curves symmetric by construction; a projection is idempotent and the identity
on its image; its derivative at a symmetric state against central differences of the
state's projection; the exchanged edges brute-forced from their node indices.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from supercoil.rod.mirror import (
    mirror_asymmetry,
    mirror_pairs,
    mirrored_direction,
    symmetric_direction,
    symmetric_state,
)
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod


def clamped_curve(n: int, seed: int) -> np.ndarray:
    """A smooth asymmetric curve on the clamped rod's nodes (end edges on the axis)."""
    rng = np.random.default_rng(seed)
    x = straight_rod(n)
    s = np.linspace(0.0, 1.0, n - 4)  # the nodes between the end edges
    for k in range(1, 4):
        shape = np.sin(np.pi * k * s) ** 2
        x[2:-2, 0] += 0.05 * rng.normal() * shape
        x[2:-2, 1] += 0.05 * rng.normal() * shape
        x[2:-2, 2] += 0.01 * rng.normal() * shape
    x[-2:, 2] -= 0.02  # the loaded end has moved along the axis
    return x.ravel()


def farthest_pin(q: np.ndarray) -> int:
    """The y coordinate of the node farthest from the axis (an azimuth pin)."""
    x = q.reshape(-1, 3)
    return 3 * int(np.argmax(np.hypot(x[:, 0], x[:, 1]))) + 1


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_symmetric_state_is_a_projection_that_keeps_the_pin(seed):
    q = clamped_curve(60, seed)
    pin = farthest_pin(q)
    assert mirror_asymmetry(q) > 1e-3
    s = symmetric_state(q, pin)
    assert mirror_asymmetry(s) < 1e-14
    assert s[pin] == q[pin]
    np.testing.assert_allclose(symmetric_state(s, pin), s, atol=1e-15)
    # the clamped end and the axis of the loaded end stay
    np.testing.assert_allclose(s.reshape(-1, 3)[[0, 1]], q.reshape(-1, 3)[[0, 1]], atol=1e-15)
    np.testing.assert_allclose(s.reshape(-1, 3)[[-2, -1], :2], 0.0, atol=1e-15)


@pytest.mark.parametrize("seed", [0, 3])
def test_the_symmetric_direction_is_the_projection_s_derivative(seed):
    """At a symmetric state, ``symmetric_direction`` is the derivative of
    ``symmetric_state``: central differences converge to it at second order (the
    axis and the turn that holds the pin move with the state), and it projects."""
    s = symmetric_state(clamped_curve(60, seed), None)
    pin = farthest_pin(s)
    rng = np.random.default_rng(10 + seed)
    d = rng.normal(size=s.size)
    d[pin] = 0.0  # a pinned coordinate does not move
    d.reshape(-1, 3)[[0, 1]] = 0.0
    d.reshape(-1, 3)[[-2, -1], :2] = 0.0
    direction = symmetric_direction(s, d, pin)

    def error(eps: float) -> float:
        fd = (symmetric_state(s + eps * d, pin) - symmetric_state(s - eps * d, pin)) / (2 * eps)
        return float(np.abs(fd - direction).max() / np.abs(direction).max())

    errors = [error(eps) for eps in (1e-3, 1e-4, 1e-5)]
    assert errors[-1] < 1e-6
    assert all(80 < a / b < 120 for a, b in pairwise(errors))  # O(eps^2)
    assert direction[pin] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(symmetric_direction(s, direction, pin), direction,
                               atol=1e-14 * np.abs(direction).max())


def test_the_linearised_half_turn_is_an_involution():
    s = symmetric_state(clamped_curve(40, 5), None)
    axis = np.array([np.cos(0.3), np.sin(0.3), 0.0])
    d = np.random.default_rng(4).normal(size=s.size)
    np.testing.assert_allclose(mirrored_direction(mirrored_direction(d, axis), axis), d,
                               atol=1e-13)


@pytest.mark.parametrize("n", [10, 11])
def test_the_exchanged_edges_pair_as_their_nodes_do(n):
    """Load control constrains edges 1 .. n-2 (edge 0, clamped, is fixed whole): edge e
    joins nodes e, e+1, whose images are nodes n-1-e, n-2-e, i.e. edge n-2-e."""
    edges = np.arange(1, n - 1)
    pairs = mirror_pairs(edges, n)
    brute = {(k, j) for k, e in enumerate(edges) for j, f in enumerate(edges)
             if k < j and {n - 1 - e, n - 2 - e} == {f, f + 1}}
    assert set(map(tuple, pairs.tolist())) == brute
    assert n - 2 not in edges[pairs.ravel()]  # its image, edge 0, is not constrained


def test_the_rod_holds_states_and_steps_only_when_told():
    n = 30
    q = clamped_curve(n, 7)
    rod = ClampedRodEnergy(Rod(n_nodes=n, twist_stiffness=1.5, closed=False), straight_rod(n), turns=1.0)
    multipliers = np.arange(rod.n_constraints, dtype=float)
    assert rod.held_part(q, multipliers) is None
    assert rod.held_direction(q, q, multipliers) is None
    rod.mirror_hold = True
    rod.repin(q)
    s, mu = rod.held_part(q, multipliers)
    assert mirror_asymmetry(s) < 1e-14
    assert s[rod.gauge_dofs[0]] == q[rod.gauge_dofs[0]]
    pairs = mirror_pairs(np.arange(1, n - 1), n)
    np.testing.assert_allclose(mu[pairs[:, 0]], mu[pairs[:, 1]])
    np.testing.assert_allclose(mu[pairs[:, 0]], 0.5 * (multipliers[pairs[:, 0]]
                                                      + multipliers[pairs[:, 1]]))
    assert mu[-1] == multipliers[-1]  # the last edge's, unpaired
