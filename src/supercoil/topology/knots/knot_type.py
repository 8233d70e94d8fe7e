"""The knot type of a closed curve: invariants of a simplified generic diagram, named from the table.

:func:`identify` projects the polygon generically (:mod:`.projection`),
simplifies the diagram by Reidemeister I and II moves (:mod:`.diagram`),
computes the Alexander polynomial and determinant (:mod:`.alexander`) and the
Jones polynomial (:mod:`.jones`), and looks them up in the table of prime knots
up to 10 crossings (:mod:`.table`).

Chirality comes from the Jones polynomial: a knot and its mirror image have
``V(t)`` and ``V(1/t)``, and among the prime knots up to 10 crossings these
differ for every chiral knot except 9_42, 10_48, 10_71, 10_91, 10_104 and
10_125 (checked against the table). The signature would be cheaper but is 0 for
many chiral knots (6_1, 7_7, 8_1, ...), and the writhe's sign is a property of
the conformation, not of the knot. ``chirality`` is +1 for the table's
chirality (KnotInfo's diagram: for 3_1 the right-handed trefoil), -1 for its
mirror image, 0 for an amphichiral knot or one whose Jones polynomial cannot
tell (V(t) = V(1/t)).

Naming:

* a prime knot of the table: ``"3_1"``. Candidates must match both
  polynomials and have a crossing number at most the crossings of the
  simplified diagram (a diagram has at least as many crossings as its knot's
  crossing number). Pairs the two polynomials do not separate are all named,
  ``"5_1|10_132"`` (within the table: 5_1 and 10_132, 8_8 and 10_129, 8_16 and
  10_156, 10_25 and 10_56, 10_40 and 10_103; up to 8 crossings the Alexander
  polynomial alone separates every knot);
* a connected sum of table knots: both polynomials are multiplicative under
  ``#``, so products of table entries (either chirality) are searched,
  ``"3_1#3_1"``. Within the table one product has a prime knot's polynomials:
  4_1 # 5_2 and 9_12, both named, ``"9_12|4_1#5_2"``. A sum's ``chirality``
  is the sign of the sum of its factors' (the granny knot of two right-handed
  trefoils +1, the square knot ``3_1 # mirror(3_1)`` 0: it is amphichiral), and
  :attr:`KnotType.factors` gives each factor's; with several candidates
  ``chirality`` is theirs if they agree, else 0;
* ``None`` when nothing matches: a knot beyond the table and its sums.

Prime knots of more than 10 crossings may share both polynomials with a table
entry (the unknot's with none known: no non-trivial knot with ``V = 1`` is
known); such a knot is named as that entry.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, field

from supercoil.topology.knots.alexander import alexander_polynomial, knot_determinant
from supercoil.topology.knots.diagram import Diagram
from supercoil.topology.knots.jones import jones_polynomial
from supercoil.topology.knots.polynomials import ONE, Laurent, divide, mirror
from supercoil.topology.knots.projection import check_polygon, project
from supercoil.topology.knots.table import KNOTS, MAX_CROSSINGS, TableKnot

Factors = tuple[tuple[str, int], ...]

# A simplified diagram with more crossings than this is looked at from more
# directions, and the one with the fewest crossings kept (cheaper polynomials).
_MORE_VIEWS_ABOVE = 12
_MORE_VIEWS = 4
_MANY_VIEWS_ABOVE = 40
_MANY_VIEWS = 24
_MAX_FACTORS = 4


@dataclass(frozen=True)
class KnotType:
    """The knot type of a closed curve (module doc).

    ``name``: the table's name (``"0_1"``, ``"3_1"``, ``"3_1#3_1"``; candidates
    joined by ``|`` if the invariants do not decide), or None if not found;
    ``chirality``: +1, -1, or 0 (amphichiral or undetermined); ``alexander``: the
    Alexander polynomial's coefficients ``a_0 .. a_2g`` (``a_0 > 0``);
    ``determinant``: ``|Δ(-1)|``; ``jones``: the Jones polynomial as ``(lowest
    power, coefficients)``; ``candidates``: each candidate as its prime factors
    ``((name, chirality), ...)``; ``crossings``: crossings of the simplified
    diagram used (depends on the view, so not compared by ``==``).
    """

    name: str | None
    chirality: int
    alexander: tuple[int, ...]
    determinant: int
    jones: Laurent
    candidates: tuple[Factors, ...] = ()
    crossings: int = field(default=0, compare=False)

    @property
    def factors(self) -> Factors:
        """Prime factors ``((name, chirality), ...)`` of the first candidate."""
        return self.candidates[0] if self.candidates else ()

    @property
    def is_unknot(self) -> bool:
        return self.name == "0_1"

    @property
    def ambiguous(self) -> bool:
        return len(self.candidates) > 1

    def same_invariants(self, other: KnotType) -> bool:
        """Whether ``other`` has this knot's Alexander and Jones polynomials (so the same
        chirality and determinant): what a strand passage would have to change. The
        name may still differ between views, through the crossing filter."""
        return self.alexander == other.alexander and self.jones == other.jones

    def __repr__(self) -> str:
        hand = {1: "+1", -1: "-1", 0: "0"}[self.chirality]
        return (f"KnotType({self.name or 'unknown'}, chirality {hand}, alexander "
                f"{list(self.alexander)}, determinant {self.determinant}, "
                f"{self.crossings} crossings)")


def _chirality_against(knot: TableKnot, jones: Laurent) -> int | None:
    """+1 / -1 if ``jones`` is the table knot's / its mirror's, 0 if both (the Jones
    polynomial cannot tell, or the knot is amphichiral), None if neither."""
    same = jones == knot.jones
    mirrored = jones == mirror(knot.jones)
    if not (same or mirrored):
        return None
    if knot.amphichiral or (same and mirrored):
        return 0
    return 1 if same else -1


_BY_ALEXANDER: dict[tuple[int, ...], list[TableKnot]] = {}
for _knot in KNOTS:
    _BY_ALEXANDER.setdefault(_knot.alexander, []).append(_knot)
_PRIMES = tuple(k for k in KNOTS if k.crossing_number > 0)
_DETERMINANTS = tuple(knot_determinant(k.alexander) for k in _PRIMES)


def _sums(alexander: Laurent, jones: Laurent, start: int, depth: int) -> list[Factors]:
    """Multisets of table knots (index >= start) whose polynomials multiply to these."""
    if alexander == ONE and jones == ONE:
        return [()]
    if depth == 0:
        return []
    found: list[Factors] = []
    width = len(alexander[1])
    determinant = knot_determinant(alexander[1])  # multiplicative: factors' divide it
    for index in range(start, len(_PRIMES)):
        knot = _PRIMES[index]
        if len(knot.alexander) > width or determinant % _DETERMINANTS[index]:
            continue
        rest_a = divide(alexander, (0, knot.alexander))
        if rest_a is None:
            continue
        hands = (0,) if knot.amphichiral else (1, -1)
        for hand in hands:
            factor_jones = mirror(knot.jones) if hand < 0 else knot.jones
            rest_j = divide(jones, factor_jones)
            if rest_j is None:
                continue
            if hand != 0 and factor_jones == mirror(factor_jones):
                hand = 0
            for tail in _sums(rest_a, rest_j, index, depth - 1):
                found.append(((knot.name, hand),) + tail)
    return found


def classify(alexander: tuple[int, ...], jones: Laurent, crossings: int) -> KnotType:
    """Name a knot from its Alexander polynomial (normal form), Jones polynomial and the
    crossings of a diagram of it (module doc)."""
    alexander = tuple(int(a) for a in alexander)
    jones = (int(jones[0]), tuple(int(c) for c in jones[1]))
    # prime candidates depend on the crossings only through the crossing-number filter
    bound = min(int(crossings), MAX_CROSSINGS)
    name, chirality, candidates = _named(alexander, jones, bound)
    return KnotType(name=name, chirality=chirality, alexander=alexander,
                    determinant=knot_determinant(alexander), jones=jones,
                    candidates=candidates, crossings=int(crossings))


@functools.lru_cache(maxsize=256)
def _named(alexander: tuple[int, ...], jones: Laurent, crossings: int
           ) -> tuple[str | None, int, tuple[Factors, ...]]:
    candidates: list[Factors] = []
    for knot in _BY_ALEXANDER.get(tuple(alexander), ()):
        if knot.crossing_number > crossings:
            continue
        hand = _chirality_against(knot, jones)
        if hand is not None:
            candidates.append(((knot.name, hand),))
    if len(alexander) > 1:  # the unknot is no sum
        sums = {tuple(sorted(f, key=lambda x: (_ORDER[x[0]], -x[1])))
                for f in _sums((0, tuple(alexander)), jones, 0, _MAX_FACTORS) if len(f) > 1}
        candidates += sorted(sums, key=lambda f: (
            sum(int(name.split("_")[0]) for name, _ in f), [_ORDER[n] for n, _ in f]))
    if not candidates:
        return None, 0, ()
    names = list(dict.fromkeys("#".join(n for n, _ in f) for f in candidates))
    hands = {_sign(sum(h for _, h in f)) for f in candidates}
    chirality = hands.pop() if len(hands) == 1 else 0
    return "|".join(names), chirality, tuple(candidates)


_ORDER = {k.name: i for i, k in enumerate(KNOTS)}


def _sign(x: int) -> int:
    return (x > 0) - (x < 0)


def identify_diagram(diagram: Diagram) -> KnotType:
    """The knot type of a diagram (simplified first)."""
    reduced = diagram.simplified()
    return classify(alexander_polynomial(reduced), jones_polynomial(reduced),
                    reduced.n_crossings)


def simplified_diagram(points, seed: int = 0) -> Diagram:
    """The simplified diagram of a generic projection of the closed polygon ``points``
    ``(n, 3)``; if it keeps more than a dozen crossings, the fewest over 4 more
    directions (24 beyond 40 crossings), drawn from ``seed`` too."""
    p = check_polygon(points)
    best = project(p, seed=seed).simplified()
    for k in itertools.count(1):
        # a view costs about a millisecond; the polynomials' cost grows as n^4 - n^5
        views = _MORE_VIEWS if best.n_crossings <= _MANY_VIEWS_ABOVE else _MANY_VIEWS
        if best.n_crossings <= _MORE_VIEWS_ABOVE or k > views:
            break
        other = project(p, seed=seed + 7919 * k).simplified()
        if other.n_crossings < best.n_crossings:
            best = other
    return best


def identify(points, seed: int = 0) -> KnotType:
    """The knot type of the closed polygon ``points`` ``(n, 3)`` (each vertex once; the
    last joined to the first): name, chirality, Alexander polynomial, determinant and
    the crossings of the simplified diagram (module doc).

    Invariant under rigid motions, scaling and resampling of the curve (the
    polynomials are knot invariants; only ``crossings`` depends on the view, and with
    it whether a candidate of more crossings with the same polynomials is named:
    :meth:`KnotType.same_invariants` compares what a view cannot change).
    Raises :class:`~supercoil.errors.InputError` for an array that is not a
    polygon, or a curve whose strands meet.
    """
    reduced = simplified_diagram(points, seed=seed)
    return classify(alexander_polynomial(reduced), jones_polynomial(reduced),
                    reduced.n_crossings)
