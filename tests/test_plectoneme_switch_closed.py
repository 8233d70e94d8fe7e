"""A branch switched at a bifurcation of a closed contact branch that comes back onto the
contact-free branch is closed there, as the contact branch is
(:mod:`supercoil.problems.tweezers.plectoneme`): the switch and the runs replaced by
hand-made branches whose return point is known (bumps across the rod, as in
``test_tweezers_returned``)."""

import dataclasses

import numpy as np
import pytest
from returned_toys import FREE, D, branch, centreline, contact_branch

from supercoil.continuation import ContinuationStatus, SpecialPoint
from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers import plectoneme as module


@pytest.fixture
def switched(monkeypatch):
    """``switch_to_plectoneme`` whose every switch gives ``candidates[k]`` for the k-th
    switch tried (its first two points as the switch's run, the whole as the runs that
    follow)."""
    candidates = []
    tried = []

    def switch_branch(cp, contact, point, base, **kwargs):
        tried.append(kwargs["name"])
        whole = candidates[min(len(tried) - 1, len(candidates) - 1)]
        return dataclasses.replace(whole, parameter_values=whole.parameter_values[:2],
                                   states=whole.states[:2], name=kwargs["name"])

    def follow(cp, rod, first, base, name, *args, **kwargs):
        whole = candidates[min(len(tried) - 1, len(candidates) - 1)]
        return dataclasses.replace(whole, name=name), ((0, (1,)),)

    monkeypatch.setattr(module, "switch_branch", switch_branch)
    monkeypatch.setattr(module, "follow", follow)
    monkeypatch.setattr(module, "classify_contact_events", lambda b, cp: b)
    monkeypatch.setattr(module, "set_pin", lambda cp, rod, q: None)
    monkeypatch.setattr(module, "hold_azimuth", lambda rod, dofs, cp=None: None)
    return candidates, tried


def closed_contact():
    """A closed contact branch with one located bifurcation at its point 3."""
    contact = contact_branch(back_shift=0.0)
    q = contact.states[3]
    point = SpecialPoint(kind="bifurcation", label="BP", branch=contact.name, index=3,
                         parameter=1.8, arclength=3.0, q=q, multipliers=np.zeros(0),
                         tangent=np.zeros(q.size + 1))
    records = dict(contact.records) | {"azimuth_pin": np.full(len(contact), -1)}
    return dataclasses.replace(contact, special_points=(point,), records=records,
                               status=ContinuationStatus.CLOSED_LOOP)


OPTS = TweezersOptions(twist_ratio=1.5, length_over_diameter=1 / D, tension=100.0,
                       turns=(0.0, 3.0), n_nodes=41)


def test_a_switched_branch_back_on_the_contact_free_branch_is_closed_there(switched):
    # oracle: the hand-made branch releases its contacts and lies on FREE (turned about
    # the axis) from its point 5 (turns 1.63) on, between FREE's turns, where the chord
    # errs by 0.05 (0.05)^2 < 0.1 D; past it, it goes on along FREE (as on to the
    # straight rod)
    candidates, tried = switched
    candidates.append(contact_branch(back_shift=0.0))
    best, *_ = module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE)
    assert best.status is ContinuationStatus.CLOSED_LOOP
    assert len(best) == 6 and best.parameter_values[-1] == 1.63
    # closed: every other switch was tried too (2 amplitudes x 2 sides)
    assert len(tried) == 2 * len(module.AMPLITUDES)


def test_a_switched_branch_elsewhere_is_followed_and_kept(switched):
    # the bump moved along the rod by 2 D: 0.05 t^2 pi 0.02 > 0.1 D away from FREE, so
    # the switched branch is kept whole, and preferred to the closed one as it reaches
    # further in turns
    candidates, _ = switched
    candidates.append(contact_branch(back_shift=0.0))
    away = contact_branch(back_shift=2 * D)
    turns = np.array([1.8, 1.9, 2.0, 2.2, 2.4, 2.6, 2.8, 3.0])
    candidates.append(branch("away", turns, np.array([centreline(t, shift=0.2) for t in turns]),
                             away.records["n_contact_points"],
                             away.records["min_gap_over_diameter"]))
    best, *_ = module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE)
    assert best.status is ContinuationStatus.MAX_POINTS
    assert best.parameter_values[-1] == 3.0


