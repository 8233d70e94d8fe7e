"""Exports of one state (supercoil.io.exports, 'supercoil export'): files re-read and checked."""

from __future__ import annotations

import math

import numpy as np
import pytest

from supercoil.cli.main import run as cli
from supercoil.continuation import Branch, ContinuationStatus
from supercoil.io.exports import (
    edge_counts,
    resample,
    tube_mesh,
    write_obj,
    write_pdb,
    write_vtk,
    write_xyz,
)
from supercoil.io.store import ResultWriter


def figure_eight_ish(n=40):
    """A closed, non-planar curve (a bent ring) with length about 1."""
    t = 2 * np.pi * np.arange(n) / n
    p = np.column_stack([np.cos(t), np.sin(2 * t) / 2, 0.3 * np.sin(t)])
    perimeter = np.sum(np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1))
    return p / perimeter


def helix_open(n=30):
    t = np.linspace(0, 4 * np.pi, n)
    return np.column_stack([0.1 * np.cos(t), 0.1 * np.sin(t), 0.05 * t])


# ----------------------------------------------------------------------- readers (oracles)
def read_vtk(path):
    words = path.read_text().split("\n")
    assert words[0].startswith("# vtk DataFile") and words[2] == "ASCII"
    assert words[3] == "DATASET POLYDATA"
    n = int(words[4].split()[1])
    points = np.array([[float(v) for v in line.split()] for line in words[5:5 + n]])
    head = words[5 + n].split()
    assert head[0] == "LINES" and head[1] == "1"
    ids = [int(v) for v in words[6 + n].split()]
    assert ids[0] == len(ids) - 1 and int(head[2]) == len(ids)
    scalars = {}
    i = 7 + n
    assert words[i] == f"POINT_DATA {n}"
    i += 1
    while i < len(words) and words[i].startswith("SCALARS"):
        name = words[i].split()[1]
        assert words[i + 1] == "LOOKUP_TABLE default"
        scalars[name] = np.array([float(v) for v in words[i + 2:i + 2 + n]])
        i += 2 + n
    return points, ids[1:], scalars


def read_xyz(path):
    lines = path.read_text().splitlines()
    n = int(lines[0])
    rows = [line.split() for line in lines[2:2 + n]]
    assert len(rows) == n and all(r[0] == "C" for r in rows)
    return lines[1], np.array([[float(v) for v in r[1:]] for r in rows])


def read_pdb(path):
    atoms, bonds = [], {}
    for line in path.read_text().splitlines():
        assert len(line) <= 80, line
        if line.startswith("ATOM  "):
            assert len(line) == 78
            atoms.append((int(line[6:11]), float(line[30:38]), float(line[38:46]),
                          float(line[46:54])))
            assert line[17:20] == "DNA" and line[12:16] == " P  " and line[76:78] == " P"
        elif line.startswith("CONECT"):
            ids = [int(line[k:k + 5]) for k in range(6, len(line), 5)]
            bonds[ids[0]] = set(ids[1:])
    serials = [a[0] for a in atoms]
    assert serials == list(range(1, len(atoms) + 1))
    return np.array([a[1:] for a in atoms]), bonds


def read_obj(path):
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            vertices.append([float(v) for v in line.split()[1:]])
        elif line.startswith("f "):
            faces.append([int(w.split("/")[0]) - 1 for w in line.split()[1:]])
    return np.array(vertices), np.array(faces)


