"""Exports of one state for other tools: VTK polydata, XYZ, PDB-style DNA beads, OBJ tube.

Every writer takes the centreline ``points`` (n, 3) in the output's length
unit, whether the rod is ``closed`` and the tube ``radius`` (D/2, same unit),
and writes one text file atomically (temporary file + rename):

* :func:`write_vtk`: legacy VTK ASCII ``POLYDATA`` (ParaView, VisIt): the
  centreline as one polyline (closed for rings: the first point repeated in the
  connectivity), point data ``TubeRadius`` (for ParaView's Tube filter: *Vary
  Radius* = By Absolute Scalar) and ``arc_length`` (s/L);
* :func:`write_xyz`: the XYZ format (count, comment, ``C x y z`` lines);
* :func:`write_pdb`: PDB ``ATOM`` records, one coarse-grained bead per base
  pair (atom ``P``, residue ``DNA``, chain ``A``), the centreline resampled at
  equal arc-length steps of the rise (0.34 nm) by :func:`resample`,
  coordinates in Å with the bounding box shifted to start at 0 (the fixed-width
  fields hold 0 .. 9999.999 Å), ``CONECT`` records along the chain
  (closed for rings);
* :func:`write_obj`: Wavefront OBJ triangle mesh of the tube of radius D/2
  around the centreline: ``sides`` vertices on a circle in the plane normal to
  the node tangent (the bisector of the two edges), framed by parallel
  transport with the holonomy of a closed curve spread evenly (no seam), so
  a ring's mesh is a closed torus-like surface (every edge shared by exactly
  two triangles); open rods get flat end caps.

Library code: raises ``ValueError`` for bad input (message names what is valid),
``OSError`` if the file cannot be written.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

FORMATS = ("vtk", "xyz", "pdb", "obj")
SUFFIXES = {"vtk": ".vtk", "xyz": ".xyz", "pdb": ".pdb", "obj": ".obj"}
DEFAULT_SIDES = 16
PDB_MAX_BEADS = 99_999  # five-digit atom serial numbers
PDB_COORDINATE_LIMIT = 9999.999  # %8.3f in Å


def _write_text(path: str | os.PathLike, text: str) -> Path:
    target = Path(path)
    handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp",
                                         dir=target.parent)
    try:
        with os.fdopen(handle, "w", encoding="ascii") as stream:
            stream.write(text)
        os.chmod(temporary, 0o644)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return target


def _points(points) -> np.ndarray:
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 2:
        raise ValueError(f"points must be an (n, 3) array with n >= 2, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("points must be finite")
    return p


def arc_length(points: np.ndarray, closed: bool) -> np.ndarray:
    """(n,) arc length of each node from node 0 along the polyline."""
    p = _points(points)
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def resample(points, closed: bool, spacing: float) -> np.ndarray:
    """Points at equal arc-length steps ``spacing`` along the polyline, from node 0.

    Closed: ``round(perimeter / spacing)`` points (the last step closes the loop,
    so the spacing is adjusted by less than half a step over the whole ring);
    open: ``floor(length / spacing) + 1`` points.
    """
    p = _points(points)
    if not spacing > 0:
        raise ValueError(f"spacing must be positive, got {spacing!r}")
    if closed:
        p = np.vstack([p, p[:1]])
    s = arc_length(p, False)
    total = s[-1]
    if closed:
        count = max(3, round(total / spacing))
        targets = np.arange(count) * (total / count)
    else:
        count = math.floor(total / spacing + 1e-9) + 1
        targets = np.arange(count) * spacing
    return np.column_stack([np.interp(targets, s, p[:, k]) for k in range(3)])


# ------------------------------------------------------------------------------ VTK
def write_vtk(path, points, *, closed: bool, radius: float | None,
              title: str = "supercoil state") -> Path:
    """Legacy ASCII VTK polydata (see the module docstring); without ``radius`` (a rod
    without a tube) the ``TubeRadius`` point data is left out."""
    p = _points(points)
    n = len(p)
    s = arc_length(p, closed)
    length = s[-1] + (np.linalg.norm(p[0] - p[-1]) if closed else 0.0)
    ids = list(range(n)) + ([0] if closed else [])
    lines = ["# vtk DataFile Version 3.0", " ".join(title.split())[:250], "ASCII",
             "DATASET POLYDATA", f"POINTS {n} double"]
    lines += [f"{x:.12g} {y:.12g} {z:.12g}" for x, y, z in p]
    lines += [f"LINES 1 {len(ids) + 1}", " ".join(map(str, [len(ids), *ids]))]
    lines += [f"POINT_DATA {n}"]
    if radius is not None:
        lines += ["SCALARS TubeRadius double 1", "LOOKUP_TABLE default"]
        lines += [f"{radius:.12g}"] * n
    lines += ["SCALARS arc_length double 1", "LOOKUP_TABLE default"]
    lines += [f"{v / length:.12g}" for v in s]
    return _write_text(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------------------ XYZ
def write_xyz(path, points, *, comment: str = "", element: str = "C") -> Path:
    """XYZ file: atom count, one comment line, ``element x y z`` per point."""
    p = _points(points)
    lines = [str(len(p)), " ".join(comment.split())]
    lines += [f"{element} {x:.10f} {y:.10f} {z:.10f}" for x, y, z in p]
    return _write_text(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------------------ PDB
def write_pdb(path, points_nm, *, closed: bool, rise_nm: float = 0.34, title: str = ""
              ) -> Path:
    """One bead per base pair (see the module docstring); ``points_nm`` in nm."""
    p = _points(points_nm)
    length = float(arc_length(np.vstack([p, p[:1]]) if closed else p, False)[-1])
    if not rise_nm > 0 or length / rise_nm > PDB_MAX_BEADS:  # before any bead is made
        raise ValueError(f"about {length / rise_nm:.3g} beads: PDB atom numbers have five "
                         f"digits (at most {PDB_MAX_BEADS} beads); export xyz or vtk instead")
    beads = resample(p, closed, rise_nm)
    if len(beads) > PDB_MAX_BEADS:
        raise ValueError(f"{len(beads)} beads: PDB atom numbers have five digits (at most "
                         f"{PDB_MAX_BEADS} beads); export xyz or vtk instead")
    # %8.3f holds -999.999 .. 9999.999: shift the bounding box to start at 0
    angstrom = 10.0 * (beads - beads.min(axis=0))
    if np.max(angstrom) > PDB_COORDINATE_LIMIT:
        raise ValueError(f"the molecule spans {np.max(angstrom) / 10:.0f} nm: PDB coordinates "
                         "hold at most 9999.999 Å (1 um); export xyz or vtk instead")
    lines = []
    words = " ".join(title.split())
    for i in range(0, min(len(words), 4 * 69), 69):  # TITLE with continuation lines
        lines.append("TITLE   " + (f"{i // 69 + 1:2d}" if i else "  ") + words[i:i + 69])
    lines += ["REMARK   1 supercoil: coarse-grained DNA, one bead per base pair",
              f"REMARK   1 on the centreline (rise {rise_nm:g} nm)"]
    for i, (x, y, z) in enumerate(angstrom):
        serial, residue = i + 1, (i + 1) % 10000
        lines.append(f"ATOM  {serial:5d}  P   DNA A{residue:4d}    {x:8.3f}{y:8.3f}{z:8.3f}"
                     f"{1.0:6.2f}{0.0:6.2f}           P")
    n = len(angstrom)
    for i in range(n):
        bonded = [j for j in (i - 1, i + 1) if 0 <= j < n]
        if closed and n > 2 and i in (0, n - 1):
            bonded.append(n - 1 if i == 0 else 0)
        lines.append("CONECT" + "".join(f"{j + 1:5d}" for j in [i, *sorted(set(bonded))]))
    lines.append("END")
    return _write_text(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------------------ OBJ
def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation of ``v`` about the unit ``axis``."""
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * (axis @ v) * (1 - c)


