"""A step that lands beyond a fold on the fold's other sheet is taken again shorter.

Oracle: along a smooth branch the unstable count changes only at folds (by one) and at
bifurcations; a change of count with no fold and no bifurcation is a step that left the
branch for another sheet. The tweezers' contact branch of a rod with L/D = 100,
lambda = 80, C/A = 1.5 on N = 102 nodes (the quintic contact curve) passes within 0.03
turns of a fold at 12.028 turns after a fold at 12.188: a step of 5.2e-4 from 12.06 turns
used to land on the sheet beyond the fold (its count zero, the branch's one), and the
branch then followed that sheet down to the fold, back up, and onto its own path (a
located "count change" at 12.03 turns with no fold, and later a closed loop). The path
is that of the barrier's stiffness ``A/h^3`` (``contact_stiffness="bending"``): the load's
stiffer barrier (the default) moves the folds.
"""

from __future__ import annotations

import numpy as np

from supercoil.problems.greenhill import critical_turns
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches


def test_the_contact_branch_goes_through_the_fold_it_used_to_step_over():
    tension = 80.0**2
    options = TweezersOptions(twist_ratio=1.5, length_over_diameter=100, tension=tension,
                              n_nodes=102, contact_curve="quintic", max_points=360,
                              contact_stiffness="bending",
                              turns=(0.0, 1.5 * critical_turns(1.5, tension)))
    result = tweezers_branches(options)
    branch = next(b for b in result.branches if b.name in result.contact_branches)
    assert len(branch) == 360
    kinds = {p.kind for p in branch.special_points}
    assert "count_change" not in kinds
    # every change of the count lies on a step with a fold or a verified bifurcation
    events = {p.index for p in branch.special_points if p.kind in ("fold", "bifurcation")}
    counts = np.asarray(branch.unstable_count)
    changes = set(np.flatnonzero(np.diff(counts) != 0).tolist())
    assert changes <= events, sorted(changes - events)
    # the fold at 12.028 turns is passed and the branch goes on beyond the fold before it
    folds = [p.parameter for p in branch.special_points if p.kind == "fold"]
    assert any(abs(f - 12.028) < 2e-3 for f in folds), folds
    after = branch.parameter_values[next(p.index for p in branch.special_points
                                         if p.kind == "fold"
                                         and abs(p.parameter - 12.028) < 2e-3):]
    assert after.max() > 12.19
