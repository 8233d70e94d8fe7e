"""The axial closure fails when the rod wraps around a tail: the records say so.

The writhe of an open clamped rod is that of the rod closed by straight tails along
the axis, so that turns = Tw + Wr (Fuller) while no strand passes through a tail. A
family of shapes sweeps the middle of the rod once across the lower tail (the
half-line of the axis below the first clamp); the twist, carried continuously by
the reference frames, does not notice, while the double-sum writhe of the closed
curve jumps by 2 (a crossing change of the closed curve). The records must keep
|Tw + Wr - turns| at round-off before the crossing and flag ``closure_failed``
(error 2) after it.
"""

import numpy as np
import pytest

from supercoil.problems.tweezers import tweezers_records
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod


def shape(n, beta, mu):
    """Nodes (n, 3): a bump of size beta whose middle sits at (beta mu, 0, 0.5 - 0.8 beta)."""
    pts = straight_rod(n)
    s = pts[:, 2].copy()
    w = np.sin(np.pi * np.clip(s, 0.0, 1.0)) ** 4
    pts[:, 0] = beta * mu * w
    pts[:, 1] = beta * 0.1 * w * np.sin(2 * np.pi * s)
    pts[:, 2] = s - 0.8 * beta * w
    pts[[0, 1, -2, -1], :2] = 0.0
    pts[[0, 1, -2, -1], 2] = s[[0, 1, -2, -1]]
    return pts


def test_wrapping_a_tail_is_flagged():
    n = 60
    problem = ClampedRodEnergy(Rod(n, closed=False), straight_rod(n), 0.3, tension=1.0)
    records = tweezers_records(problem, problem, False)
    mu = np.zeros(problem.n_constraints)
    errors_before, errors_after = [], []
    path = [(b, 0.2) for b in np.linspace(0.0, 1.0, 60)[1:]]
    path += [(1.0, m) for m in np.linspace(0.2, -0.2, 80)[1:]]  # 0 (touching) left out
    for beta, m in path:
        q = shape(n, beta, m).ravel()
        problem.accept(q)
        rec = records(q, mu, 0.3)
        (errors_before if m > 0 else errors_after).append(
            (rec["closure_error"], rec["closure_failed"]))
    assert max(e for e, _ in errors_before) < 1e-9
    assert not any(flag for _, flag in errors_before)
    assert all(flag for _, flag in errors_after)
    assert all(e == pytest.approx(2.0, abs=1e-9) for e, _ in errors_after)
