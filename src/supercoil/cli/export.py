"""``supercoil export RESULT``: one state of a result file to VTK, XYZ, PDB or OBJ.

Thin: checks the options and the output path, then writes with :func:`supercoil.export`.
Lengths are written in the result's units: nm for a DNA study, units of the
rod length L otherwise (then ``pdb`` needs ``--bp`` to know the base pairs).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil import checks
from supercoil.cli._common import checked_path, fail, path_kind, refused, require_count
from supercoil.cli._options import overwrite_option, quiet_option
from supercoil.units.dna import RISE_NM_PER_BP

FORMATS = ("vtk", "xyz", "pdb", "obj")
MIN_SIDES, MAX_SIDES = 3, 256  # vertices around the tube of an obj mesh
Quiet = quiet_option("Print nothing on standard output; errors still go to standard error.")
Overwrite = overwrite_option("Replace an existing --out file.")



def export_command(
    result: Annotated[Path, typer.Argument(metavar="RESULT", help="A result: the --out "
                                           "folder of any command that computes, its "
                                           "result.h5, or its diagram.json or branch.json.",
                                           show_default=False, callback=checked_path)],
    out: Annotated[Path, typer.Option("--out", metavar="FILE", help="The file to write; an "
                                      "existing file is refused unless --overwrite.",
                                      show_default=False, callback=checked_path)],
    branch: Annotated[str | None, typer.Option(
        "--branch", metavar="NAME", help="Branch name (default: the only branch, or the "
        "last one computed).", show_default=False)] = None,
    point: Annotated[int, typer.Option("--point", metavar="I", help="Point index on the "
                                       "branch, from -K to K - 1 for a branch of K points "
                                       "(negative counts from the end).")] = -1,
    fmt: Annotated[str | None, typer.Option(
        "--format", metavar="FORMAT", help="vtk (polyline + TubeRadius, ParaView), xyz, pdb "
        "(one bead per base pair, DNA) or obj (tube mesh); default: from the --out suffix.",
        show_default=False)] = None,
    sides: Annotated[int, typer.Option("--sides", metavar="N", help="Vertices around the "
                                       f"tube (obj), {MIN_SIDES} to {MAX_SIDES}.")] = 16,
    bp: Annotated[int | None, typer.Option(
        "--bp", metavar="N", help="pdb of a nondimensional result: read the rod as N base "
        f"pairs of DNA, {checks.MIN_BASE_PAIRS} to {checks.MAX_BASE_PAIRS} (L = N x "
        f"{RISE_NM_PER_BP:g} nm).", show_default=False)] = None,
    overwrite: Overwrite = False,
    quiet: Quiet = False,
) -> None:
    """Export one state of a result file: VTK, XYZ, PDB (DNA beads) or OBJ tube.

    VTK polydata with the tube radius (ParaView), XYZ, PDB-style coarse-grained DNA
    (one bead per base pair) or an OBJ tube mesh, in the result's units (nm for DNA)."""
    from supercoil.io.exports import SUFFIXES
    if fmt is None:
        by_suffix = {v: k for k, v in SUFFIXES.items()}
        fmt = by_suffix.get(out.suffix.lower())
        if fmt is None:
            fail(f"--out {out}: cannot tell the format from the suffix "
                 f"{out.suffix or '(none)'!r}; give --format {'|'.join(FORMATS)}")
    if fmt not in FORMATS:
        fail(f"--format {fmt!r}: give one of {', '.join(FORMATS)}")
    require_count("--sides", sides, MIN_SIDES, MAX_SIDES)
    if bp is not None:
        with refused({"base_pairs": "--bp"}):
            checks.integer("base_pairs", bp, checks.MIN_BASE_PAIRS, checks.MAX_BASE_PAIRS)
    kind = path_kind("--out", out)
    if kind == "folder":
        fail(f"--out {out}: is a folder; give a file path")
    if out.exists() and not overwrite:
        fail(f"--out {out}: exists; give another path or add --overwrite to replace it")
    if len(out.name.encode()) > 255:
        fail(f"--out {str(out)[:80]}...: the file name is longer than 255 bytes; give a "
             "shorter name")
    if path_kind("--out", out.parent) != "folder":
        fail(f"--out {out}: folder {out.parent} does not exist; give a path in an existing "
             "folder")
    import supercoil

    with refused({"branch": "--branch", "point": "--point", "format": "--format",
                  "base_pairs": "--bp", "path": "--out", "sides": "--sides"}):
        done = supercoil.export(result, out, format=fmt, branch=branch, point=point,
                                sides=sides, base_pairs=bp, overwrite=overwrite)
    if not quiet:
        print(f"wrote {out} ({done.format}, branch {done.branch}, point {done.point}, lengths "
              f"in {done.unit})")
