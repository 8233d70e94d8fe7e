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
from supercoil.units.dna import DNAPreset


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

    model: ClassVar[str] = "kirchhoff"

    def __post_init__(self) -> None:
        object.__setattr__(self, "twist_ratio", checks.number(
            "twist_ratio", self.twist_ratio, 0.0, checks.MAX_MAGNITUDE, low_open=True,
            meaning="C/A"))
        object.__setattr__(self, "nodes", checks.integer(
            "nodes", self.nodes, checks.MIN_NODES, checks.MAX_NODES, meaning="nodes of the rod"))
        checks.choice("curvature", self.curvature, CURVATURE_FORMS,
                      meaning="form of the discrete curvature")


DEFAULT_SLENDERNESS = 100.0  # L/D of the section when no stiffness is given
DEFAULT_POISSON_RATIO = 0.3


def section_stiffnesses(slenderness: float, poisson_ratio: float) -> tuple[float, float]:
    """``(EA L^2/A, GA L^2/A)`` of a solid circular section of diameter ``D = L /
    slenderness`` of an isotropic material of Poisson ratio ``nu``.

    With ``A = E pi D^4 / 64``: ``EA L^2/A = 16 (L/D)^2``; with Cowper's (1966) shear
    coefficient ``k = 6 (1 + nu) / (7 + 6 nu)``, ``GA L^2/A = 48 (L/D)^2 / (7 + 6 nu)``.
    """
    s = checks.number("slenderness", slenderness, 1.0, checks.MAX_MAGNITUDE, low_open=True,
                      meaning="L/D of the section")
    nu = checks.number("poisson_ratio", poisson_ratio, -1.0, 0.5, low_open=True,
                       meaning="Poisson ratio")
    return 16.0 * s * s, 48.0 * s * s / (7.0 + 6.0 * nu)


@dataclass(frozen=True)
class CosseratRod:
    """A special Cosserat (Simo-Reissner) rod of length 1: bending, torsion, shear and
    extension (Simo 1985; Chamekh, Mani-Aouadi & Moakher 2009).

    ``twist_ratio``: C / A. ``stretch_stiffness``: EA L^2 / A; ``shear_stiffness``:
    GA L^2 / A (both directions of an isotropic section). Either left out is that of a
    solid circular section of ``slenderness`` L/D (default 100) of a material of
    ``poisson_ratio`` (default 0.3): ``EA L^2/A = 16 (L/D)^2`` and ``GA L^2/A =
    48 (L/D)^2 / (7 + 6 nu)`` (Cowper's shear coefficient; :func:`section_stiffnesses`).
    As both grow the rod tends to the Kirchhoff :class:`Rod`, at first order in their
    inverses. ``nodes``: N, the nodes of two-node elements with geodesic rotation
    interpolation and one-point shear and stretch; results converge as O(1/N^2).
    """

    twist_ratio: float
    stretch_stiffness: float | None = None
    shear_stiffness: float | None = None
    nodes: int = 100
    slenderness: float = DEFAULT_SLENDERNESS
    poisson_ratio: float = DEFAULT_POISSON_RATIO

    model: ClassVar[str] = "cosserat"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "twist_ratio", checks.number(
            "twist_ratio", self.twist_ratio, 0.0, checks.MAX_MAGNITUDE, low_open=True,
            meaning="C/A"))
        set_(self, "nodes", checks.integer(
            "nodes", self.nodes, checks.MIN_NODES, checks.MAX_NODES, meaning="nodes of the rod"))
        stretch, shear = section_stiffnesses(self.slenderness, self.poisson_ratio)
        set_(self, "slenderness", float(self.slenderness))
        set_(self, "poisson_ratio", float(self.poisson_ratio))
        for name, default in (("stretch_stiffness", stretch), ("shear_stiffness", shear)):
            value = getattr(self, name)
            set_(self, name, default if value is None else checks.number(
                name, value, 0.0, 1e12, low_open=True,
                meaning=f"{'EA' if name.startswith('stretch') else 'GA'} L^2/A"))

    @property
    def curvature(self) -> str:
        """The discrete curvature's form: ``"geodesic"``, the relative rotation of the two
        nodes' frames over the element length (exact for the interpolated frame)."""
        return "geodesic"


ROD_TYPES = (Rod, CosseratRod)
MODELS = {"kirchhoff": Rod, "cosserat": CosseratRod}


def make_rod(model: str, twist_ratio: float, nodes: int, stretch_stiffness: float | None,
             shear_stiffness: float | None, slenderness: float | None = None,
             preset=None):
    """The :class:`Rod` (``model = "kirchhoff"``) or :class:`CosseratRod` (``"cosserat"``)
    of a command's or study's settings; ``slenderness`` the Cosserat section's L/D;
    ``preset`` a DNA preset, whose stretch modulus and helix diameter set the Cosserat
    rod's defaults. InputError on bad values."""
    checks.choice("model", model, tuple(MODELS), meaning="rod model")
    if model != "cosserat":
        return Rod(twist_ratio, nodes)
    if preset is not None:
        slenderness = preset.section_slenderness
        if stretch_stiffness is None:
            stretch_stiffness = preset.stretch_stiffness
    return CosseratRod(twist_ratio, stretch_stiffness, shear_stiffness, nodes,
                       slenderness=DEFAULT_SLENDERNESS if slenderness is None else slenderness)


def rod_model(rod) -> str:
    """``"kirchhoff"`` or ``"cosserat"``: the model of a rod object."""
    return "cosserat" if isinstance(rod, CosseratRod) else "kirchhoff"


