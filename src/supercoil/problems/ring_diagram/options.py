"""The options of a ring diagram (:class:`DiagramOptions`) and the parsing of its modes."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from supercoil import checks
from supercoil.contact.options import DEFAULT_TREATMENT, ContactOptions, validate_contact_choice
from supercoil.problems.branch_options import PREDICTORS, branch_tolerances, check_steps
from supercoil.problems.ring_contact import validate_diameter

# energy treatments whose equilibria are plain stationary points of E + sum psi
CONTINUATION_TREATMENTS = ("barrier", "penalty")
MAX_MODE = 12  # highest Michell mode whose primary branch is followed
MAX_SECONDARY_BRANCHES = 1000


@dataclass(frozen=True)
class DiagramOptions:
    """What :func:`~supercoil.problems.ring_diagram.ring_diagram` computes; validated on
    construction.

    ``twist_ratio`` C/A; ``length_over_diameter`` L/D (> pi); ``n_nodes`` N;
    ``modes`` the circle's bifurcation modes (integers >= 2) whose primary
    branches are followed; ``max_excess_link`` the upper bound of ``dLk``
    (the circle is followed at least 10 % beyond its highest requested
    Michell point); ``contact`` the treatment of self-contact.
    ``free_max_step`` / ``contact_max_step``: largest arclength steps of the
    contact-free branches (units of L) and of the contact branches (units of
    D); ``free_max_points`` / ``contact_max_points`` bound their lengths.
    ``event_tolerance``: arclength accuracy of the contact-free branches'
    events (the geometric contact onset included);
    ``contact_event_tolerance`` that of the contact branches' events.
    ``contact_tolerance``: corrector tolerance (max |KKT residual|) on the
    contact branches; the barrier's stiffness (``A / h^3`` growing like
    ``1 / gap``) puts the residual's round-off floor near 1e-7 at N = 60,
    L/D = 122, so the contact-free default 1e-10 cannot be reached there.
    ``contact_gauge``: pin the material sliding on contact branches
    (``ContinuationOptions.near_symmetry_gauge``; docs/continuation.md, "Closed
    rods: the sliding gauge and the pins"). Without it the branch does not pass
    the contact onset.
    ``branch_depth``: 1 computes the primary branches only, 2 adds the
    secondary branches switched from their bifurcation points, 3 the tertiary
    ones too (:mod:`supercoil.problems.ring_diagram.secondary`), each half-branch at
    most ``secondary_max_points`` points and ``secondary_max_branches``
    half-branches in all.
    ``contact_curve``: ``"polygon"``, ``"spline"`` or ``"quintic"``, the curve whose
    self-distance is the contact distance (``ContactOptions.curve``; the
    contact onset of the contact-free branches is measured on it too).
    ``contact_formulation``: ``"pairs"`` or ``"integral"``
    (``ContactOptions.formulation``). ``contact_predictor``: the predictor of the
    contact branches (``ContinuationOptions.predictor``).

    Defaults: the double-integral contact on the cubic B-spline, the integral
    phase condition as the sliding gauge, the quadratic predictor. At C/A = 2/3,
    L/D = 122, N = 200 (benchmarks/bench_ring_diagram.py, whose flags choose the
    others) alpha reaches dLk 6 with the three folds of Coleman & Swigon 2002's
    Figure 1 only; the pair sum on the polygon reaches it through artefact folds
    (and its beta branch leaves D_3 under refinement), the node gauge failed to
    restart a run at dLk 3.50.
    """

    twist_ratio: float
    length_over_diameter: float
    n_nodes: int = 100
    modes: tuple[int, ...] = (2, 3)
    max_excess_link: float = 6.0
    contact: str = DEFAULT_TREATMENT
    free_max_step: float = 0.1
    free_max_points: int = 80
    contact_max_step: float = 0.5
    contact_max_points: int = 150
    event_tolerance: float = 1e-8
    contact_event_tolerance: float = 1e-6
    contact_tolerance: float = 1e-8
    contact_gauge: bool = True
    gauge: str = "integral"
    branch_depth: int = 1
    secondary_max_points: int = 40
    secondary_max_branches: int = 12
    contact_curve: str = "spline"
    contact_formulation: str = "integral"
    contact_predictor: str = "quadratic"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "twist_ratio", checks.number("twist_ratio", self.twist_ratio, 0.0,
                                                checks.MAX_MAGNITUDE, low_open=True,
                                                meaning="C/A"))
        validate_diameter(self.length_over_diameter)
        set_(self, "length_over_diameter", float(self.length_over_diameter))
        set_(self, "n_nodes", checks.integer("n_nodes", self.n_nodes, checks.MIN_NODES,
                                             checks.MAX_NODES, meaning="nodes of the ring"))
        set_(self, "modes", checks.distinct_integers("modes", self.modes, 2, MAX_MODE,
                                                     meaning="Michell modes"))
        set_(self, "max_excess_link", checks.number(
            "max_excess_link", self.max_excess_link, 0.0, checks.MAX_MAGNITUDE,
            low_open=True, meaning="largest dLk in turns"))
        if self.contact not in CONTINUATION_TREATMENTS:
            raise checks.refuse("contact", f"must be one of {', '.join(CONTINUATION_TREATMENTS)}"
                                f", got {self.contact!r} (the exact and augmented treatments "
                                "need their active-set or multiplier loops, which the "
                                "continuation does not run)")
        check_steps(self, points=("free_max_points", "contact_max_points", "secondary_max_points"))
        checks.integer("secondary_max_branches", self.secondary_max_branches, 0,
                       MAX_SECONDARY_BRANCHES, meaning="secondary and tertiary half-branches")
        checks.choice("contact_predictor", self.contact_predictor, PREDICTORS)
        checks.choice("gauge", self.gauge, ("node", "integral"))
        checks.flag("contact_gauge", self.contact_gauge)
        checks.integer("branch_depth", self.branch_depth, 1, 3,
                       meaning="1 primary, 2 and secondary, 3 and tertiary branches")
        validate_contact_choice(self.contact_curve, self.contact_formulation)

    @property
    def diameter(self) -> float:
        """Tube diameter D in units of L."""
        return 1.0 / self.length_over_diameter

    @property
    def tolerances(self) -> dict:
        return branch_tolerances(self)

    def contact_options(self, diameter: float) -> ContactOptions:
        """The :class:`ContactOptions` of the contact branches, tube ``diameter`` (a length)."""
        return ContactOptions(diameter=diameter, treatment=self.contact, curve=self.contact_curve,
                              formulation=self.contact_formulation)


def parse_modes(text: str | Sequence[int]) -> tuple[int, ...]:
    """``"2,3"`` -> ``(2, 3)``; a ValueError naming what is valid otherwise."""
    words = text.replace(",", " ").split() if isinstance(text, str) else list(text)
    try:
        modes = tuple(int(w) for w in words)
    except ValueError:
        raise ValueError(f"modes {text!r}: give integers >= 2 separated by commas, like 2,3"
                         ) from None
    if not modes or any(m < 2 for m in modes) or len(set(modes)) != len(modes):
        raise ValueError(f"modes {text!r}: give distinct integers >= 2 (2 = alpha, 3 = beta), "
                         "like 2,3")
    return tuple(sorted(modes))
