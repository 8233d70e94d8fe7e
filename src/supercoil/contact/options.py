"""How self-contact is imposed: the options of :class:`~supercoil.contact.problem.ContactProblem`.

The treatments (docs/contact.md, "The four treatments"): ``barrier``, ``augmented``
and ``penalty`` add a potential of the gap ``g = d - D`` to the energy
(:mod:`supercoil.contact.potentials`); ``exact`` imposes ``g >= 0`` as inequality
constraints. The contact curve and the formulation are described in
:mod:`supercoil.contact.curve` and docs/contact.md ("Contact energy: pair sum or
double integral").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil import checks

TREATMENTS = ("barrier", "augmented", "penalty", "exact")
DEFAULT_TREATMENT = "barrier"
# the curve whose self-distance is the contact distance (quintic: integral formulation only)
CURVES = ("polygon", "spline", "quintic")
FORMULATIONS = ("pairs", "integral")  # how the potential is summed, see ContactOptions


def validate_contact_choice(curve: str, formulation: str) -> None:
    """The drivers' check of ``contact_curve`` and ``contact_formulation`` (their key names
    in the messages); raises :class:`~supercoil.errors.InputError`."""
    checks.choice("contact_curve", curve, CURVES)
    checks.choice("contact_formulation", formulation, FORMULATIONS)
    if curve == "quintic" and formulation != "integral":
        raise checks.refuse("contact_curve", f"'quintic' needs contact_formulation "
                            f"'integral', got {formulation!r}; valid: spline or polygon with "
                            "pairs, any curve with integral")


@dataclass(frozen=True)
class ContactOptions:
    """How self-contact is imposed; validated on construction.

    ``diameter`` D (in units of L). ``exclusion``: arc length below which two
    points are neighbours, default ``pi D / 2``. ``stiffness``: ``k`` of the
    penalty and augmented Lagrangian, ``kappa`` of the barrier; default
    ``stiffness_scale * max(A / h^3, force_scale / (pi g_hat))``: ``A / h^3`` is
    the stiffness with which one node of the discrete rod resists a transverse
    displacement in bending, so that the contact neither dominates the
    conditioning nor is soft next to the rod; ``force_scale / (pi g_hat)``
    (``g_hat = barrier_activation * D``) is the barrier's stiffness under a load:
    two strands crossing at right angles and pressed together by ``force_scale``
    sit at the gap ``0.149 g_hat`` (integral formulation; ``g_hat / pi`` for the
    pair sum), where a softer barrier lets a crossing force ``P`` compress the gap
    as ``exp(-P / (pi kappa g_hat))`` (docs/contact.md, "The barrier's stiffness
    under a load"). ``force_scale``: the contact force the load sets (the
    tweezers' tension ``F L^2/A``); ``None``: no load term.
    ``penetration_tolerance``: largest accepted penetration over D (augmented,
    exact). ``penalty_tolerance``: the same for the penalty, which needs a
    penetration ``F / k`` to carry a force ``F`` (with the default ``k`` a few
    per cent of D for DNA-like L/D at N = 100, falling like ``h^3``): the solve
    raises ``k`` until the penetration is within it
    (:func:`~supercoil.contact.solve.solve_contact`); states beyond it (the
    stiffness at its bound) are flagged, not returned silently. ``barrier_activation``: the
    barrier acts on gaps below ``barrier_activation * D``. ``curve``: the
    centreline whose self-distance is the contact distance, ``"polygon"``
    (segment pairs), ``"spline"`` (the uniform cubic B-spline of the nodes;
    see :mod:`supercoil.contact.curve`) or ``"quintic"`` (the quintic B-spline,
    integral formulation only: :func:`~supercoil.contact.sample_weights.quintic_samples`).
    ``count_local_minima`` (spline only, experimental): sum the potential only
    over pairs whose closest points are a local minimum of the distance between
    the whole curves, dropping the *shadows* of a contact seen by the
    neighbouring pairs through their shared piece ends
    (``spline_distance.local_minimum_pairs``). The plain sum counts a point
    contact once inside a piece pair and up to four times at a piece junction,
    a ripple of period h of its own; dropping the shadows removes it, but the
    energy then jumps where a local minimum is born inside the barrier's reach
    (line contacts): it helps point contacts (the ring) and stalls line
    contacts (tweezers).
    ``formulation``: ``"pairs"`` sums the potential of the closest distance of
    every segment (piece) pair; ``"integral"`` integrates it over both strands
    (:mod:`supercoil.contact.integral`), so that a contact counts once wherever
    it lies relative to the nodes (barrier and penalty only).
    ``samples_per_segment``: quadrature points per segment of the integral,
    default :func:`~supercoil.contact.sample_weights.default_samples`.
    """

    diameter: float
    treatment: str = DEFAULT_TREATMENT
    exclusion: float | None = None
    stiffness: float | None = None
    stiffness_scale: float = 1.0
    force_scale: float | None = None
    penetration_tolerance: float = 1e-4
    penalty_tolerance: float = 1e-3
    barrier_activation: float = 1e-2
    max_outer_iterations: int = 50
    force_tolerance: float = 1e-8
    curve: str = "polygon"
    count_local_minima: bool = False
    formulation: str = "pairs"
    samples_per_segment: int | None = None

    def __post_init__(self) -> None:
        checks.number("diameter", self.diameter, 0.0, low_open=True, meaning="tube diameter D")
        checks.choice("treatment", self.treatment, TREATMENTS, meaning="contact treatment")
        checks.optional_number("exclusion", self.exclusion, 0.0,
                               meaning="arc length of neighbours")
        checks.optional_number("stiffness", self.stiffness, 0.0, low_open=True,
                               meaning="contact stiffness")
        checks.number("stiffness_scale", self.stiffness_scale, 0.0, low_open=True)
        checks.optional_number("force_scale", self.force_scale, 0.0,
                               meaning="the contact force the load sets")
        for name in ("penetration_tolerance", "penalty_tolerance", "barrier_activation"):
            checks.number(name, getattr(self, name), 0.0, 1.0, low_open=True,
                          meaning="over D")
        checks.number("force_tolerance", self.force_tolerance, 0.0, low_open=True)
        checks.integer("max_outer_iterations", self.max_outer_iterations, 1, 100_000)
        checks.flag("count_local_minima", self.count_local_minima)
        checks.choice("formulation", self.formulation, FORMULATIONS,
                      meaning="a sum over segment pairs or a double integral over the strands")
        checks.choice("curve", self.curve, CURVES,
                      meaning="the polygon's segments, the cubic or the quintic B-spline")
        if self.count_local_minima and self.curve != "spline":
            raise checks.refuse("count_local_minima", "needs curve='spline'")
        if self.formulation == "integral" and self.treatment not in ("barrier", "penalty"):
            raise checks.refuse("formulation", f"'integral' takes the barrier or the penalty "
                                f"treatment, not {self.treatment!r}")
        if self.formulation == "integral" and self.count_local_minima:
            raise checks.refuse("count_local_minima", "belongs to the pairs formulation")
        if self.samples_per_segment is not None:
            checks.integer("samples_per_segment", self.samples_per_segment, 1, 1000)
        if self.curve == "quintic" and self.formulation != "integral":
            raise checks.refuse("curve", "'quintic' needs formulation='integral' (its "
                                "distance is only sampled)")

    @property
    def tolerance(self) -> float:
        """Largest accepted penetration over D for this treatment."""
        return self.penalty_tolerance if self.treatment == "penalty" else self.penetration_tolerance

    @property
    def exclusion_length(self) -> float:
        return 0.5 * np.pi * self.diameter if self.exclusion is None else float(self.exclusion)

    def default_stiffness(self, bending_stiffness: float, edge_length: float) -> float:
        """The stiffness used where ``stiffness`` is ``None`` (class doc): ``stiffness_scale
        * max(A / h^3, force_scale / (pi g_hat))`` for the bending stiffness ``A`` and the
        segment length ``h``."""
        stiffness = bending_stiffness / edge_length**3
        if self.force_scale is not None:
            g_hat = self.barrier_activation * self.diameter
            stiffness = max(stiffness, self.force_scale / (np.pi * g_hat))
        return self.stiffness_scale * stiffness
