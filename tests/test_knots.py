"""Tests of supercoil.topology.knots: knot types of closed curves. Every test has an oracle.

Oracles used here:

- KnotInfo (Livingston & Moore): the PD codes, Alexander and Jones polynomials
  and determinants of the prime knots up to 10 crossings
  (tests/data/knotinfo_pd_codes.txt, and the table module);
- closed formulas: the Alexander and Jones polynomials of the torus knots
  T(p, q) (Rolfsen 1976; Jones 1985), products under connected sum;
- brute force: Kauffman's bracket summed over all 2^n states, determinants by
  rational Gaussian elimination;
- hand-made diagrams whose Reidemeister simplification is known;
- invariants: mirror images (same Alexander polynomial, opposite chirality),
  amphichirality of 4_1 and of the square knot, unknots drawn with many
  crossings, rigid motions, resampling, relabelling, other projections.
"""

from __future__ import annotations

import itertools
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from supercoil.errors import InputError
from supercoil.geometry.curves import resample_closed
from supercoil.topology.knots import (
    KNOTS,
    Diagram,
    alexander_polynomial,
    classify,
    identify,
    jones_polynomial,
    knot_curve,
    knot_determinant,
    project,
    torus_knot,
)
from supercoil.topology.knots.alexander import alexander_matrix_at
from supercoil.topology.knots.jones import kauffman_bracket
from supercoil.topology.knots.polynomials import (
    ONE,
    divide,
    evaluate,
    from_dict,
    laurent,
    mirror,
    multiply,
)
from supercoil.topology.knots.table import BY_NAME

DATA = Path(__file__).parent / "data" / "knotinfo_pd_codes.txt"


def knotinfo_pd_codes() -> list[tuple[str, int, list[tuple[int, ...]]]]:
    rows = []
    for line in DATA.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        name, det, code = line.split()
        rows.append((name, int(det), [tuple(map(int, x.split(","))) for x in code.split(";")]))
    return rows


PD_CODES = knotinfo_pd_codes()
UP_TO_8 = [row for row in PD_CODES if int(row[0].split("_")[0]) <= 8]


# ------------------------------------------------------------- the table itself


def test_table_lists_rolfsens_knots_up_to_ten_crossings():
    """Rolfsen's table: 1, 1, 2, 3, 7, 21, 49, 165 prime knots of 3 .. 10 crossings."""
    counts = {}
    for k in KNOTS:
        counts[k.crossing_number] = counts.get(k.crossing_number, 0) + 1
    assert counts == {0: 1, 3: 1, 4: 1, 5: 2, 6: 3, 7: 7, 8: 21, 9: 49, 10: 165}
    names = [k.name for k in KNOTS if k.crossing_number == 8]
    assert names == [f"8_{i}" for i in range(1, 22)]


@pytest.mark.parametrize("name, det, pd", PD_CODES, ids=[row[0] for row in PD_CODES])
def test_polynomials_of_knotinfo_diagrams(name, det, pd):
    """From KnotInfo's PD code: its Alexander polynomial, its determinant, and its Jones
    polynomial (that of KnotInfo's diagram, whose chirality is the table's)."""
    diagram = Diagram.from_pd(pd)
    alexander = alexander_polynomial(diagram)
    assert alexander == BY_NAME[name].alexander
    assert knot_determinant(alexander) == det
    assert jones_polynomial(diagram) == BY_NAME[name].jones
    assert jones_polynomial(diagram.mirror()) == mirror(BY_NAME[name].jones)
    assert alexander_polynomial(diagram.mirror()) == alexander


def test_named_alexander_polynomials_and_determinants():
    """Values read from the Knot Atlas and KnotInfo pages, written out by hand."""
    expected = {
        "3_1": ((1, -1, 1), 3), "4_1": ((1, -3, 1), 5), "5_1": ((1, -1, 1, -1, 1), 5),
        "5_2": ((2, -3, 2), 7), "6_1": ((2, -5, 2), 9), "6_2": ((1, -3, 3, -3, 1), 11),
        "6_3": ((1, -3, 5, -3, 1), 13), "7_1": ((1, -1, 1, -1, 1, -1, 1), 7),
        "8_19": ((1, -1, 0, 1, 0, -1, 1), 3), "8_20": ((1, -2, 3, -2, 1), 9),
        "8_21": ((1, -4, 5, -4, 1), 15),
    }
    for name, (alexander, det) in expected.items():
        assert BY_NAME[name].alexander == alexander
        assert knot_determinant(alexander) == det
    assert BY_NAME["3_1"].jones == laurent(1, [1, 0, 1, -1])  # t + t^3 - t^4


