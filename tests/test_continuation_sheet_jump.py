"""A step that changes the count with no fold, whose half step fails, is taken again shorter.

Oracle: along a smooth branch the unstable count changes only at folds (by one, where
the parameter's tangent component changes sign) and at bifurcations; a change of count
on a step with no fold and no branch point is a step that left the branch for another
sheet. The two stored points (``data/tweezers_sheet_jump.h5``) are points of the
tweezers' contact branch of a rod with L/D = 200, lambda = 150, C/A = 1 on N = 202 nodes,
at 32.92478 and 32.92432 turns, either side of a fold. The next step reaches 32.92518
turns (count zero, the turns rising), just before another fold at 32.92521 turns. From
there a step of 2.9e-5 lands at 32.92775 turns with the count one and the turns still
rising, on a closed curve of equilibria beside the branch, and its half step fails the
turn test. Kept, that step carries the branch round the curve (reported closed on
itself after 53 more points); refused and taken again shorter, it leaves the branch
turning back at the fold. Followed again from the second point in a new run (fresh
azimuth pins, as ``problems/tweezers/rejoin.py`` starts one), the branch turns there
too and goes on over 400 points.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import supercoil as sc
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.problems.contact_events import contact_count_event
from supercoil.problems.segments import RunRecords
from supercoil.problems.tweezers import TweezersOptions
from supercoil.problems.tweezers.buckled import resume_stored
from supercoil.problems.tweezers.contact import contact_options
from supercoil.problems.tweezers.problem import clamped_problem, tweezers_records

DATA = Path(__file__).parent / "data" / "tweezers_sheet_jump.h5"


def _continued(points: int):
    stored = sc.load(DATA)
    settings = dict(stored.settings["options"])
    settings["turns"] = tuple(settings["turns"])
    options = TweezersOptions(**settings)
    rod, _ = clamped_problem(options)
    cp = ContactProblem(rod, ContactOptions(diameter=options.diameter,
                                            curve=options.contact_curve,
                                            formulation=options.contact_formulation))
    old = stored.branches["buckled_contact"]
    records = RunRecords(tweezers_records(cp, rod, True))
    return resume_stored({old.name: (old, False)}, rod, cp, old.name,
                         contact_options(options), records, (contact_count_event(cp),),
                         sliding=False, max_points=len(old) + points)


def test_the_branch_goes_through_the_sharp_fold_instead_of_onto_the_closed_curve():
    branch = _continued(12)
    assert len(branch) == 14
    turns = branch.parameter_values
    t_turns = branch.tangents[:, -1]
    counts = np.asarray(branch.unstable_count)
    folds = np.flatnonzero(np.diff(np.sign(t_turns)) != 0)
    changes = np.flatnonzero(np.diff(counts) != 0)
    # every change of the count lies on a step with a fold
    assert set(changes.tolist()) <= set(folds.tolist()), (changes, folds)
    # the fold at 32.92521 turns is met: the turns go up from 32.9243, then down
    top = int(np.argmax(turns))
    assert 0 < top < len(turns) - 1
    assert abs(turns[top] - 32.92521) < 2e-5, turns[top]
    assert counts[top + 1] == 1 and turns[-1] < turns[top]
    # nothing of the closed curve's sheet: count one with the turns still rising
    assert not np.any((counts == 1) & (t_turns > 0) & (turns > 32.926))
