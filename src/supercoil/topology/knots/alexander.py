"""The Alexander polynomial and the determinant of a knot diagram, in exact integers.

Alexander's matrix (Alexander 1928; Fox's free calculus on the Wirtinger
presentation, Lickorish 1997, ch. 6) has one row per crossing and one column
per arc (the pieces of the curve between under passes). At a crossing with
over arc ``k``, incoming under arc ``i`` and outgoing under arc ``j`` the row
holds

    positive crossing:  1 - t at k,   t at i,  -1 at j,
    negative crossing:  1 - t at k,  -1 at i,   t at j

(entries add where arcs coincide). Deleting any one row and one column leaves a
square matrix whose determinant is ``Δ(t)`` up to a unit ``± t^m``.

The determinant is taken exactly: at the integer ``t = B`` by fraction-free
Gaussian elimination (Bareiss 1968) over Python integers, and ``Δ`` is read off
as the balanced base-``B`` digits of ``det M(B)`` (Kronecker substitution).
That is exact when ``B`` exceeds twice every coefficient: a row's entries have
coefficient sums (L1 norms) adding to at most 4, so each coefficient of the
``(n-1) × (n-1)`` determinant is at most ``4^(n-1)`` in magnitude (the
permanent of the norms bounds it), and ``B = 2·4^(n-1) + 2`` suffices.

Normal form (as KnotInfo lists it): the coefficients ``a_0, ..., a_2g`` of
``a_0 + a_1 t + ... + a_2g t^2g`` with ``a_0 > 0``; the list is a palindrome
(``Δ(t) = Δ(1/t)`` up to units) and ``Δ(1) = ±1``, both checked. The
determinant of the knot is ``|Δ(-1)|``.
"""

from __future__ import annotations

from supercoil.topology.knots.diagram import Diagram


def bareiss_determinant(matrix: list[list[int]]) -> int:
    """Determinant of a square integer matrix by Bareiss' fraction-free elimination
    (every division exact), with row pivoting; exact in Python integers."""
    a = [list(row) for row in matrix]
    n = len(a)
    if n == 0:
        return 1
    sign = 1
    previous = 1
    for k in range(n - 1):
        if a[k][k] == 0:
            swap = next((r for r in range(k + 1, n) if a[r][k] != 0), None)
            if swap is None:
                return 0
            a[k], a[swap] = a[swap], a[k]
            sign = -sign
        pivot = a[k][k]
        row_k = a[k]
        for i in range(k + 1, n):
            row_i = a[i]
            factor = row_i[k]
            for j in range(k + 1, n):
                row_i[j] = (pivot * row_i[j] - factor * row_k[j]) // previous
            row_i[k] = 0
        previous = pivot
    return sign * a[n - 1][n - 1]


def alexander_matrix_at(diagram: Diagram, t: int) -> list[list[int]]:
    """Alexander's matrix ``(n, n)`` evaluated at the integer ``t`` (module doc)."""
    n = diagram.n_crossings
    over_arc, arc_in, arc_out = diagram.arcs()
    matrix = [[0] * n for _ in range(n)]
    for c in range(n):
        row = matrix[c]
        row[int(over_arc[c])] += 1 - t
        if diagram.signs[c] > 0:
            row[int(arc_in[c])] += t
            row[int(arc_out[c])] -= 1
        else:
            row[int(arc_in[c])] -= 1
            row[int(arc_out[c])] += t
    return matrix


def alexander_polynomial(diagram: Diagram) -> tuple[int, ...]:
    """Coefficients ``(a_0, ..., a_2g)`` of the Alexander polynomial in normal form
    (module doc); ``(1,)`` for a diagram without crossings."""
    n = diagram.n_crossings
    if n <= 1:
        return (1,)
    base = 2 * 4 ** (n - 1) + 2
    matrix = alexander_matrix_at(diagram, base)
    minor = [row[:-1] for row in matrix[:-1]]
    value = bareiss_determinant(minor)
    digits = []
    half = base // 2
    while value:
        digit = value % base
        if digit > half:
            digit -= base
        digits.append(digit)
        value = (value - digit) // base
    while digits and digits[0] == 0:
        digits.pop(0)
    if not digits:
        raise ValueError("Alexander's minor is singular: the diagram is not a knot's")
    if digits[0] < 0:
        digits = [-d for d in digits]
    coefficients = tuple(digits)
    if coefficients != coefficients[::-1] or abs(sum(coefficients)) != 1:
        raise ValueError(f"Alexander polynomial {coefficients} is not symmetric with "
                         "|Δ(1)| = 1: the diagram is not a knot's")
    return coefficients


def knot_determinant(alexander: tuple[int, ...]) -> int:
    """``|Δ(-1)|`` from the coefficients of ``Δ``."""
    return abs(sum(a * (-1) ** k for k, a in enumerate(alexander)))
