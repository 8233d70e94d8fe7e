"""The options of the tweezers' branches (:class:`TweezersOptions`) and their checks."""

from __future__ import annotations

import math
from dataclasses import dataclass

from supercoil import checks
from supercoil.contact.options import ContactOptions, validate_contact_choice
from supercoil.problems.branch_options import PREDICTORS, branch_tolerances, check_steps

# in contact the loop's sliding is an approximate symmetry only on segments no longer
# than this many times sqrt(A/F) (TweezersOptions.loop_slides_in_contact)
SLIDING_CORE = 0.5
# the segments no longer than resolved_core(F L^2/A) times the loop's core sqrt(A/F)
# resolve the plectoneme's end loop (resolved_nodes; the DNA runs' default nodes): on
# coarser meshes its growth crossed a pair of folds of the discrete contact per node of
# each strand (the mesh's snake: supercoil.problems.tweezers.coarse), between which the
# unstable count is the mesh's. At most a third of the core (measured at C/A = 1.5,
# lambda = 80: at h sqrt(F/A) = 0.4, L/D = 200, N = 202, the contact branch's count
# changed 170 times against 23 at N = 303 (0.27), whose counts agree state by state
# with N = 454 (0.18) away from its events; benchmarks/grid_counts_refinement.py), and
# less under higher tensions: the mesh's pinning of the end loop falls off like
# exp(-c / (h sqrt(F/A))) (Peierls 1940; Nabarro 1947) while the force that drives the
# plectoneme's growth by a node falls like 1 / lambda, so the snake ends near
# h sqrt(F/A) = RESOLVED_SCALE / ln(lambda / RESOLVED_LAMBDA); both constants chosen so
# that the rule lies at or below the coarsest mesh measured clean at each lambda at
# L/D = 200, C/A = 1.5 (the finest snaking against the coarsest clean: 0.266 against
# 0.250 at lambda = 80, 0.286 against 0.250 at 100, 0.333 against 0.242 at 150; the rule
# 0.250, 0.239, 0.222; benchmarks/snake_edge.py; benchmarks/results/long_dna_grid.md,
# "The snake's edge")
RESOLVED_CORE = 1.0 / 3.0
RESOLVED_SCALE = 1.25
RESOLVED_LAMBDA = 0.54
# the largest end distance z/L: an extensible rod stretched to twice its length (a
# stretch strain of 1); an inextensible one stays below 1 (check_inextensible)
MAX_END_DISTANCE = 2.0
# the rules of the barrier's stiffness (TweezersOptions.contact_stiffness)
STIFFNESS_RULES = ("load", "bending")


