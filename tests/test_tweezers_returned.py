"""A contact branch that comes back onto the contact-free branch is found
(:mod:`supercoil.problems.tweezers.returned`): hand-made branches of centrelines whose
distances are known, against one stored branch."""

import numpy as np

from supercoil.continuation import Branch, ContinuationStatus
from supercoil.problems.tweezers.returned import (
    RETURN_TOLERANCE,
    axis_distance,
    close_on_return,
    returned_onto,
)

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


def test_axis_distance_removes_the_rotation_about_the_axis():
    # oracle: a rotated copy is at distance 0; nodes moved along the axis by up to d
    # (at the middle node), which no rotation about it undoes, are at distance d
    p = centreline(1.5)
    assert axis_distance(centreline(1.5, angle=2.1), p) < 1e-12
    q = p.reshape(-1, 3).copy()
    q[:, 2] += 0.003 * np.sin(np.pi * S)
    assert abs(axis_distance(q.ravel(), p) - 0.003) < 1e-15


def test_a_branch_back_on_the_stored_one_is_found_where_it_released_its_contacts():
    # between stored turns the linear interpolation errs by 0.05 (0.05)^2 / 1 < 0.1 D;
    # its first two points coincide with the stored branch but precede any contact
    contact = contact_branch(back_shift=0.0)
    assert returned_onto(contact, FREE, D) == 5
    closed = close_on_return(contact, FREE, D)
    assert closed.status is ContinuationStatus.CLOSED_LOOP
    assert len(closed) == 6 and closed.parameter_values[-1] == 1.63
    assert "buckled" in closed.message


def test_a_point_within_the_contact_reach_is_not_back():
    contact = contact_branch(back_shift=0.0, back_gap=1.005)
    assert returned_onto(contact, FREE, D, reach=1.01) == 6


def test_a_branch_elsewhere_at_the_same_turns_is_not_back():
    # the bump moved by 2 D along the rod: 0.05 t^2 pi 0.02 > 0.08 t^2 D away, above
    # the tolerance at every turns in 1.31-1.63
    assert 0.05 * 1.31**2 * np.pi * 2 * D > RETURN_TOLERANCE * D * 1.5
    contact = contact_branch(back_shift=2 * D)
    assert returned_onto(contact, FREE, D) is None
    assert close_on_return(contact, FREE, D) is contact


def test_turns_beyond_the_stored_branch_are_not_back():
    # the same shapes, their turns outside the stored ones: no chord brackets them
    contact = contact_branch(back_shift=0.0)
    outside = branch("c", [2.0, 1.98, 1.9, 1.8, 1.7, 0.9, 0.8, 0.7], contact.states,
                     contact.records["n_contact_points"],
                     contact.records["min_gap_over_diameter"])
    assert returned_onto(outside, FREE, D) is None
