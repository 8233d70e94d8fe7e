"""Tests of the knot builders, of the writhe of exact torus knots, and of ``supercoil knot``.

Oracles used here:

- the exact parametrisations: the polygons' vertices lie on the curves, at equal
  arc length, with perimeter 1;
- the Gauss double integral of the smooth torus knots by a spectrally accurate
  quadrature (trapezoidal in the first parameter, Gauss-Legendre in the
  parameter difference, where the integrand is analytic), against which the
  exact polygon writhe converges with observed order 2;
- the positive knots built (right-handed torus knots, 5_2) have positive writhe;
- the command's JSON equals the API's values; bad input exits 2.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from numpy.polynomial.legendre import leggauss

from supercoil.cli.main import app
from supercoil.geometry.curves import circle
from supercoil.io.results import ENVELOPE_KEYS
from supercoil.topology import writhe
from supercoil.topology.knots import KNOT_CURVES, identify, knot_curve, torus_knot
from supercoil.topology.knots.builders import torus_curve

# ------------------------------------------------------------------- builders


@pytest.mark.parametrize("name", sorted(KNOT_CURVES))
def test_built_polygons_have_perimeter_one_and_equal_chords(name):
    spread = []
    for n in (200, 400):
        points = knot_curve(name, n)
        assert points.shape == (n, 3)
        chords = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
        assert chords.sum() == pytest.approx(1.0, rel=1e-13)
        assert np.abs(points.mean(axis=0)).max() < 1e-14
        spread.append(chords.max() / chords.min() - 1)
    # equal arc length on the smooth curve: a chord is shorter than its arc by
    # κ^2 h^3 / 24, so the relative spread of the chords falls as h^2
    assert spread[1] < 0.01
    assert spread[1] < spread[0] / 3 or spread[1] < 1e-12


def test_the_built_circle_is_the_regular_polygon():
    assert np.allclose(knot_curve("0_1", 64), circle(64), atol=1e-12, rtol=0)


@pytest.mark.parametrize("p, q", [(2, 3), (2, 5), (3, 4), (3, -5)])
def test_torus_knot_vertices_lie_on_the_torus(p, q):
    """On the torus (ρ - 2s)^2 + z^2 = s^2, ρ = sqrt(x^2 + y^2), for one scale s (the
    centroid is the torus' centre when the nodes respect the q-fold symmetry)."""
    points = torus_knot(p, q, 240)
    rho, z = np.hypot(points[:, 0], points[:, 1]), points[:, 2]
    s = rho[0] / 3  # the first vertex is r(0), on the outer equator, ρ = 3 s
    assert abs(z[0]) < 1e-12
    assert np.abs((rho - 2 * s) ** 2 + z**2 - s**2).max() < 1e-9 * s**2


def test_torus_knot_winds_p_times_around_the_axis():
    """T(p, q) on a torus about z: the angle about z advances by 2πp over the curve."""
    for p, q in [(2, 3), (3, 4), (3, -5)]:
        points = torus_knot(p, q, 600)
        angle = np.arctan2(points[:, 1], points[:, 0])
        steps = np.angle(np.exp(1j * (np.roll(angle, -1) - angle)))  # each in (-π, π]
        assert steps.sum() / (2 * np.pi) == pytest.approx(p, abs=1e-12)


# -------------------------------------------------- writhe of exact torus knots


def gauss_writhe(p: int, q: int, m: int, k: int) -> float:
    """Wr = (1/4π) ∫∫ (r'(φ1) × r'(φ2))·(r(φ1) - r(φ2)) / |r(φ1) - r(φ2)|^3 dφ1 dφ2 over
    the smooth torus knot, as ∫ dφ ∫_0^2π dε with φ2 = φ + ε: trapezoidal in φ (periodic,
    spectral) and Gauss-Legendre in ε, where the integrand is analytic on [0, 2π]
    (it behaves as |ε| at both ends, a kink only across the diagonal)."""
    curve = torus_curve(p, q)
    nodes, weights = leggauss(k)
    eps = np.pi * (nodes + 1.0)
    w_eps = np.pi * weights
    phi = 2 * np.pi * np.arange(m) / m
    r1, d1 = curve(phi)
    total = 0.0
    for e, w in zip(eps, w_eps):
        r2, d2 = curve(phi + e)
        diff = r1 - r2
        integrand = np.einsum("ij,ij->i", np.cross(d1, d2), diff) / np.linalg.norm(
            diff, axis=1) ** 3
        total += w * integrand.sum() * (2 * np.pi / m)
    return total / (4 * np.pi)


@pytest.mark.parametrize("p, q", [(2, 3), (2, 5), (3, 4)])
def test_polygon_writhe_of_torus_knots_converges_to_the_gauss_integral(p, q):
    exact = gauss_writhe(p, q, 400, 300)
    assert gauss_writhe(p, q, 600, 400) == pytest.approx(exact, abs=1e-11)
    assert exact > 0  # positive knots, right-handed
    sizes = np.array([100, 200, 400, 800]) * (p * q // 6 + 1)
    errors = np.array([abs(writhe(torus_knot(p, q, int(n))) - exact) for n in sizes])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2.0) < 0.15), orders
    assert errors[-1] < 1e-3
    assert writhe(torus_knot(p, -q, int(sizes[-1]))) == pytest.approx(-writhe(
        torus_knot(p, q, int(sizes[-1]))), abs=1e-12)


