"""Knot diagrams as signed Gauss codes, their Reidemeister I/II simplification and PD codes.

A diagram of a knot with ``n`` crossings is the sequence of its ``2 n`` passes
through crossings in the order met along the oriented curve: each pass names
its crossing (``0 .. n-1``) and says whether the curve goes over or under
there; each crossing has a sign, +1 when the over strand's direction turns
counter-clockwise onto the under strand's (right-hand rule, viewer above the
projection plane). For a knot this signed Gauss code determines the diagram on
the sphere, and so every invariant computed here.

:meth:`Diagram.simplified` removes crossings by Reidemeister moves read on the
code itself:

* I: a crossing whose two passes are consecutive bounds a loop with no crossing
  on it (a monogon on the sphere): it is removed;
* II: two crossings ``a``, ``b`` of opposite signs passed consecutively over
  (``a`` then ``b``) and, elsewhere, consecutively under (either order) bound a
  bigon with one strand over the other: both are removed.

Both moves are isotopies, so the simplified diagram is the same knot with fewer
crossings. They do not reduce every diagram to a minimal one (that may need
third moves), so the invariants are computed on what is left.

:meth:`Diagram.pd_code` gives the planar-diagram code in the convention of the
Knot Atlas and KnotInfo: ``X[i, j, k, l]`` lists the four edges at a crossing
counter-clockwise from the incoming under edge ``i``, edges numbered from 1
along the orientation; :meth:`Diagram.from_pd` reads one back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil.errors import InputError


@dataclass(frozen=True)
class Diagram:
    """A knot diagram: ``passes`` ``(2 n,)`` crossing indices in the order along the
    curve, ``over`` ``(2 n,)`` True where that pass goes over, ``signs`` ``(n,)`` ±1."""

    passes: tuple[int, ...]
    over: tuple[bool, ...]
    signs: tuple[int, ...]

    @property
    def n_crossings(self) -> int:
        return len(self.signs)

    @property
    def writhe(self) -> int:
        """Sum of the crossing signs (a diagram's writhe, not the curve's)."""
        return int(sum(self.signs))

    def gauss_code(self) -> tuple[int, ...]:
        """The signed Gauss code: ``+k`` over, ``-k`` under crossing ``k`` (from 1)."""
        return tuple((c + 1) if o else -(c + 1) for c, o in zip(self.passes, self.over))

    def mirror(self) -> Diagram:
        """The mirror image (every crossing switched)."""
        return Diagram(self.passes, tuple(not o for o in self.over),
                       tuple(-s for s in self.signs))

    def simplified(self) -> Diagram:
        """The diagram after Reidemeister I and II moves until none applies (module doc)."""
        m = len(self.passes)
        if m == 0:
            return self
        crossing = list(self.passes)
        over = list(self.over)
        signs = self.signs
        nxt = [(k + 1) % m for k in range(m)]
        prv = [(k - 1) % m for k in range(m)]
        alive = [True] * m
        partner = [0] * m
        first: dict[int, int] = {}
        for k, c in enumerate(crossing):
            if c in first:
                partner[k], partner[first[c]] = first[c], k
            else:
                first[c] = k
        remaining = m
        work = list(range(m))

        def remove(k: int) -> None:
            nonlocal remaining
            alive[k] = False
            remaining -= 1
            p, q = prv[k], nxt[k]
            nxt[p], prv[q] = q, p
            if alive[p]:
                work.append(p)
            if alive[q]:
                work.append(q)

        while work and remaining:
            k = work.pop()
            if not alive[k]:
                continue
            j = nxt[k]
            if j == k:
                continue
            if crossing[j] == crossing[k]:  # Reidemeister I
                remove(k)
                remove(j)
                continue
            if over[j] != over[k] or signs[crossing[j]] == signs[crossing[k]]:
                continue
            pk, pj = partner[k], partner[j]
            if nxt[pk] == pj or nxt[pj] == pk:  # Reidemeister II
                for r in (k, j, pk, pj):
                    if alive[r]:
                        remove(r)
        if not remaining:
            return Diagram((), (), ())
        start = next(k for k in range(m) if alive[k])
        order = [start]
        k = nxt[start]
        while k != start:
            order.append(k)
            k = nxt[k]
        kept = sorted({crossing[k] for k in order})
        index = {c: i for i, c in enumerate(kept)}
        return Diagram(tuple(index[crossing[k]] for k in order),
                       tuple(over[k] for k in order),
                       tuple(signs[c] for c in kept))

    def pd_code(self) -> tuple[tuple[int, int, int, int], ...]:
        """``X[i, j, k, l]`` per crossing, edges from 1 (module doc). Edge ``e`` runs from
        pass ``e - 1`` to pass ``e`` (pass 0 ends edge ``2 n``)."""
        m = len(self.passes)
        under_in = [0] * self.n_crossings
        under_out = [0] * self.n_crossings
        over_in = [0] * self.n_crossings
        over_out = [0] * self.n_crossings
        for k, (c, o) in enumerate(zip(self.passes, self.over)):
            incoming = k if k else m  # edge ending at pass k
            outgoing = k + 1  # edge starting at pass k
            if o:
                over_in[c], over_out[c] = incoming, outgoing
            else:
                under_in[c], under_out[c] = incoming, outgoing
        code = []
        for c, s in enumerate(self.signs):
            if s > 0:  # the over strand runs from l to j
                code.append((under_in[c], over_out[c], under_out[c], over_in[c]))
            else:
                code.append((under_in[c], over_in[c], under_out[c], over_out[c]))
        return tuple(code)

    @classmethod
    def from_pd(cls, pd) -> Diagram:
        """The diagram of a PD code (Knot Atlas / KnotInfo convention, edges ``1 .. 2 n``
        numbered along the orientation)."""
        pd = [tuple(int(e) for e in x) for x in pd]
        m = 2 * len(pd)
        if any(len(x) != 4 for x in pd) or sorted(e for x in pd for e in x) != sorted(
                list(range(1, m + 1)) * 2):
            raise InputError(f"PD code {pd}: each crossing needs 4 edges and each edge "
                             f"1..{m} must appear exactly twice")
        at_pass: dict[int, tuple[int, bool]] = {}
        signs = []

        def successor(e: int) -> int:
            return e % m + 1

        for c, (i, j, k, l) in enumerate(pd):
            if successor(i) != k:
                raise InputError(f"PD code crossing {c + 1} {(i, j, k, l)}: the under "
                                 "strand must run from edge i to edge i + 1")
            at_pass[i] = (c, False)
            if successor(l) == j and not (m == 2 and l == j):  # over strand from l to j
                at_pass[l] = (c, True)
                signs.append(1)
            elif successor(j) == l:
                at_pass[j] = (c, True)
                signs.append(-1)
            else:
                raise InputError(f"PD code crossing {c + 1} {(i, j, k, l)}: edges j and l "
                                 "must be consecutive")
        if len(at_pass) != m:
            raise InputError(f"PD code {pd}: not the diagram of a knot (one component)")
        passes = tuple(at_pass[e][0] for e in range(1, m + 1))
        over = tuple(at_pass[e][1] for e in range(1, m + 1))
        return cls(passes, over, tuple(signs))

    def arcs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each crossing its over arc, incoming under arc and outgoing under arc
        (arcs: the pieces of the curve between under passes, numbered ``0 .. n-1``)."""
        n = self.n_crossings
        over_arc = np.zeros(n, dtype=np.int64)
        arc_in = np.zeros(n, dtype=np.int64)
        arc_out = np.zeros(n, dtype=np.int64)
        arc = 0
        for c, o in zip(self.passes, self.over):
            if o:
                over_arc[c] = arc % n
            else:
                arc_in[c] = arc % n
                arc += 1
                arc_out[c] = arc % n
        return over_arc, arc_in, arc_out