def test_each_switched_branch_is_handed_over_under_its_own_name(switched):
    # oracle: try_names, written out: the 2 amplitudes x 2 sides of the one bifurcation
    candidates, tried = switched
    candidates.append(contact_branch(back_shift=0.0))
    ended = []
    module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE,
                                on_branch=lambda b, final: ended.append((b.name, final)))
    names = ["buckled_contact/bifurcation3"] + [
        f"buckled_contact/bifurcation3_try{k}" for k in (2, 3, 4)]
    assert tried == names and ended == [(n, True) for n in names]


def test_a_resumed_switch_takes_the_tries_stored_and_continues_the_last(switched,
                                                                       monkeypatch):
    """Resumed with what an interrupted run stored: the finished tries are taken as
    stored and not switched again, one stored as not started is passed over, the
    incomplete one is continued from its last point (its first points here), not
    switched again; only the tries after it are switched.
    Oracle: the best branch of the uninterrupted call, and which tries were switched."""
    candidates, tried = switched
    candidates.append(contact_branch(back_shift=0.0))
    ended = {}
    full, *_ = module.switch_to_plectoneme(
        OPTS, None, None, closed_contact(), free=FREE,
        on_branch=lambda b, final: ended.__setitem__(b.name, b))
    names = list(ended)
    continued = []

    def resume_stored(stored, rod, cp, name, *args, **kwargs):
        continued.append(name)
        return stored[name][0]

    monkeypatch.setattr(module, "resume_stored", resume_stored)
    monkeypatch.setattr(module, "stored_pins", lambda branch: ((0, (1,)),))
    monkeypatch.setattr(module, "resumed_pins", lambda old, later: later)

    def first_two(name):  # the first points of a try, as the interrupted run stored them
        return dataclasses.replace(candidates[0], name=name, states=candidates[0].states[:2],
                                   parameter_values=candidates[0].parameter_values[:2])

    not_started = dataclasses.replace(first_two(names[1]),
                                      status=ContinuationStatus.START_FAILED)
    stored = {names[0]: (ended[names[0]], True), names[1]: (not_started, True),
              names[2]: (first_two(names[2]), False)}
    tried.clear()
    collected = []
    best, *_ = module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE,
                                          stored=stored, tried=collected)
    assert continued == [names[2]] and tried == [names[3]]
    # every try once, in order: two taken as stored, one continued, one switched
    assert [b.name for b in collected] == names
    assert collected[0] is ended[names[0]] and collected[1] is not_started
    assert best.name == full.name and len(best) == len(full)
    np.testing.assert_array_equal(best.parameter_values, full.parameter_values)


