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

from supercoil.errors import InputError
from supercoil.rod.kernels import CURVATURE_FORMS

MAX_NODES = 20_000  # the largest discretisation accepted (memory grows like N)
MAX_MAGNITUDE = 1e6  # bound of the scalar inputs (twist ratio, excess link, tension)


def _finite(name: str, value, *, low: float | None = None, high: float | None = None,
            low_open: bool = True, valid: str) -> float:
    """``value`` as a float, or an InputError naming ``name`` and what is ``valid``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a number, got {value!r}; valid: {valid}")
    x = float(value)
    bad = not math.isfinite(x)
    if low is not None:
        bad = bad or (x <= low if low_open else x < low)
    if high is not None:
        bad = bad or x > high
    if bad:
        raise InputError(f"{name}: got {value!r}; valid: {valid}")
    return x


def _nodes(name: str, value, minimum: int) -> int:
    valid = f"an integer with {minimum} <= N <= {MAX_NODES}"
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InputError(f"{name}: expected an integer, got {value!r}; valid: {valid}")
    if not minimum <= int(value) <= MAX_NODES:
        raise InputError(f"{name}: got {value!r}; valid: {valid}")
    return int(value)


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
        object.__setattr__(self, "twist_ratio", _finite(
            "twist_ratio", self.twist_ratio, low=0.0, high=MAX_MAGNITUDE,
            valid=f"a finite C/A with 0 < C/A <= {MAX_MAGNITUDE:g}"))
        object.__setattr__(self, "nodes", _nodes("nodes", self.nodes, 8))
        if self.curvature not in CURVATURE_FORMS:
            raise InputError(f"curvature: got {self.curvature!r}; valid: "
                             f"{', '.join(map(repr, CURVATURE_FORMS))}")


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
        object.__setattr__(self, "length_over_diameter", _finite(
            "length_over_diameter", self.length_over_diameter, low=math.pi,
            high=MAX_MAGNITUDE,
            valid=f"a finite L/D with pi < L/D <= {MAX_MAGNITUDE:g} (a tube of diameter D "
                  "closes into a ring only if L > pi D)"))

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


CONTACTS = {c.treatment: c for c in (Barrier, Penalty, AugmentedLagrangian, ExactContact)}


def contact_from_name(treatment: str, length_over_diameter: float) -> Contact:
    """The contact object of a treatment's name (``barrier``, ``penalty``, ``augmented``,
    ``exact``), as the command line and study files name them."""
    if treatment not in CONTACTS:
        raise InputError(f"contact treatment: got {treatment!r}; valid: "
                         f"{', '.join(CONTACTS)}")
    return CONTACTS[treatment](length_over_diameter)


def _contact_or_none(value) -> Contact | None:
    if value is not None and not isinstance(value, Contact):
        raise InputError(f"contact: expected None or a Barrier, Penalty, AugmentedLagrangian "
                         f"or ExactContact, got {value!r}")
    return value


def _read_only(points) -> np.ndarray:
    a = np.array(points, dtype=float)
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
    it needs ``contact``.
    """

    rod: Rod
    excess_link: float = 0.0
    contact: Contact | None = None
    initial: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.rod, Rod):
            raise InputError(f"rod: expected a supercoil.Rod, got {self.rod!r}")
        object.__setattr__(self, "excess_link", _finite(
            "excess_link", self.excess_link, high=MAX_MAGNITUDE,
            valid=f"a finite number of turns with |dLk| <= {MAX_MAGNITUDE:g}"))
        if abs(self.excess_link) > MAX_MAGNITUDE:
            raise InputError(f"excess_link: got {self.excess_link!r}; valid: a finite number "
                             f"of turns with |dLk| <= {MAX_MAGNITUDE:g}")
        _contact_or_none(self.contact)
        if self.initial is not None:
            if self.contact is None:
                raise InputError("initial: a starting curve needs contact (e.g. "
                                 "contact=supercoil.Barrier(length_over_diameter=100)); "
                                 "without it the ring relaxes to the circle")
            points = _read_only(self.initial)
            if points.ndim != 2 or points.shape[1] != 3 or len(points) < 4 \
                    or not np.isfinite(points).all():
                raise InputError(f"initial: expected a finite array of shape (m, 3) with "
                                 f"m >= 4 points, got shape {points.shape}")
            object.__setattr__(self, "initial", points)

    def __repr__(self) -> str:
        start = "" if self.initial is None else f", initial=<{len(self.initial)} points>"
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
        if self.rod.nodes < 12:
            raise InputError(f"rod.nodes: got {self.rod.nodes}; valid: a clamped rod needs "
                             f"at least 12 nodes")
        if (self.tension is None) == (self.end_distance is None):
            raise InputError("give exactly one of tension (F L^2/A, load control) and "
                             "end_distance (z/L, displacement control)")
        if self.tension is not None:
            object.__setattr__(self, "tension", _finite(
                "tension", self.tension, low=0.0, low_open=False, high=MAX_MAGNITUDE,
                valid=f"a finite F L^2/A with 0 <= F L^2/A <= {MAX_MAGNITUDE:g}"))
        else:
            value = _finite("end_distance", self.end_distance, low=0.0, high=1.0,
                            valid="a number z/L with 0 < z/L < 1 (an inextensible rod cannot "
                                  "be longer than L)")
            if value >= 1.0:
                raise InputError(f"end_distance: got {self.end_distance!r}; valid: 0 < z/L < 1 "
                                 "(at z/L = 1 the rod cannot deflect)")
            object.__setattr__(self, "end_distance", value)
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
