"""The hard-core plectoneme: a uniform two-ply of contacting helical strands.

Two strands of a rod of diameter ``D`` wind about a common axis at the distance
``R = D / 2`` from it, with the ply angle ``theta`` between each strand and the axis,
and touch along a line (Neukirch & van der Heijden 2002, J. Elasticity 69:41;
Clauvelin, Audoly & Neukirch 2009 without electrostatics). Each strand is a helix of
curvature ``kappa = sin^2(theta) / R``; a length ``l`` of rod in the ply carries the
writhe ``l sin(2 theta) / (4 pi R)`` (Fuller 1971; White & Bauer 1986). Under the dead
load ``T`` with the torque ``M`` uniform along the rod, the ply grows at the expense of
the straight tails; the energy is stationary in ``l`` and ``theta`` where

    M R / A = sin^2(theta) sin(2 theta) / cos(2 theta),
    T R^2 / A = sin^4(theta) (1 + 2 cos^2(theta)) / (2 cos(2 theta)),

and each turn of the end adds ``4 pi R / sin(2 theta)`` of rod to the ply, taken from
the extension. The twist carries the rest of the turns: ``Tw = M L / (2 pi C)``. So
the torque stays on the plateau ``M`` and the extension falls linearly with the turns
until the ply spans the whole rod, at

    turns = M L / (2 pi C) + L sin(2 theta) / (4 pi R),

beyond which the plectoneme cannot grow: the turns go into twist, the torque rises
and the extension stays near zero (in an experiment the bead meets the surface, which
the clamped rod here does not have). The end loop and the tails take some of the rod,
so a finite rod's ply spans it a little before that.

Units as everywhere: ``A = 1``, ``L = 1``; ``tension = T L^2 / A``, ``diameter = D / L``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq


def _tension_r2(theta: float) -> float:
    s, c = math.sin(theta), math.cos(theta)
    return s**4 * (1 + 2 * c * c) / (2 * math.cos(2 * theta))


@dataclass(frozen=True)
class HardCorePly:
    """The uniform hard-core two-ply (module doc) of a rod of ``diameter`` ``D/L`` under
    ``tension`` ``T L^2/A`` with ``twist_ratio`` ``C/A``.

    ``angle``: the ply angle theta (radians); ``torque``: ``M L / A`` on the plateau;
    ``extension_per_turn``: the change of the extension ``z/L`` per turn of the end
    (negative); ``rod_per_turn``: the rod ``l/L`` one turn adds to the ply;
    ``twist_turns``: ``Tw`` on the plateau; ``spanning_turns``: the turns at which
    the ply would span the whole rod."""

    diameter: float
    tension: float
    twist_ratio: float
    angle: float
    torque: float
    rod_per_turn: float

    @property
    def extension_per_turn(self) -> float:
        return -self.rod_per_turn

    @property
    def twist_turns(self) -> float:
        return self.torque / (2 * math.pi * self.twist_ratio)

    @property
    def spanning_turns(self) -> float:
        return self.twist_turns + 1.0 / self.rod_per_turn

    def summary(self) -> dict:
        """JSON-ready: the angle in degrees, the rest as the attributes."""
        return {"angle_degrees": math.degrees(self.angle), "torque": self.torque,
                "extension_per_turn": self.extension_per_turn,
                "twist_turns": self.twist_turns, "spanning_turns": self.spanning_turns}


def hard_core_ply(diameter: float, tension: float, twist_ratio: float) -> HardCorePly:
    """The hard-core ply (module doc) at ``diameter = D/L``, ``tension = T L^2/A`` and
    ``twist_ratio = C/A``, all positive and finite."""
    for name, value in (("diameter", diameter), ("tension", tension),
                        ("twist_ratio", twist_ratio)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    R = 0.5 * diameter
    target = tension * R * R
    # T R^2/A grows monotonically from 0 at theta = 0 (as 3 theta^4 / 2) to infinity at
    # theta = pi/4: the root lies between half the small angles' estimate and pi/4
    low = min(0.5 * (2.0 * target / 3.0) ** 0.25, 1e-3)
    high = math.pi / 4 - 1e-12
    if not target < _tension_r2(high):
        raise ValueError(f"tension * (diameter/2)^2 = {target!r} is beyond the ply's range "
                         f"(below {_tension_r2(high):.3g})")
    theta = brentq(lambda t: _tension_r2(t) - target, low, high, xtol=1e-15, rtol=1e-14)
    torque = math.sin(theta) ** 2 * math.sin(2 * theta) / math.cos(2 * theta) / R
    rod_per_turn = 4 * math.pi * R / math.sin(2 * theta)
    return HardCorePly(diameter=diameter, tension=tension, twist_ratio=twist_ratio,
                       angle=theta, torque=torque, rod_per_turn=rod_per_turn)


def spanning_note(ply: HardCorePly | None, last_turn: float) -> str | None:
    """A note when ``last_turn`` lies beyond the turns at which ``ply`` spans the rod:
    the run's end then lies past the plectoneme's growth. None otherwise."""
    if ply is None or not last_turn > ply.spanning_turns:
        return None
    return (f"the hard-core ply (Neukirch & van der Heijden 2002) would span the whole rod "
            f"at {ply.spanning_turns:.4g} turns, below the last turn {last_turn:.4g}: past "
            f"it the plectoneme cannot grow and the turns go into twist, the torque rising "
            f"above the ply's {ply.torque:.4g} (the clamped rod has no surface for the bead "
            f"to meet)")
