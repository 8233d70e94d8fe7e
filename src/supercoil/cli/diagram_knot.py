"""``supercoil diagram knot``: a knotted ring's diagram in its excess link.

Thin: parses the options, checks them by building
:class:`~supercoil.problems.knot_diagram.KnotDiagramOptions` and the output
folder (with ``--resume``, the stored result's options, a point limit only raised)
before anything is computed, then calls :func:`supercoil.knot_diagram`, which appends every
accepted point to ``result.h5`` as it comes (Ctrl-C or SIGTERM leave an
``interrupted`` result that ``--resume`` continues), writes ``diagram.json`` and
draws the figures from its summary: ``link_writhe.png`` (dLk against Wr, as for
``diagram ring``), ``energy.png`` (energy against dLk) and ``configurations.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    checked_path,
    parse_ratio,
    parse_span,
    refused,
)
from supercoil.cli._options import MAGNITUDE, DiagramResume, overwrite_option, quiet_option

KNOT_OPTIONS = {"knot": "--knot", "twist_ratio": "--twist-ratio",
                "length_over_diameter": "--length-over-diameter",
                "excess_link": "--excess-link", "n_nodes": "--nodes",
                "max_points": "--max-points", "start": "--start", "deflation": "--deflation",
                "branch_depth": "--branch-depth",
                "secondary_max_points": "--secondary-max-points",
                "secondary_max_branches": "--secondary-max-branches"}
Overwrite = overwrite_option("Write into an existing non-empty --out DIR, replacing the "
                             "diagram's own files (other files are left alone).")
Quiet = quiet_option()
FIGURES = ("link_writhe.png", "energy.png", "configurations.png")


def diagram_knot(
    knot: Annotated[str, typer.Option(
        "--knot", metavar="NAME", help="The knot: 3_1, 4_1, 5_1, 5_2, 7_1, 8_19 (a trailing * "
        "for the mirror image) or a torus knot T(p,q).", show_default=False)],
    twist_ratio: Annotated[float, typer.Option(
        "--twist-ratio", metavar="C/A", parser=parse_ratio, help="Twist stiffness over "
        f"bending stiffness, 0 < C/A <= {MAGNITUDE} (1.4 in Coleman & Swigon's Figure 5).",
        show_default=False)],
    length_over_diameter: Annotated[float, typer.Option(
        "--length-over-diameter", metavar="L/D", help="Rod length over tube diameter, "
        f"pi < L/D <= {MAGNITUDE}, and at least the knot's ropelength (about 16.4 for 3_1; "
        "170 in Coleman & Swigon's Figure 5).", show_default=False)],
    excess_link: Annotated[str, typer.Option(
        "--excess-link", metavar="A:B", help="The range of the excess link dLk in turns, "
        f"-{MAGNITUDE} <= A < B <= {MAGNITUDE}; the knot is relaxed at its middle (or "
        "--start) and followed both ways.",
        show_default=False)],
    out: Annotated[Path, typer.Option(
        "--out", metavar="DIR", help="Folder for result.h5, diagram.json and the figures; an "
        "existing result there is refused unless --overwrite.", show_default=False,
        callback=checked_path)],
    nodes: Annotated[int, typer.Option(
        "--nodes", metavar="N", help=f"Nodes of the ring, {checks.MIN_NODES} to "
        f"{checks.MAX_NODES}; contact lines need segments shorter than D (N >= L/D).")] = 60,
    max_points: Annotated[int, typer.Option(
        "--max-points", metavar="K", help="Most points of each half (up and down), 2 to "
        f"{checks.MAX_POINTS}.")] = 150,
    start: Annotated[float | None, typer.Option(
        "--start", metavar="X", help="The dLk at which the knot is relaxed, A <= X <= B "
        "(default: the middle).", show_default=False)] = None,
    deflation: Annotated[int, typer.Option(
        "--deflation", metavar="K", help="Computed points, spread over A:B, at which further "
        "equilibria are sought by deflation (Farrell, Birkisson & Funke 2015) and by "
        "relaxing the knot anew, each new one followed both ways; 0 to 50.")] = 3,
    branch_depth: Annotated[int, typer.Option(
        "--branch-depth", metavar="K", help="1 to 3. 1: the branches through the relaxed "
        "knot and the states found by --deflation; 2: also the half-branches switched "
        "from their bifurcation points (knot_I+, knot_II-, ...); 3: also those switched "
        "from the bifurcation points of these.")] = 1,
    secondary_max_points: Annotated[int, typer.Option(
        "--secondary-max-points", metavar="K", help="With --branch-depth 2 or 3: most "
        f"points of each switched half-branch, 2 to {checks.MAX_POINTS}.")] = 60,
    secondary_max_branches: Annotated[int, typer.Option(
        "--secondary-max-branches", metavar="K", help="With --branch-depth 2 or 3: most "
        "switched half-branches in all, K >= 0.")] = 12,
    overwrite: Overwrite = False,
    resume: DiagramResume = False,
    quiet: Quiet = False,
) -> None:
    """A knotted ring's diagram in its excess link, with self-contact (Coleman & Swigon
    2000, Figure 5).

    The knot is relaxed with self-contact at the middle of --excess-link and
    followed both ways by continuation (branches knot_up and knot_down), its knot
    type checked at every step; folds, bifurcations, contact events and stability
    along them; the lowest-energy state found at each dLk marked. Writes result.h5
    (every branch with its states, saved point by point; read it with
    supercoil.load), diagram.json, link_writhe.png (dLk against Wr, stable parts
    heavy), energy.png (energy against dLk) and configurations.png.
    At --deflation K computed points further equilibria are sought, by deflation
    and by relaxing the knot anew, and each new one is followed both ways
    (branches deflated_1_up, deflated_1_down, relaxed_1_up, ...). With
    --branch-depth 2 the half-branches that bifurcate from the located bifurcation
    points are switched onto along the critical mode and followed too (knot_I+,
    knot_I-, ...; their parent and origin in diagram.json).
    """
    from supercoil.api.knot_diagram import DIAGRAM_JSON, finish
    from supercoil.api.recording import stored_branches
    from supercoil.cli.diagram_output import diagram_settings
    from supercoil.cli.saving import nothing_to_resume, open_writer, prepare_folder, run_saving
    from supercoil.io.results import write_json
    from supercoil.problems.knot_diagram import KnotDiagramOptions

    span = parse_span("--excess-link", excess_link,
                      "dLk_min:dLk_max in turns, like 2:5")
    with refused(KNOT_OPTIONS):
        options = KnotDiagramOptions(knot, twist_ratio, length_over_diameter, span, nodes,
                                     max_points, start, deflation,
                                     branch_depth=branch_depth,
                                     secondary_max_points=secondary_max_points,
                                     secondary_max_branches=secondary_max_branches)
    stored = prepare_folder(out, overwrite=overwrite, resume=resume, problem="knot_diagram",
                            what="the diagram's files")
    if stored is not None:  # the stored options must be these (the verb's own check)
        with refused(KNOT_OPTIONS):
            stored_branches(stored, "knot_diagram", options)
    if nothing_to_resume(stored):
        return
    import supercoil as sc

    print(f"supercoil diagram knot: {knot}, C/A = {twist_ratio:g}, "
          f"L/D = {length_over_diameter:g}, N = {nodes}, dLk {span[0]:g}:{span[1]:g}",
          flush=True)
    writer = open_writer(out, resume=resume, problem="knot_diagram",
                         settings=diagram_settings(options, "diagram knot"),
                         attributes={"twist_ratio": options.twist_ratio, "n_nodes": nodes,
                                     "closed": True, "diameter": options.diameter,
                                     "length_over_diameter": options.length_over_diameter},
                         provenance={"contact_treatment": "barrier", "n_nodes": nodes})

    def compute(message, on_point):
        with refused(KNOT_OPTIONS):
            return sc.knot_diagram(knot, twist_ratio, length_over_diameter, span, nodes=nodes,
                                   max_points=max_points, start=start, deflation=deflation,
                                   branch_depth=branch_depth,
                                   secondary_max_points=secondary_max_points,
                                   secondary_max_branches=secondary_max_branches,
                                   out=writer, resume=resume, progress=message,
                                   on_point=on_point)

    result = run_saving(compute, writer, quiet,
                        resume_hint="continue with the same command and --resume")
    if result is None:
        raise typer.Exit(EXIT_NOT_CONVERGED)
    finish(writer, result.computed, result.summary)
    write_json(result.summary, out / DIAGRAM_JSON)
    draw_figures(result, out)
    summary = result.summary
    for b in summary["branches"]:
        specials = [p for p in summary["special_points"] if p["branch"] == b["name"]]
        kinds = ", ".join(f"{p['kind']} at dLk {p['excess_link']:.4f}" for p in specials)
        print(f"  {b['name']}: {b['n_points']} points, {b['seconds']:.1f} s, "
              f"{b['status'].lower()}" + (f"; {kinds}" if kinds and not quiet else ""))
    print(f"wrote result.h5, diagram.json, {', '.join(FIGURES)} to {out.resolve()}",
          flush=True)
    if not result.ok:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def draw_figures(result, out: Path) -> None:
    """The figures of the summary of :func:`supercoil.knot_diagram` into ``out``."""
    from supercoil.plotting.figures import through_special_points
    from supercoil.plotting.knot_diagram import draw_knot_figures

    summary = result.summary
    rows = []
    for b in summary["branches"]:
        points = [p for p in summary["points"] if p["branch"] == b["name"]]
        row = {"name": b["name"], **{k: [p[k] for p in points]
                                     for k in ("writhe", "excess_link", "energy", "stable")}}
        rows.append(row)
    specials = summary["special_points"]
    title = (f"{summary['knot_type']} ring, C/A = {summary['twist_ratio']:.4g}, "
             f"L/D = {summary['length_over_diameter']:g}, N = {summary['n_nodes']}")
    link = [through_special_points(r, specials, ("writhe", "excess_link")) for r in rows]
    energy = [through_special_points(r, specials, ("excess_link", "energy")) for r in rows]
    configurations = []
    for branch in result.branches:
        for index in sorted({0, len(branch) // 2, len(branch) - 1}):
            configurations.append({
                "label": f"{branch.name}, dLk = {branch.parameter_values[index]:.3f}, "
                         f"Wr = {float(branch.records['writhe'][index]):.3f}",
                "points": branch.states[index].reshape(-1, 3)})
    draw_knot_figures(out, link, energy, specials, configurations,
                      summary["diameter"], title)
