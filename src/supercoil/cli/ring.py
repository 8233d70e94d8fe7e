"""``supercoil ring``: one equilibrium of a closed twisted ring and its stability.

Thin: parses the options, builds ``supercoil.Ring(supercoil.Rod(...), excess_link,
contact=...)`` (which validates them), calls :func:`supercoil.equilibrium`, and
prints its record as a table, writes it as JSON (``--json``) or as a result folder
(``--out``, :mod:`supercoil.cli.ring_output`). ``--dna`` reads the ring in DNA
units (:class:`supercoil.DNAPreset`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    check_json_target,
    checked_path,
    fail,
    parse_ratio,
    refused,
    warn,
    warning_in,
    write_json_or_fail,
)
from supercoil.cli._options import MAGNITUDE, JsonOption, exponent, overwrite_option, quiet_option
from supercoil.cli.model_options import (
    ModelOption,
    ShearOption,
    StretchOption,
    check_model,
    make_rod,
)
from supercoil.contact.options import DEFAULT_TREATMENT, TREATMENTS, ContactOptions
from supercoil.units.dna import (
    BENDING_PERSISTENCE_NM,
    DEFAULT_SALT_MM,
    HELICAL_REPEAT_BP,
    KT_REFERENCE_PN_NM,
    REFERENCE_TEMPERATURE_K,
    RISE_NM_PER_BP,
    SALT_RANGE_MM,
    TWIST_PERSISTENCE_NM,
)

# the library's names of the ring's inputs -> the options of 'supercoil ring'
RING_OPTIONS = {"twist_ratio": "--twist-ratio", "excess_link": "--excess-link",
                "nodes": "--nodes", "length_over_diameter": "--length-over-diameter",
                "treatment": "--contact", "stretch_stiffness": "--stretch-stiffness",
                "shear_stiffness": "--shear-stiffness"}
DNA_OPTIONS = {"base_pairs": "--bp", "superhelical_density": "--sigma",
               "salt_mM": "--salt-mM", "diameter_nm": "--diameter-nm",
               "temperature_K": "--temperature-K",
               "twist_persistence_nm": "--twist-persistence-nm", "force_pN": "--force-pN"}
_CONTACT_DEFAULTS = ContactOptions(diameter=1.0)  # the default tolerances, for the help
_TREATMENT_HELP = {
    "barrier": f"a barrier potential on gaps below {exponent(_CONTACT_DEFAULTS.barrier_activation)}"
    " D that never lets the tube touch (its forces are the contact forces)",
    "augmented": "augmented Lagrangian (penalty plus multiplier updates), penetration below "
    f"{exponent(_CONTACT_DEFAULTS.penetration_tolerance)} D",
    "penalty": "quadratic penalty, which carries a force F only through a penetration F/k; "
    f"k is raised until the penetration is below {exponent(_CONTACT_DEFAULTS.penalty_tolerance)}"
    " D",
    "exact": "inequality constraints with an active set: the tube touches (penetration "
    f"below {exponent(_CONTACT_DEFAULTS.penetration_tolerance)} D) and the contact forces are "
    "the multipliers",
}


def contact_help() -> str:
    """The help of ``--contact``: every treatment with the library's default tolerances."""
    parts = "; ".join(f"{name} = {_TREATMENT_HELP[name]}" for name in TREATMENTS)
    return (
        f"How impenetrability is imposed (only with --length-over-diameter or --dna): {parts}. "
        f"Default: {DEFAULT_TREATMENT}."
    )


def _dna_option(name: str, metavar: str, help: str, kind=float):
    return Annotated[kind | None, typer.Option(name, metavar=metavar, help=help,
                                               show_default=False)]


BasePairs = _dna_option("--bp", "N", f"With --dna: number of base pairs, "
                        f"{checks.MIN_BASE_PAIRS} to {checks.MAX_BASE_PAIRS}; contour length "
                        f"L = {RISE_NM_PER_BP:g} nm per bp.", int)
Sigma = _dna_option("--sigma", "S", "With --dna: superhelical density sigma = dLk / Lk0 with "
                    f"Lk0 = bp / {HELICAL_REPEAT_BP:g} turns, from -1 to 1 (negative = "
                    "underwound, e.g. -0.06).")
Salt = _dna_option("--salt-mM", "MM", "With --dna: monovalent salt (NaCl) in mM, from "
                   f"{SALT_RANGE_MM[0]:g} to {SALT_RANGE_MM[1]:g} (default {DEFAULT_SALT_MM:g}); "
                   "sets the effective diameter D from an approximate table after Rybenkov "
                   "et al. 1993 (docs/units.md).")
DiameterNm = _dna_option("--diameter-nm", "D", "With --dna: the effective diameter D in nm "
                         "(> 0), instead of --salt-mM.")
