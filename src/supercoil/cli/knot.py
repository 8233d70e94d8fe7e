"""``supercoil knot FILE [--json PATH]``: the knot type of a closed curve.

Thin: reads the curve as ``supercoil writhe`` does, calls
:func:`supercoil.knot_type`, prints or writes the result with the
JSON envelope.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import check_json_target, checked_path, fail, write_json_or_fail
from supercoil.cli._options import JsonOption, quiet_option

_HANDS = {1: "+1", -1: "-1", 0: "0"}
Quiet = quiet_option("Print nothing on standard output (but the JSON of --json -); errors "
                     "still go to standard error.")


def knot(
    file: Annotated[
        Path,
        typer.Argument(
            metavar="FILE",
            help="Text file of the closed curve: one vertex 'x y z' per line (spaces, tabs "
            "or commas), each vertex once (the last is joined to the first); '#' starts a "
            "comment; blank lines are ignored. Any length unit.",
            show_default=False, callback=checked_path,
        ),
    ],
    json_path: JsonOption = None,
    quiet: Quiet = False,
) -> None:
    """Knot type of a closed polygonal curve: name, chirality, Alexander polynomial.

    Projects the curve generically, simplifies the diagram by Reidemeister I and
    II moves, computes the Alexander polynomial, the determinant |Δ(-1)| and the
    Jones polynomial exactly, and names the knot from the table of prime knots up
    to 10 crossings (KnotInfo) and their connected sums ('3_1#3_1'); candidates
    the polynomials do not separate are joined by '|', and 'unknown' means none
    matched. Chirality: +1 the table's (3_1 = right-handed trefoil), -1 its
    mirror image, 0 amphichiral or undetermined (from the Jones polynomial; the
    writhe's sign does not decide it).
    """
    check_json_target(json_path)

    from supercoil.io.curves import CurveFileError, read_curve

    try:
        points = read_curve(file)
    except CurveFileError as exc:
        fail(str(exc))
    if len(points) < 3:
        fail(f"curve file {file}: {len(points)} vertex(es); a closed curve needs at least 3")

    from supercoil import knot_type

    try:
        result = knot_type(points)
    except ValueError as exc:
        fail(f"curve file {file}: {exc}")

    low, coefficients = result.jones
    payload = {
        "knot_type": result.name,
        "chirality": result.chirality,
        "alexander_polynomial": list(result.alexander),
        "determinant": result.determinant,
        "crossings": result.crossings,
        "jones_polynomial": {"lowest_power": low, "coefficients": list(coefficients)},
        "candidates": [[{"knot_type": name, "chirality": hand} for name, hand in factors]
                       for factors in result.candidates],
        "n_nodes": len(points),
    }
    if json_path is not None:
        from supercoil.io.results import envelope

        write_json_or_fail(envelope(payload, n_nodes=len(points), tolerances={}), json_path)
    if json_path != "-" and not quiet:
        from supercoil.topology.knots.polynomials import format_laurent

        name = result.name or "unknown"
        alexander = format_laurent((0, result.alexander))
        jones = format_laurent(result.jones)
        print(f"knot {name}  chirality {_HANDS[result.chirality]}  determinant "
              f"{result.determinant}  ({result.crossings} crossings after simplification, "
              f"{len(points)} vertices)")
        print(f"alexander {alexander}")
        print(f"jones {jones}")

