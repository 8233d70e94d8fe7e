"""A result's states as files for other programs, and its interactive viewer.

* :func:`export`: one state as VTK (ParaView), XYZ, PDB (one bead per base pair
  of DNA) or an OBJ tube mesh -- what ``supercoil export`` writes;
* :func:`view`: the one-page HTML viewer -- what ``supercoil view`` writes.

Both take a result in any form: :func:`supercoil.load`'s, a result file or
output folder (or the ``diagram.json`` / ``branch.json`` beside it), or a
:class:`~supercoil.api.results.Diagram` or
:class:`~supercoil.api.results.Equilibrium` just computed (stored first, so
the files show what a stored result shows).
"""

from __future__ import annotations

import contextlib
import tempfile
from dataclasses import dataclass
from pathlib import Path

from supercoil.errors import InputError

FORMATS = ("vtk", "xyz", "pdb", "obj")
MIN_SIDES, MAX_SIDES = 3, 256  # vertices around the tube of an obj mesh


@contextlib.contextmanager
def stored(result):
    """The path of ``result`` as a stored result: a path as given, a loaded result's file, or a computed Diagram or Equilibrium saved in a temporary file
    for the duration of the block."""
    from supercoil.api.files import save
    from supercoil.api.results import Diagram, Equilibrium
    from supercoil.io.store import Result

    if isinstance(result, Result):
        yield result.path
    elif isinstance(result, (Diagram, Equilibrium)):
        with tempfile.TemporaryDirectory(prefix="supercoil-") as folder:
            yield save(result, Path(folder) / "result.h5")
    elif isinstance(result, (str, Path)):
        yield Path(result)
    else:
        raise InputError(f"result: expected a result (supercoil.load's, a path, a Diagram or "
                         f"an Equilibrium), got {type(result).__name__}", name="result")


@dataclass(frozen=True)
class Exported:
    """What :func:`export` wrote: the file, its format, the branch and point index of
    the state, and the unit of its lengths (``"nm"`` or ``"L"``)."""

    path: Path
    format: str
    branch: str
    point: int
    unit: str

    def __repr__(self) -> str:
        return (f"Exported({str(self.path)!r}: {self.format}, branch {self.branch}, point "
                f"{self.point}, lengths in {self.unit})")


