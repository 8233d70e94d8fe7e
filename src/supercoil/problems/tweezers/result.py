"""The computed tweezers' branches (:class:`TweezersResult`) and their azimuth pins."""

from __future__ import annotations

from dataclasses import dataclass, field

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import Branch
from supercoil.problems.branch_set import BranchSet
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ply import HardCorePly, hard_core_ply
from supercoil.problems.tweezers.contact import SLIDING_TAIL_CONTACT
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.pins import hold_azimuth
from supercoil.rod.open import ClampedRodEnergy
from supercoil.rod.sliding import sliding_threshold


@dataclass(frozen=True)
class TweezersResult(BranchSet):
    """Computed branches (in order), the problems to re-evaluate their states, notes."""

    options: TweezersOptions
    branches: tuple[Branch, ...]
    contact_branches: frozenset[str]
    rod_problem: ClampedRodEnergy
    contact_problem: ContactProblem | None
    seconds: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    # per branch: (first point index, pinned DOFs) at each choice of the azimuth pin
    pins: dict = field(default_factory=dict)
    # contact-free branches cut at their first contact: complete whatever the run that
    # went on beyond the contact (penetrating) ended with
    cut_at_contact: frozenset[str] = frozenset()
    # contact branches that stopped before the last turn and were followed again held on
    # their half-turn symmetry (mirrored.py): the held branch's end decides
    held_instead: frozenset[str] = frozenset()
    model: dict = field(default_factory=lambda: {"model": "kirchhoff"})  # the rod model's keys

    def branch_ok(self, branch: Branch) -> bool:
        """The branch is complete: it reached its bound (or closed a loop), or it is a
        contact-free branch handed over at its first contact to the contact branch, or a
        contact branch handed over where it stopped to the same branch held on its
        symmetry. A branch stopped by the point limit, a step failure or an interrupt is
        not."""
        return (branch.status.complete or branch.name in self.cut_at_contact
                or branch.name in self.held_instead)

    def pin_branch(self, name: str, index: int = 0):
        """Set the azimuth pin with which point ``index`` of branch ``name`` was computed.

        Returns the problem to check that branch against (the contact wrapper
        for contact branches). The pinned coordinate keeps the value it had
        at the first point of its run.
        """
        rod = self.rod_problem
        dofs: tuple[int, ...] = ()
        for start, chosen in self.pins.get(name, ((0, ()),)):
            if start <= index:
                dofs = chosen
        problem = self.contact_problem if name in self.contact_branches else rod
        rod.sliding_tail = (SLIDING_TAIL_CONTACT if name in self.contact_branches
                            else None if not self.options.loop_slides
                            else sliding_threshold(rod.rod.n_nodes))
        hold_azimuth(rod, dofs, problem)
        return problem

    @property
    def ok(self) -> bool:
        return (all(self.branch_ok(b) for b in self.branches)
                and not any(n.startswith(("failed:", "incomplete:")) for n in self.notes))

    @property
    def greenhill_turns(self) -> float | None:
        """Exact critical turns of the straight rod (load control),
        :mod:`supercoil.problems.greenhill`."""
        if not self.options.load_control:
            return None
        return critical_turns(self.options.twist_ratio, self.options.tension)

    @property
    def ply(self) -> HardCorePly | None:
        """The uniform hard-core two-ply at this force and diameter
        (:mod:`supercoil.problems.ply`): the plectoneme's torque plateau, extension per
        turn and the turns at which it would span the rod; None without a diameter or a
        force, or for the extensible rod."""
        if self.model.get("model", "kirchhoff") != "kirchhoff":
            return None
        return options_ply(self.options)


def options_ply(opts: TweezersOptions) -> HardCorePly | None:
    """The hard-core ply of ``opts`` (diameter, force, twist ratio); None without a
    diameter or a force."""
    if opts.diameter is None or not opts.load_control or not opts.tension:
        return None
    return hard_core_ply(opts.diameter, opts.tension, opts.twist_ratio)
