"""Hand-made tweezers branches of centrelines whose distances are known, for the tests of
a contact branch that comes back onto the contact-free branch (bumps across the rod)."""

import numpy as np

from supercoil.continuation import Branch, ContinuationStatus

D = 0.01
NODES = 41
S = np.linspace(0.0, 1.0, NODES)


def centreline(turns: float, angle: float = 0.0, shift: float = 0.0) -> np.ndarray:
    """A bump of amplitude 0.05 turns^2 across the rod, centred at 1/2 + shift, turned by
    ``angle`` about the z axis."""
    a = 0.05 * turns**2 * np.sin(np.pi * np.clip(S - shift, 0.0, 1.0))
    x = np.column_stack([a * np.cos(angle), a * np.sin(angle), S])
    return x.ravel()


def branch(name, turns, states, contacts, gaps) -> Branch:
    k = len(turns)
    n = states.shape[1]
    return Branch(name=name, parent=None, origin=None, parameter="turns",
                  parameter_values=np.asarray(turns, dtype=float), states=states,
                  multipliers=np.zeros((k, 0)), unstable_count=np.zeros(k, dtype=int),
                  zero_modes=np.zeros(k, dtype=int), determinant_sign=np.ones(k, dtype=int),
                  nearest_eigenvalue=np.ones(k), tangents=np.zeros((k, n + 1)),
                  arclength=np.arange(k, dtype=float), special_points=(),
                  status=ContinuationStatus.MAX_POINTS, message="computed",
                  records={"n_contact_points": np.asarray(contacts),
                           "min_gap_over_diameter": np.asarray(gaps, dtype=float)})


FREE_TURNS = np.linspace(1.0, 2.0, 11)
FREE = branch("buckled", FREE_TURNS, np.array([centreline(t) for t in FREE_TURNS]),
              np.zeros(11, dtype=int), np.full(11, 3.0))


def contact_branch(back_shift: float, back_gap: float = 2.0) -> Branch:
    """Two contact-free points on the stored branch (the start), three in contact (a
    different shape), then three contact-free points between the stored turns, turned
    by 0.7 rad about the axis and moved along the rod by ``back_shift``."""
    turns = [2.0, 1.98, 1.9, 1.8, 1.7, 1.63, 1.47, 1.31]
    states = [centreline(2.0), centreline(1.98), centreline(1.9, shift=0.1),
              centreline(1.8, shift=0.2), centreline(1.7, shift=0.1)]
    states += [centreline(t, angle=0.7, shift=back_shift) for t in turns[5:]]
    return branch("buckled_contact", turns, np.array(states), [0, 0, 1, 2, 1, 0, 0, 0],
                  [3.0, 3.0, 1.0, 1.0, 1.0, back_gap, 2.0, 2.0])