def _transport(u: np.ndarray, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
    """``u`` (normal to ``t0``) parallel transported to be normal to ``t1``."""
    axis = np.cross(t0, t1)
    sin = np.linalg.norm(axis)
    cos = float(np.clip(t0 @ t1, -1.0, 1.0))
    if sin < 1e-15:
        return u
    return _rotate(u, axis / sin, math.atan2(sin, cos))


def node_tangents(points, closed: bool) -> np.ndarray:
    """(n, 3) unit tangents at the nodes: the bisectors of the adjacent edges."""
    p = _points(points)
    edges = np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0)
    norms = np.linalg.norm(edges, axis=1)
    if np.any(norms == 0):
        raise ValueError("two consecutive points coincide: the tangent is undefined")
    unit = edges / norms[:, None]
    if closed:
        t = unit + np.roll(unit, 1, axis=0)
    else:
        t = np.vstack([unit[:1], unit[:-1] + unit[1:], unit[-1:]])
    lengths = np.linalg.norm(t, axis=1)
    if np.any(lengths < 1e-12):
        raise ValueError("the centreline folds back on itself at a node")
    return t / lengths[:, None]


def tube_frames(points, closed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tangents ``t`` and normals ``u``, ``v = t x u`` at the nodes, (n, 3) each.

    Parallel transport from node 0; for a closed curve the holonomy (the angle
    between the transported and the initial normal after one loop) is removed
    by rotating node ``i``'s normal back by ``i / n`` of it.
    """
    t = node_tangents(points, closed)
    n = len(t)
    seed = np.eye(3)[int(np.argmin(np.abs(t[0])))]
    u0 = seed - (seed @ t[0]) * t[0]
    u = np.empty_like(t)
    u[0] = u0 / np.linalg.norm(u0)
    for i in range(1, n):
        w = _transport(u[i - 1], t[i - 1], t[i])
        w -= (w @ t[i]) * t[i]
        u[i] = w / np.linalg.norm(w)
    if closed:
        back = _transport(u[-1], t[-1], t[0])
        angle = math.atan2(np.cross(back, u[0]) @ t[0], float(back @ u[0]))
        for i in range(n):
            u[i] = _rotate(u[i], t[i], angle * i / n)
    v = np.cross(t, u)
    return t, u, v


def tube_mesh(points, *, closed: bool, radius: float, sides: int = DEFAULT_SIDES
              ) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (F, 3) (0-based) of the tube (module docstring)."""
    p = _points(points)
    if not radius > 0:
        raise ValueError(f"the tube radius must be positive, got {radius!r}")
    if int(sides) != sides or sides < 3:
        raise ValueError(f"sides must be an integer >= 3, got {sides!r}")
    _, u, v = tube_frames(p, closed)
    angles = 2 * np.pi * np.arange(sides) / sides
    ring = (np.cos(angles)[None, :, None] * u[:, None, :]
            + np.sin(angles)[None, :, None] * v[:, None, :])
    vertices = (p[:, None, :] + radius * ring).reshape(-1, 3)
    n = len(p)
    faces = []
    for i in range(n if closed else n - 1):
        k = (i + 1) % n
        for j in range(sides):
            jj = (j + 1) % sides
            a, b, c, d = i * sides + j, k * sides + j, k * sides + jj, i * sides + jj
            faces += [(a, c, b), (a, d, c)]  # counter-clockwise seen from outside
    if not closed:
        start, end = len(vertices), len(vertices) + 1
        vertices = np.vstack([vertices, p[0], p[-1]])
        last = (n - 1) * sides
        for j in range(sides):
            jj = (j + 1) % sides
            faces.append((start, jj, j))
            faces.append((end, last + j, last + jj))
    return vertices, np.array(faces, dtype=np.int64)


def write_obj(path, points, *, closed: bool, radius: float, sides: int = DEFAULT_SIDES,
              title: str = "supercoil tube") -> Path:
    """Wavefront OBJ of :func:`tube_mesh` (1-based indices, outward vertex normals)."""
    p = _points(points)
    vertices, faces = tube_mesh(p, closed=closed, radius=radius, sides=sides)
    ring_count = len(p) * sides
    centres = np.repeat(p, sides, axis=0)
    normals = (vertices[:ring_count] - centres) / radius
    if not closed:
        t = node_tangents(p, closed)
        normals = np.vstack([normals, -t[0], t[-1]])
    lines = [f"# {' '.join(title.split())}", f"# tube radius {radius:.12g}, {sides} sides",
             "o tube"]
    lines += [f"v {x:.12g} {y:.12g} {z:.12g}" for x, y, z in vertices]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in normals]
    lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}" for a, b, c in faces]
    return _write_text(path, "\n".join(lines) + "\n")