def _check_rod(rod) -> None:
    if not isinstance(rod, ROD_TYPES):
        raise InputError(f"rod: expected a supercoil.Rod or supercoil.CosseratRod, got {rod!r}")


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

    ``rod``: a :class:`Rod` or a :class:`CosseratRod` (whose ring starts from the
    circle: ``initial`` and ``knot`` are Kirchhoff-only).
    Without ``contact`` nothing keeps the rod from reaching itself (the twisted
    circle is its equilibrium at every dLk, unstable above Michell's threshold
    ``dLk = (A/C) sqrt(3)``): a computation stops where a step would pass it
    through itself. With ``contact`` the ring is a tube of diameter D.
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
        _check_rod(self.rod)
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

    ``rod``: a :class:`Rod` or a :class:`CosseratRod`. Exactly one of ``tension`` (F L^2 / A >= 0, load control) and ``end_distance``
    (z / L, displacement control: in (0, 1) for a :class:`Rod`, which is inextensible;
    up to 2 for a :class:`CosseratRod`, stretched straight at z / L >= 1). ``contact``: the tube's self-contact
    (None: the rod may pass through itself, so the branch stops meaning anything
    at its first self-crossing). ``dna``: the molecule of a problem in DNA units
    (:meth:`from_dna`), whose results then carry nm, pN nm and σ beside the
    nondimensional numbers.
    """

    rod: Rod
    tension: float | None = None
    end_distance: float | None = None
    contact: Contact | None = None
    dna: DNAPreset | None = None

    @classmethod
    def from_dna(cls, dna: DNAPreset, force_pN: float, *, nodes: int | None = None,
                 contact: type[Contact] | None = None) -> Tweezers:
        """A DNA molecule pulled by ``force_pN`` (pN) and turned (magnetic tweezers).

        ``dna``: a :class:`~supercoil.units.dna.DNAPreset` (base pairs, salt or diameter,
        temperature; its superhelical density is not used: give the turns or σ to
        :func:`~supercoil.api.verbs.tweezers`). C/A, F L^2/A and L/D follow from it;
        ``nodes`` defaults to the fewest whose segments are no longer than D (n0 =
        ceil(L/D) + 2) and at most a third of the loop's core sqrt(A/F)
        (:func:`~supercoil.units.tweezers.default_nodes`); ``contact``: the
        treatment's class, :class:`Barrier` (default) or :class:`Penalty`.

        >>> problem = Tweezers.from_dna(DNAPreset(base_pairs=3000, salt_mM=150), 1.0)
        >>> problem.rod.nodes, round(problem.tension, 1)
        (240, 5062.8)
        """
        from supercoil.units.tweezers import nodes_or_default, tweezers_parameters

        if not isinstance(dna, DNAPreset):
            raise InputError(f"dna: expected a supercoil.DNAPreset, got {dna!r}", name="dna")
        numbers = tweezers_parameters(dna, force_pN)
        lod = numbers["length_over_diameter"]
        contact = Barrier if contact is None else contact
        if not (isinstance(contact, type) and issubclass(contact, Contact)):
            raise InputError(f"contact: expected Barrier or Penalty (the class), got "
                             f"{contact!r}", name="contact")
        try:
            nodes = nodes_or_default(nodes, lod, numbers["tension"])
        except InputError as exc:
            raise InputError(exc.renamed({"n_nodes": "nodes"}), name="nodes") from None
        return cls(Rod(numbers["twist_ratio"], nodes), tension=numbers["tension"],
                   contact=contact(lod), dna=dna)

    def __post_init__(self) -> None:
        _check_rod(self.rod)
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
            from supercoil.problems.tweezers.options import (
                MAX_END_DISTANCE,
                check_inextensible,
            )

            # the extensible Cosserat rod may be stretched beyond L; an inextensible rod
            # is not longer than L, and at z/L = 1 it cannot deflect
            object.__setattr__(self, "end_distance", checks.number(
                "end_distance", self.end_distance, 0.0, MAX_END_DISTANCE, low_open=True,
                meaning="z/L"))
            if not isinstance(self.rod, CosseratRod):
                check_inextensible(self.end_distance)
        _contact_or_none(self.contact)
        if self.contact is not None and self.contact.treatment not in ("barrier", "penalty"):
            raise InputError(f"contact: {type(self.contact).__name__} cannot be continued along "
                             "a branch; use Barrier or Penalty")
        if self.dna is not None:
            self._check_dna()

    def _check_dna(self) -> None:
        """A problem in DNA units has the molecule's C/A and L/D and is under a load."""
        if not isinstance(self.dna, DNAPreset):
            raise InputError(f"dna: expected None or a supercoil.DNAPreset, got {self.dna!r}",
                             name="dna")
        lod = None if self.contact is None else self.contact.length_over_diameter
        if (self.tension is None or not math.isclose(self.rod.twist_ratio, self.dna.twist_ratio,
                                                     rel_tol=1e-12)
                or lod is None or not math.isclose(lod, self.dna.length_over_diameter,
                                                   rel_tol=1e-12)):
            raise InputError("dna: a problem in DNA units is pulled by a force and has the "
                             "molecule's C/A and L/D; build it with "
                             "Tweezers.from_dna(dna, force_pN)", name="dna")

    @property
    def force_pN(self) -> float | None:
        """The pulling force in pN of a problem in DNA units (None otherwise)."""
        return None if self.dna is None else self.dna.force_to_pN(self.tension)


__all__ = [
    "AugmentedLagrangian",
    "Barrier",
    "Contact",
    "CosseratRod",
    "ExactContact",
    "Penalty",
    "Ring",
    "Rod",
    "Tweezers",
    "contact_from_name",
    "make_rod",
    "rod_model",
    "section_stiffnesses",
]
