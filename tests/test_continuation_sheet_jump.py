"""A step that changes the count with no fold, whose half step fails, is taken again shorter
(and after all where every shorter step fails).

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
    # the count of every eigenvalue, the sliding's too: the one the oracle is exact for
    # (the tool's contact branches leave the sliding out while the tails are straight,
    # an approximate count whose change here lags the fold by two points)
    rod.sliding_tail = None
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


def test_a_refused_step_is_taken_where_every_shorter_one_fails(monkeypatch):
    """The trivial branch x = 0 of ``E = sum (d_i - lambda) x_i^2 / 2 + |x|^4 / 4``
    crosses the pitchfork at lambda = d_0 = 1 exactly, its count going from 0 to 1 with
    no fold. Every step from a start at lambda >= 0.8 that ends at lambda <= 1 is made
    to fail (as steps ending close to a bifurcation can): the step across lambda = 1 is
    refused, its half failing, and every shorter one fails down to the minimum step.
    Taken after all, it carries the branch through the bifurcation (located at 1) to
    the bound; refused for good, the branch would stop there."""
    from test_continuation_toys import DiagonalQuartic

    from supercoil.continuation import ContinuationOptions, ContinuationStatus, continuation
    from supercoil.continuation import tracer as module

    real = module.take_step

    def failing_near(system, opts, x_k, *args):
        taken = real(system, opts, x_k, *args)
        if taken.failure is None and x_k[-1] >= 0.8 and x_k[-1] < taken.x[-1] <= 1.0:
            taken.failure, taken.x, taken.t = "made to fail", None, None
        return taken

    monkeypatch.setattr(module, "take_step", failing_near)
    problem = DiagonalQuartic(np.array([1.0, 2.0, 3.5]), lam=0.5)
    options = ContinuationOptions(initial_step=0.05, max_step=0.15, min_step=1e-4,
                                  parameter_bounds=(0.5, 1.5), max_points=60)
    branch = continuation(problem, np.zeros(3), parameter="lam", options=options)
    assert branch.status is ContinuationStatus.PARAMETER_BOUND, branch.message
    lam = branch.parameter_values
    k = int(np.flatnonzero(lam > 1.0)[0])
    assert 0.8 <= lam[k - 1] < 1.0 < lam[k] <= lam[k - 1] + 0.15 + 1e-12
    assert list(branch.unstable_count[k - 1:k + 1]) == [0, 1]
    crossing = [p for p in branch.special_points if p.kind == "bifurcation"]
    assert len(crossing) == 1 and abs(crossing[0].parameter - 1.0) < 1e-8
