"""DNA in magnetic tweezers: the inputs in physical units, checked once, and the output keys.

A tweezers run in DNA units is given by the molecule (a :class:`~supercoil.units.dna.DNAPreset`:
base pairs, salt or diameter, temperature), the pulling force in pN, the end's rotation as
turns or as superhelical density, and the number of nodes:

* ``superhelical_density = (start, stop)`` replaces ``turns``: σ = turns / Lk0 with
  Lk0 = N_bp / 10.5, so ``turns = σ · N_bp / 10.5``; exactly one of the two;
* the nodes default to :func:`default_nodes`: n0 (:func:`resolving_nodes`), the fewest
  whose segments are no longer than the tube's diameter D, which the contact of a
  plectoneme's two strands needs (a coarser polygon cannot resolve the ply), raised
  where the force needs more to the fewest whose segments resolve the loop's core
  ``sqrt(A/F)`` (at most a third of it, less under higher tensions:
  :func:`~supercoil.problems.tweezers.options.resolved_core`; a coarser polygon pins the plectoneme's end loop to its
  nodes, buckles late, and its unstable counts are the mesh's: docs/tweezers.md, "DNA
  units");
* the contact curve defaults to :data:`DNA_CONTACT_CURVE`, the quintic B-spline, whose
  self-distance does not ripple with the nodes' phase at segments of D, and the points
  per branch to :data:`DNA_MAX_POINTS` (:func:`dna_numerics`, the one place these
  defaults are applied).

:func:`dna_tweezers_inputs` is the one check of these inputs, shared by the command line
(``supercoil tweezers --dna``), study files (``supercoil run``) and the library
(:meth:`supercoil.Tweezers.from_dna`, :func:`supercoil.tweezers`); every invalid input is an
:class:`~supercoil.errors.InputError` naming it. :func:`tweezers_parameters` gives the
nondimensional numbers of a molecule pulled by a force; :func:`tweezers_point_in_dna_units`
and :func:`tweezers_payload_in_dna_units` add the DNA keys to a point and to a
``branch.json`` payload (the nondimensional keys unchanged).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from supercoil import checks
from supercoil.errors import InputError
from supercoil.units.dna import DNAPreset

SPAN_MEANING = "superhelical density sigma = turns * helical repeat / base pairs"
MAX_FORCE_PN = 1e4
"""The largest pulling force (pN) of the tweezers."""
DNA_CONTACT_CURVE = "quintic"
"""The contact curve of a DNA tweezers run unless one is given (docs/tweezers.md, "DNA
units"). At n0 (segments of D) the ply's strands, of radius about 4.6 D on the 3 kbp
hat curve at 1 pN, are sampled at h = D, where the cubic B-spline's shape moves with the
nodes' phase by O(h^4 kappa^3): its contact force ripples by 2.7 % as the material
slides along the contact, the quintic's by 5e-4 (strands of radius 4.6 D crossing at 3
degrees, ``tests/test_contact_integral.py``). That ripple is the energy of the
plectoneme's sliding, which the continuum leaves free: with the cubic the equilibria of
the discrete rod form a net of growing and sliding branches that the contact branch
follows from one to the other (``supercoil tweezers --dna --bp 3000 --force-pN 1
--salt-mM 150 --sigma 0:0.06`` turned back and forth between 9.07 and 9.22 turns for
1600 points, the sliding's eigenvalue swinging from -3.3e5 to 3e4); with the quintic
it grows the plectoneme to the last turn (docs/performance.md)."""


DNA_MAX_POINTS = 10000
"""The most points on a branch of a DNA tweezers run unless a number is given (the
library's default elsewhere: 2000). Measured at 3 kbp from sigma 0 to 0.06
(``benchmarks/results/long_dna_grid.md``, "DNA preset"), no run needs more than 652
points a branch, but with the barrier's stiffness ``A/h^3`` alone
(``contact_stiffness="bending"``) and the nodes at half the loop's core 0.5 pN / 25 mM
needed 2828 points on its contact branch, 1 pN / 50 mM 2141 and 0.25 pN / 10 mM 2686 on
its held branch, all beyond 2000: a mesh at the edge of the loop's core meets folds of
the snake, about 25 points each. Each point is written as it comes, so a run stopped by a signal keeps them and
``--resume`` continues it."""


def dna_numerics(options: Mapping[str, object]) -> dict:
    """``options`` (of :class:`~supercoil.problems.tweezers.TweezersOptions`) with the DNA
    runs' defaults where not given: the contact curve, :data:`DNA_CONTACT_CURVE`, and the
    points per branch, :data:`DNA_MAX_POINTS`.

    ``loop_sliding`` needs no DNA default: every run takes it where the mesh lets the
    loop slide (``TweezersOptions.loop_sliding = None``). With the sliding's phase row
    the localised loop stays centred up to its contact, and a contact branch that stops
    or closes before the last turn is followed again held on its half-turn symmetry
    from that centred start (:mod:`supercoil.problems.tweezers.mirrored`). Measured on
    3 kbp from sigma 0 to 0.06 (``benchmarks/results/long_dna_grid.md``, "DNA preset"):
    without the row, at 0.25 pN / 200 mM, 0.5 pN / 150 mM and 1 pN / 200 mM the free
    contact branch stopped a few points into its contact, the loop's sliding, driven by
    the turns, setting the tangent. With it, the last two and 1 pN / 150 mM reach sigma
    0.06 on the free contact branch (1 pN / 150 mM in fewer seconds than without), and
    at 0.25 pN / 200 mM the free branch stops after 6 points and the held one reaches
    sigma 0.06.
    """
    return {"contact_curve": DNA_CONTACT_CURVE, "max_points": DNA_MAX_POINTS, **options}


def tweezers_parameters(preset: DNAPreset, force_pN: float) -> dict[str, float]:
    """Nondimensional numbers of a tweezers run: C/A, ``tension`` = F L²/A and L/D.

    ``force_pN`` is the pulling force (pN, >= 0). The molecule's length and
    stiffnesses come from ``preset`` (its superhelical density is not used:
    the turns are the tweezers' own input, σ = turns / Lk0).
    """
    force = checks.number("force_pN", force_pN, 0.0, MAX_FORCE_PN, meaning="a pulling force")
    return {"twist_ratio": preset.twist_ratio, "tension": preset.force_from_pN(force),
            "length_over_diameter": preset.length_over_diameter}


def tweezers_point_in_dna_units(point: dict, preset: DNAPreset) -> dict:
    """A tweezers point (or special point) with DNA-unit keys added, unsuffixed ones kept.

    Adds ``superhelical_density`` (turns / Lk0), ``extension_nm``, ``torque_pN_nm``,
    ``energy_kT``, ``load_potential_kT``, ``force_pN`` (the axial force, from
    ``tension``), ``min_gap_nm`` and, in contact entries, ``force_pN`` /
    ``force_per_length_pN_per_nm``; for jumps, ``extension_after_nm`` and
    ``torque_after_pN_nm``. Keys absent from ``point`` are skipped.
    """
    out = dict(point)

    def add(key, new, convert):
        value = point.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            out[new] = convert(float(value))

    add("turns", "superhelical_density", preset.superhelical_density_of)
    add("extension", "extension_nm", preset.length_to_nm)
    add("extension_after", "extension_after_nm", preset.length_to_nm)
    add("torque", "torque_pN_nm", preset.torque_to_pN_nm)
    add("torque_after", "torque_after_pN_nm", preset.torque_to_pN_nm)
    add("energy", "energy_kT", preset.energy_to_kT)
    add("load_potential", "load_potential_kT", preset.energy_to_kT)
    add("tension", "force_pN", preset.force_to_pN)
    gap = point.get("min_gap_over_diameter")
    if isinstance(gap, (int, float)) and math.isfinite(gap):
        out["min_gap_nm"] = gap * preset.effective_diameter_nm
    if isinstance(point.get("contact_points"), list):
        out["contact_points"] = [{**c, "force_pN": preset.force_to_pN(c["force"])}
                                 for c in point["contact_points"]]
    if isinstance(point.get("contact_intervals"), list):
        out["contact_intervals"] = [
            {**c, "force_per_length_pN_per_nm":
             preset.force_per_length_to_pN_per_nm(c["force_per_length"])}
            for c in point["contact_intervals"]]
    return out


def resolving_nodes(length_over_diameter: float) -> int:
    """n0: the fewest nodes of a clamped rod whose segments are no longer than D.

    The clamped rod of N nodes has edges of length h = L / (N - 2) (its ends are the
    midpoints of the first and last edges, docs/tweezers.md), which is at most
    D = L / (L/D) when N - 2 >= L/D: ``n0 = ceil(L/D) + 2``, and at least the fewest
    nodes of a clamped rod (:data:`supercoil.checks.MIN_CLAMPED_NODES`).
    """
    lod = checks.number("length_over_diameter", length_over_diameter, 0.0,
                        checks.MAX_MAGNITUDE, low_open=True, meaning="L/D")
    return max(checks.MIN_CLAMPED_NODES, math.ceil(lod) + 2)


def default_nodes(length_over_diameter: float, tension: float = 0.0) -> int:
    """The DNA runs' default nodes: ``max(n0, core)``, n0 of :func:`resolving_nodes`
    (segments no longer than D) and, under a tension F L^2/A > 0, the fewest nodes whose
    segments are at most :func:`~supercoil.problems.tweezers.options.resolved_core` times
    the loop's core ``sqrt(A/F)`` (a third up to lambda = 22.6, a quarter at lambda = 80,
    0.22 at 150), which resolve the plectoneme's end loop
    (:func:`~supercoil.problems.tweezers.options.resolved_nodes`; on coarser meshes the
    plectoneme can grow through the mesh's snake, where the unstable counts are the
    mesh's: :mod:`supercoil.problems.tweezers.coarse`)."""
    from supercoil.problems.tweezers.options import resolved_nodes

    n0 = resolving_nodes(length_over_diameter)
    force = checks.number("tension", tension, 0.0, math.inf, meaning="F L^2/A")
    return max(n0, resolved_nodes(force)) if force > 0 else n0


def turns_of_span(preset: DNAPreset, superhelical_density) -> tuple[float, float]:
    """``(start, stop)`` turns of a superhelical density span ``(start, stop)``:
    ``turns = σ · Lk0``. The span is checked: ``0 <= start < stop``, ``stop`` at most 1
    and at most :data:`~supercoil.checks.MAX_TURNS` turns; else an InputError naming
    ``superhelical_density``."""
    highest = min(1.0, checks.MAX_TURNS / preset.relaxed_link)
    valid = (f"(start, stop) with 0 <= start < stop <= {highest:.6g} ({SPAN_MEANING}, "
             f"Lk0 = {preset.relaxed_link:.6g} turns), e.g. (0, 0.06)")
    try:
        start, stop = superhelical_density
        start = checks.number("superhelical_density", start, 0.0, highest)
        stop = checks.number("superhelical_density", stop, 0.0, highest)
    except (TypeError, ValueError):
        raise checks.refuse("superhelical_density",
                            f"must be {valid}, got {superhelical_density!r}") from None
    if not start < stop:
        raise checks.refuse("superhelical_density",
                            f"must be {valid}, got {superhelical_density!r}")
    return start * preset.relaxed_link, stop * preset.relaxed_link


def span_in_turns(preset: DNAPreset, turns=None, superhelical_density=None,
                  default: tuple[float, float] | None = None) -> tuple[float, float]:
    """The end's rotation ``(start, stop)`` in turns from exactly one of ``turns`` and
    ``superhelical_density`` (:func:`turns_of_span`); with neither, ``default`` (None: an
    InputError). The turns themselves are checked by the tweezers' options."""
    if turns is not None and superhelical_density is not None:
        raise InputError("superhelical_density and turns both give the end's rotation: give "
                         f"one of them (turns, or sigma = turns * {preset.helical_repeat_bp:g}"
                         f" / {preset.base_pairs} bp)", name="superhelical_density")
    if superhelical_density is not None:
        return turns_of_span(preset, superhelical_density)
    if turns is None:
        if default is None:
            raise InputError("turns is missing: give the end's rotation as turns (start, "
                             "stop) or as superhelical_density (start, stop)", name="turns")
        turns = default
    return tuple(turns)


def dna_tweezers_inputs(preset: DNAPreset, force_pN: float, *, turns=None,
                        superhelical_density=None, n_nodes: int | None = None,
                        default_turns: tuple[float, float] | None = None) -> dict:
    """The nondimensional inputs of a DNA tweezers run, checked.

    ``force_pN``: the pulling force (pN, >= 0); ``turns`` or ``superhelical_density``:
    the end's rotation ``(start, stop)`` (exactly one; with neither, ``default_turns``);
    ``n_nodes``: None for :func:`default_nodes` of the molecule's L/D and the force.

    Returns ``twist_ratio``, ``tension`` (F L^2/A), ``length_over_diameter``, ``turns``
    (start, stop) and ``n_nodes``; an InputError naming the input otherwise.
    """
    if not isinstance(preset, DNAPreset):
        raise InputError(f"dna: expected a supercoil.DNAPreset, got {preset!r}", name="dna")
    out = tweezers_parameters(preset, force_pN)
    out["turns"] = span_in_turns(preset, turns, superhelical_density, default_turns)
    out["n_nodes"] = nodes_or_default(n_nodes, out["length_over_diameter"], out["tension"])
    return out


def nodes_or_default(n_nodes: int | None, length_over_diameter: float,
                     tension: float = 0.0) -> int:
    """``n_nodes`` checked (a clamped rod's), or :func:`default_nodes` of
    ``length_over_diameter`` and ``tension`` when None; an InputError naming ``n_nodes``
    when the default is too many."""
    if n_nodes is None:
        n_nodes = default_nodes(length_over_diameter, tension)
        if n_nodes > checks.MAX_NODES:
            raise checks.refuse("n_nodes", f"(the default {n_nodes}: segments no longer "
                                f"than D at L/D = {length_over_diameter:.6g} and short "
                                f"enough to resolve the loop's core at F L^2/A = "
                                f"{tension:.6g}) exceeds "
                                f"the largest number of nodes, {checks.MAX_NODES}; give the "
                                "nodes, fewer base pairs, a larger diameter or a smaller force")
    return checks.integer("n_nodes", n_nodes, checks.MIN_CLAMPED_NODES, checks.MAX_NODES,
                          meaning="nodes of the clamped rod")


def dna_attributes(preset: DNAPreset, force_pN: float | None = None) -> dict:
    """The scalar attributes of a result file in DNA units (what the figures read:
    :mod:`supercoil.plotting.dna`): ``base_pairs``, ``length_nm``, ``diameter_nm``,
    ``relaxed_link``, ``temperature_K``, ``salt_mM`` (when D comes from it), the scales
    ``force_scale_pN`` and ``torque_scale_pN_nm`` and, given, ``force_pN``."""
    out = {"base_pairs": preset.base_pairs, "length_nm": preset.length_nm,
           "diameter_nm": preset.effective_diameter_nm, "relaxed_link": preset.relaxed_link,
           "temperature_K": float(preset.temperature_K),
           "force_scale_pN": preset.force_scale_pN,
           "torque_scale_pN_nm": preset.torque_scale_pN_nm}
    if preset.salt_mM is not None:
        out["salt_mM"] = float(preset.salt_mM)
    if force_pN is not None:
        out["force_pN"] = float(force_pN)
    return out


def tweezers_payload_in_dna_units(payload: dict, preset: DNAPreset, force_pN: float) -> dict:
    """A ``branch.json`` payload with the DNA keys added; the nondimensional keys unchanged.

    Every entry of ``points``, ``special_points`` and ``path`` gains the keys of
    :func:`tweezers_point_in_dna_units` (``superhelical_density``,
    ``extension_nm``, ``torque_pN_nm``, ...). Added at the top: ``base_pairs``,
    ``length_nm``, ``diameter_nm``, ``salt_mM`` (None when D was given),
    ``temperature_K``, ``force_pN``, ``relaxed_link``, the scales ``force_scale_pN``
    (A/L^2) and ``torque_scale_pN_nm`` (A/L), ``superhelical_density_range`` (the
    ``turns_range`` over Lk0) and ``greenhill_superhelical_density``. The athermal
    caveat is the envelope's (``conventions.athermal``, from
    :meth:`~supercoil.units.dna.DNAPreset.conventions`), stated there once.
    """
    out = dict(payload)
    for key in ("points", "special_points", "path"):
        if isinstance(out.get(key), list):
            out[key] = [tweezers_point_in_dna_units(p, preset) for p in out[key]]
    out.update(base_pairs=preset.base_pairs, length_nm=preset.length_nm,
               diameter_nm=preset.effective_diameter_nm,
               salt_mM=None if preset.salt_mM is None else float(preset.salt_mM),
               temperature_K=float(preset.temperature_K), force_pN=float(force_pN),
               relaxed_link=preset.relaxed_link, force_scale_pN=preset.force_scale_pN,
               torque_scale_pN_nm=preset.torque_scale_pN_nm)
    if isinstance(payload.get("turns_range"), (list, tuple)):
        out["superhelical_density_range"] = [preset.superhelical_density_of(t)
                                              for t in payload["turns_range"]]
    greenhill = payload.get("greenhill_turns")
    if isinstance(greenhill, (int, float)):
        out["greenhill_superhelical_density"] = preset.superhelical_density_of(greenhill)
    ply = payload.get("hard_core_ply")
    if isinstance(ply, dict):
        out["ply_spanning_superhelical_density"] = preset.superhelical_density_of(
            ply["spanning_turns"])
        out["ply_torque_pN_nm"] = ply["torque"] * preset.torque_scale_pN_nm
    return out


__all__ = [
    "MAX_FORCE_PN",
    "SPAN_MEANING",
    "default_nodes",
    "dna_attributes",
    "dna_tweezers_inputs",
    "nodes_or_default",
    "resolving_nodes",
    "span_in_turns",
    "turns_of_span",
    "tweezers_parameters",
    "tweezers_payload_in_dna_units",
    "tweezers_point_in_dna_units",
]
