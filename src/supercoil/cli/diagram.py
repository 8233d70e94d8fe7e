"""``supercoil diagram ring``: the ring's bifurcation diagram with self-contact.

Thin: parses the options into :class:`~supercoil.problems.ring_diagram.DiagramOptions`
(which validates them), checks the output folder, and computes the diagram with
:func:`supercoil.ring_diagram` and writes it with :mod:`supercoil.cli.diagram_output`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    FORMULATION_HELP,
    checked_path,
    fail,
    parse_ratio,
    refused,
    warn,
)
from supercoil.cli._options import MAGNITUDE, DiagramResume, overwrite_option, quiet_option
from supercoil.cli.model_options import (
    ModelOption,
    ShearOption,
    StretchOption,
    check_model,
    make_rod,
)
from supercoil.problems.ring_diagram import CONTINUATION_TREATMENTS, MAX_MODE

# the library's names of the diagram's inputs -> the options of 'supercoil diagram ring'
DIAGRAM_OPTIONS = {"twist_ratio": "--twist-ratio",
                   "length_over_diameter": "--length-over-diameter", "n_nodes": "--nodes",
                   "modes": "--modes", "max_excess_link": "--max-excess-link",
                   "contact": "--contact", "branch_depth": "--branch-depth",
                   "contact_curve": "--contact-curve",
                   "contact_formulation": "--contact-formulation",
                   "contact_max_points": "--contact-max-points",
                   "secondary_max_points": "--secondary-max-points",
                   "secondary_max_branches": "--secondary-max-branches",
                   "stretch_stiffness": "--stretch-stiffness",
                   "shear_stiffness": "--shear-stiffness", "slenderness": "--length-over-diameter"}


def _count(name: str, help: str):
    return Annotated[int, typer.Option(name, metavar="K", help=help)]


Quiet = quiet_option()
Overwrite = overwrite_option("Write into an existing non-empty --out DIR, replacing the "
                             "diagram's own files (other files are left alone).")
ContactMaxPoints = _count("--contact-max-points", "Most points of each contact branch, 2 to "
                          f"{checks.MAX_POINTS} (alpha to dLk 6 at N = 200 takes about 380).")
BranchDepth = _count("--branch-depth", "1 to 3. 1: the primary branches; 2: also the "
                     "secondary branches switched from their bifurcation points; 3: also the "
                     "tertiary ones (Coleman & Swigon 2002, Figure 2).")
SecondaryMaxPoints = _count("--secondary-max-points", "With --branch-depth 2 or 3: most "
                            "points of each secondary or tertiary half-branch, 2 to "
                            f"{checks.MAX_POINTS}.")
SecondaryMaxBranches = _count("--secondary-max-branches", "With --branch-depth 2 or 3: most "
                              "secondary and tertiary half-branches in all, K >= 0 (at a "
                              "pitchfork of a symmetric branch only one half is computed: "
                              "the other is its mirror image).")


def diagram_ring(
    twist_ratio: Annotated[float, typer.Option(
        "--twist-ratio", metavar="C/A", parser=parse_ratio, help="Twist stiffness over "
        f"bending stiffness, 0 < C/A <= {MAGNITUDE} (2/3 in Coleman & Swigon's DNA "
        "example).", show_default=False)],
    length_over_diameter: Annotated[float, typer.Option(
        "--length-over-diameter", metavar="L/D", help="Rod length over tube diameter, "
        f"pi < L/D <= {MAGNITUDE} (122 in Coleman & Swigon's DNA example).",
        show_default=False)],
    out: Annotated[Path, typer.Option(
        "--out", metavar="DIR", help="Folder for result.h5, diagram.json and the figures; an "
        "existing non-empty DIR is refused unless --overwrite or --resume.",
        show_default=False, callback=checked_path)],
    nodes: Annotated[int, typer.Option(
        "--nodes", metavar="N", help=f"Nodes of the discrete ring, {checks.MIN_NODES} to "
        f"{checks.MAX_NODES}; contact lines need segments shorter than D (N >= L/D).")] = 100,
    modes: Annotated[str, typer.Option(
        "--modes", metavar="M,M", help="Michell modes of the circle whose primary branches "
        f"are followed, from 2 to {MAX_MODE}: 2 = alpha, 3 = beta, ...")] = "2,3",
    max_excess_link: Annotated[float, typer.Option(
        "--max-excess-link", metavar="X", help="Upper bound of the excess link dLk on the "
        f"contact branches and the circle, in turns (0 < X <= {MAGNITUDE}).")] = 6.0,
    contact: Annotated[str, typer.Option(
        "--contact", metavar="TREATMENT", help="Self-contact treatment of the contact "
        f"branches: {' or '.join(CONTINUATION_TREATMENTS)} (barrier, the default, never "
        "penetrates; exact and augmented are not continued).")] = "barrier",
    contact_max_points: ContactMaxPoints = 150,
    branch_depth: BranchDepth = 1,
    secondary_max_points: SecondaryMaxPoints = 40,
    secondary_max_branches: SecondaryMaxBranches = 12,
    contact_curve: Annotated[str, typer.Option(
        "--contact-curve", metavar="CURVE", help="Curve whose self-distance is the contact "
        "distance: spline (the cubic B-spline of the nodes, default), polygon (the segments) "
        "or quintic (the quintic B-spline, with --contact-formulation integral only; "
        "docs/contact.md).")] = "spline",
    contact_formulation: Annotated[str, typer.Option(
        "--contact-formulation", metavar="FORM", help=FORMULATION_HELP)] = "integral",
    model: ModelOption = "kirchhoff",
    stretch_stiffness: StretchOption = None,
    shear_stiffness: ShearOption = None,
    overwrite: Overwrite = False,
    resume: DiagramResume = False,
    quiet: Quiet = False,
) -> None:
    """The ring's bifurcation diagram with self-contact (Coleman & Swigon 2002, Figures 1-4).

    The circle and its Michell bifurcations, the primary branches of --modes
    without contact up to the first contact (contact_onset), then with
    self-contact up to --max-excess-link; contact events and stability along
    them. Writes result.h5 (every branch with its states, saved point by point;
    read it with supercoil.load), diagram.json, link_writhe.png (dLk against Wr,
    stable parts heavy), contact_map.png (s/L of the contacts against Wr) and
    configurations.png (tubes of diameter D) into --out.

    With --model cosserat the rod shears and stretches (--stretch-stiffness,
    --shear-stiffness; by default those of a solid section of diameter D): the
    same branches, --branch-depth and --resume included; its contact acts on the
    centreline, and result.h5 keeps every point's centreline with its sections'
    rotations (frames/reference_rotations), from which --resume continues it.
    """
    check_model(model, stretch_stiffness, shear_stiffness)
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
        rod = make_rod(model, twist_ratio, nodes, stretch_stiffness, shear_stiffness,
                       slenderness=length_over_diameter)
    cosserat = rod if model == "cosserat" else None
    stored = prepare_folder(out, overwrite=overwrite, resume=resume, problem="ring_diagram",
                            settings=diagram_settings(options, "diagram ring", cosserat),
                            what="the diagram's files")
    if nothing_to_resume(stored):
        return
    print(f"supercoil diagram ring: C/A = {twist_ratio:g}, L/D = {length_over_diameter:g}, "
          f"N = {nodes}, modes {', '.join(words)}, dLk <= {max_excess_link:g}", flush=True)
    payload = run_diagram(options, out, quiet, resume=stored,
                          resume_hint="continue with the same command and --resume",
                          rod=cosserat)
    if payload is None:
        raise typer.Exit(EXIT_NOT_CONVERGED)
    message = incomplete_message(payload, out)
    if message is not None:
        warn(message)
        raise typer.Exit(EXIT_NOT_CONVERGED)


def register(app: typer.Typer, help_without_command) -> None:
    """Add the group ``diagram`` with its commands ``ring`` and ``knot`` to the ``supercoil``
    command."""
    from supercoil.cli.diagram_knot import diagram_knot

    group = typer.Typer(
        help="Bifurcation diagrams with self-contact (branches, stability, contact events).")
    group.callback(invoke_without_command=True)(help_without_command)
    group.command("ring")(diagram_ring)
    group.command("knot")(diagram_knot)
    app.add_typer(group, name="diagram")
