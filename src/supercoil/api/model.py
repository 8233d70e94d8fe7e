"""What is computed: the rod, its self-contact and the problems, as immutable descriptions.

A problem says *what* is asked (a ring at an excess link, a rod in magnetic
tweezers under a tension); the verbs of :mod:`supercoil.api.verbs` say *how* it
is solved. Every object here is a frozen dataclass that validates itself on
construction and raises :class:`~supercoil.errors.InputError` naming the input,
what is wrong and what would be valid.

Units are nondimensional: bending stiffness A = 1 and rod length L = 1, so the
tube diameter is D = 1 / ``length_over_diameter``, a tension is F L^2 / A and the
twist ratio is C / A.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from supercoil import checks
from supercoil.errors import InputError
from supercoil.rod.kernels import CURVATURE_FORMS


@dataclass(frozen=True)
class Rod:
    """An inextensible, unshearable, intrinsically straight Kirchhoff rod of length 1.

    ``twist_ratio``: C / A (torsional over bending stiffness; 2/3 for DNA with
    persistence lengths 50 nm and 75 nm, 1/(1 + Poisson's ratio) for an isotropic
    material). ``nodes``: N, the number of nodes of the discrete rod (Bergou et al.
    2008); results converge as O(1/N^2). ``curvature``: the discrete curvature's
    form: ``"angle"`` (the turning angle phi of the edges, the smallest error
    constant), ``"tan"`` (2 tan(phi/2), discrete elastic rods' form) or ``"sin"``
    (2 sin(phi/2)).
    """

    twist_ratio: float
    nodes: int = 100
    curvature: str = "angle"

    def __post_init__(self) -> None:
        object.__setattr__(self, "twist_ratio", checks.number(
            "twist_ratio", self.twist_ratio, 0.0, checks.MAX_MAGNITUDE, low_open=True,
            meaning="C/A"))
        object.__setattr__(self, "nodes", checks.integer(
            "nodes", self.nodes, checks.MIN_NODES, checks.MAX_NODES, meaning="nodes of the rod"))
        checks.choice("curvature", self.curvature, CURVATURE_FORMS,
                      meaning="form of the discrete curvature")


@dataclass(frozen=True)
class Contact:
    """Self-contact of a tube of diameter D = L / ``length_over_diameter`` (base class).

    Points of the centreline farther apart along the rod than a neighbour
    exclusion (pi D / 2) stay at least D apart; contact forces are normal,
    frictionless and never negative (Coleman & Swigon 2000). Use one of the
    treatments below.
    """

    length_over_diameter: float
    treatment: ClassVar[str] = ""

    def __post_init__(self) -> None:
        if type(self) is Contact:
            raise InputError("Contact is abstract: use Barrier, Penalty, AugmentedLagrangian "
                             "or ExactContact")
        # a tube of diameter D closes into a ring only if L > pi D
        object.__setattr__(self, "length_over_diameter", checks.number(
            "length_over_diameter", self.length_over_diameter, math.pi,
            checks.MAX_MAGNITUDE, low_open=True, meaning="L/D"))

    @property
    def diameter(self) -> float:
        """The tube diameter D in units of L."""
        return 1.0 / self.length_over_diameter


@dataclass(frozen=True)
class Barrier(Contact):
    """An intersection-free barrier energy on gaps below 1 % of D (the default).

    Its equilibria are stationary points of one smooth energy, so branches with
    contact are followed by plain continuation.
    """

    treatment: ClassVar[str] = "barrier"


@dataclass(frozen=True)
class Penalty(Contact):
    """A quadratic penalty on penetration (Chamekh, Mani-Aouadi & Moakher 2009)."""

    treatment: ClassVar[str] = "penalty"


@dataclass(frozen=True)
class AugmentedLagrangian(Contact):
    """Penalty plus multiplier updates until the penetration is below tolerance
    (Chamekh, Mani-Aouadi & Moakher 2009). Single equilibria only."""

    treatment: ClassVar[str] = "augmented"


@dataclass(frozen=True)
class ExactContact(Contact):
    """Contact as inequality constraints with an active set; returns the contact
    forces as multipliers. Single equilibria only."""

    treatment: ClassVar[str] = "exact"


# in the order of supercoil.contact.options.TREATMENTS (the command line lists them so)
CONTACTS = {c.treatment: c for c in (Barrier, AugmentedLagrangian, Penalty, ExactContact)}


def contact_from_name(treatment: str, length_over_diameter: float) -> Contact:
    """The contact object of a treatment's name (``barrier``, ``augmented``, ``penalty``,
    ``exact``), as the command line and study files name them."""
    checks.choice("treatment", treatment, tuple(CONTACTS), meaning="contact treatment")
    return CONTACTS[treatment](length_over_diameter)


def _contact_or_none(value) -> Contact | None:
    if value is not None and not isinstance(value, Contact):
        raise InputError(f"contact: expected None or a Barrier, Penalty, AugmentedLagrangian "
                         f"or ExactContact, got {value!r}")
    return value


def _initial_curve(points) -> np.ndarray:
    """The vertices of a starting curve as a read-only array, checked as the solve checks
    them (:func:`~supercoil.problems.ring_contact.check_initial_curve`), named ``initial``."""
    from supercoil.problems.ring_contact import check_initial_curve

    try:
        a = np.array(check_initial_curve(points), dtype=float)
    except InputError as exc:
        raise InputError(exc.renamed({"initial_points": "initial"}), name="initial") from None
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Ring:
    """A closed rod at a fixed excess link ``dLk = Lk - Lk0`` (turns).

    Without ``contact`` the rod may pass through itself (the twisted circle is
    its equilibrium at every dLk, unstable above Michell's threshold
    ``dLk = (A/C) sqrt(3)``). With ``contact`` the ring is a tube that cannot.
    ``initial`` (m, 3): start from this closed curve (any knot type, any length:
    it is scaled to L = 1 and resampled at the rod's nodes) instead of the circle;
    it needs ``contact``. ``knot``: start from a smooth embedding of this knot instead
    (``"3_1"``, ``"4_1"``, ``"5_1"``, ``"5_2"``, ``"7_1"``, ``"8_19"``, a trailing ``*``
    for the mirror image, or a torus knot ``(p, q)`` / ``"T(p,q)"``), tightened until it
    is free of overlap at the contact's L/D; it needs ``contact`` and excludes
    ``initial``. Either way the knot type is kept at every step.
    """

    rod: Rod
    excess_link: float = 0.0
    contact: Contact | None = None
    initial: np.ndarray | None = None
    knot: str | tuple[int, int] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.rod, Rod):
            raise InputError(f"rod: expected a supercoil.Rod, got {self.rod!r}")
        object.__setattr__(self, "excess_link", checks.number(
            "excess_link", self.excess_link, -checks.MAX_MAGNITUDE, checks.MAX_MAGNITUDE,
            meaning="dLk in turns"))
        _contact_or_none(self.contact)
        if self.initial is not None:
            if self.contact is None:
                raise checks.refuse("initial", "(a starting curve) needs contact, e.g. "
                                    "contact=supercoil.Barrier(length_over_diameter=100); "
                                    "without it the ring relaxes to the circle")
            object.__setattr__(self, "initial", _initial_curve(self.initial))
        if self.knot is not None:
            from supercoil.problems.knot_ring import parse_knot

            parse_knot(self.knot)
            if self.contact is None or self.initial is not None:
                raise checks.refuse("knot", "(a knotted starting curve) needs contact and no "
                                    "initial curve, e.g. knot='3_1', "
                                    "contact=supercoil.Barrier(length_over_diameter=100)")

    def __repr__(self) -> str:
        start = "" if self.initial is None else f", initial=<{len(self.initial)} points>"
        start += "" if self.knot is None else f", knot={self.knot!r}"
        return (f"Ring(rod={self.rod!r}, excess_link={self.excess_link:g}, "
                f"contact={self.contact!r}{start})")


@dataclass(frozen=True)
class Tweezers:
    """A rod clamped at both ends on the pulling axis z, one end turned (a magnetic
    tweezers experiment).

    Exactly one of ``tension`` (F L^2 / A >= 0, load control) and ``end_distance``
    (z / L in (0, 1), displacement control). ``contact``: the tube's self-contact
    (None: the rod may pass through itself, so the branch stops meaning anything
    at its first self-crossing).
    """

    rod: Rod
    tension: float | None = None
    end_distance: float | None = None
    contact: Contact | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.rod, Rod):
            raise InputError(f"rod: expected a supercoil.Rod, got {self.rod!r}")
        if self.rod.nodes < checks.MIN_CLAMPED_NODES:
            raise InputError(f"rod.nodes: got {self.rod.nodes}; valid: a clamped rod needs "
                             f"at least {checks.MIN_CLAMPED_NODES} nodes")
        if (self.tension is None) == (self.end_distance is None):
            raise InputError("give exactly one of tension (F L^2/A, load control) and "
                             "end_distance (z/L, displacement control)")
        if self.tension is not None:
            object.__setattr__(self, "tension", checks.number(
                "tension", self.tension, 0.0, checks.MAX_MAGNITUDE, meaning="F L^2/A"))
        else:
            # an inextensible rod is not longer than L, and at z/L = 1 it cannot deflect
            object.__setattr__(self, "end_distance", checks.number(
                "end_distance", self.end_distance, 0.0, 1.0, low_open=True, high_open=True,
                meaning="z/L"))
        _contact_or_none(self.contact)
        if self.contact is not None and self.contact.treatment not in ("barrier", "penalty"):
            raise InputError(f"contact: {type(self.contact).__name__} cannot be continued along "
                             "a branch; use Barrier or Penalty")


__all__ = [
    "AugmentedLagrangian",
    "Barrier",
    "Contact",
    "ExactContact",
    "Penalty",
    "Ring",
    "Rod",
    "Tweezers",
    "contact_from_name",
]
