"""Secondary and tertiary branches of the ring diagram (Coleman & Swigon 2002, Figures 2, 3).

Coleman & Swigon follow, beside the primary branch beta, the *secondary*
branches beta_I ... beta_IV that bifurcate from it and a *tertiary* branch beta*_II
that bifurcates from beta_II; configurations on the secondary branches have
a single two-fold axis (C_2), the tertiary one none. :func:`secondary_branches`
does this for a computed :class:`~supercoil.problems.ring_diagram.RingDiagram`:
at every located ``bifurcation`` special point of a branch of generation
``g < depth`` (the primary branches, with and without contact, are generation
1; the circle's own bifurcations are the primary branches themselves), it
switches onto the bifurcating branch along the critical mode
(:func:`~supercoil.continuation.switch_branch`), on each side of it, and
follows that half-branch with self-contact (the contact problem of the
diagram: its barrier is inactive, and the equilibria those of the rod alone,
while no pair is within its reach) with the contact branches' options.

Names. The bifurcation points of one primary family (``beta`` and
``beta_contact``, in that order along the branch) are numbered I, II, ...;
the half-branch on side ``+`` of the k-th is ``beta_<k>+`` (``beta_I+``,
``beta_II-``), and a tertiary branch from the j-th bifurcation point of
``beta_II-`` is ``beta_II-_<j>+``. ``parent`` is the branch the bifurcation
point lies on and ``origin`` that point.

A half-branch whose start fails at every amplitude in ``AMPLITUDES`` (times
D) is not kept; a note says so (at a bifurcation point inside a contact the
predictor along one side of the critical mode can push a pair into contact at
once, which collision detection refuses). The switch starts on the hyperplane
orthogonal to the parent's tangent, so it cannot fall back at its first point,
but it can run back onto the parent's family later: after a switch at a
double eigenvalue (a symmetry-breaking bifurcation), a half-branch that keeps
the parent's symmetry at every point (:func:`fell_back`) is noted as such and
not switched from again. At a double eigenvalue the switch goes along the
combination of the critical modes that keeps a two-fold axis
(:func:`switch_direction`). At a pitchfork of a state with an exact mesh axis
(its single critical mode odd under the axis, :func:`mirror_axis`: Coleman &
Swigon's S on beta_II) only the ``+`` half-branch is computed: the ``-`` half is
its mirror image, and a note says so. The per-point symmetry
(:meth:`~supercoil.problems.ring_diagram.RingDiagram.points`, ``symmetry``)
tells the branches apart once they have left the bifurcation point by more than
the symmetry tolerance (0.05 D): closer to it a secondary point still carries
its parent's label.

``supercoil run --resume`` continues the primary branches of an interrupted
study; its secondary branches are computed again.

The loop over the families' bifurcation points, their sides and generations
(:func:`switched_branches`) and the switch with its amplitudes
(:func:`switch_half_branch`) are shared with the knotted ring's diagram
(:mod:`supercoil.problems.knot_switching`), which follows each half-branch its own
way.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import numpy as np

from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint, switch_branch
from supercoil.geometry.symmetry import (
    axis_invariant_combination,
    curve_symmetry,
    reversal_axes,
    reversal_image,
    reversal_residuals,
)
from supercoil.problems.branch_options import CONTACT_MIN_STEP
from supercoil.problems.contact_events import classify_contact_events, contact_count_event
from supercoil.problems.ring_branches import PRIMARY_NAMES, ring_records
from supercoil.problems.ring_diagram.records import contact_records

AMPLITUDES = (0.05, 0.01, 0.002, 0.2, 0.5)  # first step off the bifurcation point, units of D
MAX_DEPTH = 3  # generations: 1 primary, 2 secondary, 3 tertiary
# a map of the centreline is a symmetry when its RMS misfit is below this fraction of D
# (Coleman & Swigon's symmetry classes; the polygon contact's ripple breaks them at about
# 1e-2 D)
SYMMETRY_TOLERANCE = 0.05


def roman(k: int) -> str:
    """1 -> I, 4 -> IV, 12 -> XII (k >= 1)."""
    if k < 1:
        raise ValueError(f"roman numerals start at 1, got {k}")
    out = []
    for value, letters in ((1000, "M"), (900, "CM"), (500, "D"), (400, "CD"), (100, "C"),
                           (90, "XC"), (50, "L"), (40, "XL"), (10, "X"), (9, "IX"),
                           (5, "V"), (4, "IV"), (1, "I")):
        while k >= value:
            out.append(letters)
            k -= value
    return "".join(out)


def family_bifurcations(branches: list[Branch], family: list[str],
                        located_only: bool = True) -> list[SpecialPoint]:
    """The located bifurcation points of the branches named in ``family``, in order (with
    ``located_only`` False, the unlocated ones too)."""
    out = []
    by_name = {b.name: b for b in branches}
    for name in family:
        branch = by_name.get(name)
        if branch is None:
            continue
        out += [p for p in branch.special_points if p.kind == "bifurcation"
                and (p.located or not located_only)]
    return out


def secondary_branches(diagram, depth: int = 2, *, max_points: int = 60,
                       max_branches: int = 16,
                       progress: Callable[[str], None] | None = None,
                       on_point: Callable[[Branch], None] | None = None,
                       on_branch: Callable[[Branch, bool], None] | None = None):
    """``diagram`` with the branches of generations 2 .. ``depth`` added (module doc).

    ``depth`` 2 adds the secondary branches, 3 the tertiary ones too (1 adds
    nothing). ``max_points`` bounds each half-branch, ``max_branches`` the
    number of half-branches added. ``on_point`` / ``on_branch`` as in
    :func:`~supercoil.problems.ring_diagram.ring_diagram` (every new branch is a
    contact branch). Returns a new ``RingDiagram``.
    """
    if not 1 <= depth <= MAX_DEPTH:
        raise ValueError(f"depth must be 1 (primary only), 2 (secondary) or 3 (tertiary), "
                         f"got {depth!r}")
    if max_points < 2 or max_branches < 0:
        raise ValueError("max_points must be >= 2 and max_branches >= 0")
    say = progress or (lambda message: None)
    final = on_branch or (lambda branch, contact: None)
    opts = diagram.options
    cp = diagram.contact_problem
    if depth == 1 or cp is None:
        return diagram
    D = opts.diameter
    base = _options(opts, max_points)
    records = contact_records(cp, ring_records(cp.base), free=False)
    event = contact_count_event(cp)

    def switch(parent, point, side, name):
        branch = switch_half_branch(cp, parent, point, base, side, name, records, event,
                                    on_point, D)
        if branch is None:
            return None
        branch = classify_contact_events(branch, cp)
        return dataclasses.replace(branch, parent=parent.name, origin=point)

    families = [(stem, [stem, f"{stem}_contact"]) for stem in
                (PRIMARY_NAMES.get(mode, f"mode{mode}") for mode in opts.modes)]
    added, notes = switched_branches(diagram.branches, families, depth, switch, D,
                                     max_branches=max_branches, notes=diagram.notes,
                                     say=say, on_branch=lambda b: final(b, True))
    return dataclasses.replace(
        diagram, branches=diagram.branches + tuple(a.branch for a in added),
        contact_branches=frozenset(diagram.contact_branches) | {a.branch.name for a in added},
        generations=dict(diagram.generations) | {a.branch.name: a.generation for a in added},
        seconds=dict(diagram.seconds) | {a.branch.name: a.seconds for a in added},
        notes=tuple(notes))


@dataclasses.dataclass(frozen=True)
class Switched:
    """A half-branch switched from a bifurcation point: its generation, its seconds, and
    whether it fell back onto a computed family."""

    branch: Branch
    generation: int
    seconds: float
    fell_back: bool = False


def switched_branches(branches, families, depth: int, switch, diameter: float, *,
                      max_branches: int, notes=(), say=None, on_branch=None,
                      located_only: bool = True, retraced=None
                      ) -> tuple[list[Switched], list[str]]:
    """The half-branches of generations 2 .. ``depth`` switched from the located
    bifurcation points of ``families`` (module doc; the loop that the ring diagram's
    and the knotted-ring diagram's switching share), and the notes (``notes`` and
    those added).

    ``families``: ``(stem, names)`` pairs, the branches of ``branches`` named in
    ``names`` forming one family whose bifurcation points are numbered I, II, ...
    in that order. ``switch(parent, point, side, name)``: the half-branch on ``side``
    (+1 / -1), final (contact events classified, ``parent`` and ``origin`` set), or
    None when it found no point. ``on_branch(branch)`` as each is final. A
    half-branch that did not fall back is the family of the next generation.
    ``located_only`` False: the unlocated bifurcation points are switched from too.
    ``retraced(branch, known)``: a note when ``branch`` runs along the computed branches
    ``known`` (then treated as fallen back), else None."""
    say = say or (lambda message: None)
    notes = list(notes)
    known = list(branches)
    added: list[Switched] = []
    for generation in range(2, depth + 1):
        next_families = []
        for stem, family in families:
            for k, point in enumerate(family_bifurcations(known, family, located_only),
                                      start=1):
                parent = next(b for b in known if b.name == point.branch)
                mirrored = mirror_axis(point)
                for side, sign in ((1, "+"), (-1, "-")):
                    if side == -1 and mirrored is not None:
                        notes.append(f"{stem}_{roman(k)}-: not computed, the mirror image of "
                                     f"{stem}_{roman(k)}+ under the two-fold axis c = "
                                     f"{mirrored:g} of {parent.name} at dLk = "
                                     f"{point.parameter:.5g} (the critical mode is odd "
                                     "under it: a pitchfork)")
                        continue
                    if len(added) >= max_branches:
                        notes.append(f"secondary branches: stopped at max_branches = "
                                     f"{max_branches}")
                        return added, notes
                    name = f"{stem}_{roman(k)}{sign}"
                    say(f"{name}: switched from {parent.name} at dLk = "
                        f"{point.parameter:.4g}, side {sign}")
                    start = time.perf_counter()
                    branch = switch(parent, point, side, name)
                    if branch is None:
                        notes.append(f"{name}: the switch from {parent.name} at dLk = "
                                     f"{point.parameter:.5g} found no point on side {sign} "
                                     f"(amplitudes {', '.join(f'{a:g}' for a in AMPLITUDES)} D)")
                        continue
                    back = fell_back(branch, point, diameter)
                    if back:
                        notes.append(f"{name}: the switch from {parent.name} at dLk = "
                                     f"{point.parameter:.5g} on side {sign} kept the "
                                     f"symmetry of {parent.name} at every point: it fell "
                                     "back onto that family (kept as computed, not "
                                     "switched from)")
                    elif retraced is not None:
                        note = retraced(branch, known)
                        if note:
                            notes.append(note)
                            back = True
                    if on_branch is not None:
                        on_branch(branch)
                    added.append(Switched(branch, generation, time.perf_counter() - start,
                                          back))
                    known.append(branch)
                    if not back:
                        next_families.append((name, [name]))
        families = next_families
    return added, notes


def _options(opts, max_points: int) -> ContinuationOptions:
    """The continuation options of a half-branch: the diagram's contact branches'."""
    D = opts.diameter
    return ContinuationOptions(
        min_step=CONTACT_MIN_STEP, max_step=opts.contact_max_step * D, max_points=max_points,
        parameter_bounds=(0.0, opts.max_excess_link), parameter_weight=D,
        tolerance=opts.contact_tolerance, near_symmetry_gauge=opts.contact_gauge,
        gauge=opts.gauge, rephase=opts.gauge == "integral",
        regauge=True, event_tolerance=opts.contact_event_tolerance,
        initial_step=AMPLITUDES[0] * D, predictor=opts.contact_predictor)


def follow_bifurcating_branch(diagram, parent: Branch, point: SpecialPoint, side: int, *,
                              max_points: int = 60, name: str | None = None
                              ) -> Branch | None:
    """The half-branch switched from the bifurcation ``point`` of ``parent`` on ``side``
    (+1 / -1) and followed with self-contact, as :func:`secondary_branches` does for
    every bifurcation point (same options, switch direction and amplitudes), with its
    contact events classified; None when no amplitude gives a first point. For
    following one chosen branch (a tertiary one, say) without all the others."""
    cp = diagram.contact_problem
    if cp is None:
        raise ValueError("the diagram has no contact problem (no contact branch was computed)")
    if side not in (1, -1):
        raise ValueError(f"side must be +1 or -1, got {side!r}")
    D = diagram.options.diameter
    label = name or f"{parent.name}/{point.kind}{point.index}{'+' if side > 0 else '-'}"
    records = contact_records(cp, ring_records(cp.base), free=False)
    branch = switch_half_branch(cp, parent, point, _options(diagram.options, max_points), side,
                                label, records, contact_count_event(cp), None, D)
    if branch is None:
        return None
    branch = classify_contact_events(branch, cp)
    return dataclasses.replace(branch, parent=parent.name, origin=point)


def fell_back(branch: Branch, point: SpecialPoint, diameter: float) -> bool:
    """True when ``branch``, switched at a multiple eigenvalue (several critical
    modes: a symmetry-breaking bifurcation), keeps the symmetry group of the state at
    ``point`` (or the circle's, which contains it) at every one of its points: it is
    the parent's family, not a new branch
    (measured at L/D 122, N = 132: one side of B_1 ran back along beta without
    contact to the circle, D_3 at every point, with beta's count)."""
    if np.asarray(point.critical_modes).shape[0] < 2:
        return False
    tolerance = SYMMETRY_TOLERANCE * diameter
    group = curve_symmetry(np.asarray(point.q).reshape(-1, 3), tolerance).group
    return all(curve_symmetry(q.reshape(-1, 3), tolerance).group in (group, "O(2)")
               for q in branch.states)


# a state and a mode are symmetric / odd under a mesh axis when their misfit is below
# this fraction of their size: along a branch the misfit is round-off (about 1e-11), at
# a located pitchfork the nearly singular odd mode amplifies it (measured up to 3e-7
# of the size, and 2e-6 for the mode; a mode of the other parity misfits by 2)
EXACT_SYMMETRY = 1e-5


def mirror_axis(point: SpecialPoint) -> int | None:
    """The two-fold axis ``c`` (an integer: through a node or an edge midpoint, an exact
    symmetry of the discrete ring) under which the state at ``point`` is symmetric and
    its single critical mode odd, or None.

    There the bifurcation is a pitchfork that breaks the axis, and the two
    half-branches are each other's images under it (the discrete problem, the pins and
    the phase condition included, is equivariant: rod.closed.rigid_pins), so one of
    them is enough (tests/test_ring_secondary.py computes both and compares)."""
    modes = np.asarray(point.critical_modes, dtype=float)
    if modes.ndim != 2 or modes.shape[0] != 1:
        return None
    x = np.asarray(point.q, dtype=float).reshape(-1, 3)
    n = x.shape[0]
    v = modes[0].reshape(1, n, 3)
    size = float(np.sqrt(np.mean(np.sum((x - x.mean(axis=0)) ** 2, axis=1))))
    misfits = reversal_residuals(x, np.arange(n, dtype=float), direct=True)
    for c in np.flatnonzero(misfits <= EXACT_SYMMETRY * size):
        image = reversal_image(x, float(c), v)
        if np.max(np.abs(image + v)) <= EXACT_SYMMETRY * np.max(np.abs(v)):
            return int(c)
    return None


def switch_direction(cp, point: SpecialPoint, diameter: float) -> np.ndarray | None:
    """For a bifurcation point with several critical modes (a double eigenvalue of a
    symmetric state: an E mode of D_m), the combination of them that keeps a two-fold
    axis of the state (:func:`~supercoil.geometry.symmetry.axis_invariant_combination`),
    a full DOF vector; None for a simple eigenvalue or a state without such an axis
    (the first critical mode is then used). Any other direction in the plane of an E
    mode breaks every two-fold axis, and the switch from it fell back (measured at
    L/D 122, N 204: beta_I+ continued as a D_3 branch with beta's count)."""
    modes = np.asarray(point.critical_modes, dtype=float)
    if modes.shape[0] < 2:
        return None
    x = np.asarray(point.q, dtype=float).reshape(-1, 3)
    axes = reversal_axes(x, SYMMETRY_TOLERANCE * diameter)
    if not axes:
        return None
    mass = np.asarray(cp.mass, dtype=float).reshape(-1, 3)[:, 0]
    fields = modes.reshape(modes.shape[0], -1, 3)
    # the axis through node 0 (c = 0 mod n) when there is one: the rigid pins keep that
    # axis an exact symmetry of the discrete problem (rod.closed.rigid_pins)
    n = x.shape[0]
    c = min(axes, key=lambda axis: min(axis[0] % n, n - axis[0] % n))[0]
    a = axis_invariant_combination(x, c, fields, mass)
    return (a @ modes.reshape(modes.shape[0], -1)).ravel()


def switch_half_branch(cp, parent: Branch, point: SpecialPoint, base: ContinuationOptions,
                       side: int, name: str, records, event, on_point, D: float,
                       stop=None) -> Branch | None:
    """The half-branch on ``side`` (the first amplitude whose start succeeds), or None.
    ``stop`` as in :func:`~supercoil.continuation.switch_branch`."""
    direction = switch_direction(cp, point, D)
    for amplitude in AMPLITUDES:
        opts = dataclasses.replace(base, initial_step=min(amplitude * D, base.max_step))
        branch = switch_branch(cp, parent, point, opts, side=side, amplitude=amplitude * D,
                               name=name, records=records, events=(event,),
                               on_point=on_point, direction=direction, stop=stop)
        if len(branch) >= 2:
            return branch
    return None