def test_alexander_alone_separates_the_knots_up_to_eight_crossings():
    """So the ambiguities named by identify are all with 9- and 10-crossing knots."""
    small = [k for k in KNOTS if k.crossing_number <= 8]
    assert len({k.alexander for k in small}) == len(small)
    shared = {}
    for k in KNOTS[1:]:
        shared.setdefault((k.alexander, min(k.jones, mirror(k.jones))), []).append(k.name)
    pairs = sorted(v for v in shared.values() if len(v) > 1)
    assert pairs == [["10_25", "10_56"], ["10_40", "10_103"], ["5_1", "10_132"],
                     ["8_16", "10_156"], ["8_8", "10_129"]]


# ------------------------------------------------------------ brute-force oracles


def _bracket_by_states(pd) -> dict[int, int]:
    """Kauffman's bracket as the plain sum over all 2^n states, loops by union-find."""
    total: dict[int, int] = {}
    loop = {2: -1, -2: -1}
    for state in itertools.product((1, -1), repeat=len(pd)):
        parent = {e: e for x in pd for e in x}
        for (a, b, c, d), s in zip(pd, state):
            for u, v in (((a, b), (c, d)) if s > 0 else ((a, d), (b, c))):
                parent[_root(parent, u)] = _root(parent, v)
        loops = len({_root(parent, e) for e in parent})
        term = {sum(state): 1}
        for _ in range(loops - 1):
            term = _poly_times(term, loop)
        for e, x in term.items():
            total[e] = total.get(e, 0) + x
    return {e: x for e, x in total.items() if x}


def _root(parent: dict[int, int], e: int) -> int:
    while parent[e] != e:
        e = parent[e]
    return e


def _poly_times(p, q):
    out = {}
    for e, x in p.items():
        for f, y in q.items():
            out[e + f] = out.get(e + f, 0) + x * y
    return out


@pytest.mark.parametrize("name, det, pd", UP_TO_8[:20], ids=[r[0] for r in UP_TO_8[:20]])
def test_bracket_equals_the_sum_over_all_states(name, det, pd):
    assert kauffman_bracket(pd) == _bracket_by_states(pd)


def _rational_det(matrix) -> Fraction:
    a = [[Fraction(x) for x in row] for row in matrix]
    n, det = len(a), Fraction(1)
    for k in range(n):
        pivot = next((r for r in range(k, n) if a[r][k] != 0), None)
        if pivot is None:
            return Fraction(0)
        if pivot != k:
            a[k], a[pivot] = a[pivot], a[k]
            det = -det
        det *= a[k][k]
        for r in range(k + 1, n):
            f = a[r][k] / a[k][k]
            a[r] = [x - f * y for x, y in zip(a[r], a[k])]
    return det


@pytest.mark.parametrize("name", ["3_1", "5_2", "7_4", "8_19", "9_42", "10_161"])
def test_alexander_polynomial_is_the_minor_up_to_a_unit(name):
    """det of any (n-1) minor of Alexander's matrix at t = 2, 3, 5 equals ±t^m Δ(t)
    with one m, by rational elimination."""
    pd = next(row[2] for row in PD_CODES if row[0] == name)
    diagram = Diagram.from_pd(pd)
    delta = (0, alexander_polynomial(diagram))
    for drop_row, drop_col in [(0, 0), (len(pd) - 1, 2)]:
        powers = set()
        for t in (2, 3, 5):
            m = alexander_matrix_at(diagram, t)
            minor = [[x for j, x in enumerate(row) if j != drop_col]
                     for i, row in enumerate(m) if i != drop_row]
            ratio = abs(_rational_det(minor) / evaluate(delta, t))
            k = round(np.log(float(ratio)) / np.log(t))
            assert ratio == Fraction(t) ** k
            powers.add(k)
        assert len(powers) == 1


# -------------------------------------------------------------------- diagrams


