"""Options shared by the commands, spelled one way everywhere: ``--json PATH``,
``-q/--quiet``, ``--overwrite``, the ``RESULT`` argument of the commands that read a
result, and the numbers the help texts quote."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import checked_path


def exponent(value: float) -> str:
    """``1e-4`` rather than ``0.0001`` (``:g``) or ``1e-04`` (``:.0e``)."""
    mantissa, power = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(power)}"


MAGNITUDE = exponent(checks.MAX_MAGNITUDE)  # 1e6, the bound of C/A, |dLk|, L/D, F L^2/A

JsonOption = Annotated[
    str | None,
    typer.Option(
        "--json",
        metavar="PATH",
        help="Write the machine-readable result as JSON to PATH, replaced if it exists "
        "('-' = standard output, which suppresses the human-readable output). The file "
        "carries schema_version, units, conventions and provenance.",
        show_default=False,
    ),
]

PROGRESS_HELP = ("No progress display (by default a live line on a terminal, else a plain "
                 "line every 10 points on standard error).")
SILENT_HELP = "Nothing on standard output but --json -; errors still go to standard error."


def quiet_option(help: str = PROGRESS_HELP):
    """The ``-q/--quiet`` flag with the command's own meaning of quiet."""
    return Annotated[bool, typer.Option("--quiet", "-q", help=help)]


def overwrite_option(help: str):
    """The ``--overwrite`` flag: reuse an existing output (never ``--force``)."""
    return Annotated[bool, typer.Option("--overwrite", help=help)]


# the diagrams' --resume (diagram ring, diagram knot)
DiagramResume = Annotated[bool, typer.Option(
    "--resume", help="Continue the interrupted diagram in --out DIR from its result.h5 "
    "(the same options; a point limit may be raised): finished branches are kept, the "
    "others continued from their last point, and those that stopped at their point "
    "limit continued up to a raised one.")]


def result_argument(more: str = ""):
    """The RESULT argument of the commands that read a stored result; ``more``: what
    else the command reads."""
    return Annotated[
        Path,
        typer.Argument(metavar="RESULT", help="A result: the --out folder of any command "
                       "that computes (demo, diagram ring, tweezers, run, ring --out), its "
                       "result.h5, or its diagram.json or branch.json." + more,
                       show_default=False, callback=checked_path),
    ]


ResultArgument = result_argument()