def segment_distance(x, points, closed):
    """Distance from x to the polyline (brute force)."""
    q = np.vstack([points, points[:1]]) if closed else points
    a, b = q[:-1], q[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", x - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - x, axis=1)))


# ----------------------------------------------------------------------------- writers
@pytest.mark.parametrize("closed", [True, False])
def test_vtk_round_trip(tmp_path, closed):
    p = figure_eight_ish() if closed else helix_open()
    path = write_vtk(tmp_path / "s.vtk", p, closed=closed, radius=0.0125, title="t\nx")
    points, ids, scalars = read_vtk(path)
    np.testing.assert_allclose(points, p, rtol=1e-11, atol=1e-13)
    assert ids == list(range(len(p))) + ([0] if closed else [])
    np.testing.assert_array_equal(scalars["TubeRadius"], 0.0125)
    s = scalars["arc_length"]
    assert s[0] == 0 and np.all(np.diff(s) > 0) and s[-1] <= 1.0
    if not closed:
        assert s[-1] == pytest.approx(1.0)


def test_vtk_without_tube(tmp_path):
    p = helix_open()
    points, ids, scalars = read_vtk(write_vtk(tmp_path / "s.vtk", p, closed=False,
                                              radius=None))
    np.testing.assert_allclose(points, p, rtol=1e-11, atol=1e-13)
    assert ids == list(range(len(p))) and set(scalars) == {"arc_length"}


def test_xyz_round_trip(tmp_path):
    p = figure_eight_ish()
    comment, points = read_xyz(write_xyz(tmp_path / "s.xyz", p, comment="branch a\npoint 3"))
    assert comment == "branch a point 3"
    np.testing.assert_allclose(points, p, atol=1e-10)


def test_pdb_one_bead_per_base_pair(tmp_path):
    bp, rise = 300, 0.34
    t = 2 * np.pi * np.arange(60) / 60
    radius_nm = bp * rise / (2 * np.pi)
    ring = radius_nm * np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    # scale the polygon so its perimeter is exactly bp * rise
    perimeter = np.sum(np.linalg.norm(np.diff(np.vstack([ring, ring[:1]]), axis=0), axis=1))
    ring *= bp * rise / perimeter
    beads, bonds = read_pdb(write_pdb(tmp_path / "s.pdb", ring, closed=True, title="x" * 150))
    titles = [line for line in (tmp_path / "s.pdb").read_text().splitlines()
              if line.startswith("TITLE")]
    assert "".join(t[10:] for t in titles) == "x" * 150 and titles[1][8:10] == " 2"
    assert len(beads) == bp
    steps = np.linalg.norm(np.diff(np.vstack([beads, beads[:1]]), axis=0), axis=1)
    np.testing.assert_allclose(steps, 10 * rise, rtol=2e-3, atol=2e-3)  # Å, chords of arcs
    assert beads.min() == 0.0  # the bounding box starts at 0
    assert bonds[1] == {2, bp} and bonds[bp] == {bp - 1, 1} and bonds[5] == {4, 6}
    # the beads lie on the centreline (in Å), the first at node 0
    shift = beads[0] - 10 * ring[0]
    assert max(segment_distance(b - shift, 10 * ring, True) for b in beads) < 2e-3


def test_pdb_open_chain_and_limits(tmp_path):
    line = np.column_stack([np.linspace(0, 34.0, 5), np.zeros(5), np.zeros(5)])  # nm
    beads, bonds = read_pdb(write_pdb(tmp_path / "o.pdb", line, closed=False))
    assert len(beads) == 101 and bonds[1] == {2} and bonds[101] == {100}
    np.testing.assert_allclose(np.diff(beads[:, 0]), 3.4, atol=1e-3)
    beads, _ = read_pdb(write_pdb(tmp_path / "ok.pdb", 1000 * figure_eight_ish(), closed=True))
    assert len(beads) == round(1000 / 0.34)  # 1 um of DNA: within the PDB's 9999.999 Å
    assert 0 <= beads.min() and beads.max() <= 9999.999
    with pytest.raises(ValueError, match="9999.999"):
        write_pdb(tmp_path / "big.pdb", 1e4 * figure_eight_ish(), closed=True, rise_nm=20.0)


def test_resample_spacing():
    p = np.column_stack([np.linspace(0, 1, 11), np.zeros(11), np.zeros(11)])
    r = resample(p, False, 0.25)
    np.testing.assert_allclose(r[:, 0], [0, 0.25, 0.5, 0.75, 1.0], atol=1e-12)


@pytest.mark.parametrize("closed", [True, False])
def test_obj_tube_is_watertight_at_radius(tmp_path, closed):
    p = figure_eight_ish() if closed else helix_open()
    r, sides = 0.01, 12
    vertices, faces = read_obj(write_obj(tmp_path / "t.obj", p, closed=closed, radius=r,
                                         sides=sides))
    v_mesh, f_mesh = tube_mesh(p, closed=closed, radius=r, sides=sides)
    np.testing.assert_allclose(vertices, v_mesh, rtol=0, atol=1e-11)  # 12 digits in the file
    np.testing.assert_array_equal(faces, f_mesh)
    counts = edge_counts(faces)
    assert set(counts.values()) == {2}  # every edge shared by exactly two faces
    euler = len(vertices) - len(counts) + len(faces)
    assert euler == (0 if closed else 2)  # a torus; a capped tube is a sphere
    # consistently oriented: each directed edge appears once
    directed = {(int(f[i]), int(f[(i + 1) % 3])) for f in faces for i in range(3)}
    assert len(directed) == 3 * len(faces)
    # and outward: the enclosed volume (divergence theorem) is positive, about the
    # cross-section (a regular polygon) times the length
    a, b, c = (v_mesh[f_mesh[:, k]] for k in range(3))
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6
    length = np.sum(np.linalg.norm(np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0),
                                   axis=1))
    section = 0.5 * sides * r**2 * math.sin(2 * math.pi / sides)
    assert volume == pytest.approx(section * length, rel=0.02)
    ring_vertices = v_mesh[:len(p) * sides].reshape(len(p), sides, 3)
    # every ring vertex at distance D/2 from its node, in the node's normal plane
    offsets = ring_vertices - p[:, None, :]
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=2), r, rtol=1e-12)
    from supercoil.io.exports import node_tangents

    t = node_tangents(p, closed)
    np.testing.assert_allclose(np.einsum("nsk,nk->ns", offsets, t), 0.0, atol=1e-15)
    # and at about D/2 from the centreline polyline (the bend shortens it a little)
    edges = np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0)
    unit = edges / np.linalg.norm(edges, axis=1)[:, None]
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", unit[1:], unit[:-1]), -1, 1)).max()
    distances = [segment_distance(x, p, closed) for x in v_mesh[:len(p) * sides]]
    assert min(distances) >= r * math.cos(turn / 2) - 1e-12 and max(distances) <= r + 1e-12
    # outward normals
    normals = [line for line in (tmp_path / "t.obj").read_text().splitlines()
               if line.startswith("vn ")]
    assert len(normals) == len(vertices)


