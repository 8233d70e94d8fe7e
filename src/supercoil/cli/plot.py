"""``supercoil plot RESULT --kind ... --out DIR``: figures of a result or a sweep, PNG and SVG.

Thin: reads the result through :mod:`supercoil.plotting.result_data`, draws
with :mod:`supercoil.plotting.figures`; a sweep's folder (``supercoil sweep
--out``, holding ``sweep.nc``) is drawn by :mod:`supercoil.plotting.sweep`.
matplotlib is imported inside the command, so that ``supercoil --help`` stays fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import checked_path, fail
from supercoil.cli._options import overwrite_option, quiet_option, result_argument

KINDS = ("diagram", "contact-map", "hat-curve", "configurations")  # figures.KINDS
SWEEP_KINDS = ("hat-curves", "curve-map", "map", "buckling-torque")  # plotting.sweep
FORMATS = ("png", "svg")
SweepOrResultArgument = result_argument(" Or a sweep: the --out folder of supercoil sweep, "
                                        "or its sweep.nc.")
Quiet = quiet_option("Print nothing on standard output; errors still go to standard error.")
Overwrite = overwrite_option("Replace existing figure files of the same names.")


def plot(
    result: SweepOrResultArgument,
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
                     "turns, tweezers), configurations (tubes of diameter D). Of a "
                     "sweep: hat-curves (every task's hat curve on one axes), curve-map "
                     "(extension over turns and force, or writhe over dLk or sigma and "
                     "the swept key), map (a number of the dataset, --variable, over the "
                     "swept keys), buckling-torque (against the force). Default: every "
                     "kind the result has data for.", show_default=False),
    ] = None,
    variable: Annotated[
        str | None,
        typer.Option("--variable", metavar="NAME", help="Sweeps: the dataset's number drawn "
                     "by --kind map (e.g. buckling_turns, end_extension, "
                     "alpha_contact.end.writhe). Default: end_extension (tweezers), folds "
                     "(ring diagrams), ring.end.writhe (rings).", show_default=False),
    ] = None,
    formats: Annotated[
        str,
        typer.Option("--format", metavar="FMT,FMT", help="File formats: png, svg or both."),
    ] = "png,svg",
    overwrite: Overwrite = False,
    quiet: Quiet = False,
) -> None:
    """Publication figures of a result or a sweep as PNG and SVG, in one style, axes with
    units.

    Files: DIR/diagram.png, contact_map.png, hat_curve.png, configurations.png
    (and .svg); of a sweep: hat_curves.png, curve_map.png, map_NAME.png,
    buckling_torque.png. Nothing is computed: the numbers drawn are the result's.
    """
    from supercoil.plotting.sweep import is_sweep

    sweep = is_sweep(result)
    kinds = list(dict.fromkeys(kind or []))
    valid = SWEEP_KINDS if sweep else KINDS
    bad = [k for k in kinds if k not in valid]
    if bad:
        fail(f"--kind {bad[0]!r}: give one of {', '.join(valid)}"
             + (" (the kinds of a sweep)" if sweep else ""))
    if variable is not None and not sweep:
        fail(f"--variable {variable!r}: only a sweep's map takes it; {result} is not a sweep "
             "folder (supercoil sweep --out)")
    fmts = list(dict.fromkeys(w.strip().lower() for w in formats.split(",") if w.strip()))
    if not fmts or any(f not in FORMATS for f in fmts):
        fail(f"--format {formats!r}: give png, svg or png,svg")
    if out.exists() and not out.is_dir():
        fail(f"--out {out}: is a file, not a folder; give a folder")
    if sweep:
        _plot_sweep(result, kinds, variable, out, fmts, overwrite, quiet)
        return

    from supercoil.plotting.figures import output_stem, plot_result, supported_kinds
    from supercoil.plotting.result_data import ResultError, load_result

    try:
        data = load_result(result)
        available = supported_kinds(data)  # reads the branch files
    except ResultError as exc:
        fail(str(exc))
    kinds = _chosen_kinds(kinds, available, f"{result}: a {data.kind} result")
    _prepare_out(out, [f"{output_stem(k)}.{f}" for k in kinds for f in fmts], overwrite)
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


def _chosen_kinds(kinds: list[str], available, source: str) -> list[str]:
    """The figure ``kinds`` asked for (all ``available`` when none), each refused unless
    ``source`` (e.g. ``"PATH: this sweep"``) has data for it."""
    if not kinds:
        kinds = list(available)
    missing = [k for k in kinds if k not in available]
    if missing:
        fail(f"{source} has no data for --kind {missing[0]}; kinds it has: "
             f"{', '.join(available) or 'none'}")
    return kinds


def _prepare_out(out: Path, names: list[str], overwrite: bool) -> None:
    """Refuse to replace the figure files ``names`` in ``out`` without ``--overwrite``,
    then create ``out``."""
    existing = [name for name in names if (out / name).exists()]
    if existing and not overwrite:
        fail(f"--out {out}: {existing[0]} exists; give a new folder, or add --overwrite to "
             "replace the figures")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(f"--out {out}: cannot create the folder ({exc.strerror}); give a folder in a "
             "writable location")


def _plot_sweep(folder: Path, kinds: list[str], variable: str | None, out: Path,
                fmts: list[str], overwrite: bool, quiet: bool) -> None:
    """The sweep figures of ``supercoil plot`` (see :func:`plot`)."""
    from supercoil.errors import InputError
    from supercoil.plotting import style
    from supercoil.plotting.sweep import map_variable, sweep_figure, sweep_kinds, sweep_stem
    from supercoil.sweeps.dataset import load_sweep

    try:
        dataset = load_sweep(folder)
    except InputError as exc:
        fail(str(exc))
    available = sweep_kinds(dataset)
    kinds = _chosen_kinds(kinds, available, f"{folder}: this sweep")
    if "map" in kinds:
        name = map_variable(dataset, variable)
        numbers = [v for v in dataset.data_vars if dataset[v].dtype.kind == "f"]
        if name not in numbers:
            fail(f"--variable {name!r}: not a number of this sweep; numbers: "
                 f"{', '.join(numbers[:12])}{', ...' if len(numbers) > 12 else ''}")
    _prepare_out(out, [f"{sweep_stem(dataset, k, variable)}.{f}" for k in kinds for f in fmts],
                 overwrite)
    root = folder.parent if folder.is_file() else folder
    written = []
    for k in kinds:
        try:
            fig = sweep_figure(dataset, root, k, variable)
            written += style.save(fig, out / sweep_stem(dataset, k, variable), fmts)
        except (ValueError, InputError) as exc:
            fail(str(exc))
        except OSError as exc:
            fail(f"--out {out}: cannot write the {k} figure ({exc.strerror or exc}); give a "
                 "writable folder")
    if not quiet:
        print(f"wrote {', '.join(p.name for p in written)} to {out.resolve()}")
