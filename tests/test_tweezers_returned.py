"""A contact branch that comes back onto the contact-free branch is found
(:mod:`supercoil.problems.tweezers.returned`): hand-made branches of centrelines whose
distances are known, against one stored branch."""

import numpy as np
from returned_toys import FREE, D, S, branch, centreline, contact_branch

from supercoil.continuation import ContinuationStatus
from supercoil.problems.tweezers.returned import (
    RETURN_TOLERANCE,
    axis_distance,
    close_on_return,
    returned_onto,
)


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