def test_tube_has_no_seam_twist():
    """Closed tube frames: neighbouring rings are matched vertex to vertex with the same small
    twist everywhere, the seam included (the holonomy is spread)."""
    p = figure_eight_ish(60)
    v, _ = tube_mesh(p, closed=True, radius=0.01, sides=8)
    rings = v.reshape(60, 8, 3) - p[:, None, :]
    step = np.linalg.norm(rings - np.roll(rings, -1, axis=0), axis=2).max(axis=1)
    assert step.max() < 2.5 * np.median(step)


# ----------------------------------------------------------------------- the command
@pytest.fixture()
def result_file(tmp_path):
    """A result file holding a circle branch of 3 points (n = 20 nodes, L/D = 40)."""
    n = 20
    t = 2 * np.pi * np.arange(n) / n
    circle = np.column_stack([np.cos(t), np.sin(t), np.zeros(n)]) / (2 * n * np.sin(np.pi / n))
    states = np.stack([circle.ravel() * (1 + 0.01 * k) for k in range(3)])
    branch = Branch(name="circle", parent=None, origin=None, parameter="excess_link",
                    parameter_values=np.array([0.0, 0.5, 1.0]), states=states,
                    multipliers=np.zeros((3, n)), unstable_count=np.zeros(3, int),
                    zero_modes=np.zeros(3, int), determinant_sign=np.ones(3, int),
                    nearest_eigenvalue=np.ones(3), tangents=np.zeros((3, 3 * n + n + 1)),
                    arclength=np.arange(3.0), special_points=(),
                    status=ContinuationStatus.PARAMETER_BOUND, message="done")
    path = tmp_path / "result.h5"
    with ResultWriter.create(path, problem="ring_diagram", settings={},
                             attributes={"n_nodes": n, "diameter": 1 / 40, "closed": True,
                                         "length_over_diameter": 40.0}) as w:
        w.write_branch(branch)
    return path, states


def test_export_command_formats(tmp_path, result_file, capsys):
    path, states = result_file
    out = tmp_path / "c.vtk"
    assert cli(["export", str(path), "--branch", "circle", "--point", "1", "--out",
                str(out)]) == 0
    points, _, scalars = read_vtk(out)
    np.testing.assert_allclose(points, states[1].reshape(-1, 3), rtol=1e-11, atol=1e-14)
    np.testing.assert_array_equal(scalars["TubeRadius"], 1 / 80)
    out = tmp_path / "c.xyz"
    assert cli(["export", str(path.parent), "--out", str(out)]) == 0  # folder, last branch+point
    _, points = read_xyz(out)
    np.testing.assert_allclose(points, states[-1].reshape(-1, 3), atol=1e-10)
    out = tmp_path / "c.obj"
    assert cli(["export", str(path), "--point", "0", "--format", "obj", "--out", str(out),
                "--sides", "6"]) == 0
    vertices, faces = read_obj(out)
    assert len(vertices) == 20 * 6 and set(edge_counts(faces).values()) == {2}
    out = tmp_path / "c.pdb"
    assert cli(["export", str(path), "--point", "0", "--out", str(out), "--bp", "200"]) == 0
    beads, _ = read_pdb(out)
    assert len(beads) == 200


def one_line(capsys, status):
    captured = capsys.readouterr()
    assert status == 2, captured
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), captured.err
    return lines[0]


def test_export_bad_input(tmp_path, result_file, capsys):
    path, _ = result_file
    out = tmp_path / "x.vtk"
    line = one_line(capsys, cli(["export", str(path), "--branch", "circel", "--out", str(out)]))
    assert "did you mean 'circle'" in line and "branches: circle" in line
    line = one_line(capsys, cli(["export", str(path), "--point", "3", "--out", str(out)]))
    assert "has 3 points; give 0 to 2" in line
    line = one_line(capsys, cli(["export", str(path), "--out", str(tmp_path / "x.pdb")]))
    assert "--bp N" in line
    line = one_line(capsys, cli(["export", str(path), "--out", str(tmp_path / "x.stl")]))
    assert "cannot tell the format" in line
    line = one_line(capsys, cli(["export", str(tmp_path / "none.h5"), "--out", str(out)]))
    assert "no such result file" in line
    out.write_text("keep")
    line = one_line(capsys, cli(["export", str(path), "--out", str(out)]))
    assert "exists" in line and out.read_text() == "keep"
    assert not out.with_suffix(".pdb").exists()
