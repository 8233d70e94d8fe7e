"""The contact branch held on its half-turn symmetry, where the one followed freely closed
or stopped.

From a centred localised loop (``loop_sliding``) the first contact lies at the loop's
crossing, on the axis of the half-turn across the rod's middle that maps the rod onto
itself (:mod:`supercoil.rod.mirror`), and the plectoneme grows from that crossing with
its ply along the axis, the two strands exchanged: the branch is symmetric. Along it
the sliding of the structure (odd under the half-turn) has the discrete contact's
ripple as its eigenvalue, of either sign (docs/continuation.md, "Long open rods"), and
every sign change is a pitchfork of the discrete problem, whose asymmetric branches,
the structure slid by a fraction of a segment, are the mesh's. Followed without a
phase row in contact, the branch leaves the symmetric family at one of them, folds where
the slid structure's sliding eigenvalue crosses zero, and closes a loop (measured at
C/A = 1.5: at L/D = 500, lambda = 10, N = 502 the symmetric branch is left at 1.82
turns, its single contact at the crossing with the force growing, and closes on itself
at 1.883 turns; at L/D = 200, lambda = 20, N = 404 it is left at 2.9 turns with a ply of
11 contact pairs, goes to 3.06 turns slid by 0.04 D, comes back onto the symmetric
branch at 2.86 turns and follows it down onto the contact-free branch at 1.165 turns).
No bifurcation is located on either (the sliding is left out of the count while the
tails are straight), so no switch gives a branch. Where the loop's crossing is off the
rod's middle by round-off, the turns drive the sliding, which the contact branch leaves
out of the count but carries no phase row for; softer than any counted mode by 4-5
decades, it sets the tangent by round-off, and the free branch stops a few points into
its contact at the minimum step, its tangent turning by tens of degrees (measured on the
3 kbp DNA at 0.25 pN / 200 mM, 1 pN / 200 mM and 0.5 pN / 150 mM:
``benchmarks/results/long_dna_grid.md``, "DNA preset").

:func:`mirrored_contact` follows the contact branch again from the same start on the
symmetric family: the corrector projects its start, every iterate, Newton step and
tangent onto the symmetric states (``ClampedRodEnergy.mirror_hold``,
:meth:`~supercoil.rod.open.ClampedRodEnergy.held_part`; the energy is invariant, so on
the family the gradient is even and the modes odd under the half-turn drop out of the
steps). The sliding's phase row is carried in contact too, anchored at each step at the
state's symmetric part (:func:`~supercoil.rod.mirror.mirror_offset`); on the family it
holds no force (the record ``sliding_residual``, the KKT residual without the row, shows
it). It is followed while the sliding is left out of the count (tail ratio below
``SLIDING_TAIL_CONTACT``); beyond, without the row, as the contact branch is.

Held by the row alone, without the projection, the branch stopped where an odd mode of
the Jacobian with the row went soft: on the 3 kbp DNA at 0.25 pN / 50 mM (N = 148), the
odd block restricted to the complement of the sliding had its eigenvalue fall from 1e4
to 4 at 5.334 turns (the mode at the plectoneme's end loop, overlap 0.15 with the
sliding), the corrector converged linearly from 5.0 turns, and round-off moved the state
off the symmetry by 1.3e-3 D. The full constrained Hessian has no eigenvalue crossing
there (its lowest, the stiff sliding's, stays near -7.5e4: no bifurcation); projected,
the branch passes and reaches sigma 0.06 (648 points).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch, ContinuationStatus, SpecialPoint
from supercoil.problems.contact_events import contact_start
from supercoil.problems.tweezers.contact import MIRROR_TOLERANCE, contact_branch
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.returned import close_on_return
from supercoil.problems.tweezers.verify import verify_bifurcations
from supercoil.rod.mirror import mirror_asymmetry
from supercoil.rod.open import ClampedRodEnergy

SUFFIX = "/mirrored"


def symmetric_start(free: Branch, onset: SpecialPoint, cp: ContactProblem,
                    diameter: float) -> bool:
    """Whether the contact branch from ``free`` past ``onset`` starts from a state
    symmetric under the half-turn (to ``MIRROR_TOLERANCE`` D)."""
    q = free.states[contact_start(free, onset, cp)]
    return mirror_asymmetry(q) <= MIRROR_TOLERANCE * diameter


def mirrored_contact(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
                     free: Branch, onset: SpecialPoint, name: str,
                     stored: Mapping[str, tuple[Branch, bool]], on_point=None, pinned=None,
                     say: Callable[[str], None] = lambda message: None
                     ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]] | None:
    """The contact branch ``name + SUFFIX`` held on its symmetry (module doc) and its
    azimuth pins; None where ``loop_sliding`` does not apply in contact
    (``loop_slides_in_contact``: off, or a mesh that pins the loop's core, where the row
    would hold the mesh's force) or from an asymmetric start."""
    if not opts.loop_slides_in_contact or not symmetric_start(free, onset, cp, opts.diameter):
        return None
    say(f"{name}{SUFFIX}: the contact branch again, held on its half-turn symmetry")
    return contact_branch(opts, rod, cp, free, onset, name + SUFFIX, stored, on_point,
                          pinned, say, hold=True)


def closed_before(branch: Branch, last_turn: float) -> bool:
    """Whether ``branch`` closed a loop before ``last_turn`` turns."""
    return (branch.status is ContinuationStatus.CLOSED_LOOP
            and branch.parameter_values[-1] < last_turn - 1e-9)


def held_contact(opts: TweezersOptions, rod: ClampedRodEnergy, cp: ContactProblem,
                 free: Branch, onset: SpecialPoint, name: str,
                 stored: Mapping[str, tuple[Branch, bool]], on_point=None, pinned=None,
                 say: Callable[[str], None] = lambda message: None, reach: float = 1.0
                 ) -> tuple[Branch, tuple[tuple[int, tuple[int, ...]], ...]] | None:
    """:func:`mirrored_contact` as the driver takes it where the free contact branch
    ``name`` closed or stopped: closed where it comes back onto ``free`` (within
    ``reach`` D, :func:`~supercoil.problems.tweezers.returned.close_on_return`), its
    bifurcations verified, branched off ``free`` at ``onset``; None where no symmetric
    start is held."""
    held = mirrored_contact(opts, rod, cp, free, onset, name, stored, on_point, pinned, say)
    if held is None:
        return None
    branch = close_on_return(held[0], free, opts.diameter, reach)
    branch = verify_bifurcations(dataclasses.replace(branch, parent=free.name, origin=onset),
                                 opts.segment)
    return branch, held[1]