@dataclass(frozen=True)
class TweezersOptions:
    """What :func:`~supercoil.problems.tweezers.tweezers_branches` computes; validated on
    construction.

    ``twist_ratio`` C/A; ``length_over_diameter`` L/D (> pi), or None for a
    rod without self-contact (the contact-free branch is then followed to the
    last turn); exactly one of ``tension`` (F L^2/A >= 0, load control) and
    ``end_distance`` (z/L in (0, 1) for the inextensible Kirchhoff rod, up to
    ``MAX_END_DISTANCE`` for the extensible Cosserat rod: :func:`check_inextensible`;
    displacement control); ``turns`` the
    interval ``(start, stop)`` of turns (``stop > start >= 0``; the straight
    branch starts at ``start``); ``n_nodes`` N. ``free_max_step``: largest
    arclength step without contact (units of L); ``contact_max_step``: with
    contact (units of D); ``max_points`` bounds each branch;
    ``segment_points`` the most points per continuation run: the azimuth pin is checked
    at every point (:func:`~supercoil.problems.tweezers.pins.pin_stop`) and a run ends
    where it must be picked again, so runs need no other bound (2000, the default
    ``max_points``).
    ``contact_predictor``: the predictor of the contact branch
    (``ContinuationOptions.predictor``). ``"quadratic"`` adds the curvature
    of the branch from the last two tangents: the barrier's stiffness makes
    the corrector's first residual large (5-80) even for short steps, and
    with the tangent predictor the steps stayed at a tenth of
    ``contact_max_step`` (290 points on the contact branch from 0 to 5 turns at
    N = 100, L/D = 33, F L^2/A = 75; 91 with ``"quadratic"``;
    ``benchmarks/bench_tweezers_steps.py --problems 75,33 --set
    '{"predictor": "tangent"}'``).
    Tolerances as in :class:`~supercoil.problems.ring_diagram.DiagramOptions`.
    ``contact_curve``: ``"spline"`` (default) or ``"polygon"``
    (``ContactOptions.curve``); ``loop_sliding``: treat the sliding of a localised
    loop with straight tails as an approximate symmetry (a phase row on the
    contact-free branch, out of the unstable count; docs/continuation.md, "Long open
    rods"; :attr:`loop_slides`; in contact not on segments longer than
    ``sqrt(A/F) / 2``, :attr:`loop_slides_in_contact`): it lets
    long rods reach their contact where the corrector otherwise diverges along the nearly
    free sliding and keeps a centred loop centred, from which a contact branch that
    stops or closes is followed again held on its half-turn symmetry
    (:mod:`~supercoil.problems.tweezers.mirrored`). ``None`` (default): on where it
    applies; ``True``: asked for (a note says where the mesh keeps it out of contact);
    ``False``: off;
    ``contact_formulation``:
    ``"integral"``
    (default) or ``"pairs"`` (``ContactOptions.formulation``). The default,
    the double integral over the B-spline, counts a contact once wherever it
    lies relative to the nodes: the pair sum on the polygon made a sawtooth
    of fold pairs along the plectoneme (35 folds from 0 to 5 turns at N =
    100 against 3; docs/contact.md, "Contact energy: pair sum or double
    integral"). ``contact_stiffness``: the rule of the barrier's stiffness:
    ``"load"`` (default) ``max(A/h^3, F/(pi g_hat))`` with ``g_hat`` the barrier's
    reach (1 % of D), so that two strands crossing at right angles and pressed
    together by the load F sit at 0.149 g_hat; ``"bending"`` ``A/h^3`` whatever the load,
    which at F L^2/A = 22500 (L/D = 100, N = 102) let the load close the gap to
    1-2e-6 D, the system's condition beyond double precision
    (``ContactOptions.force_scale``; docs/tweezers.md, "Contact stiffness"). Under
    displacement control the load is not known in advance and both rules are
    ``A/h^3``. ``contact_stiffness_scale``: a factor on the rule's stiffness
    (``ContactOptions.stiffness_scale``).
    """

    twist_ratio: float
    length_over_diameter: float | None
    tension: float | None = None
    end_distance: float | None = None
    turns: tuple[float, float] = (0.0, 5.0)
    n_nodes: int = 100
    free_max_step: float = 0.1
    contact_max_step: float = 0.5
    max_points: int = 2000
    segment_points: int = 2000
    contact_predictor: str = "quadratic"
    event_tolerance: float = 1e-8
    contact_event_tolerance: float = 1e-6
    contact_tolerance: float = 1e-8
    contact_curve: str = "spline"
    contact_formulation: str = "integral"
    loop_sliding: bool | None = None
    contact_stiffness: str = "load"
    contact_stiffness_scale: float = 1.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "twist_ratio", checks.number("twist_ratio", self.twist_ratio, 0.0,
                                                checks.MAX_MAGNITUDE, low_open=True,
                                                meaning="C/A"))
        set_(self, "length_over_diameter", checks.optional_number(
            "length_over_diameter", self.length_over_diameter, math.pi, checks.MAX_MAGNITUDE,
            low_open=True, meaning="L/D; a thicker tube cannot bend"))
        if (self.tension is None) == (self.end_distance is None):
            raise checks.refuse("tension", "and end_distance: give exactly one of tension "
                                "(F L^2/A, load control) and end_distance (z/L, displacement "
                                "control)")
        set_(self, "tension", checks.optional_number(
            "tension", self.tension, 0.0, checks.MAX_MAGNITUDE, meaning="F L^2/A"))
        set_(self, "end_distance", checks.optional_number(
            "end_distance", self.end_distance, 0.0, MAX_END_DISTANCE, low_open=True,
            meaning="z/L; below 1 for an inextensible rod of length L"))
        set_(self, "turns", check_turns(self.turns))
        set_(self, "n_nodes", checks.integer("n_nodes", self.n_nodes, checks.MIN_CLAMPED_NODES,
                                             checks.MAX_NODES,
                                             meaning="nodes of the clamped rod"))
        check_steps(self, points=("max_points", "segment_points"))
        checks.choice("contact_predictor", self.contact_predictor, PREDICTORS)
        validate_contact_choice(self.contact_curve, self.contact_formulation)
        checks.choice("contact_stiffness", self.contact_stiffness, STIFFNESS_RULES,
                      meaning="max(A/h^3, F/(pi g_hat)) or A/h^3")
        set_(self, "contact_stiffness_scale", checks.number(
            "contact_stiffness_scale", self.contact_stiffness_scale, 0.0, checks.MAX_MAGNITUDE,
            low_open=True, meaning="a factor on the barrier's stiffness"))
        if self.loop_sliding not in (None, True, False):
            raise checks.refuse("loop_sliding", f"must be True, False or None (where it "
                                f"applies), got {self.loop_sliding!r}")

    def contact_options(self) -> ContactOptions:
        """The self-contact of these options: the barrier on their curve and formulation,
        its stiffness ``contact_stiffness_scale`` times the ``contact_stiffness`` rule's."""
        load = self.tension if self.contact_stiffness == "load" else None
        return ContactOptions(diameter=self.diameter, curve=self.contact_curve,
                              formulation=self.contact_formulation,
                              stiffness_scale=self.contact_stiffness_scale, force_scale=load)

    @property
    def load_control(self) -> bool:
        return self.tension is not None

    @property
    def loop_slides(self) -> bool:
        """``loop_sliding`` where it applies on the contact-free runs: on every mesh, unless
        off. Where the mesh pins the loop's core (:attr:`mesh_pins_loop`) the row holds
        the force of the mesh, which stays small before the contact: at L/D = 100,
        lambda = 150, N = 102 (``h sqrt(F/A)`` = 1.47) the KKT residual without the row
        (the record ``sliding_residual``) was below 2e-6 at 99 % of the contact-free
        points and 4.2e-4 at the onset; at L/D = 200, N = 202 (0.74) at most 2.4e-5
        (C/A = 1.5) and 9.6e-6 (C/A = 1). Without the row the branch at N = 102 stopped
        at 37.92 turns, before its contact: the continued system had a nearly neutral mode (an
        eigenvalue of -7e-4 to 1e-3 against a next one of 2.2e5, changing sign five
        times within 0.05 turns) on which the corrector diverged. A held force above
        ``SLIDING_NOTE`` is noted with the result."""
        return self.loop_sliding is not False

    @property
    def loop_slides_in_contact(self) -> bool:
        """The row on the contact branch's runs where no contact acts, and the branch
        held on its half-turn symmetry (:mod:`~supercoil.problems.tweezers.mirrored`):
        :attr:`loop_slides`, not on a mesh that pins the loop's core. There the contact
        makes the end loop's energy depend on where the nodes sit in it (the mesh's
        force, which a row would hold), and the contact branch is followed without the
        row: at L/D = 100, lambda = 150, N = 102 it starts from the onset that the
        contact-free branch's row held (a force of 4.2e-4 there, within the KKT residual
        of the contact branch's own points, which carry no row: median 5.5e-5, at most
        1.4e-3, under the tension F L^2/A = 22500) and grows its plectoneme
        (docs/tweezers.md, "The plectoneme on coarse meshes")."""
        return self.loop_slides and not self.mesh_pins_loop

    @property
    def segment(self) -> float:
        """The edge ``h = L / (N - 2)`` over L (:func:`segment_length`)."""
        return segment_length(self.n_nodes)

    @property
    def core_segments(self) -> float | None:
        """``h sqrt(F/A)``: the segment ``h = L / (N - 2)`` over the localised loop's core
        ``sqrt(A/F)`` (None without a tension: no core)."""
        return core_segments(self.tension, self.n_nodes)

    @property
    def mesh_pins_loop(self) -> bool:
        """The segments are longer than ``SLIDING_CORE`` times the loop's core
        (:attr:`core_segments`): the mesh pins the localised loop and the plectoneme's
        end loop (:mod:`~supercoil.problems.tweezers.coarse`)."""
        return mesh_pins_loop(self.tension, self.n_nodes)

    @property
    def diameter(self) -> float | None:
        return None if self.length_over_diameter is None else 1.0 / self.length_over_diameter

    @property
    def tolerances(self) -> dict:
        return branch_tolerances(self)


