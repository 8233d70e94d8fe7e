"""A contact branch closed on a curve it entered is followed again from before the curve
(:mod:`supercoil.problems.tweezers.rejoin`): the curve and its entry found on hand-made
branches whose geometry gives them, the guard that refuses the curve, and the driver's
bookkeeping with the computation mocked."""

import dataclasses

import numpy as np
import pytest
from returned_toys import branch

from supercoil.continuation import ContinuationStatus
from supercoil.continuation.resume import head
from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers import rejoin as module
from supercoil.problems.tweezers.plectoneme import OnParent

LAP = 40  # points a lap of the circle


def circled(extra: int = 12, approach: int = 10) -> tuple:
    """``approach`` points on a line into the unit circle at angle -pi/2 (at 45 degrees
    to it), then a lap of the circle and ``extra`` points more (a closed branch in four
    dimensions): the entry is point ``approach``, and the end coincides with the
    circle's point ``extra``, the branch's point ``approach + extra``."""
    line = [(-1.0 + 0.1 * k, -2.0 + 0.1 * k) for k in range(approach)]
    angles = -np.pi / 2 + 2 * np.pi * np.arange(LAP + extra + 1) / LAP
    circle = [(np.cos(a), np.sin(a)) for a in angles]
    xy = np.array(line + circle)
    states = np.column_stack([xy, np.zeros((len(xy), 2))])
    k = len(states)
    closed = branch("buckled_contact", np.linspace(1.0, 2.0, k), states,
                    np.ones(k, dtype=int), np.zeros(k))
    return dataclasses.replace(closed, status=ContinuationStatus.CLOSED_LOOP)


def test_the_curve_and_its_entry_are_found_on_a_branch_that_went_round_it():
    # oracle: the construction (module circled)
    assert module.cycle_entry(circled()) == (10, 22)
    assert module.cycle_entry(circled(extra=25, approach=7)) == (7, 32)


def test_a_branch_not_closed_on_itself_has_no_curve():
    assert module.cycle_entry(dataclasses.replace(
        circled(), status=ContinuationStatus.MAX_POINTS)) is None


def test_points_are_the_branch_between_two_indices():
    closed = circled()
    part = module.points(closed, 3, 9)
    np.testing.assert_array_equal(part.states, closed.states[3:9])
    np.testing.assert_array_equal(part.parameter_values, closed.parameter_values[3:9])
    np.testing.assert_array_equal(part.records["n_contact_points"],
                                  closed.records["n_contact_points"][3:9])
    assert part.special_points == ()


def test_the_guard_refuses_the_curve_away_from_the_entry_only():
    # the curve's states (its polygon) refused farther than PARENT_REACH steps from the
    # entry; the entry itself and a state off the curve by a tenth of a step pass
    closed = circled()
    entry, back = module.cycle_entry(closed)
    curve = module.points(closed, back, len(closed))
    guard = OnParent(curve, module._point(closed, entry, "cycle_entry"),
                     what="the closed curve the branch had entered")
    far = closed.states[entry + LAP // 2]
    assert guard(far).startswith("back on the closed curve the branch had entered")
    assert guard(closed.states[entry]) is None
    assert guard(far * 1.016) is None  # 0.1 of a step (2 pi / 40) outside


def test_the_driver_keeps_the_branch_followed_again_where_it_reaches_further(monkeypatch):
    """The contact branch of a small rod taken as closed on a curve; ``rejoined`` mocked
    to give it again, named ``/rejoined``, reaching the last turn: a final branch after
    the contact branch, with its pins, and a note naming where it started; no switch."""
    from supercoil.problems.tweezers import compute

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24,
                           tension=20, turns=(0.0, 1.6))
    monkeypatch.setattr(compute, "held_contact", lambda *args, **kwargs: None)

    def closing(branch, last):
        return branch.name == "buckled_contact" and branch.parameter_values[-1] < last

    original = compute.contact_branch
    made = {}

    def again(opts, rod, cp, closed, *args, **kwargs):
        made["from"] = closed.name
        whole = original_branch["branch"]
        return module.Rejoined(dataclasses.replace(whole, name=closed.name + "/rejoined"),
                               ((0, (7,)),), 6, 2, ())

    original_branch = {}

    def remember(*args, **kwargs):
        branch, pins = original(*args, **kwargs)
        original_branch["branch"] = branch
        return cut_branch(branch), pins

    def cut_branch(branch):
        return dataclasses.replace(head(branch, 10), status=ContinuationStatus.CLOSED_LOOP,
                                   message="closed here")

    monkeypatch.setattr(compute, "contact_branch", remember)
    monkeypatch.setattr(compute, "closed_before", closing)
    monkeypatch.setattr(compute, "rejoined", again)
    monkeypatch.setattr(compute, "switch_to_plectoneme", lambda *a, **k: pytest.fail("switched"))
    result = compute.tweezers_branches(opts)
    names = [b.name for b in result.branches]
    assert names[-2:] == ["buckled_contact", "buckled_contact/rejoined"]
    assert made["from"] == "buckled_contact"
    assert result.pins["buckled_contact/rejoined"] == ((0, (7,)),)
    assert result.branches[-1].parameter_values[-1] == pytest.approx(1.6)
    assert any(n.startswith("buckled_contact: closed (closed here); followed again from "
                            "its point 2, before the closed curve it entered at its point 6")
               and n.endswith("buckled_contact/rejoined (parameter_bound at 1.6 turns, 1.6 at "
                              "most)") for n in result.notes)
    assert not any(n.startswith("incomplete") for n in result.notes)


def test_a_run_started_from_the_closed_branch_is_not_said_resumed():
    """``rejoined`` for real on a small rod's contact branch, cut and taken as closed:
    the run it starts from two of the branch's points is a new one, and its message
    does not say "resumed"; continued from its own stored points, it does (as every
    continued run's message does: ``continuation.resume``)."""
    from supercoil.problems.tweezers.compute import tweezers_branches
    from supercoil.problems.tweezers.options import TweezersOptions as Options

    opts = Options(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24, tension=20,
                   turns=(0.0, 1.6), max_points=40)
    result = tweezers_branches(opts)
    contact = next(b for b in result.branches if b.name in result.contact_branches)
    closed = dataclasses.replace(head(contact, 12), status=ContinuationStatus.CLOSED_LOOP,
                                 message="closed here")
    again = module.rejoined(opts, result.rod_problem, result.contact_problem, closed)
    assert again is not None and len(again.branch) > 2
    assert again.branch.name == "buckled_contact/rejoined"
    assert "resumed" not in again.branch.message, again.branch.message
    stored = {again.branch.name: (head(again.branch, 4), False)}
    resumed = module.rejoined(opts, result.rod_problem, result.contact_problem, closed,
                              stored)
    assert resumed.branch.message.endswith("(resumed after point 3)"), resumed.branch.message
