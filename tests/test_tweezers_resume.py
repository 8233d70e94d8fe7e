"""The tweezers resumed after an interrupt at any point end where the uninterrupted run ends.

Oracle: the uninterrupted run itself. Its branches are computed in runs of a few points
(``segment_points``), each starting afresh from the last point of the previous (its pins,
phase rows, step, stops); the run is stopped in ``on_point`` after point k of the
contact-free or the contact branch (as a signal would stop it after point k was
written), in the first run, at a junction and in later runs, then resumed from what it
had reported: every branch, its special points, last states, step controller's state
and pins must equal the uninterrupted run's to 1e-8.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_resume_every_point import assert_same_end

from supercoil.problems.tweezers.compute import tweezers_branches
from supercoil.problems.tweezers.options import TweezersOptions

SEGMENT = 8
OPTIONS = TweezersOptions(twist_ratio=4 / 3, length_over_diameter=20, n_nodes=24,
                          tension=20, turns=(0.0, 2.0), segment_points=SEGMENT)


def run(on_point=None, resume=None, stored=None):
    final = None if stored is None else (
        lambda branch, contact: stored.__setitem__(branch.name, (branch, True)))
    return tweezers_branches(OPTIONS, on_point=on_point, on_branch=final, resume=resume)


def interrupted_after(name: str, k: int) -> dict:
    """What a run stopped after point ``k`` of branch ``name`` had stored: the final
    branches complete, the one it was computing as far as it had reported it."""
    stored, partial = {}, {}

    def stop(branch):
        partial[branch.name] = branch
        if branch.name == name and len(branch) == k:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(stop, stored=stored)
    assert len(partial[name]) == k
    return stored | {name: (partial[name], False)}


@pytest.fixture(scope="module")
def full():
    result = run()
    lengths = {b.name: len(b) for b in result.branches}
    # the cases below cut the contact-free branch in both its runs and the contact
    # branch in its first three
    assert lengths["buckled"] > SEGMENT and lengths["buckled_contact"] > 3 * SEGMENT - 2
    return result


@pytest.mark.parametrize("name,k", [("buckled", 3), ("buckled", SEGMENT),
                                    ("buckled", SEGMENT + 3), ("buckled_contact", 5),
                                    ("buckled_contact", SEGMENT + 4),
                                    ("buckled_contact", 2 * SEGMENT - 1),
                                    ("buckled_contact", 2 * SEGMENT + 4)])
def test_tweezers_resumed_after_a_point_of_any_run_end_as_the_uninterrupted_run(full, name,
                                                                                  k):
    resumed = run(resume=interrupted_after(name, k))
    assert [b.name for b in resumed.branches] == [b.name for b in full.branches]
    for b, ref in zip(resumed.branches, full.branches):
        assert_same_end(b, ref, f"{name} {k}: {b.name}")
        np.testing.assert_array_equal(b.records["azimuth_pin"], ref.records["azimuth_pin"])
    assert resumed.pins == full.pins
    assert resumed.notes == full.notes


@pytest.mark.parametrize("limit", [12, 20])
def test_a_run_stopped_at_its_point_limit_continues_to_a_higher_one(full, tmp_path, limit):
    """``resume`` with a higher ``max_points``: the branch the stored run stopped at
    ``limit`` points (the contact-free one at 12, within a run; the contact branch at
    20) is continued, in runs as before, and the branches end as the uninterrupted
    run's; the file then records the new limit. A lower limit is refused."""
    import supercoil as sc
    from supercoil.continuation import ContinuationStatus

    problem = sc.Tweezers(sc.Rod(OPTIONS.twist_ratio, nodes=OPTIONS.n_nodes),
                          tension=OPTIONS.tension,
                          contact=sc.Barrier(OPTIONS.length_over_diameter))
    kwargs = {"segment_points": SEGMENT, "out": tmp_path}
    cut = sc.tweezers(problem, OPTIONS.turns, max_points=limit, **kwargs)
    assert any(b.status is ContinuationStatus.MAX_POINTS and len(b) == limit
               for b in cut.branches.values())
    with pytest.raises(sc.InputError, match="not lower it"):
        sc.tweezers(problem, OPTIONS.turns, max_points=limit - 1, resume=True, **kwargs)
    sc.tweezers(problem, OPTIONS.turns, max_points=OPTIONS.max_points, resume=True, **kwargs)
    stored = sc.load(tmp_path)
    assert stored.settings["options"]["max_points"] == OPTIONS.max_points
    assert stored.status == "complete"
    assert list(stored.branches) == [b.name for b in full.branches]
    for branch in full.branches:
        assert_same_end(stored.branches[branch.name], branch, branch.name)
