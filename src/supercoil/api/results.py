"""What the verbs return: immutable results with a status, a message and plain arrays.

* :class:`Equilibrium`: one state of a :class:`~supercoil.api.model.Ring`, its
  topology (twist, writhe), energy, contacts and stability.
* :class:`Stability`: the unstable count, zero modes, determinant sign and lowest
  eigenpairs of a state.
* :class:`Diagram`: the branches of a ring diagram or of a tweezers run, by name,
  with their special points.

``repr`` of each is a few lines, never the arrays; the arrays are attributes.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

import numpy as np

from supercoil.continuation.branch import Branch, SpecialPoint, special_point_counts


class EquilibriumStatus(enum.Enum):
    """How an equilibrium computation ended; the value is its meaning."""

    STABLE = "a converged equilibrium, a strict local minimum (no negative eigenvalue, no zero mode)"
    MARGINAL = "a converged equilibrium with zero modes and no negative eigenvalue"
    UNSTABLE = "a converged equilibrium with negative eigenvalues (a saddle)"
    NOT_CONVERGED = "Newton did not converge: the state is not an equilibrium"

    @property
    def converged(self) -> bool:
        return self is not EquilibriumStatus.NOT_CONVERGED

    @classmethod
    def of(cls, converged: bool, stability) -> EquilibriumStatus:
        """The status of a computation that ``converged`` (or not) to a state of
        ``stability`` (its ``unstable_count`` and ``zero_modes``)."""
        if not converged:
            return cls.NOT_CONVERGED
        if stability.unstable_count > 0:
            return cls.UNSTABLE
        if stability.zero_modes > 0:
            return cls.MARGINAL
        return cls.STABLE


class RunStatus(enum.Enum):
    """How a run of several branches ended."""

    COMPLETE = "every branch ended where it was asked to"
    INCOMPLETE = "a branch stopped before its end (see the message)"

    @property
    def ok(self) -> bool:
        return self is RunStatus.COMPLETE


def _read_only(a) -> np.ndarray:
    a = np.array(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Stability:
    """Stability of a state (Coleman & Swigon 2000: a strict local minimum among
    admissible neighbours).

    ``unstable_count``: negative eigenvalues of the Hessian of the Lagrangian on the
    tangent space of the constraints, rigid motions and continuous symmetries
    removed (0 means stable); ``zero_modes``: eigenvalues with
    ``|lambda| <= zero_tolerance``, never given a sign; ``negative_count``: the
    inertia of the factorisation; ``determinant_sign``: the sign of the determinant
    of the reduced Hessian (Chamekh, Mani-Aouadi & Moakher 2014's test; it misses
    eigenvalues that cross in pairs). ``eigenvalues`` (k,) ascending, in the lumped
    mass metric; ``modes`` (k, N, 3) the node displacements of each eigenvector.
    """

    unstable_count: int
    zero_modes: int
    negative_count: int
    determinant_sign: int
    eigenvalues: np.ndarray
    modes: np.ndarray
    zero_tolerance: float
    certified: bool = True
    message: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "eigenvalues", _read_only(self.eigenvalues))
        object.__setattr__(self, "modes", _read_only(self.modes))

    @property
    def stable(self) -> bool:
        return self.unstable_count == 0 and self.zero_modes == 0

    def __repr__(self) -> str:
        lowest = ", ".join(f"{v:.4g}" for v in self.eigenvalues[:3])
        return (f"Stability(unstable_count={self.unstable_count}, zero_modes={self.zero_modes}, "
                f"determinant_sign={self.determinant_sign:+d}, lowest=[{lowest}])")


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """An equilibrium of a ring (nondimensional: A = 1, L = 1).

    ``problem``: the :class:`~supercoil.api.model.Ring` solved. ``points`` (N, 3):
    the centreline; ``tensions`` (N,): the multipliers of the edges'
    inextensibility. ``energy`` E L / A (elastic only); ``twist``, ``writhe`` in
    turns, computed independently (frames; the Gauss double sum), with
    ``link_error = |twist + writhe - excess_link|``. ``stability``: the
    :class:`Stability` of the state (its eigenvalues; :func:`~supercoil.stability`
    recomputes it with the modes). ``contacts``: the contact summary
    (``contact_points``, ``contact_intervals``, ``contacts``,
    ``n_contact_points``, ``n_contact_intervals``, ``min_gap_over_diameter``, ...),
    None without contact. ``record``: every key of the ``supercoil ring --json``
    output. ``frames`` (N, 3, 3): the sections' directors as columns, for a
    :class:`~supercoil.api.model.CosseratRod` (None for a Kirchhoff rod, whose frame
    follows from the centreline). ``tolerances``: those the state was computed with (``newton_residual``,
    ``zero_modes`` and with contact ``penetration_over_diameter``), as result files
    record them.
    """

    problem: object
    status: EquilibriumStatus
    message: str
    points: np.ndarray
    tensions: np.ndarray
    energy: float
    twist: float
    writhe: float
    link_error: float
    residual: float
    iterations: int
    stability: Stability
    contacts: Mapping | None = None
    record: Mapping = field(default_factory=dict)
    tolerances: Mapping = field(default_factory=dict)
    frames: np.ndarray | None = None  # (N, 3, 3) section frames d1, d2, d3 (Cosserat rods)

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _read_only(self.points))
        if self.frames is not None:
            object.__setattr__(self, "frames", _read_only(self.frames))
        object.__setattr__(self, "tensions", _read_only(self.tensions))
        object.__setattr__(self, "record", MappingProxyType(dict(self.record)))
        object.__setattr__(self, "tolerances", MappingProxyType(dict(self.tolerances)))
        if self.contacts is not None:
            object.__setattr__(self, "contacts", MappingProxyType(dict(self.contacts)))

    @property
    def excess_link(self) -> float:
        return self.problem.excess_link

    @property
    def converged(self) -> bool:
        return self.status.converged

    @property
    def unstable_count(self) -> int:
        return self.stability.unstable_count

    @property
    def stable(self) -> bool:
        return self.status is EquilibriumStatus.STABLE

    def __repr__(self) -> str:
        lines = [(f"Equilibrium({self.status.name}: dLk = {self.excess_link:g}, "
                 f"E = {self.energy:.8g}, Tw = {self.twist:.6g}, Wr = {self.writhe:.6g},"),
                 (f"  unstable_count = {self.unstable_count}, zero_modes = "
                 f"{self.stability.zero_modes}, N = {len(self.points)}")]
        if self.contacts is not None:
            lines[-1] += (f", contact points {self.contacts.get('n_contact_points', 0)}, "
                          f"intervals {self.contacts.get('n_contact_intervals', 0)}, "
                          f"min gap {self.contacts.get('min_gap_over_diameter', float('nan')):.4g} D")
        return "\n".join(lines) + ")"


@dataclass(frozen=True, eq=False)
class Diagram:
    """Branches of equilibria computed together: a ring's bifurcation diagram, or the
    branches of a rod in tweezers.

    ``kind``: ``"ring_diagram"`` or ``"tweezers"``; ``problem``: what was solved (a
    :class:`~supercoil.api.model.Ring` without excess link, or a
    :class:`~supercoil.api.model.Tweezers`); ``settings``: the full options the
    branches were computed with; ``branches``: a read-only mapping of names to
    :class:`~supercoil.continuation.Branch` (in the order computed);
    ``status``/``message``: complete, or which branch stopped and why; ``notes``:
    what the run observed (thresholds, hand-overs). :attr:`summary` is the JSON
    document the command line writes (``diagram.json`` or ``branch.json``).
    """

    kind: str
    problem: object
    settings: object
    branches: Mapping[str, Branch]
    status: RunStatus
    message: str
    notes: tuple[str, ...] = ()
    computed: object = field(default=None, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "branches", MappingProxyType(dict(self.branches)))

    @property
    def ok(self) -> bool:
        return self.status.ok

    @property
    def special_points(self) -> tuple[SpecialPoint, ...]:
        return tuple(p for b in self.branches.values() for p in b.special_points)

    def __len__(self) -> int:
        return len(self.branches)

    @cached_property
    def summary(self) -> dict:
        """The JSON summary of the run with its envelope, as ``diagram.json`` (a ring
        diagram) or ``branch.json`` (tweezers) holds it: one record per point, the
        special points, the branches with their status, the notes (``docs/results.md``).
        Computed once."""
        from supercoil.io.results import envelope

        computed, settings = self.computed, self.settings
        if self.kind == "tweezers":
            from supercoil.problems.tweezers_output import TWEEZERS_CONVENTIONS, result_payload

            payload = result_payload(computed)
            dna = getattr(self.problem, "dna", None)
            if dna is not None:
                from supercoil.units.tweezers import tweezers_payload_in_dna_units

                payload = tweezers_payload_in_dna_units(payload, dna, self.problem.force_pN)
            data = envelope(payload, n_nodes=settings.n_nodes, tolerances=settings.tolerances,
                            contact_treatment="barrier" if computed.contact_problem
                            else "none",
                            units="nondimensional" if dna is None else dna.name)
            data["conventions"].update(TWEEZERS_CONVENTIONS)
            if dna is not None:
                data["conventions"].update(dna.conventions())
                data["provenance"]["units_preset"] = dna.record()
            return data
        return envelope(computed.payload(), n_nodes=settings.n_nodes,
                        tolerances=settings.tolerances, contact_treatment=settings.contact)

    def __repr__(self) -> str:
        names = ", ".join(f"{name} ({len(b)})" for name, b in self.branches.items())
        special = special_point_counts(self.special_points)
        return (f"Diagram({self.kind}, {self.status.name}: {len(self.branches)} branches\n"
                f"  points per branch: {names}\n  special points: {special})")
