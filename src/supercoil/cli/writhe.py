"""``supercoil writhe FILE``: the writhe of a polygonal curve.

Thin: reads the curve (:func:`supercoil.io.curves.read_curve`), calls
:func:`supercoil.writhe`, prints or writes the number with the JSON envelope.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import (
    check_json_target,
    checked_path,
    fail,
    parse_vector,
    refused,
    write_json_or_fail,
)
from supercoil.cli._options import JsonOption, quiet_option

CLOSURES = ("closed", "none", "chord", "axis")
Quiet = quiet_option("Print nothing on standard output (but the JSON of --json -); errors "
                     "still go to standard error.")


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
    quiet: Quiet = False,
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

    from supercoil import writhe as compute_writhe
    from supercoil.io.curves import read_curve

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
    if json_path != "-" and not quiet:
        tail = f", axis {axis}" if closure == "axis" else ""
        print(f"writhe {value:.15g}  ({len(points)} vertices, closure {closure}{tail})")