Temperature = _dna_option("--temperature-K", "T", "With --dna: temperature in kelvin (> 0, "
                          f"default {REFERENCE_TEMPERATURE_K:g}) of the kT unit, kT = "
                          f"{KT_REFERENCE_PN_NM:g} pN nm * T / {REFERENCE_TEMPERATURE_K:g}; "
                          f"the stiffnesses stay those of {REFERENCE_TEMPERATURE_K:g} K.")
TwistPersistence = _dna_option("--twist-persistence-nm", "P_T", "With --dna: twist persistence "
                               f"length in nm (> 0, default {TWIST_PERSISTENCE_NM:g}; "
                               "published estimates about 75-120).")
Quiet = quiet_option("Print no table on standard output (the JSON of --json - still); "
                     "warnings and errors still go to standard error.")
Overwrite = overwrite_option("With --out: write into an existing non-empty DIR, replacing "
                             "this command's files (other files are left alone).")


def ring(
    twist_ratio: Annotated[float | None, typer.Option(
        "--twist-ratio", metavar="C/A", parser=parse_ratio,
        help=f"Twist stiffness over bending stiffness, 0 < C/A <= {MAGNITUDE} (dimensionless; "
        "1/(1 + Poisson ratio) for an isotropic elastic rod; "
        f"{TWIST_PERSISTENCE_NM:g}/{BENDING_PERSISTENCE_NM:g} = "
        f"{TWIST_PERSISTENCE_NM / BENDING_PERSISTENCE_NM:g} for DNA with --dna). Required "
        "unless --dna.", show_default=False)] = None,
    excess_link: Annotated[float | None, typer.Option(
        "--excess-link", metavar="TURNS",
        help="Excess linking number dLk = Lk - Lk0 of the closed rod, in turns (positive = "
        f"right-handed, overwinding for DNA; |dLk| <= {MAGNITUDE}). Required unless --dna.",
        show_default=False)] = None,
    nodes: Annotated[int, typer.Option(
        "--nodes", metavar="N",
        help=f"Number of nodes (vertices) of the discrete ring, {checks.MIN_NODES} <= N <= "
        f"{checks.MAX_NODES}; the discretisation error falls as 1/N^2.")] = 100,
    length_over_diameter: Annotated[float | None, typer.Option(
        "--length-over-diameter", metavar="L/D",
        help=f"Rod length over tube diameter, pi < L/D <= {MAGNITUDE}: switches on "
        "self-contact. Above Michell's threshold the ring leaves the circle for a "
        "supercoiled equilibrium that never passes through itself.",
        show_default=False)] = None,
    contact: Annotated[str | None, typer.Option(
        "--contact", metavar="TREATMENT", help=contact_help(), show_default=False)] = None,
    initial: Annotated[Path | None, typer.Option(
        "--initial", metavar="PATH",
        help="Start from the closed curve in PATH instead of the circle (the format of "
        "'supercoil writhe': one vertex 'x y z' per line, each vertex once, the last joined "
        "to the first; at least 3 vertices). The curve is scaled to length L = 1 and "
        "resampled at --nodes equally spaced points, so its size in the file does not "
        "matter; its knot type is kept. Needs --length-over-diameter (or --dna), and the "
        "resampled curve must not penetrate itself (non-neighbouring points at least D "
        "apart). The excess link counts as for the circle (twist = dLk - writhe), so a knot "
        "of writhe about W carries little twist only near --excess-link W (a trefoil: about "
        "+3 or -3).", show_default=False, callback=checked_path)] = None,
    knot: Annotated[str | None, typer.Option(
        "--knot", metavar="NAME",
        help="Start from a smooth embedding of this knot instead of the circle: 3_1, 4_1, "
        "5_1, 5_2, 7_1 or 8_19 (a trailing '*' for the mirror image), scaled to length "
        "L = 1 and tightened (continuation in L/D downward) until it is free of overlap at "
        "--length-over-diameter, which it needs. The knot type is kept at every step and "
        "reported (knot_type, chirality).", show_default=False)] = None,
    torus_knot: Annotated[str | None, typer.Option(
        "--torus-knot", metavar="P,Q",
        help="As --knot, the torus knot T(P,Q) (coprime P, Q; a negative one for the mirror "
        "image): 2,3 is the right-handed trefoil, 2,5 the knot 5_1.",
        show_default=False)] = None,
    dna: Annotated[bool, typer.Option(
        "--dna",
        help="DNA units instead of --twist-ratio/--excess-link/--length-over-diameter: the "
        "plasmid is given by --bp and --sigma; C/A = "
        f"{TWIST_PERSISTENCE_NM:g}/{BENDING_PERSISTENCE_NM:g} (twist/bending persistence "
        f"lengths), dLk = sigma * bp / {HELICAL_REPEAT_BP:g}, tube diameter D from --salt-mM "
        f"(default {DEFAULT_SALT_MM:g} mM) or --diameter-nm, so self-contact is always on; "
        "the JSON adds keys in nm, kT and pN and its units become 'dna'. The model is "
        "athermal (zero temperature).")] = False,
    bp: BasePairs = None,
    sigma: Sigma = None,
    salt_mM: Salt = None,
    diameter_nm: DiameterNm = None,
    temperature_K: Temperature = None,
    twist_persistence_nm: TwistPersistence = None,
    model: ModelOption = "kirchhoff",
    stretch_stiffness: StretchOption = None,
    shear_stiffness: ShearOption = None,
    json_path: JsonOption = None,
    out: Annotated[Path | None, typer.Option(
        "--out", metavar="DIR", help="Also write the result into folder DIR: result.h5 (the "
        "state, read with supercoil.load) and ring.json; an existing non-empty DIR is "
        "refused unless --overwrite.", show_default=False, callback=checked_path)] = None,
    overwrite: Overwrite = False,
    quiet: Quiet = False,
) -> None:
    """Equilibrium of a closed twisted ring and its stability.

    Starts from the circle (length L = 1) twisted by the excess link and
    reports energy (E*L/A), twist and writhe (turns), |Tw + Wr - dLk| from
    independent computations, and the unstable count. The circle loses
    stability at Michell's thresholds dLk = (A/C) sqrt(m^2 - 1), m = 2, 3, ...;
    without --length-over-diameter it is then reported as an unstable
    equilibrium; with it, the ring leaves the circle for a stable supercoiled
    state with self-contact (contacts, contact points and intervals, closest
    approach); a state that is not stable exits with status 1. With --initial
    the ring is relaxed from a given closed curve instead, with --knot or
    --torus-knot from a knot; the knot type is kept and reported.

    With --dna the ring is a DNA plasmid: --bp N base pairs at superhelical
    density --sigma S, in monovalent salt --salt-mM (tube diameter D); the
    output adds energies in kT, lengths in nm and contact forces in pN. The
    model is athermal: energies and writhes are those of the elastic minimum,
    not thermal averages.
    """
    check_model(model, stretch_stiffness, shear_stiffness)
    if model == "cosserat":
        for option, value in (("--initial", initial), ("--knot", knot),
                              ("--torus-knot", torus_knot)):
            if value is not None:
                fail(f"{option} is not available with --model cosserat (the sections' frames "
                     "are unknowns too: the ring is wound from the circle); drop it, or use "
                     "--model kirchhoff")
    preset = None
    if dna:
        preset = _dna_preset(twist_ratio, excess_link, length_over_diameter, bp, sigma,
                             salt_mM, diameter_nm, temperature_K, twist_persistence_nm)
        twist_ratio, excess_link = preset.twist_ratio, preset.excess_link
        length_over_diameter = preset.length_over_diameter
    else:
        _check_plain(twist_ratio, excess_link, bp, sigma, salt_mM, diameter_nm, temperature_K,
                     twist_persistence_nm)
    given = [o for o, v in (("--initial", initial), ("--knot", knot),
                            ("--torus-knot", torus_knot)) if v is not None]
    if len(given) > 1:
        fail(f"{' and '.join(given)} both give the starting curve; give one of them")
    for option, value in (("--contact", contact), ("--initial", initial), ("--knot", knot),
                          ("--torus-knot", torus_knot)):
        if value is not None and length_over_diameter is None:
            fail(f"{option} needs --length-over-diameter L/D (self-contact of a tube of "
                 "diameter D = L/(L/D)); give it, e.g. --length-over-diameter 100")
    treatment = DEFAULT_TREATMENT if contact is None else contact
    check_json_target(json_path)
    if overwrite and out is None:
        fail("--overwrite needs --out DIR (the folder whose files it replaces)")
    if out is not None:
        from supercoil.cli.saving import prepare_folder

        prepare_folder(out, overwrite=overwrite, resume=False, what="the ring's files",
                       create=False)
    names = dict(RING_OPTIONS)
    initial_points = None
    if initial is not None:
        from supercoil.io.curves import read_curve

        with refused(prefix="--initial: "):
            initial_points = read_curve(initial)
        names["initial"] = names["initial_points"] = f"--initial {initial}"

    knot_given = knot if torus_knot is None else f"T({torus_knot})"
    if knot_given is not None:
        names["knot"] = f"--knot {knot}" if torus_knot is None else f"--torus-knot {torus_knot}"

    from supercoil import Ring, equilibrium
    from supercoil.api.model import contact_from_name

    with refused(names):
        rod = make_rod(model, twist_ratio, nodes, stretch_stiffness, shear_stiffness,
                       slenderness=length_over_diameter, preset=preset)
        problem = Ring(rod, excess_link,
                       contact=None if length_over_diameter is None else
                       contact_from_name(treatment, length_over_diameter),
                       initial=initial_points, knot=knot_given)
        state = equilibrium(problem)
    # an inextensible, unshearable rod: no stretch and no shear
    summary = {"model": "kirchhoff", "max_stretch_strain": 0.0, "max_shear_strain": 0.0,
               **state.record}
    start_curve = (str(initial) if initial is not None
                   else None if knot_given is None else f"knot {knot_given}")
    if preset is not None:
        from supercoil.units.dna import ring_summary_in_dna_units

        summary = ring_summary_in_dna_units(summary, preset)
    if json_path is not None or out is not None:
        from supercoil.cli.ring_output import ring_document, write_ring_folder

        data = ring_document(state, summary, preset,
                             initial=start_curve)
        if json_path is not None:
            write_json_or_fail(data, json_path)
        if out is not None:
            write_ring_folder(out, state, summary, data, preset)
            if json_path != "-" and not quiet:
                print(f"wrote result.h5 and ring.json to {out.resolve()}")
    if json_path != "-" and not quiet:
        from rich.console import Console

        from supercoil.cli._format import ring_table

        Console().print(ring_table(summary, initial=start_curve))
    warning = warning_in(summary.get("message"))
    if warning is not None:
        warn(warning)
    if not summary["converged"]:
        where = (
            f"the last state was written to {json_path}"
            if json_path not in (None, "-")
            else "the last state was written to standard output"
            if json_path == "-"
            else "pass --json PATH to save the last state"
        )
        warn(
            f"not converged: Newton stopped with status {summary['status']} "
            f"({summary['message']}); {where}"
        )
        raise typer.Exit(EXIT_NOT_CONVERGED)
    if length_over_diameter is not None and summary["unstable_count"] > 0:
        # with contact the answer is the state of a slow winding: a saddle is a failure
        warn(f"unstable: the state reached has {summary['unstable_count']} negative "
             f"eigenvalue(s) ({summary['message']})")
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _check_plain(twist_ratio, excess_link, *dna_values) -> None:
    """Without --dna: no DNA option, and both --twist-ratio and --excess-link."""
    given = [option for option, value in zip(("--bp", "--sigma", "--salt-mM", "--diameter-nm",
                                              "--temperature-K", "--twist-persistence-nm"),
                                             dna_values, strict=True) if value is not None]
    if given:
        verb = "needs" if len(given) == 1 else "need"
        fail(f"{', '.join(given)} {verb} --dna (DNA units); give --dna --bp N --sigma S, "
             "or drop them and give --twist-ratio and --excess-link")
    for option, value, meaning in (("--twist-ratio", twist_ratio, "C/A"),
                                   ("--excess-link", excess_link, "turns")):
        if value is None:
            fail(f"Missing option '{option}' ({meaning}); give --twist-ratio C/A "
                 "--excess-link TURNS, or DNA units --dna --bp N --sigma S "
                 "(see 'supercoil ring --help')")


