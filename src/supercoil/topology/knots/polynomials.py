"""Integer Laurent polynomials as ``(lowest power, coefficients)`` pairs.

A Laurent polynomial ``c_0 t^m + c_1 t^(m+1) + ... + c_k t^(m+k)`` is the pair
``(m, (c_0, ..., c_k))`` with ``c_0 != 0`` and ``c_k != 0`` (the zero polynomial
is ``(0, ())``). Exact integer arithmetic (Python ints) throughout: the knot
invariants here are compared for equality, never approximately.
"""

from __future__ import annotations

Laurent = tuple[int, tuple[int, ...]]

ONE: Laurent = (0, (1,))


def laurent(low: int, coefficients) -> Laurent:
    """The normal form of ``sum_k coefficients[k] t^(low + k)`` (zeros at both ends dropped)."""
    c = [int(x) for x in coefficients]
    start = 0
    while start < len(c) and c[start] == 0:
        start += 1
    end = len(c)
    while end > start and c[end - 1] == 0:
        end -= 1
    if start == end:
        return (0, ())
    return (low + start, tuple(c[start:end]))


def from_dict(terms: dict[int, int]) -> Laurent:
    """The Laurent polynomial ``sum_e terms[e] t^e``."""
    terms = {e: c for e, c in terms.items() if c}
    if not terms:
        return (0, ())
    low, high = min(terms), max(terms)
    return laurent(low, [terms.get(e, 0) for e in range(low, high + 1)])


def multiply(p: Laurent, q: Laurent) -> Laurent:
    """The product ``p q``."""
    (lp, cp), (lq, cq) = p, q
    if not cp or not cq:
        return (0, ())
    out = [0] * (len(cp) + len(cq) - 1)
    for i, a in enumerate(cp):
        if a:
            for j, b in enumerate(cq):
                out[i + j] += a * b
    return laurent(lp + lq, out)


def divide(p: Laurent, q: Laurent) -> Laurent | None:
    """The exact quotient ``p / q`` as a Laurent polynomial with integer
    coefficients, or None if ``q`` does not divide ``p`` in ``Z[t, 1/t]``."""
    (lp, cp), (lq, cq) = p, q
    if not cq:
        raise ZeroDivisionError("division by the zero polynomial")
    if not cp:
        return (0, ())
    if len(cq) > len(cp):
        return None
    rest = list(cp)
    quotient = [0] * (len(cp) - len(cq) + 1)
    lead = cq[0]
    for i in range(len(quotient)):
        if rest[i] % lead:
            return None
        factor = rest[i] // lead
        quotient[i] = factor
        if factor:
            for j, b in enumerate(cq):
                rest[i + j] -= factor * b
    if any(rest):
        return None
    return laurent(lp - lq, quotient)


def mirror(p: Laurent) -> Laurent:
    """``p(1/t)``: the Jones polynomial of the mirror image."""
    low, c = p
    if not c:
        return p
    return (-(low + len(c) - 1), tuple(reversed(c)))


def evaluate(p: Laurent, t: int) -> int | float:
    """``p(t)`` (exact for integer ``t = ±1``)."""
    low, c = p
    return sum(x * t ** (low + k) for k, x in enumerate(c))


def format_laurent(p: Laurent, variable: str = "t") -> str:
    """A readable form such as ``t - t^3 + 2 t^-2`` (``0`` for the zero polynomial)."""
    low, c = p
    words = []
    for k, x in enumerate(c):
        if not x:
            continue
        e = low + k
        sign = "-" if x < 0 else "+"
        mag = abs(x)
        if e == 0:
            body = str(mag)
        else:
            power = variable if e == 1 else f"{variable}^{e}"
            body = power if mag == 1 else f"{mag} {power}"
        words.append((sign, body))
    if not words:
        return "0"
    first_sign, first = words[0]
    text = ("-" if first_sign == "-" else "") + first
    for sign, body in words[1:]:
        text += f" {sign} {body}"
    return text
