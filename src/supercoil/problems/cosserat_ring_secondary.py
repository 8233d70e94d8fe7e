"""Secondary and tertiary branches of the Cosserat ring's diagram.

As for the Kirchhoff ring (:mod:`supercoil.problems.ring_diagram.secondary`, whose loop
over the families' bifurcation points, names, fall-back test and options are used
here): at every located bifurcation point of a primary family (``beta`` and
``beta_contact``) the bifurcating branch is switched to along the critical mode, on
each side, and followed with self-contact; with ``branch_depth`` 3 the same again from
the bifurcation points of those. The switch, the run and the contact are the Cosserat
ring's (:class:`~supercoil.contact.problem.ContactProblem` over
:class:`~supercoil.cosserat.closed.ClosedCosseratEnergy`, in its unknowns, from the
frames the special point was located with); the symmetry tests (the two-fold axis a
direction keeps, a pitchfork's mirror image, a half-branch that fell back onto its
parent's family) read the centreline: the positions of the states and of the critical
modes. Every state keeps the ring's link, ``Lk = Tw + Wr`` with the twist of the ribbon
of ``d1`` (:mod:`supercoil.cosserat.closed`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation import Branch, SpecialPoint, switch_branch
from supercoil.cosserat.rod import DOFS_PER_NODE
from supercoil.geometry.symmetry import axis_invariant_combination, reversal_axes
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.ring_branches import PRIMARY_NAMES
from supercoil.problems.ring_diagram.records import contact_records
from supercoil.problems.ring_diagram.secondary import (
    AMPLITUDES,
    SYMMETRY_TOLERANCE,
    Switched,
    _options,
    switched_branches,
)


def _positions(a: np.ndarray) -> np.ndarray:
    """The position rows of vectors in the Cosserat unknowns, ``(..., 3 N)``."""
    a = np.asarray(a, dtype=float)
    return a.reshape(a.shape[:-1] + (-1, DOFS_PER_NODE))[..., :3].reshape(
        a.shape[:-1] + (-1,))


def switch_direction(point: SpecialPoint, diameter: float, mass: np.ndarray
                     ) -> np.ndarray | None:
    """For a bifurcation point with several critical modes, the combination of them (in
    the unknowns) whose centreline part keeps a two-fold axis of the point's centreline
    (as :func:`supercoil.problems.ring_diagram.secondary.switch_direction`, ``mass``
    per node); None for a simple eigenvalue or a state without such an axis."""
    modes = np.asarray(point.critical_modes, dtype=float)
    if modes.ndim != 2 or modes.shape[0] < 2:
        return None
    x = _positions(point.q).reshape(-1, 3)
    axes = reversal_axes(x, SYMMETRY_TOLERANCE * diameter)
    if not axes:
        return None
    n = x.shape[0]
    c = min(axes, key=lambda axis: min(axis[0] % n, n - axis[0] % n))[0]
    fields = _positions(modes).reshape(modes.shape[0], n, 3)
    a = axis_invariant_combination(x, c, fields, mass)
    return a @ modes


class _Views:
    """The branches in the unknowns and their centreline views (states and special
    points' states and modes restricted to the positions), which the shared loop reads."""

    def __init__(self):
        self.full: dict[str, Branch] = {}
        self.points: dict[int, SpecialPoint] = {}

    def view(self, branch: Branch) -> Branch:
        self.full[branch.name] = branch
        specials = []
        for p in branch.special_points:
            v = dataclasses.replace(p, q=_positions(p.q),
                                    critical_modes=_positions(p.critical_modes)
                                    if np.size(p.critical_modes) else p.critical_modes)
            self.points[id(v)] = p
            specials.append(v)
        k = len(branch)
        states = _positions(branch.states) if k else branch.states
        return dataclasses.replace(branch, states=states, special_points=tuple(specials))


def cosserat_secondary_branches(cp, branches: list[Branch], opts, records, *, notes=(),
                                say=None, on_point=None, on_branch=None
                                ) -> tuple[list[Switched], list[str]]:
    """The half-branches of generations 2 .. ``opts.branch_depth`` switched from the
    bifurcation points of the primary families among ``branches`` (in the unknowns),
    with the contact problem ``cp``; ``records`` the ring's own per-point records.
    Returns them (:class:`~supercoil.problems.ring_diagram.secondary.Switched`, their
    branches in the unknowns) and the notes. ``on_point`` sees each half-branch's
    points, ``on_branch`` each final half-branch (in the unknowns)."""
    diameter = opts.diameter
    base = _options(opts, opts.secondary_max_points)
    own = contact_records(cp, records, free=False)
    event = contact_count_event(cp)
    mass = np.asarray(cp.mass, dtype=float).reshape(-1, DOFS_PER_NODE)[:, 0]
    views = _Views()

    def switch(parent_view: Branch, point_view: SpecialPoint, side: int, name: str):
        parent = views.full[parent_view.name]
        point = views.points[id(point_view)]
        direction = switch_direction(point, diameter, mass)
        for amplitude in AMPLITUDES:
            options = dataclasses.replace(base, initial_step=min(amplitude * diameter,
                                                                 base.max_step))
            branch = switch_branch(cp, parent, point, options, side=side,
                                   amplitude=amplitude * diameter, name=name, records=own,
                                   events=(event,), on_point=on_point, direction=direction)
            if len(branch) >= 2:
                branch = classify_contact_events(branch, cp)
                return views.view(dataclasses.replace(branch, parent=parent.name,
                                                      origin=point))
        return None

    families = [(stem, [stem, f"{stem}_contact"]) for stem in
                (PRIMARY_NAMES.get(mode, f"mode{mode}") for mode in opts.modes)]
    known = [views.view(b) for b in branches]
    added, notes = switched_branches(
        known, families, opts.branch_depth, switch, diameter,
        max_branches=opts.secondary_max_branches, notes=notes, say=say,
        on_branch=None if on_branch is None else (lambda v: on_branch(views.full[v.name])))
    return [dataclasses.replace(a, branch=views.full[a.branch.name]) for a in added], notes