def _dna_preset(twist_ratio, excess_link, length_over_diameter, bp, sigma, salt_mM,
                diameter_nm, temperature_K, twist_persistence_nm):
    """The DNA preset of ``ring --dna``, or a one-line error (exit 2) naming the option."""
    mixed = [option for option, value in (("--twist-ratio", twist_ratio),
                                          ("--excess-link", excess_link),
                                          ("--length-over-diameter", length_over_diameter))
             if value is not None]
    if mixed:
        fail(f"{', '.join(mixed)} cannot be combined with --dna: in DNA units the ring is "
             "given by --bp N and --sigma S (C/A, dLk and L/D follow from the preset); drop "
             f"{', '.join(mixed)}, or drop --dna")
    missing = [option for option, value in (("--bp N (base pairs)", bp),
                                            ("--sigma S (superhelical density)", sigma))
               if value is None]
    if missing:
        fail(f"--dna needs {' and '.join(missing)}, e.g. supercoil ring --dna --bp 3000 "
             "--sigma -0.06")
    if salt_mM is not None and diameter_nm is not None:
        fail("--salt-mM and --diameter-nm both set the tube diameter; give one of them")
    from supercoil import DNAPreset

    options = {"salt_mM": salt_mM, "diameter_nm": diameter_nm}
    if temperature_K is not None:
        options["temperature_K"] = temperature_K
    if twist_persistence_nm is not None:
        options["twist_persistence_nm"] = twist_persistence_nm
    with refused(DNA_OPTIONS):
        return DNAPreset(base_pairs=bp, superhelical_density=sigma, **options)
