"""Branches switched from the bifurcation points of a knotted ring's diagram.

As for the ring diagram (:mod:`supercoil.problems.ring_diagram.secondary`,
whose loop, switch and names this uses): at every ``bifurcation`` special
point of a branch of generation ``g < depth`` the half-branch on each side of
the critical mode is switched onto
(:func:`~supercoil.problems.ring_diagram.secondary.switch_half_branch`: its
amplitudes, and at a double eigenvalue the combination of the critical modes
that keeps a two-fold axis) and followed as the diagram's own branches are
(:func:`~supercoil.problems.knot_branch.follow_knot`: in runs with the rigid
pins re-picked, the first run's picked at the bifurcation point, every state
vetted by the knot guard), within the diagram's range of ``dLk``.

Unlike the ring diagram, the unlocated bifurcation points are switched from
too: on a knotted branch pressed together by the barrier, a change of the
unstable count within the barrier's reach of a contact event is not located
(the determinant's sign change is the event's), nor is one at which the
branch stopped, and a switch needs only the point's state and its critical
mode.

Families and names. ``knot_up`` and ``knot_down`` (in that order) are the
family ``knot``, a pair ``deflated_K_up``/``_down`` (``relaxed_K_...``) the
family ``deflated_K``; the bifurcation points of a family are numbered I, II,
... and the half-branch on side ``+`` of the k-th is ``knot_I+``,
``deflated_1_II-``; a tertiary branch from the j-th bifurcation point of
``knot_I+`` is ``knot_I+_<j>+``. ``parent`` is the branch the point lies on,
``origin`` the point.

Resuming: a stored complete half-branch is kept, an incomplete one with at
least two points continued from its last point within the run that computed it
(as :func:`~supercoil.problems.knot_branch.follow_knot` continues any branch),
one with fewer switched anew.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from supercoil.problems.knot_branch import follow_knot
from supercoil.problems.ring_diagram.secondary import (
    Switched,
    switch_half_branch,
    switched_branches,
)

PAIR = re.compile(r"^(.*)_(up|down)$")
# a switched branch runs along a computed one when at every point its writhe and energy
# are those of a computed segment at its dLk, linearly interpolated, to these (turns,
# relative): measured at Figure 5's parameters, a switch at the fold at dLk 4.596 ran
# back along the doubly covered circle to 3e-5 turns, and the energy interpolated on
# steps of up to 0.4 in dLk missed by up to 1.1 %; the branches that leave differ in
# writhe by more than 1.7e-3 turns somewhere
RETRACE_WRITHE, RETRACE_ENERGY = 1e-3, 2e-2
# or a computed point within this of its dLk (turns) agrees so: at a fold, the two
# computations' turning points differ in dLk by about 1e-6
RETRACE_LINK = 1e-3


def families(branches) -> list[tuple[str, list[str]]]:
    """``(stem, names)`` of the diagram's generation-1 families: ``knot_up``/``knot_down`` is
    ``knot``, ``deflated_K_up``/``_down`` is ``deflated_K`` (module doc)."""
    out: dict[str, list[str]] = {}
    for branch in branches:
        match = PAIR.match(branch.name)
        stem = match.group(1) if match else branch.name
        out.setdefault(stem, []).append(branch.name)
    return [(stem, sorted(names, key=lambda n: not n.endswith("_up")))
            for stem, names in out.items()]


def knot_switched(opts, cp, branches, stored: dict, say, on_point, on_branch,
                  pins) -> tuple[list[Switched], list[str]]:
    """The half-branches of generations 2 .. ``opts.branch_depth`` switched from the
    bifurcation points of ``branches``, located or not (module doc), and the notes. ``stored``:
    name -> ``(branch, complete)`` of an interrupted run; ``on_point(branch)`` after every
    accepted point, ``on_branch(branch)`` as each is final; ``pins``: the rod's
    ``(fixed, gauge_dofs)`` and the contact problem's ``fixed`` to restore after each."""
    rod = cp.base
    D = cp.diameter
    low, high = opts.excess_link

    def switch(parent, point, side, name):
        old, complete = stored.get(name, (None, False))
        if complete:
            say(f"{name}: kept ({len(old)} points)")
            return old

        def first(options, records, events, report, stop):
            return switch_half_branch(cp, parent, point, options, side, name, records,
                                      events[0], report, D, stop=stop)

        rod.fixed, rod.gauge_dofs, cp.fixed = pins
        branch = follow_knot(cp, point.q.copy(), float(point.parameter), high,
                             opts.secondary_max_points, opts.tolerance, name,
                             on_point=on_point,
                             old=old if old is not None and len(old) >= 2 else None,
                             first=first, bounds=(low, high))
        rod.fixed, rod.gauge_dofs, cp.fixed = pins
        if branch is None:
            return None
        return dataclasses.replace(branch, parent=parent.name, origin=point)

    return switched_branches(branches, families(branches), opts.branch_depth, switch, D,
                             max_branches=opts.secondary_max_branches, say=say,
                             on_branch=on_branch, located_only=False, retraced=retraced)


def retraced(branch, known) -> str | None:
    """A note when every point of ``branch`` is a state of the branches ``known`` at its
    ``dLk`` (its writhe and energy those of a segment of theirs there, linearly
    interpolated, to :data:`RETRACE_WRITHE` turns and :data:`RETRACE_ENERGY`
    relative, or one of their points within :data:`RETRACE_LINK` of it): the switch ran along a computed family (at a fold, whose critical mode
    is the branch's own tangent), else None."""
    others = [(b.name, np.asarray(b.parameter_values, float),
               np.asarray(b.records["energy"], float), np.asarray(b.records["writhe"], float))
              for b in known if b.name != branch.name and len(b.parameter_values) >= 2]
    along = set()
    for lam, energy, writhe in zip(branch.parameter_values, branch.records["energy"],
                                   branch.records["writhe"]):
        found = set()
        for name, x, e, w in others:
            lo, hi = np.minimum(x[:-1], x[1:]), np.maximum(x[:-1], x[1:])
            for j in np.flatnonzero((lo <= lam) & (lam <= hi)):
                t = 0.0 if x[j + 1] == x[j] else (lam - x[j]) / (x[j + 1] - x[j])
                if (abs((1 - t) * w[j] + t * w[j + 1] - writhe) <= RETRACE_WRITHE
                        and abs((1 - t) * e[j] + t * e[j + 1] - energy)
                        <= RETRACE_ENERGY * abs(energy)):
                    found.add(name)
            near = ((np.abs(x - lam) <= RETRACE_LINK) & (np.abs(w - writhe) <= RETRACE_WRITHE)
                    & (np.abs(e - energy) <= RETRACE_ENERGY * abs(energy)))
            if near.any():  # a point of theirs next to it (past their fold, say)
                found.add(name)
        if not found:
            return None
        along |= found
    return (f"{branch.name}: every point is a state of {', '.join(sorted(along))} at its dLk "
            "(the switch ran along a computed family): kept as computed, not switched from "
            "and not counted in by_excess_link")