def test_a_switched_branch_that_closes_on_itself_is_switched_at_its_crossing(switched,
                                                                            monkeypatch):
    """The first switch closes on itself (away from FREE) with located count changes
    at its points 2 and 5, the loop closing at its last point, nearest point 5's state:
    the change at 5 verified (the counts 0 before it, 1 after), the one at 2 not (0 on
    both sides): it is switched again at 5 (and only there), and that branch, reaching
    the last turn, is the result, reached via the closed one. Oracle: the hand-made
    branches' names, counts, closure and turns."""
    candidates, tried = switched
    away = contact_branch(back_shift=2 * D)
    turns = np.array([1.8, 1.9, 2.0, 2.1, 2.2, 2.1, 2.0, 2.05])
    states = np.array([centreline(t, shift=0.2) for t in turns])
    states[-1] = states[5] + 1e-3  # back round the loop, next to the crossing at point 5
    marks = [SpecialPoint(kind="bifurcation", label="BP", branch="closed", index=i,
                          parameter=float(turns[i]), arclength=float(i), q=states[i],
                          multipliers=np.zeros(0), tangent=np.zeros(states.shape[1] + 1),
                          count_before=0, count_after=after)
             for i, after in ((2, 1), (5, 1))]
    loop = dataclasses.replace(
        branch("closed", turns, states, away.records["n_contact_points"],
               away.records["min_gap_over_diameter"]),
        special_points=tuple(marks), status=ContinuationStatus.CLOSED_LOOP,
        unstable_count=np.array([0, 0, 0, 0, 0, 0, 1, 1]),
        records=dict(away.records) | {"azimuth_pin": np.full(8, -1)})
    reach = np.array([2.0, 2.2, 2.4, 2.6, 2.8, 3.0, 3.0, 3.0])[:7]
    onward = branch("onward", reach, np.array([centreline(t, shift=0.4) for t in reach]),
                    away.records["n_contact_points"][:7],
                    away.records["min_gap_over_diameter"][:7])
    onward = dataclasses.replace(onward, status=ContinuationStatus.PARAMETER_BOUND)
    candidates.extend([loop, onward])

    def switch_branch(cp, contact, point, base, **kwargs):  # each switch starts
        tried.append(kwargs["name"])
        whole = candidates[min(len(tried) - 1, len(candidates) - 1)]
        return dataclasses.replace(whole, parameter_values=whole.parameter_values[:2],
                                   states=whole.states[:2],
                                   status=ContinuationStatus.MAX_POINTS)

    monkeypatch.setattr(module, "switch_branch", switch_branch)
    collected = []
    best = module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE,
                                       tried=collected)
    assert tried == ["buckled_contact/bifurcation3",
                     "buckled_contact/bifurcation3/bifurcation5"]
    assert [b.name for b in collected] == tried  # the nested try collected too
    assert best.branch.name == "buckled_contact/bifurcation3/bifurcation5"
    assert best.branch.parameter_values[-1] == 3.0
    assert [b.name for b, _ in best.via] == ["buckled_contact/bifurcation3"]
    assert [p.kind for p in best.via[0][0].special_points] == ["count_change", "bifurcation"]


def test_a_switch_that_does_not_start_is_handed_over_as_such(switched):
    # the switch's first run closes at once: not followed, stored as not started
    candidates, tried = switched
    candidates.append(dataclasses.replace(contact_branch(back_shift=0.0),
                                          status=ContinuationStatus.CLOSED_LOOP))
    ended = []
    best = module.switch_to_plectoneme(OPTS, None, None, closed_contact(), free=FREE,
                                       on_branch=lambda b, final: ended.append(b.status))
    assert best is None and len(tried) == 4
    assert ended == [ContinuationStatus.START_FAILED] * 4


def test_the_tries_and_why_they_did_not_start_are_collected_and_noted(switched):
    # oracle: the mocked switch's runs, each closed at once (message "closed here"), and
    # on resuming, the same tries stored as not started: collected again, none computed
    candidates, tried = switched
    candidates.append(dataclasses.replace(contact_branch(back_shift=0.0), message="closed here",
                                          status=ContinuationStatus.CLOSED_LOOP))
    contact = closed_contact()
    collected, stored = [], {}
    best = module.switch_to_plectoneme(
        OPTS, None, None, contact, free=FREE, tried=collected,
        on_branch=lambda b, final: stored.update({b.name: (b, final)}))
    names = [name for *_, name in module.try_names(contact)]
    assert best is None and [b.name for b in collected] == names == tried
    assert all(b.message == "the switch did not start: closed here" for b in collected)
    note = module.tries_note(contact, collected)
    assert note.startswith(f"switches tried from {contact.name}: ")
    assert note.count("the switch did not start: closed here") == len(names)
    again = []
    assert module.switch_to_plectoneme(OPTS, None, None, contact, free=FREE, stored=stored,
                                       tried=again) is None
    assert len(tried) == len(names) and [b.name for b in again] == names
    # a try that was followed is noted by where it ended and how far it reached
    run = dataclasses.replace(contact_branch(back_shift=0.0), name="b/bifurcation3")
    turns = run.parameter_values
    assert module.tries_note(contact, [run]).endswith(
        f"b/bifurcation3: {run.status.name.lower()} at {turns[-1]:.6g} turns after "
        f"{len(run)} points ({turns.min():.6g} to {turns.max():.6g} turns)")


