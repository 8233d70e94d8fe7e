"""``supercoil tighten --knot NAME [--nodes N] [--json PATH]``: the tight knot, its ropelength.

Thin: validates the options, calls
:func:`supercoil.problems.knot_ring.tight_knot`, prints its record or writes it
as JSON with the coordinates of the tight curve.
"""

from __future__ import annotations

from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import (
    EXIT_NOT_CONVERGED,
    check_json_target,
    fail,
    refused,
    warn,
    write_json_or_fail,
)
from supercoil.cli._options import JsonOption, quiet_option

Quiet = quiet_option("Print nothing on standard output (but the JSON of --json -); errors "
                     "still go to standard error.")


def tighten(
    knot: Annotated[str | None, typer.Option(
        "--knot", metavar="NAME",
        help="The knot: 3_1, 4_1, 5_1, 5_2, 7_1 or 8_19 (a trailing '*' for the mirror "
        "image).", show_default=False)] = None,
    torus_knot: Annotated[str | None, typer.Option(
        "--torus-knot", metavar="P,Q", help="Instead of --knot, the torus knot T(P,Q).",
        show_default=False)] = None,
    nodes: Annotated[int, typer.Option(
        "--nodes", metavar="N",
        help=f"Nodes of the discrete ring, {checks.MIN_NODES} <= N <= {checks.MAX_NODES}; "
        "the ropelength falls towards its limit as about 1/N^2 (the trefoil: 16.73 at "
        "N = 40, 16.47 at 80, 16.42 at 120).")] = 60,
    json_path: JsonOption = None,
    quiet: Quiet = False,
) -> None:
    """The tight (ideal) shape of a knot: the thickest tube it can be tied in.

    Continuation in L/D downward: the knot, of length L = 1, is relaxed with a
    barrier on its gaps and the tube diameter D raised step by step, every step
    guarded so that the knot type never changes, until the tube cannot thicken
    (the gap of the tightest pair below 1e-4 D). The JSON reports
    length_over_diameter (the ropelength L/D at the tight limit, reached from
    above), writhe, the contacts, the smallest radius of curvature over D (a
    tube must keep it >= 1/2), the knot type and the coordinates ('points').
    The ideal trefoil has L/D about 16.37 and writhe about 3.41 (Pieranski 1998;
    Baranska, Pieranski & Rawdon 2005; Carlen et al. 2005). The rod carries no
    twist stiffness to speak of (C/A = 1e-3), as an ideal knot.
    """
    check_json_target(json_path)
    if (knot is None) == (torus_knot is None):
        fail("give one of --knot NAME and --torus-knot P,Q, e.g. --knot 3_1")
    given = knot if torus_knot is None else f"T({torus_knot})"
    names = {"knot": f"--knot {knot}" if torus_knot is None else f"--torus-knot {torus_knot}",
             "n_nodes": "--nodes"}

    from supercoil.problems.knot_ring import parse_knot, tight_knot

    with refused(names):
        parse_knot(given)
        checks.integer("n_nodes", nodes, checks.MIN_NODES, checks.MAX_NODES,
                       meaning="nodes of the ring")
        result = tight_knot(given, nodes)
    record = result.record()
    if json_path is not None:
        from supercoil.io.results import envelope

        payload = {**record, "knot": given, "points": result.points.tolist()}
        write_json_or_fail(envelope(payload, n_nodes=nodes, tolerances={
            "relative_thickening": 1e-4}, contact_treatment="barrier"), json_path)
    if json_path != "-" and not quiet:
        hand = {1: "+1", -1: "-1", 0: "0"}[record["chirality"]]
        print(f"{record['knot_type']} (chirality {hand}) at {nodes} nodes: "
              f"L/D = {record['length_over_diameter']:.5g}, writhe "
              f"{record['writhe']:.4g}, {record['n_contact_points']} contact points, "
              f"{record['n_contact_intervals']} contact intervals, smallest radius of "
              f"curvature {record['min_radius_of_curvature_over_diameter']:.3g} D")
    if not record["tight"]:
        warn(f"not tight: {record['message']}")
        raise typer.Exit(EXIT_NOT_CONVERGED)