def test_pd_code_round_trip():
    for _, _, pd in PD_CODES[:40]:
        diagram = Diagram.from_pd(pd)
        again = Diagram.from_pd(diagram.pd_code())
        assert again.n_crossings == diagram.n_crossings
        assert again.writhe == diagram.writhe
        assert jones_polynomial(again) == jones_polynomial(diagram)


def _from_gauss(code, signs):
    """Diagram from a signed Gauss code (+k over, -k under, k from 1)."""
    return Diagram(tuple(abs(c) - 1 for c in code), tuple(c > 0 for c in code), tuple(signs))


def test_reidemeister_one_removes_kinks_in_cascade():
    # a twisted band closed at both ends: each end loop is a kink, then the next one
    code = [1, -1, 2, -2, 3, -3]
    assert _from_gauss(code, [1, -1, 1]).simplified().n_crossings == 0
    nested = [1, 2, 3, -3, -2, -1]  # loops inside loops: R1 innermost first
    assert _from_gauss(nested, [1, 1, -1]).simplified().n_crossings == 0


def test_reidemeister_two_removes_a_clasp_but_not_a_twist():
    clasp = [1, 2, -2, -1]  # one strand over the other twice: opposite signs
    assert _from_gauss(clasp, [1, -1]).simplified().n_crossings == 0
    trefoil = [1, -2, 3, -1, 2, -3]
    assert _from_gauss(trefoil, [1, 1, 1]).simplified().n_crossings == 3
    # the trefoil with a kink and a clasp added on its arcs keeps exactly its 3
    decorated = [1, -2, 4, -4, 3, -1, 5, 6, 2, -3, -6, -5]
    d = _from_gauss(decorated, [1, 1, 1, -1, 1, -1]).simplified()
    assert d.n_crossings == 3
    assert alexander_polynomial(d) == (1, -1, 1)
    assert jones_polynomial(d) == BY_NAME["3_1"].jones


# -------------------------------------------------------- curves: prime knots


def torus_alexander(p: int, q: int) -> tuple[int, ...]:
    """Δ = (t^pq - 1)(t - 1) / ((t^p - 1)(t^q - 1)) (Rolfsen 1976, 7.D)."""
    def power_minus_one(k):
        return laurent(0, [-1] + [0] * (k - 1) + [1])
    num = multiply(power_minus_one(p * q), power_minus_one(1))
    delta = divide(divide(num, power_minus_one(p)), power_minus_one(q))
    return delta[1] if delta[1][0] > 0 else tuple(-c for c in delta[1])


