"""The ``supercoil`` command: thin, no numerics (parse, call the API, format, write).

The commands parse their options and construct the library's options and problems,
which validate them: an :class:`~supercoil.errors.InputError` becomes the command's
``error:`` line (exit 2), with the library's name of the input replaced by the option.
"""

from __future__ import annotations

import errno
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from supercoil import __version__, checks
from supercoil.cli._common import (
    EXIT_BAD_INPUT,
    EXIT_NOT_CONVERGED,
    FORMULATION_HELP,
    check_json_target,
    checked_path,
    fail,
    parse_ratio,
    parse_vector,
    raised_while_solving,
    refused,
    warn,
    warning_in,
    write_json_or_fail,
)
from supercoil.contact.problem import DEFAULT_TREATMENT, TREATMENTS, ContactOptions
from supercoil.errors import InputError
from supercoil.problems.ring_diagram import CONTINUATION_TREATMENTS, MAX_MODE
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

UNITS_NOTE = (
    "Units are nondimensional: bending stiffness A = 1 and rod length L = 1, so energies are "
    "E*L/A, forces F*L^2/A, torques M*L/A; the twist ratio is C/A; link, twist and writhe "
    "are in turns (positive = right-handed). 'ring --dna' takes DNA units instead (base pairs, "
    "superhelical density, salt in mM) and adds nm, kT and pN to its output."
)

app = typer.Typer(
    name="supercoil",
    help="Equilibria and stability of elastic rods (Kirchhoff rods, closed rings, writhe). "
    + UNITS_NOTE
    + " Exit status: 0 done, 1 computed but not converged, 2 bad input.",
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)

# the first run's compilation, measured: 'supercoil demo' on a fresh install
COMPILE_TIME = "1 to 2 minutes"
CLOSURES = ("closed", "none", "chord", "axis")
NEWTON_TOLERANCE = 1e-10
CONTACT_NEWTON_TOLERANCE = 1e-9  # residual of the contact solves (the default of the API)
_CONTACT_DEFAULTS = ContactOptions(diameter=1.0)  # the default tolerances, for the help
_MAGNITUDE = f"{checks.MAX_MAGNITUDE:.0e}".replace("e+0", "e")  # 1e6, as the help says it
# the library's names of the ring's inputs -> the options of 'supercoil ring'
RING_OPTIONS = {"twist_ratio": "--twist-ratio", "excess_link": "--excess-link",
                "n_nodes": "--nodes", "length_over_diameter": "--length-over-diameter",
                "treatment": "--contact"}
DNA_OPTIONS = {"base_pairs": "--bp", "superhelical_density": "--sigma",
               "salt_mM": "--salt-mM", "diameter_nm": "--diameter-nm",
               "temperature_K": "--temperature-K",
               "twist_persistence_nm": "--twist-persistence-nm", "force_pN": "--force-pN"}
DIAGRAM_OPTIONS = {"twist_ratio": "--twist-ratio",
                   "length_over_diameter": "--length-over-diameter", "n_nodes": "--nodes",
                   "modes": "--modes", "max_excess_link": "--max-excess-link",
                   "contact": "--contact", "branch_depth": "--branch-depth",
                   "contact_curve": "--contact-curve",
                   "contact_formulation": "--contact-formulation",
                   "contact_max_points": "--contact-max-points",
                   "secondary_max_points": "--secondary-max-points",
                   "secondary_max_branches": "--secondary-max-branches"}


