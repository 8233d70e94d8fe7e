"""The centreline of a Cosserat rod, as self-contact sees it.

Contact between two cross-sections of a rod is a condition on its centreline alone:
two points farther apart along the rod than the neighbour exclusion stay a tube
diameter apart (:mod:`supercoil.contact.problem`). The Cosserat unknowns hold, per
node ``i``, the position ``q[6i:6i+3]`` and the rotation coordinates
``q[6i+3:6i+6]`` (:mod:`supercoil.cosserat.problem`); the centreline is the polygon
of the positions, a linear selection of ``q``::

    x = P q,   P[3i + c, 6i + c] = 1   (c = 0, 1, 2),

so a contact energy ``Psi(x)`` has ``grad_q = P^T grad_x`` and ``hess_q = P^T hess_x P``:
its gradient and Hessian are those of the polygon scattered into the position
entries, and the rotations carry no contact term. The polygon joins the nodes of
the elements (the chord of each element; the rod's centreline between two nodes is
the chord in the two-node elements' interpolation). The chart of the rotations plays
no part: positions are chart-free.

:class:`CosseratCentreline` gives a Cosserat energy the centreline interface that
:class:`~supercoil.contact.problem.ContactProblem` asks of its rod (``centreline``,
``centreline_dofs``, ``edge_nodes``); the ring adds the writhe its link carries
(:meth:`~supercoil.cosserat.closed.ClosedCosseratEnergy.writhe_local`), which the
contact's link guard compares with the polygon's double sum.
"""

from __future__ import annotations

import numpy as np

from supercoil.cosserat.rod import DOFS_PER_NODE


def centreline_dofs(n_nodes: int) -> np.ndarray:
    """``(3 n_nodes,)``: the entries of ``q`` holding the nodes' positions, in order."""
    return (DOFS_PER_NODE * np.arange(n_nodes)[:, None] + np.arange(3)).ravel()


def positions_of(q: np.ndarray) -> np.ndarray:
    """The centreline ``(n, 3)`` of a Cosserat state ``q`` (a view when ``q`` is an array)."""
    return np.asarray(q, dtype=float).reshape(-1, DOFS_PER_NODE)[:, :3]


class CosseratCentreline:
    """The centreline interface of a Cosserat energy (module doc); mixed into
    :class:`~supercoil.cosserat.problem.CosseratEnergy`, whose ``rod`` and ``n_dofs`` it
    reads."""

    def centreline(self, q: np.ndarray) -> np.ndarray:
        """The centreline ``(3 n,)`` of ``q``: the nodes' positions (linear in ``q``)."""
        return positions_of(q).ravel()

    @property
    def centreline_dofs(self) -> np.ndarray:
        """The entries of ``q`` that :meth:`centreline` selects (:func:`centreline_dofs`)."""
        return centreline_dofs(self.rod.n_nodes)

    @property
    def edge_nodes(self) -> np.ndarray:
        """``(n_elements, 2)``: the nodes of each element, the centreline's segments."""
        return self.rod.element_nodes()

    # the rod's ends are its first and last nodes
    centreline_origin = 0.0


class StoredCentrelines(CosseratCentreline):
    """A Cosserat rod seen through its centreline alone: the unknowns are the centreline
    ``(3 n,)`` (the map is the identity), for the contact of centrelines stored along a
    branch (contact lists of the outputs). Its contact terms are those of the Cosserat
    energy of the same ``rod`` at the same centreline."""

    n_constraints = 0

    def __init__(self, rod):
        self.rod = rod
        self.n_dofs = 3 * rod.n_nodes
        self.fixed = np.zeros(0, dtype=np.int64)
        self.mass = np.full(self.n_dofs, rod.edge_length)

    def centreline(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(q, dtype=float)

    @property
    def centreline_dofs(self) -> np.ndarray:
        return np.arange(self.n_dofs)