def core_segments(tension: float | None, n_nodes: int) -> float | None:
    """``h sqrt(F/A)`` of N nodes under the tension F L^2/A (None without one)."""
    if not tension:
        return None
    return math.sqrt(tension) * segment_length(n_nodes)


def core_nodes(tension: float) -> int:
    """The fewest nodes whose segments are at most ``SLIDING_CORE`` times the loop's core
    ``sqrt(A/F)`` under the tension F L^2/A > 0: ``2 + ceil(sqrt(F L^2/A) / SLIDING_CORE)``."""
    return 2 + math.ceil(math.sqrt(tension) / SLIDING_CORE)


def segment_length(n_nodes: int) -> float:
    """The clamped rod's edge ``h = L / (N - 2)`` over L (its ends are the midpoints of the
    first and last edges)."""
    return 1.0 / (n_nodes - 2)


def resolved_core(tension: float) -> float:
    """The largest ``h sqrt(F/A)`` that resolves the plectoneme's end loop under the tension
    F L^2/A > 0 (the ``RESOLVED_CORE`` comment): ``min(1/3, 1.25 / ln(lambda / 0.54))``
    with ``lambda = sqrt(F L^2/A)``, a third up to lambda = 22.6."""
    lam = math.sqrt(tension)
    if lam <= RESOLVED_LAMBDA * math.exp(RESOLVED_SCALE / RESOLVED_CORE):
        return RESOLVED_CORE
    return RESOLVED_SCALE / math.log(lam / RESOLVED_LAMBDA)