def test_the_tweezers_keep_the_closed_branches_a_switch_came_through(monkeypatch):
    """The driver's bookkeeping of a switch reached through a closed switched branch: the
    closed one and the switched one are both final branches of the result, in that
    order after the contact branch, with their pins, seconds and a note each naming
    where it was switched. Oracle: the hand-made Switched (the switch itself mocked,
    and the contact branch of a small rod taken as closed)."""
    from supercoil.problems.tweezers import compute

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24,
                           tension=20, turns=(0.0, 1.6))
    monkeypatch.setattr(compute, "closed_before", lambda branch, last: True)
    monkeypatch.setattr(compute, "held_contact", lambda *args, **kwargs: None)
    made = {}

    def switch(opts, rod, cp, last, *args, **kwargs):
        point = last.special_points[0]
        closed = dataclasses.replace(last, name=f"{last.name}/bifurcation{point.index}",
                                     origin=point, status=ContinuationStatus.CLOSED_LOOP)
        onward = dataclasses.replace(last, name=f"{closed.name}/bifurcation2",
                                     origin=dataclasses.replace(point, parameter=1.25))
        made.update(closed=closed.name, onward=onward.name)
        kwargs["tried"].append(closed)
        return module.Switched(onward, ((0, (5,)),), ((closed, ((0, (3,)),)),),
                               {closed.name: 2.5, onward.name: 1.5})

    monkeypatch.setattr(compute, "switch_to_plectoneme", switch)
    ended = []
    result = compute.tweezers_branches(opts, on_branch=lambda b, c: ended.append(b.name))
    names = [b.name for b in result.branches]
    assert names[-3:] == ["buckled_contact", made["closed"], made["onward"]]
    assert ended[-2:] == [made["closed"], made["onward"]]
    assert result.pins[made["closed"]] == ((0, (3,)),)
    assert result.pins[made["onward"]] == ((0, (5,)),)
    assert result.seconds[made["closed"]] == 2.5
    assert {made["closed"], made["onward"]} <= result.contact_branches
    assert any(n.startswith(f"{made['closed']}: closed") and n.endswith(made["onward"])
               for n in result.notes)
    assert any(n.startswith("buckled_contact: closed") and n.endswith(made["closed"])
               for n in result.notes)
    # the switched branch reaches the last turn: the tries are not listed
    assert result.branches[-1].parameter_values[-1] == opts.turns[1]
    assert not any(n.startswith("switches tried") for n in result.notes)


def test_a_switch_back_on_its_parent_is_refused_away_from_the_bifurcation():
    """OnParent on a hand-made parent (a helix in 12 dimensions, 200 points): a state on
    its polygon farther than 3 steps from the bifurcation is refused, naming the segment;
    the same state near the bifurcation, or moved off the path by more than 1e-2 of a
    step, is not. The pruned distance equals the brute-force one over every segment."""
    s = np.linspace(0.0, 4.0, 200)
    states = np.stack([np.cos(3 * s), np.sin(3 * s), s] + [np.sin((k + 2) * s) / (k + 2)
                                                            for k in range(9)], axis=1)
    parent = dataclasses.replace(contact_branch(back_shift=0.0), states=states,
                                 parameter_values=s)
    point = SpecialPoint(kind="bifurcation", label="BP", branch=parent.name, index=100,
                         parameter=s[100], arclength=s[100], q=states[100],
                         multipliers=np.zeros(0), tangent=np.zeros(13))
    guard = module.OnParent(parent, point)
    step = float(np.median(np.linalg.norm(np.diff(states, axis=0), axis=1)))
    on_path = 0.5 * (states[40] + states[41])
    message = guard(on_path)
    assert "between its points 40 and 41" in message
    stopped = dataclasses.replace(parent, status=ContinuationStatus.STOPPED,
                                  message=f"stopped after 7 points at turns = 1.5: {message}")
    assert guard.ended(stopped)  # a run it stopped, not one that went on past a refusal
    assert not guard.ended(dataclasses.replace(stopped, status=ContinuationStatus.MAX_POINTS))
    fresh = module.OnParent(parent, point)
    assert fresh(0.5 * (states[100] + states[101])) is None  # within reach of the point
    normal = np.cross(states[41, :3] - states[40, :3], [0.0, 0.0, 1.0])
    off = on_path.copy()
    off[:3] += 0.05 * step * normal / np.linalg.norm(normal)
    assert fresh(off) is None and not fresh.refusals
    rng = np.random.default_rng(1)
    for q in states[rng.integers(0, 200, 20)] + 1e-3 * rng.standard_normal((20, 12)):
        brute = min(np.linalg.norm(q - (states[i] + t * (states[i + 1] - states[i])))
                    for i in range(199) for t in [np.clip(
                        (q - states[i]) @ (states[i + 1] - states[i])
                        / np.sum((states[i + 1] - states[i]) ** 2), 0.0, 1.0)])
        d, _ = guard.distance(q)
        assert d == pytest.approx(brute, rel=1e-12, abs=1e-15)
        pruned, _ = guard.distance(q, within=2 * brute)
        assert pruned == pytest.approx(brute, rel=1e-12, abs=1e-15)


