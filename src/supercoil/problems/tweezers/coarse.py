"""What a mesh too coarse for the loop's core does to the contact branch, said plainly.

The localised loop of a rod under the tension ``F``, and the end loop of the
plectoneme that grows from it, bend over the core length ``sqrt(A/F)``
(:mod:`supercoil.problems.greenhill`). On segments longer than ``SLIDING_CORE`` of
it (:attr:`~supercoil.problems.tweezers.options.TweezersOptions.mesh_pins_loop`) the
core spans a segment or two and the mesh pins it: the energy of the discrete end loop
depends on where the nodes sit in it, and the plectoneme grows by one node of each
strand at a time, across a pair of folds per node (docs/tweezers.md, "The plectoneme
on coarse meshes"). Measured at L/D = 100, ``lambda = L sqrt(F/A)`` = 80, N = 102
(segments 0.8 of the core): the torque of the ply rises from 90.8 to 94.5 and falls
back as each node enters, the turns going back by 0.3 across the period, and the
contact branch folded 415 times between 6.5 and 13.6 turns in 4000 points; at
``lambda`` = 150, N = 204 (0.74 of the core) 204 times between 20 and 41.4 turns;
on segments of 0.37-0.4 of the core (``lambda`` = 40, N = 102; 80, N = 204; 150 at
L/D = 200, N = 404) the contact branches reach the last turn in 863-2606 points.
:func:`pinned_loop_note` names that cause where such a branch ends before its last
turn. On segments up to ``RESOLVED_CORE`` (a third) of the core the end loop is resolved:
the pairs of folds end there (none at 0.33 and 0.27 of the core, lambda = 80), and the
unstable counts agree with a mesh 1.5 times finer away from the branch's events
(``benchmarks/grid_counts_refinement.py``); between a third and a half they may still
come (170 count changes at 0.4 of the core, L/D = 200, lambda = 80, N = 202), and
:func:`unresolved_loop_note` says so on every contact branch computed on such a mesh.
"""

from __future__ import annotations

import math

from supercoil.continuation import Branch
from supercoil.problems.tweezers.options import (
    RESOLVED_CORE,
    SLIDING_CORE,
    TweezersOptions,
    mesh_resolves_loop,
    resolved_nodes,
)


def resolving_nodes(options: TweezersOptions) -> int | None:
    """The fewest nodes whose segments are at most ``RESOLVED_CORE`` times the loop's core
    ``sqrt(A/F)`` (None without a tension)."""
    if not options.load_control or not options.tension:
        return None
    return resolved_nodes(options.tension)


def pinned_loop_note(options: TweezersOptions, branch: Branch) -> str | None:
    """A note for a contact ``branch`` that ended before the last turn on a mesh that pins
    the loop's core (module doc): the ratio of the segments to the core, the folds the
    branch went through and the turns they spanned, and the ``--nodes`` that resolve the
    core. None where the mesh resolves it or the branch reached the last turn."""
    if not options.mesh_pins_loop or not len(branch):
        return None
    turns = branch.parameter_values
    if turns[-1] >= options.turns[1] - 1e-9:
        return None
    k = math.sqrt(options.tension)
    folds = len(branch.points_of_kind("fold"))
    return (f"{branch.name}: the mesh pins the loop's core: its segments "
            f"({1 / (options.n_nodes - 2):.3g} L) are {options.core_segments:.2g} times "
            f"sqrt(A/F) = {1 / k:.3g} L (more than {SLIDING_CORE:g}), so the plectoneme grows "
            f"by a node of each strand at a time, across a pair of folds per node: "
            f"{folds} folds between {float(turns.min()):.4g} and {float(turns.max()):.4g} "
            f"turns in {len(branch)} points; --nodes >= {resolving_nodes(options)} resolve "
            f"the core")


def unresolved_loop_note(options: TweezersOptions, branch: Branch) -> str | None:
    """A note for a contact ``branch`` computed on segments longer than ``RESOLVED_CORE``
    of the loop's core (module doc): its growth may cross the mesh's pairs of folds, and
    its counts between them are the mesh's; the ``--nodes`` that resolve the core. None on
    a mesh that resolves it, without a tension or for an empty branch."""
    if not options.load_control or mesh_resolves_loop(options.tension, options.n_nodes) \
            or not len(branch):
        return None
    folds = len(branch.points_of_kind("fold"))
    return (f"{branch.name}: its segments are {options.core_segments:.2g} times the loop's "
            f"core sqrt(A/F) (more than {RESOLVED_CORE:.2g}): the plectoneme's end loop is "
            f"under-resolved, and its growth may cross a pair of folds of the discrete "
            f"contact per node of each strand, between which the unstable count is the "
            f"mesh's, not the rod's ({folds} folds on this branch); --nodes >= "
            f"{resolving_nodes(options)} resolve it")
