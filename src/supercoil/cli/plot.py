"""``supercoil plot RESULT --kind ... --out DIR``: figures of a result, PNG and SVG.

Thin: reads the result through :mod:`supercoil.plotting.result_data`, draws
with :mod:`supercoil.plotting.figures`. matplotlib is imported inside the
command, so that ``supercoil --help`` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import checked_path, fail
from supercoil.cli._options import ResultArgument, overwrite_option, quiet_option

KINDS = ("diagram", "contact-map", "hat-curve", "configurations")  # figures.KINDS
FORMATS = ("png", "svg")
Quiet = quiet_option("Print nothing on standard output; errors still go to standard error.")
Overwrite = overwrite_option("Replace existing figure files of the same names.")


def plot(
    result: ResultArgument,
    out: Annotated[
        Path,
        typer.Option("--out", metavar="DIR", help="Folder for the figures (created if "
                     "missing). Existing figure files of the same names are refused "
                     "unless --overwrite; other files are left alone.", show_default=False,
                       callback=checked_path),
    ],
    kind: Annotated[
        list[str] | None,
        typer.Option("--kind", metavar="KIND", help="Figure to draw, repeatable: diagram "
                     "(dLk against Wr, stable parts heavy, special points), contact-map "
                     "(s/L of the contacts against Wr), hat-curve (extension against "
                     "turns, tweezers), configurations (tubes of diameter D). Default: "
                     "every kind the result has data for.", show_default=False),
    ] = None,
    formats: Annotated[
        str,
        typer.Option("--format", metavar="FMT,FMT", help="File formats: png, svg or both."),
    ] = "png,svg",
    overwrite: Overwrite = False,
    quiet: Quiet = False,
) -> None:
    """Publication figures of a result as PNG and SVG, in one style, axes with units.

    Files: DIR/diagram.png, contact_map.png, hat_curve.png, configurations.png
    (and .svg). Nothing is computed: the numbers drawn are the result's.
    """
    kinds = list(dict.fromkeys(kind or []))
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        fail(f"--kind {bad[0]!r}: give one of {', '.join(KINDS)}")
    fmts = list(dict.fromkeys(w.strip().lower() for w in formats.split(",") if w.strip()))
    if not fmts or any(f not in FORMATS for f in fmts):
        fail(f"--format {formats!r}: give png, svg or png,svg")
    if out.exists() and not out.is_dir():
        fail(f"--out {out}: is a file, not a folder; give a folder")

    from supercoil.plotting.figures import output_stem, plot_result, supported_kinds
    from supercoil.plotting.result_data import ResultError, load_result

    try:
        data = load_result(result)
        available = supported_kinds(data)  # reads the branch files
    except ResultError as exc:
        fail(str(exc))
    if not kinds:
        kinds = list(available)
    missing = [k for k in kinds if k not in available]
    if missing:
        fail(f"{result}: a {data.kind} result has no data for --kind {missing[0]}; kinds it "
             f"has: {', '.join(available) or 'none'}")
    targets = [out / f"{output_stem(k)}.{f}" for k in kinds for f in fmts]
    existing = [t for t in targets if t.exists()]
    if existing and not overwrite:
        fail(f"--out {out}: {existing[0].name} exists; give a new folder, or add --overwrite to "
             "replace the figures")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(f"--out {out}: cannot create the folder ({exc.strerror}); give a folder in a "
             "writable location")
    written = []
    for k in kinds:
        try:
            written += plot_result(data, k, out, fmts)
        except ValueError as exc:
            fail(str(exc))
        except OSError as exc:
            fail(f"--out {out}: cannot write the {k} figure ({exc.strerror or exc}); give a "
                 "writable folder")
    if not quiet:
        print(f"wrote {', '.join(p.name for p in written)} to {out.resolve()}")