def _e(value: float) -> str:
    """``1e-4`` rather than ``0.0001`` (``:g``) or ``1e-04`` (``:.0e``)."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


_TREATMENT_HELP = {
    "barrier": f"a barrier potential on gaps below {_e(_CONTACT_DEFAULTS.barrier_activation)} "
    "D that never lets "
    "the tube touch (its forces are the contact forces)",
    "augmented": "augmented Lagrangian (penalty plus multiplier updates), penetration below "
    f"{_e(_CONTACT_DEFAULTS.penetration_tolerance)} D",
    "penalty": "quadratic penalty, which carries a force F only through a penetration F/k; "
    f"k is raised until the penetration is below {_e(_CONTACT_DEFAULTS.penalty_tolerance)} D",
    "exact": "inequality constraints with an active set: the tube touches (penetration "
    f"below {_e(_CONTACT_DEFAULTS.penetration_tolerance)} D) and the contact forces are the "
    "multipliers",
}


def _contact_help() -> str:
    parts = "; ".join(f"{name} = {_TREATMENT_HELP[name]}" for name in TREATMENTS)
    return (
        f"How impenetrability is imposed (only with --length-over-diameter or --dna): {parts}. "
        f"Default: {DEFAULT_TREATMENT}."
    )


JsonOption = Annotated[
    str | None,
    typer.Option(
        "--json",
        metavar="PATH",
        help="Write the machine-readable result as JSON to PATH ('-' = standard output, "
        "which suppresses the human-readable output). The file carries schema_version, "
        "units, conventions and provenance.",
    ),
]


def _version_callback(value: bool) -> None:
    if value:
        print(f"supercoil {__version__}")
        raise typer.Exit()


def _help_without_command(ctx: typer.Context) -> None:
    """A group called without a command: its help, exit status 2."""
    if ctx.invoked_subcommand is None:
        print(ctx.get_help())
        raise typer.Exit(EXIT_BAD_INPUT)


@app.callback(invoke_without_command=True)
def _root(
    ctx: typer.Context,
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_version_callback,
            is_eager=True,
            help="Print the supercoil version and exit.",
        ),
    ] = False,
) -> None:
    """Equilibria and stability of elastic rods."""
    _help_without_command(ctx)


# --------------------------------------------------------------------- writhe


@app.command()
def writhe(
    file: Annotated[
        Path,
        typer.Argument(
            metavar="FILE",
            help="Text file of the curve: one vertex 'x y z' per line (spaces, tabs or "
            "commas), each vertex once (a closed curve does not repeat its first vertex); "
            "'#' starts a comment; blank lines are ignored. Any length unit: the writhe is "
            "scale-free.",
            show_default=False, callback=checked_path
        ),
    ],
    closure: Annotated[
        str,
        typer.Option(
            "--closure",
            metavar="closed|none|chord|axis",
            help="How the curve is closed before the Gauss integral: 'closed' = closed "
            "polygon (last vertex joined to the first); 'none' = the open polygon alone (not "
            "a topological quantity); 'chord' = open curve closed by the straight chord "
            "from its last vertex to its first; 'axis' = open curve closed by straight "
            "semi-infinite tails along --axis (magnetic-tweezers convention).",
        ),
    ] = "closed",
    axis: Annotated[
        str | None,
        typer.Option(
            "--axis",
            metavar="X,Y,Z",
            help="Direction of the tails for --closure axis (normalised; the first vertex "
            "continues along -axis, the last along +axis). Default 0,0,1. Only with "
            "--closure axis: giving it with another closure is an error.",
            show_default=False,
        ),
    ] = None,
    json_path: JsonOption = None,
) -> None:
    """Writhe of a polygonal curve (turns; a right-handed helix has positive writhe).

    Exact Gauss double integral of the polygon, in its solid-angle (atan2) form.
    """
    if closure not in CLOSURES:
        fail(f"--closure {closure!r} is unknown; valid closures are {', '.join(CLOSURES)}")
    if axis is not None and closure != "axis":
        fail(
            f"--axis {axis} is only used with --closure axis, but --closure is {closure!r}; "
            "drop --axis, or give --closure axis"
        )
    if axis is None:
        axis = "0,0,1"
    direction = parse_vector("--axis", axis)
    check_json_target(json_path)

    from supercoil.io.curves import read_curve
    from supercoil.topology import writhe as compute_writhe

    with refused({"points": f"curve file {file}", "axis": "--axis", "closure": "--closure"}):
        points = read_curve(file)
        value = compute_writhe(points, closure=closure, axis=direction)

    payload = {"writhe": value, "n_nodes": len(points), "closure": closure}
    if closure == "axis":
        payload["axis"] = list(direction)
    if json_path is not None:
        from supercoil.io.results import envelope

        data = envelope(payload, n_nodes=len(points), tolerances={})
        write_json_or_fail(data, json_path)
    if json_path != "-":
        tail = f", axis {axis}" if closure == "axis" else ""
        print(f"writhe {value:.15g}  ({len(points)} vertices, closure {closure}{tail})")


# ----------------------------------------------------------------------- ring


@app.command()
def ring(
    twist_ratio: Annotated[
        float | None,
        typer.Option(
            "--twist-ratio",
            metavar="C/A",
            parser=parse_ratio,
            help=f"Twist stiffness over bending stiffness, 0 < C/A <= {_MAGNITUDE} (dimensionless; "
            "1/(1 + Poisson ratio) for an isotropic elastic rod; "
            f"{TWIST_PERSISTENCE_NM:g}/{BENDING_PERSISTENCE_NM:g} = "
            f"{TWIST_PERSISTENCE_NM / BENDING_PERSISTENCE_NM:g} for DNA with --dna). Required "
            "unless --dna.",
            show_default=False,
        ),
    ] = None,
    excess_link: Annotated[
        float | None,
        typer.Option(
            "--excess-link",
            metavar="TURNS",
            help="Excess linking number dLk = Lk - Lk0 of the closed rod, in turns "
            f"(positive = right-handed, overwinding for DNA; |dLk| <= {_MAGNITUDE}). Required "
            "unless "
            "--dna.",
            show_default=False,
        ),
    ] = None,
    nodes: Annotated[
        int,
        typer.Option(
            "--nodes",
            metavar="N",
            help=f"Number of nodes (vertices) of the discrete ring, {checks.MIN_NODES} <= N <= "
            f"{checks.MAX_NODES}; the "
            "discretisation error falls as 1/N^2.",
        ),
    ] = 100,
    length_over_diameter: Annotated[
        float | None,
        typer.Option(
            "--length-over-diameter",
            metavar="L/D",
            help="Rod length over tube diameter (L/D > pi): switches on self-contact. "
            "Above Michell's threshold the circle is pushed off along its lowest mode and "
            "relaxed to a supercoiled equilibrium that never passes through itself.",
            show_default=False,
        ),
    ] = None,
    contact: Annotated[
        str | None,
        typer.Option(
            "--contact",
            metavar="TREATMENT",
            help=_contact_help(),
            show_default=False,
        ),
    ] = None,
    initial: Annotated[
        Path | None,
        typer.Option(
            "--initial",
            metavar="PATH",
            help="Start from the closed curve in PATH instead of the circle (the format "
            "of 'supercoil writhe': one vertex 'x y z' per line, each vertex once, the "
            "last joined to the first; at least 3 vertices). The curve is scaled to "
            "length L = 1 and resampled at --nodes equally spaced points, so its size in "
            "the file does not matter; its knot type is kept. Needs "
            "--length-over-diameter (or --dna), and the resampled curve must not penetrate "
            "itself (non-neighbouring points at least D apart). The excess link counts as for "
            "the circle (twist = dLk - writhe), so a knot of writhe about W carries "
            "little twist only near --excess-link W (a trefoil: about +3 or -3).",
            show_default=False, callback=checked_path
        ),
    ] = None,
    dna: Annotated[
        bool,
        typer.Option(
            "--dna",
            help="DNA units instead of --twist-ratio/--excess-link/--length-over-diameter: "
            "the plasmid is given by --bp and --sigma; C/A = "
            f"{TWIST_PERSISTENCE_NM:g}/{BENDING_PERSISTENCE_NM:g} (twist/bending persistence "
            f"lengths), dLk = sigma * bp / {HELICAL_REPEAT_BP:g}, tube diameter D from "
            f"--salt-mM (default {DEFAULT_SALT_MM:g} mM) or --diameter-nm, so self-contact is "
            "always on; the JSON adds keys in nm, kT and "
            "pN and its units become 'dna'. The model is athermal (zero temperature).",
        ),
    ] = False,
    bp: Annotated[
        int | None,
        typer.Option("--bp", metavar="N", help="With --dna: number of base pairs (>= 1); "
                     f"contour length L = {RISE_NM_PER_BP:g} nm per bp.", show_default=False),
    ] = None,
    sigma: Annotated[
        float | None,
        typer.Option("--sigma", metavar="S", help="With --dna: superhelical density "
                     f"sigma = dLk / Lk0 with Lk0 = bp / {HELICAL_REPEAT_BP:g} turns "
                     "(negative = underwound, "
                     "e.g. -0.06).", show_default=False),
    ] = None,
    salt_mM: Annotated[
        float | None,
        typer.Option("--salt-mM", metavar="MM", help="With --dna: monovalent salt (NaCl) "
                     f"in mM, from {SALT_RANGE_MM[0]:g} to {SALT_RANGE_MM[1]:g} (default "
                     f"{DEFAULT_SALT_MM:g}); sets the effective diameter D "
                     "from an approximate table after Rybenkov et al. 1993 (docs/units.md).",
                     show_default=False),
    ] = None,
    diameter_nm: Annotated[
        float | None,
        typer.Option("--diameter-nm", metavar="D", help="With --dna: the effective "
                     "diameter D in nm, instead of --salt-mM.", show_default=False),
    ] = None,
    temperature_K: Annotated[
        float | None,
        typer.Option("--temperature-K", metavar="T", help="With --dna: temperature in "
                     f"kelvin (> 0, default {REFERENCE_TEMPERATURE_K:g}) of the kT unit, "
                     f"kT = {KT_REFERENCE_PN_NM:g} pN nm * T / {REFERENCE_TEMPERATURE_K:g}; "
                     f"the stiffnesses stay those of {REFERENCE_TEMPERATURE_K:g} K.",
                     show_default=False),
    ] = None,
    twist_persistence_nm: Annotated[
        float | None,
        typer.Option("--twist-persistence-nm", metavar="P_T", help="With --dna: twist "
                     f"persistence length in nm (default {TWIST_PERSISTENCE_NM:g}; published "
                     "estimates about 75-120).",
                     show_default=False),
    ] = None,
    json_path: JsonOption = None,
    out: Annotated[
        Path | None,
        typer.Option("--out", metavar="DIR", help="Also write the result into folder DIR: "
                     "result.h5 (the state, read with supercoil.load) and ring.json; an "
                     "existing non-empty DIR is refused unless --overwrite.",
                     show_default=False),
    ] = None,
    overwrite: Annotated[
        bool,
        typer.Option("--overwrite", help="With --out: write into an existing non-empty DIR, "
                     "replacing this command's files (other files are left alone)."),
    ] = False,
) -> None:
    """Equilibrium of a closed twisted ring and its stability.

    Starts from the circle (length L = 1) twisted by the excess link and
    reports energy (E*L/A), twist and writhe (turns), |Tw + Wr - dLk| from
    independent computations, and the unstable count. The circle loses
    stability at Michell's thresholds dLk = (A/C) sqrt(m^2 - 1), m = 2, 3, ...;
    without --length-over-diameter it is then reported as an unstable
    equilibrium; with it, the ring is perturbed along its lowest mode (largest
    node displacement 0.01 L) and relaxed to a stable supercoiled state with
    self-contact (contacts, contact points and intervals, closest approach).
    With --initial the relaxation starts from a given closed curve (a knot,
    say) instead.

    With --dna the ring is a DNA plasmid: --bp N base pairs at superhelical
    density --sigma S, in monovalent salt --salt-mM (tube diameter D); the
    output adds energies in kT, lengths in nm and contact forces in pN. The
    model is athermal: energies and writhes are those of the elastic minimum,
    not thermal averages.
    """
    preset = None
    if dna:
        preset = _dna_preset(twist_ratio, excess_link, length_over_diameter, bp, sigma,
                             salt_mM, diameter_nm, temperature_K, twist_persistence_nm)
        twist_ratio, excess_link = preset.twist_ratio, preset.excess_link
        length_over_diameter = preset.length_over_diameter
    else:
        dna_options = (("--bp", bp), ("--sigma", sigma), ("--salt-mM", salt_mM),
                       ("--diameter-nm", diameter_nm), ("--temperature-K", temperature_K),
                       ("--twist-persistence-nm", twist_persistence_nm))
        given = [option for option, value in dna_options if value is not None]
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
    if contact is not None and length_over_diameter is None:
        fail("--contact needs --length-over-diameter L/D (self-contact of a tube of diameter "
             "D = L/(L/D)); give it, e.g. --length-over-diameter 100")
    if initial is not None and length_over_diameter is None:
        fail("--initial needs --length-over-diameter L/D (self-contact of a tube of diameter "
             "D = L/(L/D)); give it, e.g. --length-over-diameter 100")
    treatment = DEFAULT_TREATMENT if contact is None else contact
    check_json_target(json_path)
    if overwrite and out is None:
        fail("--overwrite needs --out DIR (the folder whose files it replaces)")
    if out is not None:
        from supercoil.cli.saving import prepare_folder

        prepare_folder(out, overwrite=overwrite, resume=False, what="the ring's files",
                       create=False)
    initial_points = None
    names = dict(RING_OPTIONS)
    if initial is not None:
        from supercoil.io.curves import read_curve

        with refused(prefix="--initial: "):
            initial_points = read_curve(initial)
        names["initial_points"] = f"--initial {initial}"

    with refused(names):
        if length_over_diameter is None:
            from supercoil.problems.ring import solve_ring

            result = solve_ring(twist_ratio, excess_link, n_nodes=nodes,
                                tolerance=NEWTON_TOLERANCE)
        else:
            from supercoil.problems.ring_contact import solve_supercoiled_ring

            result = solve_supercoiled_ring(twist_ratio, excess_link, length_over_diameter,
                                            n_nodes=nodes, treatment=treatment,
                                            tolerance=CONTACT_NEWTON_TOLERANCE,
                                            initial_points=initial_points)
    summary = result.summary()
    if preset is not None:
        from supercoil.units.dna import ring_summary_in_dna_units

        summary = ring_summary_in_dna_units(summary, preset)
    if json_path is not None or out is not None:
        from supercoil.cli.ring_output import ring_payload
        from supercoil.io.results import envelope

        payload = {**summary, "curvature_form": result.curvature}
        tolerances = {"newton_residual": NEWTON_TOLERANCE, "zero_modes": result.zero_tolerance}
        treatment_name = "none"
        if length_over_diameter is not None:
            from supercoil.contact.problem import ContactOptions

            treatment_name = treatment
            payload["initial_curve"] = None if initial is None else str(initial)
            tolerances["newton_residual"] = CONTACT_NEWTON_TOLERANCE
            # the options solve_supercoiled_ring uses (their defaults)
            tolerances["penetration_over_diameter"] = ContactOptions(
                diameter=1.0 / length_over_diameter, treatment=treatment
            ).tolerance
        data = envelope(payload, n_nodes=nodes, tolerances=tolerances,
                        contact_treatment=treatment_name,
                        units="nondimensional" if preset is None else preset.name)
        if preset is not None:
            data["conventions"].update(preset.conventions())
            data["provenance"]["units_preset"] = preset.record()
        if json_path is not None:
            write_json_or_fail(data, json_path)
        if out is not None:
            _write_ring_folder(out, result, summary, data, ring_payload, preset,
                               twist_ratio, excess_link, length_over_diameter, nodes,
                               treatment_name, initial, announce=json_path != "-")
    if json_path != "-":
        from rich.console import Console

        from supercoil.cli._format import ring_table

        Console().print(ring_table(summary, initial=None if initial is None else str(initial)))
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


def _write_ring_folder(out, result, summary, data, ring_payload, preset, twist_ratio,
                       excess_link, length_over_diameter, nodes, treatment, initial, *,
                       announce: bool = True) -> None:
    """``supercoil ring --out DIR``: result.h5 and ring.json (the --json data with the
    one point)."""
    from supercoil.cli.ring_output import ring_branch, write_ring

    envelope_keys = ("schema_version", "units", "conventions", "provenance")
    data = {**{k: v for k, v in data.items() if k not in envelope_keys},
            **{k: v for k, v in ring_payload(summary, result.curvature).items()
               if k in ("branch", "points")},
            **{k: data[k] for k in envelope_keys}}
    attributes = {"twist_ratio": twist_ratio, "n_nodes": nodes, "closed": True}
    if length_over_diameter is not None:
        attributes.update(length_over_diameter=length_over_diameter,
                          diameter=1.0 / length_over_diameter)
    settings = {"command": "ring", "twist_ratio": twist_ratio, "excess_link": excess_link,
                "length_over_diameter": length_over_diameter, "nodes": nodes,
                "contact": treatment, "initial": None if initial is None else str(initial),
                "dna": None if preset is None else preset.record()}
    write_ring(out, ring_branch(result, excess_link, summary), data, settings=settings,
               attributes=attributes, provenance=data["provenance"], units=data["units"],
               converged=bool(summary["converged"]))
    if announce:
        print(f"wrote result.h5 and ring.json to {out.resolve()}")


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
    from supercoil.units.dna import DNAPreset

    options = {"salt_mM": salt_mM, "diameter_nm": diameter_nm}
    if temperature_K is not None:
        options["temperature_K"] = temperature_K
    if twist_persistence_nm is not None:
        options["twist_persistence_nm"] = twist_persistence_nm
    with refused(DNA_OPTIONS):
        return DNAPreset(base_pairs=bp, superhelical_density=sigma, **options)


# ----------------------------------------------------------------------- demo


@app.command()
def demo(
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Folder for the result and figures. Default: ./supercoil-demo, or "
            "./supercoil-demo-2, -3, ... if that exists. An existing non-empty DIR is "
            "refused unless --overwrite or --resume.",
            show_default=False, callback=checked_path
        ),
    ] = None,
    overwrite: Annotated[
        bool,
        typer.Option(
            "--overwrite",
            help="Write into an existing non-empty --out DIR, "
            "replacing the demo's own files (other files are left alone).",
        ),
    ] = False,
    resume: Annotated[
        bool,
        typer.Option("--resume", help="Continue the interrupted demo in --out DIR (default "
                     "./supercoil-demo) from its result.h5: finished branches are kept."),
    ] = False,
    quiet: Annotated[
        bool,
        typer.Option("--quiet", help="No progress display (by default a live line on a "
                     "terminal, else a plain line every 10 points on standard error)."),
    ] = False,
) -> None:
    """The bifurcation diagram of a DNA-like ring with self-contact (seed 001).

    C/A = 2/3 and L/D = 122, Coleman & Swigon's DNA example, at N = 128 nodes:
    the circle and its Michell bifurcations, the alpha and beta branches
    without contact up to their first contact, then with self-contact up to
    dLk = 3.5 (at most 150 points each). Writes what 'supercoil diagram ring'
    writes (result.h5, diagram.json, link_writhe.png, contact_map.png,
    configurations.png) into a new folder and says where. About 30 s. Exit
    status 1 when a branch stopped before dLk = 3.5 (today beta's contact
    branch does, at a point the continuation cannot pass yet): what was
    computed is written all the same.
    """
    from supercoil.cli.demo import prepare_folder, run_demo
    from supercoil.cli.saving import nothing_to_resume

    folder, stored = prepare_folder(out, overwrite, resume)
    if nothing_to_resume(stored):
        return
    converged = run_demo(folder, quiet, stored)
    if not converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)


# -------------------------------------------------------------------- diagram

diagram_app = typer.Typer(
    help="Bifurcation diagrams with self-contact (branches, stability, contact events).",
)
app.add_typer(diagram_app, name="diagram")
diagram_app.callback(invoke_without_command=True)(_help_without_command)


@diagram_app.command("ring")
def diagram_ring(
    twist_ratio: Annotated[
        float,
        typer.Option("--twist-ratio", metavar="C/A", parser=parse_ratio,
                     help="Twist stiffness over bending "
                     f"stiffness, 0 < C/A <= {_MAGNITUDE} (2/3 in seed 001's DNA example).",
                     show_default=False),
    ],
    length_over_diameter: Annotated[
        float,
        typer.Option("--length-over-diameter", metavar="L/D", help="Rod length over tube "
                     "diameter, L/D > pi (122 in seed 001's DNA example).",
                     show_default=False),
    ],
    out: Annotated[
        Path,
        typer.Option("--out", metavar="DIR", help="Folder for result.h5, diagram.json and "
                     "the figures; an existing non-empty DIR is refused unless --overwrite "
                     "or --resume.", show_default=False, callback=checked_path),
    ],
    nodes: Annotated[
        int,
        typer.Option("--nodes", metavar="N", help="Nodes of the discrete ring; contact "
                     "lines need segments shorter than D (N >= L/D)."),
    ] = 100,
    modes: Annotated[
        str,
        typer.Option("--modes", metavar="M,M", help="Michell modes of the circle whose "
                     "primary branches are followed: 2 = alpha, 3 = beta, ..."),
    ] = "2,3",
    max_excess_link: Annotated[
        float,
        typer.Option("--max-excess-link", metavar="X", help="Upper bound of the excess link "
                     "dLk (turns) on the contact branches and the circle."),
    ] = 6.0,
    contact: Annotated[
        str,
        typer.Option("--contact", metavar="TREATMENT", help="Self-contact treatment of the "
                     f"contact branches: {' or '.join(CONTINUATION_TREATMENTS)} (barrier, the "
                     "default, never penetrates; exact and augmented are not continued)."),
    ] = "barrier",
    contact_max_points: Annotated[
        int,
        typer.Option("--contact-max-points", metavar="K", help="Most points of each contact "
                     "branch (alpha to dLk 6 at N = 200 takes about 380)."),
    ] = 150,
    branch_depth: Annotated[
        int,
        typer.Option("--branch-depth", metavar="K", help="1: the primary branches; 2: also "
                     "the secondary branches switched from their bifurcation points; 3: also "
                     "the tertiary ones (seed 001, Figure 2)."),
    ] = 1,
    secondary_max_points: Annotated[
        int,
        typer.Option("--secondary-max-points", metavar="K", help="With --branch-depth 2 or "
                     "3: most points of each secondary or tertiary half-branch."),
    ] = 40,
    secondary_max_branches: Annotated[
        int,
        typer.Option("--secondary-max-branches", metavar="K", help="With --branch-depth 2 or "
                     "3: most secondary and tertiary half-branches in all (at a pitchfork "
                     "of a symmetric branch only one half is computed: the other is its "
                     "mirror image)."),
    ] = 12,
    contact_curve: Annotated[
        str,
        typer.Option("--contact-curve", metavar="CURVE", help="Curve whose self-distance is "
                     "the contact distance: spline (the cubic B-spline of the nodes, default), "
                     "polygon (the segments) or quintic (the quintic B-spline, with "
                     "--contact-formulation integral only; docs/benchmarks.md)."),
    ] = "spline",
    contact_formulation: Annotated[
        str, typer.Option("--contact-formulation", metavar="FORM", help=FORMULATION_HELP),
    ] = "integral",
    overwrite: Annotated[
        bool,
        typer.Option("--overwrite", help="Write into an existing non-empty --out DIR, "
                     "replacing the diagram's own files (other files are left alone)."),
    ] = False,
    resume: Annotated[
        bool,
        typer.Option("--resume", help="Continue the interrupted diagram in --out DIR from its "
                     "result.h5 (the same options): finished branches are kept, the others "
                     "continued from their last point."),
    ] = False,
    quiet: Annotated[
        bool,
        typer.Option("--quiet", help="No progress display (by default a live line on a "
                     "terminal, else a plain line every 10 points on standard error)."),
    ] = False,
) -> None:
    """The ring's bifurcation diagram with self-contact (seed 001, Figures 1-4).

    The circle and its Michell bifurcations, the primary branches of --modes
    without contact up to the first contact (contact_onset), then with
    self-contact up to --max-excess-link; contact events and stability along
    them. Writes result.h5 (every branch with its states, saved point by point;
    read it with supercoil.load), diagram.json, link_writhe.png (dLk against Wr,
    stable parts heavy), contact_map.png (s/L of the contacts against Wr) and
    configurations.png (tubes of diameter D) into --out.
    """
    words = modes.replace(",", " ").split()
    if not words or not all(w.isdigit() for w in words):
        fail(f"--modes {modes!r}: give distinct Michell modes from 2 to {MAX_MODE} separated "
             "by commas, like 2,3 (2 = alpha, 3 = beta)")
    from supercoil.cli.diagram_output import diagram_settings, incomplete_message, run_diagram
    from supercoil.cli.saving import nothing_to_resume, prepare_folder
    from supercoil.problems.ring_diagram import DiagramOptions

    with refused(DIAGRAM_OPTIONS):
        options = DiagramOptions(twist_ratio, length_over_diameter, nodes,
                                 tuple(int(w) for w in words), max_excess_link, contact,
                                 branch_depth=branch_depth, contact_curve=contact_curve,
                                 contact_formulation=contact_formulation,
                                 contact_max_points=contact_max_points,
                                 secondary_max_points=secondary_max_points,
                                 secondary_max_branches=secondary_max_branches)
    stored = prepare_folder(out, overwrite=overwrite, resume=resume, problem="ring_diagram",
                            settings=diagram_settings(options, "diagram ring"),
                            what="the diagram's files")
    if nothing_to_resume(stored):
        return
    print(f"supercoil diagram ring: C/A = {twist_ratio:g}, L/D = {length_over_diameter:g}, "
          f"N = {nodes}, modes {', '.join(words)}, dLk <= {max_excess_link:g}", flush=True)
    payload = run_diagram(options, out, quiet, resume=stored,
                          resume_hint="continue with the same command and --resume")
    if payload is None:
        raise typer.Exit(EXIT_NOT_CONVERGED)
    message = incomplete_message(payload, out)
    if message is not None:
        warn(message)
        raise typer.Exit(EXIT_NOT_CONVERGED)


# ------------------------------------------------------------- plot and view
# (defined in their own modules; each imports matplotlib or the viewer lazily)

from supercoil.cli import plot as _plot_command
from supercoil.cli import view as _view_command

_plot_command.register(app)
_view_command.register(app)

from supercoil.cli import knot as _knot_command

_knot_command.register(app)

from supercoil.cli.tweezers import tweezers as _tweezers_command

app.command("tweezers")(_tweezers_command)

# ------------------------------------------------------------- run and export
# (study files and result files; their modules import h5py and the numerics lazily)

from supercoil.cli import export as _export_command
from supercoil.cli import run as _run_command
from supercoil.cli import sweep as _sweep_command

_run_command.register(app)
_export_command.register(app)
_sweep_command.register(app)


def _single_threaded_blas() -> None:
    """Default the BLAS/LAPACK thread pools to one thread (the user's setting wins).

    The solves of one rod call LAPACK on many small blocks; threads only add
    contention there. Measured on the 2-core development machine under load:
    the mode-3 threshold at N = 100 takes 0.9 s with one OpenBLAS thread and
    9 s with two. Must run before numpy is imported, hence here.
    """
    for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")


def _compiling() -> None:
    print(f"supercoil: first run: compiling the numerical kernels ({COMPILE_TIME}; "
          "cached for later runs)", file=sys.stderr, flush=True)


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def run(argv: Sequence[str] | None = None) -> int:
    """Run the command on ``argv`` (default: ``sys.argv[1:]``) and return the exit status.

    Parse errors of typer/click, bad input and unexpected exceptions all end as
    one line on standard error (DESIGN.md, CLI): ``error: ...`` with status 2
    for bad input, ``error: internal error: ...`` with status 1 for a bug.
    RuntimeWarnings (numpy's overflow and invalid-value warnings) are silenced.
    ``SUPERCOIL_DEBUG=1`` re-raises unexpected exceptions with their traceback
    and shows the warnings.
    """
    _single_threaded_blas()
    from supercoil._numba import announce_compilation

    announce_compilation(_compiling)
    args = list(sys.argv[1:] if argv is None else argv)
    debug = os.environ.get("SUPERCOIL_DEBUG", "") not in ("", "0")
    try:
        with warnings.catch_warnings():
            if not debug:
                # numpy's overflow/invalid-value warnings from trial steps that a
                # solver then rejects: the result's status and message say what
                # happened, so they would only break the one-line stderr contract
                warnings.simplefilter("ignore", RuntimeWarning)
            status = app(args=args, prog_name="supercoil", standalone_mode=False)
    except typer.TyperException as exc:  # typer's parse errors (click's, in typer's copy)
        ctx = getattr(exc, "ctx", None)
        command = ctx.command_path if ctx is not None else "supercoil"
        print(
            f"error: {_one_line(exc.format_message())} (see '{command} --help')",
            file=sys.stderr,
            flush=True,
        )
        return exc.exit_code
    except typer.Abort:
        print("error: aborted", file=sys.stderr, flush=True)
        return 1
    except InputError as exc:
        if debug:
            raise
        if raised_while_solving(exc):  # a failure of the numerics, not of the input
            print(f"error: internal error: {type(exc).__name__}: {_one_line(exc)} (please "
                  "report)", file=sys.stderr, flush=True)
            return EXIT_NOT_CONVERGED
        print(f"error: {_one_line(exc)}", file=sys.stderr, flush=True)
        return EXIT_BAD_INPUT
    except OSError as exc:
        if debug:
            raise
        if exc.errno in (errno.ENAMETOOLONG, errno.ELOOP):  # a path the user gave
            print(f"error: {exc.filename}: {exc.strerror}; give a shorter, valid path",
                  file=sys.stderr, flush=True)
            return EXIT_BAD_INPUT
        print(f"error: internal error: {type(exc).__name__}: {_one_line(exc)} (please report)",
              file=sys.stderr, flush=True)
        return EXIT_NOT_CONVERGED
    except Exception as exc:
        if debug:
            raise
        print(
            f"error: internal error: {type(exc).__name__}: {_one_line(exc)} (please report)",
            file=sys.stderr,
            flush=True,
        )
        return EXIT_NOT_CONVERGED
    return status if isinstance(status, int) else 0


def main(argv: Sequence[str] | None = None) -> NoReturn:
    """Entry point of the ``supercoil`` console script."""
    sys.exit(run(argv))


if __name__ == "__main__":
    main()
