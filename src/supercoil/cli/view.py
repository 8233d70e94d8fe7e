"""``supercoil view RESULT [--out FILE.html]``: the interactive viewer as one HTML file.

Thin: checks the options, writes the page with :func:`supercoil.view`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import checked_path, fail, refused
from supercoil.cli._options import ResultArgument, overwrite_option, quiet_option

Quiet = quiet_option("Print nothing on standard output; errors still go to standard error.")
Overwrite = overwrite_option("Replace an existing --out file.")


def view(
    result: ResultArgument,
    out: Annotated[
        Path | None,
        typer.Option("--out", metavar="FILE.html", help="The page to write. Default: "
                     "viewer.html in the result's folder. An existing file is refused "
                     "unless --overwrite.", show_default=False,
                       callback=checked_path),
    ] = None,
    overwrite: Overwrite = False,
    quiet: Quiet = False,
) -> None:
    """One self-contained HTML page (no server, works offline) to explore a result.

    Left the bifurcation diagram (stable parts heavy, special points by kind),
    right the selected state as a tube of diameter D with its contacts in red,
    and its numbers (excess link, writhe, twist, energy, unstable count,
    contacts, minimum gap). Click the diagram, drag the slider or press the
    arrow keys to move along a branch; drag the tube to turn it. A link to a
    state: FILE.html#branch=NAME&point=K.
    """
    if out is not None and out.suffix.lower() not in (".html", ".htm"):
        fail(f"--out {out}: give a file name ending in .html")
    target = out if out is not None else (
        (result if result.is_dir() else result.parent) / "viewer.html")
    if target.is_file() and not overwrite:
        fail(f"--out {target}: file exists; give a new file name, or add --overwrite to "
             "replace it")
    import supercoil

    with refused({"path": "--out"}):
        out = supercoil.view(result, out, overwrite=overwrite)
    if not quiet:
        size = out.stat().st_size
        print(f"wrote {out.resolve()} ({size / 1e6:.1f} MB); open it in a web browser")