def resolved_nodes(tension: float) -> int:
    """The fewest nodes whose segments are at most :func:`resolved_core` times the loop's
    core ``sqrt(A/F)`` under the tension F L^2/A > 0:
    ``2 + ceil(sqrt(F L^2/A) / resolved_core)``."""
    return 2 + math.ceil(round(math.sqrt(tension) / resolved_core(tension), 9))


def mesh_resolves_loop(tension: float | None, n_nodes: int) -> bool:
    """Whether N nodes' segments are at most :func:`resolved_core` times the loop's core
    (True without a tension: no core)."""
    core = core_segments(tension, n_nodes)
    return core is None or core <= resolved_core(tension) * (1 + 1e-9)


def mesh_pins_loop(tension: float | None, n_nodes: int) -> bool:
    """Whether N nodes' segments are longer than ``SLIDING_CORE`` times the loop's core
    ``sqrt(A/F)`` (:attr:`TweezersOptions.mesh_pins_loop`)."""
    core = core_segments(tension, n_nodes)
    return core is not None and core > SLIDING_CORE


def check_inextensible(end_distance: float | None) -> None:
    """InputError for an end distance ``z/L >= 1`` of an inextensible rod (the Kirchhoff
    rod: not longer than L, and at z/L = 1 straight and unable to deflect)."""
    if end_distance is not None and not end_distance < 1.0:
        raise checks.refuse("end_distance", f"(z/L) must lie in (0, 1) for the inextensible "
                            f"Kirchhoff rod, got {end_distance!r}; a stretched rod (z/L up "
                            f"to {MAX_END_DISTANCE:g}) needs the extensible Cosserat model")


def check_turns(turns) -> tuple[float, float]:
    """``(start, stop)`` turns with ``0 <= start < stop <= 1000``, or an InputError."""
    valid = (f"(start, stop) turns with 0 <= start < stop <= "
             f"{checks.MAX_TURNS:g}")
    try:
        start, stop = turns
        start = checks.number("turns", start, 0.0, checks.MAX_TURNS)
        stop = checks.number("turns", stop, 0.0, checks.MAX_TURNS)
    except (TypeError, ValueError):
        raise checks.refuse("turns", f"must be {valid}, got {turns!r}") from None
    if not start < stop:
        raise checks.refuse("turns", f"must be {valid}, got {turns!r}")
    return start, stop
