"""``supercoil view RESULT [--out FILE.html]``: the interactive viewer as one HTML file.

Thin: reads the result through :mod:`supercoil.plotting.result_data`, writes
the page with :mod:`supercoil.plotting.viewer`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import checked_path, fail
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
    from supercoil.plotting.result_data import ResultError, load_result

    if out is not None and out.suffix.lower() not in (".html", ".htm"):
        fail(f"--out {out}: give a file name ending in .html")
    try:
        data = load_result(result)
    except ResultError as exc:
        fail(str(exc))
    if out is None:
        out = (result if result.is_dir() else result.parent) / "viewer.html"
    if out.is_dir():
        fail(f"--out {out}: is a folder; give a file name ending in .html")
    if out.exists() and not overwrite:
        fail(f"--out {out}: file exists; give a new file name, or add --overwrite to replace it")
    if not out.parent.is_dir():
        fail(f"--out {out}: folder {out.parent} does not exist; give a file in an existing "
             "folder")

    from supercoil.plotting.viewer import write_viewer

    try:
        write_viewer(data, out)
    except ValueError as exc:
        fail(str(exc))
    except OSError as exc:
        fail(f"--out {out}: cannot write ({exc.strerror or exc}); give a file in a writable "
             "folder")
    if not quiet:
        size = out.stat().st_size
        print(f"wrote {out.resolve()} ({size / 1e6:.1f} MB); open it in a web browser")