def torus_jones(p: int, q: int):
    """Positive T(p, q): V = t^((p-1)(q-1)/2) (1 - t^(p+1) - t^(q+1) + t^(p+q)) / (1 - t^2)
    (Jones 1987)."""
    num = from_dict({0: 1, p + 1: -1, q + 1: -1, p + q: 1})
    if p + 1 == q + 1:
        num = from_dict({0: 1, p + 1: -2, p + q: 1})
    v = divide(num, from_dict({0: 1, 2: -1}))
    return multiply(v, (((p - 1) * (q - 1)) // 2, (1,)))


@pytest.mark.parametrize("p, q, name", [(2, 3, "3_1"), (2, 5, "5_1"), (2, 7, "7_1"),
                                        (3, 4, "8_19")])
def test_torus_knots_against_closed_formulas(p, q, name):
    points = torus_knot(p, q, 240)
    k = identify(points)
    assert k.name == name
    assert k.alexander == torus_alexander(p, q)
    assert k.jones == torus_jones(p, q)
    assert k.chirality == 1
    assert k.determinant == knot_determinant(torus_alexander(p, q))
    m = identify(torus_knot(p, -q, 240))
    assert (m.name, m.chirality, m.alexander) == (name, -1, k.alexander)
    assert m.jones == mirror(k.jones)


@pytest.mark.parametrize("name, det, chirality", [("0_1", 1, 0), ("3_1", 3, 1),
                                                  ("4_1", 5, 0), ("5_1", 5, 1),
                                                  ("5_2", 7, 1), ("7_1", 7, 1),
                                                  ("8_19", 3, 1)])
def test_built_knots_and_their_mirror_images(name, det, chirality):
    k = identify(knot_curve(name, 200))
    assert (k.name, k.chirality, k.determinant) == (name, chirality, det)
    assert k.alexander == BY_NAME[name].alexander
    assert k.crossings >= BY_NAME[name].crossing_number
    m = identify(knot_curve(name, 200, mirror=True))
    assert (m.name, m.chirality, m.alexander) == (name, -chirality, k.alexander)
    if name in ("0_1", "4_1"):  # amphichiral: V(t) = V(1/t)
        assert k.jones == mirror(k.jones) == m.jones


def test_ambiguous_polynomials_name_every_candidate():
    five = BY_NAME["5_1"]
    assert classify(five.alexander, five.jones, 5).name == "5_1"
    both = classify(five.alexander, five.jones, 12)
    assert both.name == "5_1|10_132" and both.ambiguous
    # KnotInfo's 10_132 has the mirror of 5_1's Jones polynomial: the candidates'
    # chiralities differ, so the knot's is undetermined
    assert both.candidates == ((("5_1", 1),), (("10_132", -1),))
    assert both.chirality == 0
    nine = BY_NAME["9_42"]  # chiral, but V(t) = V(1/t): undetermined
    assert classify(nine.alexander, nine.jones, 9).chirality == 0
    unknown = classify((1, -1, 1), laurent(0, [1, 1]), 3)
    assert unknown.name is None and unknown.candidates == () and unknown.chirality == 0


# ----------------------------------------------------------- connected sums


def connected_sum(k1: np.ndarray, k2: np.ndarray, cut: int = 3) -> np.ndarray:
    """K1 # K2: K2 placed beside K1 along +x, each opened at its extreme point facing the
    other (a sphere, the plane between them, meets the result in two points), joined
    by two segments."""
    k1 = k1 - k1.mean(axis=0)
    k2 = k2 - k2.mean(axis=0)
    i, j = int(np.argmax(k1[:, 0])), int(np.argmin(k2[:, 0]))
    k2 = k2 + np.array([k1[:, 0].max() - k2[:, 0].min() + 0.3, 0.0, 0.0])
    a1 = np.roll(k1, -(i + cut), axis=0)[: len(k1) - 2 * cut + 1]
    a2 = np.roll(k2, -(j + cut), axis=0)[: len(k2) - 2 * cut + 1]
    if np.linalg.norm(a1[-1] - a2[0]) > np.linalg.norm(a1[-1] - a2[-1]):
        a2 = a2[::-1]  # the two joining segments side by side, not crossed
    return np.vstack([a1, a2])


TURN = np.diag([-1.0, -1.0, 1.0])  # a rotation by π about z (not a mirror)
REFLECT = np.diag([-1.0, 1.0, 1.0])  # a mirror


def test_granny_and_square_knots():
    """Same Alexander polynomial (Δ(3_1)^2) and determinant (9); the Jones polynomial
    tells them apart: V(3_1)^2 for the granny knot (chiral), V(3_1) V(3_1)(1/t) for the
    square knot (amphichiral)."""
    t = knot_curve("3_1", 160)
    granny = identify(connected_sum(t, t @ TURN.T))
    square = identify(connected_sum(t, t @ REFLECT.T))
    v = BY_NAME["3_1"].jones
    assert granny.alexander == square.alexander == (1, -2, 3, -2, 1)
    assert granny.determinant == square.determinant == 9
    assert granny.jones == multiply(v, v)
    assert square.jones == multiply(v, mirror(v)) == mirror(square.jones)
    assert (granny.name, granny.chirality) == ("3_1#3_1", 1)
    assert granny.factors == (("3_1", 1), ("3_1", 1))
    assert (square.name, square.chirality) == ("3_1#3_1", 0)
    assert square.factors == (("3_1", 1), ("3_1", -1))
    left = identify(connected_sum(t, t @ TURN.T) @ REFLECT.T)
    assert (left.name, left.chirality) == ("3_1#3_1", -1)


def test_sum_of_different_knots_and_its_shared_polynomials():
    k = identify(connected_sum(knot_curve("3_1", 160), knot_curve("4_1", 160)))
    assert k.name == "3_1#4_1" and k.chirality == 1
    assert k.alexander == multiply((0, (1, -1, 1)), (0, (1, -3, 1)))[1]
    assert k.determinant == 15
    # 4_1 # 5_2 has the polynomials of the prime knot 9_12 (KnotInfo): both named
    s = identify(connected_sum(knot_curve("4_1", 160), knot_curve("5_2", 160)))
    assert s.name == "9_12|4_1#5_2"
    assert s.candidates[1] == (("4_1", 0), ("5_2", 1))


# -------------------------------------------------------------------- unknots


def wild_unknot(n: int, seed: int) -> np.ndarray:
    """A graph over the angle θ, (ρ(θ) cos θ, ρ(θ) sin θ, z(θ)) with ρ > 0: an unknot
    (the straight homotopy to the circle in (ρ, z) stays embedded) whose random
    high-amplitude z makes many crossings in a generic projection."""
    rng = np.random.default_rng(seed)
    th = 2 * np.pi * np.arange(n) / n
    rho = 1.0 + sum(0.4 / k * rng.standard_normal() * np.cos(k * th + rng.uniform(0, 7))
                    for k in range(1, 6))
    z = sum(1.5 * rng.standard_normal() * np.cos(k * th + rng.uniform(0, 7))
            for k in range(3, 12))
    rho = 0.2 + np.abs(rho)
    return np.stack([rho * np.cos(th), rho * np.sin(th), z], axis=1)


@pytest.mark.parametrize("seed", range(6))
def test_unknots_with_many_crossings(seed):
    points = wild_unknot(400, seed)
    crossings = [project(points, seed=s).n_crossings for s in range(5)]
    assert max(crossings) >= 8
    k = identify(points)
    assert (k.name, k.chirality, k.alexander, k.determinant) == ("0_1", 0, (1,), 1)
    assert k.jones == ONE


def curled_circle(n: int, loops: int, depth: float) -> np.ndarray:
    """A circle with ``loops - 1`` small curls (an epitrochoid), lifted by
    depth·sin((loops - 1)θ), odd about every curl: each crossing is a kink."""
    th = 2 * np.pi * np.arange(n) / n
    b = 0.35
    return np.stack([np.cos(th) + b * np.cos(loops * th), np.sin(th) + b * np.sin(loops * th),
                     depth * np.sin((loops - 1) * th)], axis=1)


@pytest.mark.parametrize("depth", [0.05, -0.2])
def test_unknot_with_reidemeister_one_kinks(depth):
    points = curled_circle(700, 7, depth)
    assert project(points).n_crossings >= 4
    k = identify(points)
    assert (k.name, k.crossings) == ("0_1", 0)


def test_trefoil_with_kinks_added_stays_a_trefoil():
    t = knot_curve("3_1", 600)
    s = np.arange(600) / 600 * 2 * np.pi
    wiggle = 0.004 * np.stack([np.cos(80 * s), np.sin(80 * s), np.cos(80 * s)], axis=1)
    seen = project(t + wiggle).n_crossings
    k = identify(t + wiggle)
    assert (k.name, k.chirality) == ("3_1", 1)
    assert 3 <= k.crossings < seen  # kinks removed (all of them, in some views)
    assert project(t + wiggle, seed=1).simplified().n_crossings == 3


# ----------------------------------------------------------------- invariance


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@pytest.mark.parametrize("name", ["3_1", "4_1", "5_2", "8_19"])
def test_invariance_under_rigid_motions_resampling_relabelling_and_views(name):
    rng = np.random.default_rng(7)
    points = knot_curve(name, 300)
    reference = identify(points)
    moved = 37.0 * points @ random_rotation(rng).T + rng.standard_normal(3)
    assert identify(moved) == reference
    assert identify(resample_closed(points, 211)) == reference
    assert identify(np.roll(points, 101, axis=0)) == reference
    assert identify(points[::-1]) == reference  # these knots are invertible
    for seed in (1, 2, 3):
        assert identify(points, seed=seed) == reference


# -------------------------------------------------------------- bad input


def test_bad_curves_are_refused():
    with pytest.raises(InputError, match=r"\(n, 3\)"):
        identify(np.zeros((5, 2)))
    with pytest.raises(InputError, match="non-finite"):
        identify(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]))
    th = 2 * np.pi * np.arange(200) / 200
    eight = np.stack([np.sin(2 * th), np.sin(th), 0 * th], axis=1)  # passes through itself
    with pytest.raises(InputError, match="passes through itself"):
        identify(eight)
    with pytest.raises(InputError, match="give one of"):
        knot_curve("6_1", 100)
    with pytest.raises(InputError, match="coprime"):
        torus_knot(2, 4, 200)
    with pytest.raises(InputError, match="at least"):
        torus_knot(3, 4, 20)