def export_state(path, fmt: str, points, *, closed: bool, radius: float,
                 rise: float | None = None, title: str = "", sides: int = DEFAULT_SIDES
                 ) -> Path:
    """Write ``points`` in ``fmt`` (one of :data:`FORMATS`); ``rise`` (same unit as the
    points) is the bead spacing of ``pdb``, whose points must be in nm."""
    if fmt == "vtk":
        return write_vtk(path, points, closed=closed, radius=radius, title=title)
    if fmt == "xyz":
        return write_xyz(path, points, comment=title)
    if fmt == "pdb":
        if rise is None:
            raise ValueError("pdb needs the rise per base pair (DNA units)")
        return write_pdb(path, points, closed=closed, rise_nm=rise, title=title)
    if fmt == "obj":
        return write_obj(path, points, closed=closed, radius=radius, sides=sides, title=title)
    raise ValueError(f"format {fmt!r}: give one of {', '.join(FORMATS)}")


def edge_counts(faces: Sequence[Sequence[int]]) -> dict[tuple[int, int], int]:
    """How many faces share each (unordered) edge (watertight: all 2)."""
    counts: dict[tuple[int, int], int] = {}
    for face in faces:
        m = len(face)
        for i in range(m):
            a, b = int(face[i]), int(face[(i + 1) % m])
            key = (a, b) if a < b else (b, a)
            counts[key] = counts.get(key, 0) + 1
    return counts
