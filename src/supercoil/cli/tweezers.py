"""``supercoil tweezers``: a clamped rod pulled and turned (magnetic tweezers).

Thin: parses and checks the options, calls :func:`supercoil.tweezers` through
:func:`~supercoil.cli.saving.run_saving` (every accepted point appended to
``result.h5`` as it comes), then writes ``branch.json`` and the figures into
``--out`` (:mod:`supercoil.cli.tweezers_output`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    checked_path,
    fail,
    parse_ratio,
    parse_span,
    refused,
    warn,
)
from supercoil.cli._options import MAGNITUDE, overwrite_option, quiet_option
from supercoil.cli.model_options import (
    ModelOption,
    ShearOption,
    StretchOption,
    check_model,
    make_rod,
    model_record,
)
from supercoil.units.dna import (
    DEFAULT_SALT_MM,
    HELICAL_REPEAT_BP,
    REFERENCE_TEMPERATURE_K,
    SALT_RANGE_MM,
)
from supercoil.units.tweezers import DNA_MAX_POINTS

PROTOCOLS = ("up", "up-down", "force-ramp")
OUTPUT_FILES = ("result.h5", "branch.json", "hat_curve.png", "torque.png", "writhe.png",
                "configurations.png")


# the library's names of the inputs -> the options of 'supercoil tweezers'
TWEEZERS_OPTIONS = {"twist_ratio": "--twist-ratio",
                    "length_over_diameter": "--length-over-diameter", "tension": "--tension",
                    "end_distance": "--end-distance", "turns": "--turns", "n_nodes": "--nodes",
                    "max_points": "--max-points", "contact_curve": "--contact-curve",
                    "loop_sliding": "--loop-sliding",
                    "contact_formulation": "--contact-formulation", "protocol": "--protocol",
                    "contact_stiffness": "--contact-stiffness",
                    "contact_stiffness_scale": "--contact-stiffness-scale",
                    "step": "--step", "force_range": "--force-range",
                    "force_step": "--force-step", "base_pairs": "--bp",
                    "force_pN": "--force-pN", "salt_mM": "--salt-mM",
                    "diameter_nm": "--diameter-nm", "temperature_K": "--temperature-K",
                    "superhelical_density": "--sigma",
                    "stretch_stiffness": "--stretch-stiffness",
                    "shear_stiffness": "--shear-stiffness"}
Quiet = quiet_option()
Overwrite = overwrite_option("Write into an existing non-empty --out DIR, replacing this "
                             "command's own files (other files are left alone).")


def tweezers(
    out: Annotated[Path, typer.Option(
        "--out", metavar="DIR", help="Folder for result.h5, branch.json and the figures; "
        "an existing non-empty DIR is refused unless --overwrite or --resume.",
        show_default=False, callback=checked_path)],
    turns: Annotated[str | None, typer.Option(
        "--turns", metavar="START:STOP", help="Turns of the end, from START to STOP "
        f"(0 <= START < STOP <= {checks.MAX_TURNS:g}), e.g. 0:5; with --dna, this or "
        "--sigma.", show_default=False)] = None,
    twist_ratio: Annotated[float | None, typer.Option(
        "--twist-ratio", metavar="C/A", parser=parse_ratio, help="Twist stiffness over "
        f"bending stiffness, 0 < C/A <= {MAGNITUDE}; not with --dna.",
        show_default=False)] = None,
    length_over_diameter: Annotated[float | None, typer.Option(
        "--length-over-diameter", metavar="L/D", help="Rod length over tube diameter, "
        f"pi < L/D <= {MAGNITUDE}; omit for a rod without self-contact.",
        show_default=False)] = None,
    tension: Annotated[float | None, typer.Option(
        "--tension", metavar="F", help=f"Dead load F L^2/A, 0 <= F <= {MAGNITUDE}, on the "
        "turned end (load control, the magnetic tweezers).", show_default=False)] = None,
    end_distance: Annotated[float | None, typer.Option(
        "--end-distance", metavar="Z/L", help="End-to-end distance z/L held fixed "
        "(displacement control): in (0, 1) for the Kirchhoff rod (inextensible); up to 2 "
        "with --model cosserat, whose rod is stretched straight at z/L >= 1 (tension EA "
        "(z/L - 1)).", show_default=False)] = None,
    nodes: Annotated[int | None, typer.Option(
        "--nodes", metavar="N", help=f"Nodes of the discrete rod, {checks.MIN_CLAMPED_NODES} "
        f"to {checks.MAX_NODES}; contact lines need segments L/(N - 2) no longer than D "
        "(N >= L/D + 2). Default 100; with --dna the fewest nodes whose segments are no "
        "longer than the tube diameter D (n0 = ceil(L/D) + 2: the ply resolved) and at "
        "most min(1/3, 1.25/ln(lambda/0.54)) of the loop's core sqrt(A/F), lambda = "
        "L sqrt(F/A) (the end loop, the buckling and the unstable counts resolved).",
        show_default=False)] = None,
    protocol: Annotated[str, typer.Option(
        "--protocol", metavar="P", help="up: the branches from START to STOP; up-down: "
        "also the quasi-static path of an experiment turning up to STOP and back (stable "
        "states, jumps at folds); force-ramp: up to STOP, then the force ramped over "
        "--force-range and back.")] = "up",
    step: Annotated[float, typer.Option(
        "--step", metavar="DT", help="With --protocol up-down or force-ramp: turns per "
        "quasi-static step (0 < DT <= STOP - START).")] = 0.02,
    force_range: Annotated[str | None, typer.Option(
        "--force-range", metavar="LOW:HIGH", help="With --protocol force-ramp: the force "
        "F L^2/A (pN with --dna) is ramped from --tension down to LOW, up to HIGH and back "
        "(default 0:2F).", show_default=False)] = None,
    force_step: Annotated[float | None, typer.Option(
        "--force-step", metavar="DF", help="With --protocol force-ramp: force per step, "
        "F L^2/A (pN with --dna), 0 < DF <= HIGH - LOW (default 1/50 of the range).",
        show_default=False)] = None,
    max_points: Annotated[int | None, typer.Option(
        "--max-points", metavar="K", help=f"Largest number of points per branch, 2 to "
        f"{checks.MAX_POINTS} (a branch stopped by it is incomplete: exit status 1). Default "
        f"2000; with --dna {DNA_MAX_POINTS}, as DNA runs at the default mesh meet many folds.",
        show_default=False)] = None,
    contact_curve: Annotated[str | None, typer.Option(
        "--contact-curve", metavar="CURVE", help="Curve whose self-distance is the contact "
        "distance: spline (the cubic B-spline of the nodes, default), quintic (the quintic "
        "B-spline, integral formulation only; default with --dna, whose segments of D "
        "make the cubic's contact force ripple as the ply slides) or polygon (the "
        "segments, whose sag ripples with period h; docs/contact.md).",
        show_default=False)] = None,
    contact_formulation: Annotated[str, typer.Option(
        "--contact-formulation", metavar="FORM", help="How the contact potential is summed: "
        "integral (a double integral over the strands, which counts a contact once wherever "
        "it lies; default) or pairs (over segment pairs: a sawtooth of fold pairs along the "
        "plectoneme; docs/contact.md).")] = "integral",
    loop_sliding: Annotated[bool | None, typer.Option(
        "--loop-sliding/--no-loop-sliding", help="Hold the sliding of a localised loop "
        "with straight tails along the rod by a phase row up to its contact, and follow a "
        "contact branch that stops or closes again held on its half-turn symmetry "
        "(docs/continuation.md, \"Long open rods\"): what long rods (L sqrt(F/A) of 20 "
        "and more) need to reach their plectoneme. Default: on; in contact only where "
        "the segments are at most half the loop's core sqrt(A/F) (a coarser mesh pins the "
        "loop there); --loop-sliding on a coarser mesh adds a note that says so.",
        show_default=False)] = None,
    contact_stiffness: Annotated[str, typer.Option(
        "--contact-stiffness", metavar="RULE", help="The barrier's stiffness: load "
        "(default), max(A/h^3, F/(pi g_hat)) with g_hat the barrier's reach (1 % of D), so "
        "that strands crossing at right angles under the load F stay at 0.15 g_hat; or "
        "bending, A/h^3 whatever the load, which lets a large load close the gap to 1e-6 D, "
        "where the tangent is lost in round-off (docs/tweezers.md, \"Contact "
        "stiffness\").")] = "load",
    contact_stiffness_scale: Annotated[float, typer.Option(
        "--contact-stiffness-scale", metavar="S", help="A factor on the barrier's "
        "stiffness (--contact-stiffness), 0 < S <= 1e6 (default 1).")] = 1.0,
    overwrite: Overwrite = False,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue the interrupted run in --out DIR from its result.h5 (the "
        "same options; --max-points may be raised): finished branches are kept, the others "
        "continued from their last point, and those that stopped at --max-points continued "
        "up to a raised one.")] = False,
    dna: Annotated[bool, typer.Option(
        "--dna", help="A DNA molecule in physical units (--bp, --force-pN, --salt-mM or "
        "--diameter-nm, --temperature-K) instead of --twist-ratio, --tension and "
        "--length-over-diameter. The model is athermal. DNA runs take the quintic contact "
        "curve unless --contact-curve is given (docs/tweezers.md).")] = False,
    bp: Annotated[int | None, typer.Option(
        "--bp", metavar="N", help=f"With --dna: number of base pairs, "
        f"{checks.MIN_BASE_PAIRS} to {checks.MAX_BASE_PAIRS}.", show_default=False)] = None,
    force_pN: Annotated[float | None, typer.Option(
        "--force-pN", metavar="F", help="With --dna: pulling force in pN (>= 0).",
        show_default=False)] = None,
    sigma: Annotated[str | None, typer.Option(
        "--sigma", metavar="START:STOP", help="With --dna, instead of --turns: the "
        "superhelical density from START to STOP, sigma = turns * "
        f"{HELICAL_REPEAT_BP:g} / bp (0 <= START < STOP <= 1), e.g. 0:0.06.",
        show_default=False)] = None,
    salt_mM: Annotated[float | None, typer.Option(
        "--salt-mM", metavar="MM", help=f"With --dna: monovalent salt in mM, from "
        f"{SALT_RANGE_MM[0]:g} to {SALT_RANGE_MM[1]:g}, giving the effective diameter "
        f"(default {DEFAULT_SALT_MM:g} mM).", show_default=False)] = None,
    diameter_nm: Annotated[float | None, typer.Option(
        "--diameter-nm", metavar="D", help="With --dna: the effective diameter in nm, > 0 "
        "(instead of --salt-mM).", show_default=False)] = None,
    temperature_K: Annotated[float | None, typer.Option(
        "--temperature-K", metavar="T", help="With --dna: temperature in K (> 0) of the "
        f"kT unit (default {REFERENCE_TEMPERATURE_K:g} K).", show_default=False)] = None,
    model: ModelOption = "kirchhoff",
    stretch_stiffness: StretchOption = None,
    shear_stiffness: ShearOption = None,
    quiet: Quiet = False,
) -> None:
    """A rod clamped at both ends on the pulling axis, turned at one end.

    Load control (--tension): the straight rod, its buckling (bifurcation,
    checked against the exact clamped condition), the buckled branch without
    contact up to the first contact, then with self-contact (plectoneme) up to
    STOP. Displacement control (--end-distance): from the planar clamped
    buckle at 0 turns. Writes branch.json (points with turns, extension,
    torque, writhe, twist, energy, load_potential, unstable_count, zero_modes,
    contact counts, min_gap_over_diameter; special_points; path for the
    protocols), result.h5 (every branch with its states, saved point by
    point; read it with supercoil.load), hat_curve.png (extension against turns; under
    displacement control tension.png), torque.png, writhe.png,
    configurations.png (tubes) and, for force-ramp, force_extension.png into
    --out.

    With --model cosserat the rod shears and stretches (--stretch-stiffness,
    --shear-stiffness): load or displacement control, with or without contact
    (its contact acts on the centreline); the extension and --end-distance include
    the stretch.
    """
    check_model(model, stretch_stiffness, shear_stiffness)
    preset, span = None, None
    if dna:
        preset, span, (twist_ratio, tension, length_over_diameter, (start, stop), nodes) = \
            _dna_inputs(twist_ratio, tension, length_over_diameter, end_distance, bp,
                        force_pN, salt_mM, diameter_nm, temperature_K, turns, sigma, nodes)
        from supercoil.units.tweezers import dna_numerics

        given = {"contact_curve": contact_curve, "max_points": max_points}
        numerics = dna_numerics({k: v for k, v in given.items() if v is not None})
        contact_curve, max_points = numerics["contact_curve"], numerics["max_points"]
    else:
        for option, value in (("--bp", bp), ("--force-pN", force_pN), ("--salt-mM", salt_mM),
                              ("--diameter-nm", diameter_nm),
                              ("--temperature-K", temperature_K), ("--sigma", sigma)):
            if value is not None:
                fail(f"{option} needs --dna (DNA units); without it give --twist-ratio, "
                     "--tension or --end-distance, --length-over-diameter and --turns")
        if twist_ratio is None:
            fail("--twist-ratio C/A is missing; give it (e.g. --twist-ratio 1.3333), or use "
                 "--dna --bp N --force-pN F")
        if turns is None:
            fail("--turns START:STOP is missing; give the end's rotation in turns, like "
                 "--turns 0:5")
        start, stop = parse_span("--turns", turns, "START:STOP in turns, like 0:5")
        nodes = 100 if nodes is None else nodes
        max_points = 2000 if max_points is None else max_points
        contact_curve = "spline" if contact_curve is None else contact_curve
    if (tension is None) == (end_distance is None):
        fail("give exactly one of --tension F (load control, F L^2/A >= 0) and "
             "--end-distance Z/L (displacement control, 0 < z/L < 1; up to 2 with --model "
             "cosserat)")
    if protocol not in PROTOCOLS:
        fail(f"--protocol {protocol!r}: give one of {', '.join(PROTOCOLS)}")
    if protocol != "up" and tension is None:
        fail(f"--protocol {protocol} needs --tension (load control, the tweezers experiment)")
    ramp = None
    if protocol == "force-ramp":
        ramp = _force_range(force_range, tension, preset)
        if force_step is not None and preset is not None:
            with refused(TWEEZERS_OPTIONS):
                force_step = preset.force_from_pN(force_step)
    elif force_range is not None or force_step is not None:
        fail("--force-range and --force-step need --protocol force-ramp")
    from supercoil.cli.saving import nothing_to_resume, prepare_folder
    from supercoil.problems.tweezers import TweezersOptions
    from supercoil.problems.tweezers.options import check_inextensible
    from supercoil.problems.tweezers_protocol import check_path

    with refused(TWEEZERS_OPTIONS):
        options = TweezersOptions(twist_ratio=twist_ratio,
                                  length_over_diameter=length_over_diameter, tension=tension,
                                  end_distance=end_distance, turns=(start, stop),
                                  n_nodes=nodes, max_points=max_points,
                                  contact_curve=contact_curve,
                                  contact_formulation=contact_formulation,
                                  loop_sliding=loop_sliding,
                                  contact_stiffness=contact_stiffness,
                                  contact_stiffness_scale=contact_stiffness_scale)
        if protocol != "up":
            check_path(options, protocol, step, force_range=ramp, force_step=force_step)
        if model != "cosserat":
            check_inextensible(end_distance)
        rod = make_rod(model, twist_ratio, nodes, stretch_stiffness, shear_stiffness,
                       slenderness=length_over_diameter, preset=preset)
    settings = {"command": "tweezers", "twist_ratio": twist_ratio,
                "length_over_diameter": length_over_diameter, "tension": tension,
                "end_distance": end_distance, "turns": [start, stop], "nodes": nodes,
                "max_points": max_points, "contact_curve": contact_curve,
                "contact_formulation": contact_formulation, "loop_sliding": loop_sliding,
                "contact_stiffness": contact_stiffness,
                "contact_stiffness_scale": contact_stiffness_scale, "protocol": protocol,
                "step": step, "force_range": ramp, "force_step": force_step,
                "superhelical_density": None if span is None else list(span),
                "dna": None if preset is None else preset.record(),
                **model_record(rod)}
    stored = prepare_folder(out, overwrite=overwrite, resume=resume, problem="tweezers",
                            settings=settings)
    if nothing_to_resume(stored):
        return
    control = (f"F L^2/A = {tension:g}" if tension is not None else f"z/L = {end_distance:g}")
    print(f"supercoil tweezers: C/A = {twist_ratio:g}, {control}, L/D = "
          f"{length_over_diameter if length_over_diameter is not None else 'no contact'}, "
          f"N = {nodes}, turns {start:g} to {stop:g}"
          + ("" if preset is None else f" (sigma {start / preset.relaxed_link:.4g} to "
             f"{stop / preset.relaxed_link:.4g}; DNA {preset.base_pairs} bp, "
             f"{force_pN:g} pN, D = {preset.effective_diameter_nm:.3g} nm)"), flush=True)
    from supercoil.api.recording import from_interrupt
    from supercoil.api.verbs import diagram_of, tweezers_arguments, tweezers_path
    from supercoil.cli.saving import (
        interrupted,
        open_writer,
        run_saving,
        terminate_as_interrupt,
    )
    from supercoil.cli.tweezers_output import tweezers_attributes, write_tweezers

    writer = open_writer(out, resume=stored is not None, problem="tweezers",
                         settings=settings, attributes=tweezers_attributes(options, preset),
                         provenance={"contact_treatment": "barrier" if length_over_diameter
                                     else "none", "n_nodes": nodes},
                         units="nondimensional" if preset is None else preset.name)
    hint = "continue with the same command and --resume"

    def compute(message, on_point):
        return diagram_of(options, rod=rod if model == "cosserat" else None, progress=message,
                          on_point=on_point, out=writer, resume=stored is not None).computed

    result = run_saving(compute, writer, quiet, hint)
    if result is None:
        raise typer.Exit(EXIT_NOT_CONVERGED)
    path = None
    if protocol != "up":
        what = ("and back" if protocol == "up-down" else
                f"then the force from {tension:g} to {ramp[0]:g}, {ramp[1]:g} and back")
        warn(f"  path: quasi-static up to {stop:g} turns {what}, steps of {step:g} turns")
        try:
            with terminate_as_interrupt():
                problem, numerics = tweezers_arguments(
                    options, rod if model == "cosserat" else None)
                path = tweezers_path(problem, protocol=protocol, step=step, force_range=ramp,
                                     force_step=force_step, **numerics)
        except BaseException as exc:
            if not from_interrupt(exc):  # Ctrl-C or SIGTERM, even inside a kernel
                raise
            interrupted(writer, hint + " (the quasi-static path is computed again)")
            raise typer.Exit(EXIT_NOT_CONVERGED) from None
    payload = write_tweezers(result, out, writer, path, preset)
    if not payload["ok"] or (path is not None and not path.ok):
        if path is not None and not path.ok:
            payload["notes"].append(f"path: {path.message}")
        warn("not complete: " + "; ".join(payload["notes"] or
                                          [b["message"] for b in payload["branches"]
                                           if not b["ok"]]))
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _force_range(text, tension, preset) -> tuple[float, float]:
    """``--force-range LOW:HIGH`` in F L^2/A (pN with --dna); default ``0:2F``."""
    if text is None:
        return 0.0, 2.0 * tension if tension > 0 else 1.0
    low, high = parse_span("--force-range", text, "LOW:HIGH, like 0:100")
    if preset is not None:
        with refused(TWEEZERS_OPTIONS):
            low, high = preset.force_from_pN(low), preset.force_from_pN(high)
    return low, high


def _dna_inputs(twist_ratio, tension, length_over_diameter, end_distance, bp, force_pN,
                salt_mM, diameter_nm, temperature_K, turns, sigma, nodes):
    """``(preset, sigma span or None, (C/A, F L^2/A, L/D, (start, stop) turns, nodes))`` of
    the --dna options (:func:`~supercoil.units.tweezers.dna_tweezers_inputs`); one-line
    errors otherwise."""
    from supercoil.units.dna import DNAPreset
    from supercoil.units.tweezers import dna_tweezers_inputs

    given = "--bp N --force-pN F (--turns START:STOP | --sigma START:STOP) [--salt-mM S | " \
        "--diameter-nm D] [--temperature-K T]"
    if end_distance is not None:
        fail("--end-distance cannot be combined with --dna: DNA runs are under a force "
             f"(load control, --force-pN F); give {given}")
    for option, value in (("--twist-ratio", twist_ratio), ("--tension", tension),
                          ("--length-over-diameter", length_over_diameter)):
        if value is not None:
            fail(f"{option} cannot be combined with --dna (the DNA preset sets it); give "
                 f"{given}")
    if bp is None or force_pN is None:
        fail("--dna needs --bp N (base pairs) and --force-pN F (pulling force in pN)")
    if (turns is None) == (sigma is None):
        fail(f"{'both' if turns else 'neither of'} --turns and --sigma given: with --dna give "
             "exactly one, the end's rotation in turns (--turns 0:10) or as superhelical "
             f"density (--sigma 0:0.06, sigma = turns * {HELICAL_REPEAT_BP:g} / bp)")
    turns = None if turns is None else parse_span("--turns", turns, "START:STOP in turns, like 0:5")
    span = None if sigma is None else parse_span(
        "--sigma", sigma, "START:STOP as superhelical densities, like 0:0.06")
    kwargs = {"base_pairs": bp, "salt_mM": salt_mM, "diameter_nm": diameter_nm}
    if temperature_K is not None:
        kwargs["temperature_K"] = temperature_K
    with refused(TWEEZERS_OPTIONS):
        preset = DNAPreset(**kwargs)
        numbers = dna_tweezers_inputs(preset, force_pN, turns=turns,
                                      superhelical_density=span, n_nodes=nodes)
    return preset, span, tuple(numbers[k] for k in (
        "twist_ratio", "tension", "length_over_diameter", "turns", "n_nodes"))
