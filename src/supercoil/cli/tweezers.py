"""``supercoil tweezers``: a clamped rod pulled and turned (magnetic tweezers).

Thin: parses and checks the options, calls
:func:`supercoil.problems.tweezers.tweezers_branches`, writes ``branch.json``
(with the JSON envelope), ``branches/<name>.npz`` and the figures of
:mod:`supercoil.plotting.tweezers` into ``--out``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    check_contact_choice,
    fail,
    parse_ratio,
    prepare_output_folder,
    require_count,
    require_magnitude,
    require_nodes,
    require_positive,
    warn,
)

PROTOCOLS = ("up", "up-down", "force-ramp")
OUTPUT_FILES = ("branch.json", "hat_curve.png", "torque.png", "writhe.png",
                "configurations.png")


def parse_turns(text: str) -> tuple[float, float]:
    """``"START:STOP"`` -> ``(start, stop)``, ``0 <= start < stop``; one-line error otherwise."""
    words = text.split(":")
    try:
        if len(words) != 2:
            raise ValueError
        start, stop = float(words[0]), float(words[1])
    except ValueError:
        fail(f"--turns {text!r}: give START:STOP in turns, like 0:5")
    if not (math.isfinite(start) and math.isfinite(stop) and 0 <= start < stop <= 1e3):
        fail(f"--turns {text!r}: need 0 <= START < STOP <= 1000 (turns), like 0:5")
    return start, stop


def tweezers(
    turns: Annotated[str, typer.Option(
        "--turns", metavar="START:STOP", help="Turns of the end, from START to STOP "
        "(0 <= START < STOP), e.g. 0:5.", show_default=False)],
    out: Annotated[Path, typer.Option(
        "--out", metavar="DIR", help="Folder for branch.json, branches/*.npz and the "
        "figures; an existing non-empty DIR is refused unless --force.",
        show_default=False)],
    twist_ratio: Annotated[float | None, typer.Option(
        "--twist-ratio", metavar="C/A", parser=parse_ratio, help="Twist stiffness over bending stiffness, "
        "0 < C/A <= 1e6 (4/3 in the benchmark); not with --dna.", show_default=False)] = None,
    length_over_diameter: Annotated[float | None, typer.Option(
        "--length-over-diameter", metavar="L/D", help="Rod length over tube diameter, "
        "L/D > pi; omit for a rod without self-contact.", show_default=False)] = None,
    tension: Annotated[float | None, typer.Option(
        "--tension", metavar="F", help="Dead load F L^2/A >= 0 on the turned end (load "
        "control, the magnetic tweezers).", show_default=False)] = None,
    end_distance: Annotated[float | None, typer.Option(
        "--end-distance", metavar="Z/L", help="End-to-end distance z/L in (0, 1) held fixed "
        "(displacement control).", show_default=False)] = None,
    nodes: Annotated[int, typer.Option(
        "--nodes", metavar="N", help="Nodes of the discrete rod; contact lines need "
        "segments shorter than D (N >= L/D + 2).")] = 100,
    protocol: Annotated[str, typer.Option(
        "--protocol", metavar="P", help="up: the branches from START to STOP; up-down: "
        "also the quasi-static path of an experiment turning up to STOP and back (stable "
        "states, jumps at folds); force-ramp: up to STOP, then the force ramped over "
        "--force-range and back.")] = "up",
    step: Annotated[float, typer.Option(
        "--step", metavar="DT", help="With --protocol up-down or force-ramp: turns per "
        "quasi-static step.")] = 0.02,
    force_range: Annotated[str | None, typer.Option(
        "--force-range", metavar="LOW:HIGH", help="With --protocol force-ramp: the force "
        "F L^2/A (pN with --dna) is ramped from --tension down to LOW, up to HIGH and back "
        "(default 0:2F).", show_default=False)] = None,
    force_step: Annotated[float | None, typer.Option(
        "--force-step", metavar="DF", help="With --protocol force-ramp: force per step "
        "(default 1/50 of the range).", show_default=False)] = None,
    max_points: Annotated[int, typer.Option(
        "--max-points", metavar="K", help="Largest number of points per branch (a branch "
        "stopped by it is incomplete: exit status 1).")] = 2000,
    contact_curve: Annotated[str, typer.Option(
        "--contact-curve", metavar="CURVE", help="Curve whose self-distance is the contact "
        "distance: spline (the cubic B-spline of the nodes, default), quintic (the quintic "
        "B-spline, integral formulation only) or polygon (the segments, whose sag ripples "
        "with period h; docs/benchmarks.md).")] = "spline",
    contact_formulation: Annotated[str, typer.Option(
        "--contact-formulation", metavar="FORM", help="How the contact potential is summed: "
        "integral (a double integral over the strands, which counts a contact once wherever "
        "it lies; default) or pairs (over segment pairs: a sawtooth of fold pairs along the "
        "plectoneme; docs/benchmarks.md).")] = "integral",
    force: Annotated[bool, typer.Option(
        "--force", help="Write into an existing non-empty --out DIR, overwriting this "
        "command's own files (other files are left alone).")] = False,
    dna: Annotated[bool, typer.Option(
        "--dna", help="A DNA molecule in physical units (--bp, --force-pN, --salt-mM or "
        "--diameter-nm, --temperature-K) instead of --twist-ratio, --tension and "
        "--length-over-diameter. The model is athermal.")] = False,
    bp: Annotated[int | None, typer.Option(
        "--bp", metavar="N", help="With --dna: number of base pairs.",
        show_default=False)] = None,
    force_pN: Annotated[float | None, typer.Option(
        "--force-pN", metavar="F", help="With --dna: pulling force in pN (>= 0).",
        show_default=False)] = None,
    salt_mM: Annotated[float | None, typer.Option(
        "--salt-mM", metavar="MM", help="With --dna: monovalent salt in mM, giving the "
        "effective diameter (default 150 mM).", show_default=False)] = None,
    diameter_nm: Annotated[float | None, typer.Option(
        "--diameter-nm", metavar="D", help="With --dna: the effective diameter in nm "
        "(instead of --salt-mM).", show_default=False)] = None,
    temperature_K: Annotated[float | None, typer.Option(
        "--temperature-K", metavar="T", help="With --dna: temperature in K of the kT "
        "unit (default 298 K).", show_default=False)] = None,
    quiet: Annotated[bool, typer.Option(
        "--quiet", help="No progress display (by default a live line on a terminal, else a "
        "plain line every 10 points on standard error).")] = False,
) -> None:
    """A rod clamped at both ends on the pulling axis, turned at one end.

    Load control (--tension): the straight rod, its buckling (bifurcation,
    checked against the exact clamped condition), the buckled branch without
    contact up to the first contact, then with self-contact (plectoneme) up to
    STOP. Displacement control (--end-distance): from the planar clamped
    buckle at 0 turns. Writes branch.json (points with turns, extension,
    torque, writhe, twist, energy, load_potential, unstable_count, zero_modes,
    contact counts, min_gap_over_diameter; special_points; path for the
    protocols), branches/*.npz, hat_curve.png (extension against turns; under
    displacement control tension.png), torque.png, writhe.png,
    configurations.png (tubes) and, for force-ramp, force_extension.png into
    --out.
    """
    preset = None
    if dna:
        preset, twist_ratio, tension, length_over_diameter = _dna_inputs(
            twist_ratio, tension, length_over_diameter, end_distance, bp, force_pN, salt_mM,
            diameter_nm, temperature_K)
    else:
        for option, value in (("--bp", bp), ("--force-pN", force_pN), ("--salt-mM", salt_mM),
                              ("--diameter-nm", diameter_nm),
                              ("--temperature-K", temperature_K)):
            if value is not None:
                fail(f"{option} needs --dna (DNA units); without it give --twist-ratio, "
                     "--tension or --end-distance and --length-over-diameter")
        if twist_ratio is None:
            fail("--twist-ratio C/A is missing; give it (e.g. --twist-ratio 1.3333), or use "
                 "--dna --bp N --force-pN F")
    require_magnitude("--twist-ratio", twist_ratio, "a positive number up to 1e6")
    require_positive("--twist-ratio", twist_ratio, "a positive number up to 1e6")
    start, stop = parse_turns(turns)
    if (tension is None) == (end_distance is None):
        fail("give exactly one of --tension F (load control, F L^2/A >= 0) and "
             "--end-distance Z/L (displacement control, 0 < z/L < 1)")
    if tension is not None and not (math.isfinite(tension) and 0 <= tension <= 1e6):
        fail(f"--tension {tension:g}: give a force F L^2/A from 0 to 1e6")
    if end_distance is not None and not (math.isfinite(end_distance)
                                         and 0 < end_distance < 1):
        fail(f"--end-distance {end_distance:g}: give z/L strictly between 0 and 1 (an "
             "inextensible rod of length L)")
    if length_over_diameter is not None:
        require_positive("--length-over-diameter", length_over_diameter,
                         f"a finite number above pi ({math.pi:.4f})")
        if length_over_diameter <= math.pi:
            fail(f"--length-over-diameter {length_over_diameter:g} is too small: a tube of "
                 f"diameter D needs L/D > pi ({math.pi:.4f})")
    require_nodes("--nodes", nodes)
    if nodes < 12:
        fail(f"--nodes {nodes}: a clamped rod needs at least 12 nodes")
    if protocol not in PROTOCOLS:
        fail(f"--protocol {protocol!r}: give up or up-down (force-ramp is not implemented "
             "yet)")
    if protocol != "up" and tension is None:
        fail(f"--protocol {protocol} needs --tension (load control, the tweezers experiment)")
    ramp = None
    if protocol == "force-ramp":
        ramp = _force_range(force_range, tension, preset)
        if force_step is not None:
            if not (math.isfinite(force_step) and force_step > 0):
                fail(f"--force-step {force_step:g}: give a positive force step")
            if preset is not None:
                force_step = preset.force_from_pN(force_step)
    elif force_range is not None or force_step is not None:
        fail("--force-range and --force-step need --protocol force-ramp")
    if not (math.isfinite(step) and 0 < step <= stop - start):
        fail(f"--step {step:g}: give a positive number of turns up to STOP - START")
    require_count("--max-points", max_points, 2, 100_000)
    check_contact_choice(contact_curve, contact_formulation)
    prepare_output_folder(out, force, "this command's files")
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    try:
        options = TweezersOptions(twist_ratio=twist_ratio,
                                  length_over_diameter=length_over_diameter, tension=tension,
                                  end_distance=end_distance, turns=(start, stop),
                                  n_nodes=nodes, max_points=max_points,
                                  contact_curve=contact_curve,
                                  contact_formulation=contact_formulation)
    except ValueError as exc:
        fail(str(exc))
    control = (f"F L^2/A = {tension:g}" if tension is not None else f"z/L = {end_distance:g}")
    print(f"supercoil tweezers: C/A = {twist_ratio:g}, {control}, L/D = "
          f"{length_over_diameter if length_over_diameter is not None else 'no contact'}, "
          f"N = {nodes}, turns {start:g} to {stop:g}", flush=True)
    from supercoil.cli.diagram_output import run_saving

    def compute(message, on_point, on_branch):
        return tweezers_branches(options, progress=message, on_point=on_point,
                                 on_branch=on_branch)

    # each final branch written uncompressed as it comes; write_tweezers writes them
    # compressed
    result = run_saving(compute, out, quiet, compress_final=False)
    if result is None:
        raise typer.Exit(EXIT_NOT_CONVERGED)
    path = None
    if protocol != "up":
        from supercoil.problems.tweezers_protocol import quasistatic_path

        what = ("and back" if protocol == "up-down" else
                f"then the force from {tension:g} to {ramp[0]:g}, {ramp[1]:g} and back")
        warn(f"  path: quasi-static up to {stop:g} turns {what}, steps of {step:g} turns")
        path = quasistatic_path(options, protocol, step=step, force_range=ramp,
                                force_step=force_step)
    payload = write_tweezers(result, out, path, preset)
    if not payload["ok"] or (path is not None and not path.ok):
        if path is not None and not path.ok:
            payload["notes"].append(f"path: {path.message}")
        warn("not complete: " + "; ".join(payload["notes"] or
                                          [b["message"] for b in payload["branches"]
                                           if not b["ok"]]))
        raise typer.Exit(EXIT_NOT_CONVERGED)


def write_tweezers(result, out: Path, path=None, preset=None) -> dict:
    """Save the branches, branch.json (with the envelope) and the figures; return the payload.

    Every branch is written compressed to ``out/branches``; the command's
    :func:`~supercoil.cli.diagram_output.run_saving` wrote each uncompressed when it
    became final, which an interrupt before the figures leaves (they load the same).

    ``path``: the quasi-static path (:class:`~supercoil.problems.tweezers_protocol.PathResult`)
    of the up-down protocol, written as the list ``path`` with its jumps among the special
    points, and its states as ``branches/path.npz``. ``preset``: a
    :class:`~supercoil.units.dna.DNAPreset`; its suffixed keys are added to every point,
    special point and path point, and ``units`` is ``dna``.
    """
    from supercoil.cli.diagram_output import save_branch
    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.tweezers import pick_configurations, picked_points, write_figures
    from supercoil.problems.tweezers_output import (
        TWEEZERS_CONVENTIONS,
        add_contact_lists,
        result_payload,
    )

    # the contact lists of the states drawn as tubes, which show them
    payload = result_payload(result, contacts=False)
    states = {b.name: b.states for b in result.branches}
    if path is not None:
        import numpy as np

        payload["path"] = list(path.points)
        payload["path_ok"] = path.ok
        payload["path_message"] = path.message
        payload["special_points"] += list(path.jumps)
        np.savez_compressed(out / "branches" / "path.npz", states=path.states,
                            turns=np.array([p["turns"] for p in path.points]))
    add_contact_lists(result, [entry for _, _, entry in picked_points(payload, states)])
    configurations = pick_configurations(payload, states)

    def write_payload() -> None:
        """branch.json and the compressed branch files."""
        add_contact_lists(result, payload["points"])
        if preset is not None:
            from supercoil.units.dna import ATHERMAL_CAVEAT, tweezers_point_in_dna_units

            for key in ("points", "special_points", "path"):
                if key in payload:
                    payload[key] = [tweezers_point_in_dna_units(p, preset)
                                    for p in payload[key]]
            payload.update(base_pairs=preset.base_pairs, length_nm=preset.length_nm,
                           diameter_nm=preset.effective_diameter_nm,
                           force_pN=preset.force_to_pN(result.options.tension),
                           relaxed_link=preset.relaxed_link, athermal=ATHERMAL_CAVEAT)
        data = envelope(payload, n_nodes=result.options.n_nodes,
                        tolerances=result.options.tolerances,
                        units="nondimensional" if preset is None else preset.name,
                        contact_treatment="barrier" if result.contact_problem else "none")
        data["conventions"].update(TWEEZERS_CONVENTIONS)
        if preset is not None:
            data["conventions"].update(preset.conventions())
            data["provenance"]["units_preset"] = preset.record()
        write_json(data, out / "branch.json")
        for branch in result.branches:
            save_branch(branch, out / "branches")

    write_figures(payload, configurations, out)
    write_payload()
    for b in payload["branches"]:
        specials = [p for p in payload["special_points"] if p["branch"] == b["name"]
                    and p["kind"] != "fold"]
        folds = sum(p["kind"] == "fold" for p in payload["special_points"]
                    if p["branch"] == b["name"])
        kinds = ", ".join(f"{p['kind']} at {p['turns']:.4f} turns" for p in specials[:6])
        if len(specials) > 6:
            kinds += f", ... ({len(specials)} in all)"
        print(f"  {b['name']}: {b['n_points']} points, {b['seconds']:.1f} s, "
              f"{b['status'].lower()}" + (f"; {kinds}" if kinds else "")
              + (f"; {folds} folds" if folds else ""))
    if payload.get("greenhill_turns") is not None:
        print(f"  exact buckling of the straight rod (clamped Greenhill with tension): "
              f"{payload['greenhill_turns']:.6f} turns")
    if path is not None:
        jumps = ", ".join(f"{j['turns']:.3f} ({'up' if j['direction'] > 0 else 'down'}, "
                          f"z/L {j['extension']:.3f} -> {j['extension_after']:.3f})"
                          for j in path.jumps)
        print(f"  path: {len(path.points)} quasi-static steps; jumps at {jumps or 'none'}")
    if preset is not None:
        last = payload["points"][-1]
        print(f"  DNA: {preset.base_pairs} bp = {preset.length_nm:.4g} nm, F = "
              f"{payload['force_pN']:.4g} pN, D = {preset.effective_diameter_nm:.3g} nm; last "
              f"state: extension {last['extension_nm']:.4g} nm, torque "
              f"{last['torque_pN_nm']:.4g} pN nm")
        warn(f"note: {payload['athermal']}")
    print(f"wrote branch.json, branches/*.npz and figures to {out.resolve()}", flush=True)
    for note in payload["notes"]:
        warn(f"note: {note}")
    return payload


def _force_range(text, tension, preset) -> tuple[float, float]:
    """``--force-range LOW:HIGH`` in F L^2/A (pN with --dna); default ``0:2F``."""
    if text is None:
        return 0.0, 2.0 * tension if tension > 0 else 1.0
    words = text.split(":")
    try:
        if len(words) != 2:
            raise ValueError
        low, high = float(words[0]), float(words[1])
    except ValueError:
        fail(f"--force-range {text!r}: give LOW:HIGH, like 0:100")
    if not (math.isfinite(low) and math.isfinite(high) and 0 <= low < high <= 1e6):
        fail(f"--force-range {text!r}: need 0 <= LOW < HIGH <= 1e6")
    if preset is not None:
        low, high = preset.force_from_pN(low), preset.force_from_pN(high)
    return low, high


def _dna_inputs(twist_ratio, tension, length_over_diameter, end_distance, bp, force_pN,
                salt_mM, diameter_nm, temperature_K):
    """``(preset, C/A, F L^2/A, L/D)`` of the --dna options; one-line errors otherwise."""
    from supercoil.units.dna import DNAPreset, tweezers_parameters

    if end_distance is not None:
        fail("--end-distance cannot be combined with --dna: DNA runs are under a force "
             "(load control, --force-pN F); give --bp N --force-pN F [--salt-mM S | "
             "--diameter-nm D] [--temperature-K T]")
    for option, value in (("--twist-ratio", twist_ratio), ("--tension", tension),
                          ("--length-over-diameter", length_over_diameter)):
        if value is not None:
            fail(f"{option} cannot be combined with --dna (the DNA preset sets it); give "
                 "--bp N --force-pN F [--salt-mM S | --diameter-nm D] [--temperature-K T]")
    if bp is None or force_pN is None:
        fail("--dna needs --bp N (base pairs) and --force-pN F (pulling force in pN)")
    kwargs = {"base_pairs": bp, "salt_mM": salt_mM, "diameter_nm": diameter_nm}
    if temperature_K is not None:
        kwargs["temperature_K"] = temperature_K
    try:
        preset = DNAPreset(**kwargs)
        numbers = tweezers_parameters(preset, force_pN)
    except (TypeError, ValueError) as exc:
        fail(f"--dna: {exc}")
    return (preset, numbers["twist_ratio"], numbers["tension"],
            numbers["length_over_diameter"])