def _branch_name(data, branch: str | None) -> str:
    names = list(data.branch_names)
    if not names:
        raise InputError(f"{data.path}: has no branch yet (the run stopped before its first "
                         "point)")
    name = names[-1] if branch is None else branch
    if name not in names:
        from difflib import get_close_matches

        close = get_close_matches(name, names, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(f"branch {name!r}: {data.path} has no such branch{hint}; branches: "
                         f"{', '.join(names)}", name="branch")
    return name


def export(result, path: str | Path, *, format: str | None = None, branch: str | None = None,
           point: int = -1, sides: int = 16, base_pairs: int | None = None,
           overwrite: bool = False) -> Exported:
    """Write one state of ``result`` to the file ``path``.

    ``format``: ``vtk`` (polyline with the tube radius, for ParaView), ``xyz``, ``pdb``
    (coarse-grained DNA, one bead per base pair) or ``obj`` (a tube mesh of ``sides``
    vertices around, 3 to 256); default: from the suffix of ``path``. ``branch``:
    its name (default: the last one computed); ``point``: its index, negative from
    the end. Lengths are in nm for a result in DNA units, else in units of L; with
    ``base_pairs`` a nondimensional rod is read as that many base pairs of DNA (a
    ``pdb`` of a nondimensional result needs it). An existing file is refused unless
    ``overwrite``.
    """
    from supercoil import checks
    from supercoil.io.exports import SUFFIXES, export_state
    from supercoil.io.store import Result, load
    from supercoil.units.dna import RISE_NM_PER_BP

    path = Path(path)
    if format is None:
        format = {v: k for k, v in SUFFIXES.items()}.get(path.suffix.lower())
        if format is None:
            raise InputError(f"path {path}: cannot tell the format from the suffix "
                             f"{path.suffix or '(none)'!r}; give format, one of "
                             f"{', '.join(FORMATS)}", name="path")
    if format not in FORMATS:
        raise InputError(f"format {format!r}: give one of {', '.join(FORMATS)}", name="format")
    checks.integer("sides", sides, MIN_SIDES, MAX_SIDES)
    if base_pairs is not None:
        checks.integer("base_pairs", base_pairs, checks.MIN_BASE_PAIRS, checks.MAX_BASE_PAIRS)
    if path.is_dir():
        raise InputError(f"path {path}: is a folder; give a file path", name="path")
    if path.exists() and not overwrite:
        raise InputError(f"path {path}: exists; give another path, or overwrite=True",
                         name="path")
    if not path.parent.is_dir():
        raise InputError(f"path {path}: folder {path.parent} does not exist; give a path in an "
                         "existing folder", name="path")
    with stored(result) as source:
        if source.suffix == ".json" and source.is_file():
            source = source.parent  # a summary names the result file beside it
        data = result if isinstance(result, Result) else load(source)
        name = _branch_name(data, branch)
        k = len(data.branch(name))
        if not -k <= point < k:
            raise InputError(f"point {point}: branch {name!r} has {k} points; give 0 to "
                             f"{k - 1} (or -1 for the last)", name="point")
        index = point % k
        points = data.centreline(name, index)
        b = data.branch(name)
        parameter = float(b.parameter_values[index])
    radius = data.diameter / 2 if data.diameter is not None else None
    length_nm = data.attributes.get("length_nm")
    scale, unit = 1.0, "L"
    if length_nm is not None:
        scale, unit = float(length_nm), "nm"
    elif base_pairs is not None:
        scale, unit = base_pairs * RISE_NM_PER_BP, "nm"
    if format == "pdb" and unit != "nm":
        raise InputError(f"base_pairs: {data.path} is nondimensional; give base_pairs N to "
                         "read the rod as N base pairs of DNA, or export xyz/vtk/obj",
                         name="base_pairs")
    if format == "obj" and radius is None:
        raise InputError(f"format obj: {data.path} has no tube diameter (a study without "
                         "self-contact); export vtk or xyz", name="format")
    title = (f"supercoil {data.problem}: branch {name}, point {index}, {b.parameter} = "
             f"{parameter:.10g}, lengths in {unit}")
    try:
        export_state(path, format, points * scale, closed=data.closed,
                     radius=None if radius is None else radius * scale,
                     rise=RISE_NM_PER_BP, title=title, sides=sides)
    except OSError as exc:
        raise InputError(f"path {path}: cannot write ({exc.strerror or exc})",
                         name="path") from None
    except ValueError as exc:
        raise InputError(f"format {format}: {exc}", name="format") from None
    return Exported(path=path, format=format, branch=name, point=index, unit=unit)


def view(result, path: str | Path | None = None, *, overwrite: bool = False) -> Path:
    """Write the interactive viewer of ``result`` as one self-contained HTML page (no
    server, works offline) and return its path: the bifurcation diagram beside the
    selected state as a tube with its contacts (``docs/viewer.md``). ``path``: a file
    ending in ``.html``; default ``viewer.html`` in the result's folder (give it for a
    result computed in memory). An existing file is refused unless ``overwrite``."""
    from supercoil.io.store import Result
    from supercoil.plotting.result_data import load_result
    from supercoil.plotting.viewer import write_viewer

    if path is not None and Path(path).suffix.lower() not in (".html", ".htm"):
        raise InputError(f"path {path}: give a file name ending in .html", name="path")
    with stored(result) as source:
        if path is None:
            if not isinstance(result, (str, Path, Result)):
                raise InputError("path: give the page's file name (the result has no folder)",
                                 name="path")
            path = (source if source.is_dir() else source.parent) / "viewer.html"
        path = Path(path)
        if path.is_dir():
            raise InputError(f"path {path}: is a folder; give a file name ending in .html",
                             name="path")
        if path.exists() and not overwrite:
            raise InputError(f"path {path}: file exists; give a new file name, or "
                             "overwrite=True to replace it", name="path")
        if not path.parent.is_dir():
            raise InputError(f"path {path}: folder {path.parent} does not exist; give a file "
                             "in an existing folder", name="path")
        data = load_result(source)
        try:
            write_viewer(data, path)
        except OSError as exc:
            raise InputError(f"path {path}: cannot write ({exc.strerror or exc}); give a file "
                             "in a writable folder", name="path") from None
        except ValueError as exc:
            raise InputError(str(exc)) from None
    return path