def test_positive_knots_are_built_with_positive_writhe():
    for name in ("3_1", "5_1", "5_2", "7_1", "8_19"):
        assert writhe(knot_curve(name, 400)) > 1.0
        assert writhe(knot_curve(name, 400, mirror=True)) < -1.0


# ------------------------------------------------------------------ the command


def write_curve(path, points) -> str:
    lines = ["# a closed curve", ""] + [f"{float(x)!r} {float(y)!r}, {float(z)!r}"
                                        for x, y, z in points]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(path)


def test_knot_command_json_matches_the_api(runner, tmp_path):
    points = knot_curve("5_2", 180, mirror=True)
    path = write_curve(tmp_path / "k.txt", points)
    result = runner.invoke(app, ["knot", path, "--json", "-"], catch_exceptions=False)
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    expected = identify(points)
    assert data["knot_type"] == "5_2" == expected.name
    assert data["chirality"] == -1 == expected.chirality
    assert data["alexander_polynomial"] == [2, -3, 2]
    assert data["determinant"] == 7
    assert data["crossings"] == expected.crossings
    assert data["jones_polynomial"]["lowest_power"] == expected.jones[0]
    assert tuple(data["jones_polynomial"]["coefficients"]) == expected.jones[1]
    assert data["candidates"] == [[{"knot_type": "5_2", "chirality": -1}]]
    for key in ENVELOPE_KEYS:
        assert key in data


def test_knot_command_human_output_and_file(runner, tmp_path):
    path = write_curve(tmp_path / "k.txt", torus_knot(2, 3, 120))
    target = tmp_path / "out.json"
    result = runner.invoke(app, ["knot", path, "--json", str(target)],
                           catch_exceptions=False)
    assert result.exit_code == 0
    assert result.stdout.startswith("knot 3_1  chirality +1  determinant 3")
    assert "alexander 1 - t + t^2" in result.stdout
    assert "jones t + t^3 - t^4" in result.stdout
    assert json.loads(target.read_text())["knot_type"] == "3_1"


def test_knot_command_refuses_bad_input(runner, tmp_path):
    missing = runner.invoke(app, ["knot", str(tmp_path / "none.txt")])
    assert missing.exit_code == 2 and "no such file" in missing.stderr
    two = write_curve(tmp_path / "two.txt", [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)])
    short = runner.invoke(app, ["knot", two])
    assert short.exit_code == 2 and "at least 3" in short.stderr
    th = 2 * np.pi * np.arange(100) / 100
    eight = write_curve(tmp_path / "eight.txt",
                        np.stack([np.sin(2 * th), np.sin(th), 0 * th], axis=1))
    crossing = runner.invoke(app, ["knot", eight])
    assert crossing.exit_code == 2 and "passes through itself" in crossing.stderr
    folder = runner.invoke(app, ["knot", two, "--json", str(tmp_path / "no" / "x.json")])
    assert folder.exit_code == 2 and "does not exist" in folder.stderr
