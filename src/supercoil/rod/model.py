"""The discrete Kirchhoff rod's parameters: nodes, stiffnesses, length, curvature form.

Nondimensional units (docs/model.md, "Nondimensional units"): bending stiffness
A = 1 and contour length L = 1 unless given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil.rod import kernels


@dataclass(frozen=True)
class Rod:
    """Material and discretisation of an isotropic Kirchhoff rod.

    ``bending_stiffness`` A, ``twist_stiffness`` C, ``length`` L (A = L = 1 in
    the nondimensional default), ``n_nodes`` vertices, ``curvature`` form,
    ``closed`` (a ring has ``n_nodes`` edges, an open rod ``n_nodes - 1``).
    """

    n_nodes: int
    twist_stiffness: float = 1.0
    bending_stiffness: float = 1.0
    length: float = 1.0
    curvature: str = "angle"
    closed: bool = True

    def __post_init__(self) -> None:
        for name in ("twist_stiffness", "bending_stiffness", "length"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
        if int(self.n_nodes) != self.n_nodes or self.n_nodes < 8:
            raise ValueError(f"n_nodes must be an integer >= 8, got {self.n_nodes!r}")
        if self.curvature not in kernels.CURVATURE_FORMS:
            raise ValueError(
                f"curvature must be one of {kernels.CURVATURE_FORMS}, got {self.curvature!r}"
            )

    @property
    def twist_ratio(self) -> float:
        return self.twist_stiffness / self.bending_stiffness

    @property
    def n_edges(self) -> int:
        return self.n_nodes if self.closed else self.n_nodes - 1

    @property
    def edge_length(self) -> float:
        """Rest length ``h`` of every edge.

        A ring has ``L / n_nodes``. An open rod has ``L / (n_nodes - 2)``: its
        ends are the midpoints of the first and last edges, where the clamps
        act (with the clamps at the end nodes instead, the clamped rod would be
        ``h`` too short and its buckling load first-order accurate — measured).
        """
        return self.length / (self.n_nodes if self.closed else self.n_nodes - 2)