def test_a_run_whose_switches_give_no_branch_says_why_each_ended(monkeypatch):
    """The driver's note when no switch gives a branch: each try named with the reason
    it was handed back for (oracle: the mocked switch's two hand-made tries)."""
    from supercoil.problems.tweezers import compute

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24,
                           tension=20, turns=(0.0, 1.6))
    monkeypatch.setattr(compute, "closed_before", lambda branch, last: True)
    monkeypatch.setattr(compute, "held_contact", lambda *args, **kwargs: None)

    def switch(opts, rod, cp, last, *args, tried, **kwargs):
        for k, why in enumerate(("the corrector diverged", "back on its parent")):
            tried.append(dataclasses.replace(
                last, name=f"{last.name}/bifurcation9_try{k + 2}",
                status=ContinuationStatus.START_FAILED,
                message=f"the switch did not start: {why}"))

    from supercoil.continuation.resume import head

    original = compute.contact_branch

    def cut(*args, **kwargs):  # the contact branch closed before the last turn
        branch, pins = original(*args, **kwargs)
        return head(branch, 10), pins

    monkeypatch.setattr(compute, "contact_branch", cut)
    monkeypatch.setattr(compute, "switch_to_plectoneme", switch)
    result = compute.tweezers_branches(opts)
    said = [n for n in result.notes if n.startswith("switches tried from buckled_contact")]
    assert said == [("switches tried from buckled_contact: "
                     "buckled_contact/bifurcation9_try2: the switch did not start: the "
                     "corrector diverged; buckled_contact/bifurcation9_try3: the switch did "
                     "not start: back on its parent")]
    assert any(n.startswith("incomplete: buckled_contact closed") for n in result.notes)


@pytest.mark.parametrize("with_bifurcation", [False, True])
def test_a_closed_branch_without_a_bifurcation_says_so(monkeypatch, with_bifurcation):
    """The driver's note when the switch gives no branch names why: the branch has no
    bifurcation to switch at (its count changes all ``count_change``), or none of the
    switches at its bifurcations gave a branch (oracle: the special points handed over)."""
    from supercoil.continuation.resume import head
    from supercoil.problems.tweezers import compute

    opts = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24,
                           tension=20, turns=(0.0, 1.6))
    monkeypatch.setattr(compute, "closed_before", lambda branch, last: True)
    monkeypatch.setattr(compute, "held_contact", lambda *args, **kwargs: None)
    monkeypatch.setattr(compute, "switch_to_plectoneme", lambda *args, **kwargs: None)
    monkeypatch.setattr(compute, "verify_bifurcations", lambda branch, segment=None: branch)
    original = compute.contact_branch

    def cut(*args, **kwargs):
        branch, pins = original(*args, **kwargs)
        branch = head(branch, 10)
        kinds = [p.kind for p in branch.special_points]
        assert "bifurcation" not in kinds
        if with_bifurcation:
            point = dataclasses.replace(branch.special_points[0], kind="bifurcation",
                                        label="bifurcation", index=5)
            branch = dataclasses.replace(branch, special_points=(point,))
        return branch, pins

    monkeypatch.setattr(compute, "contact_branch", cut)
    result = compute.tweezers_branches(opts)
    [note] = [n for n in result.notes if n.startswith("incomplete: buckled_contact closed")]
    assert note.endswith("no switch at its bifurcations gave a branch" if with_bifurcation
                         else "it has no bifurcation to switch at (its count changes are "
                              "count_change)")
