"""DNA units on the figures of a rod in tweezers: nm, pN·nm, pN and σ.

A result computed in DNA units (``units`` = ``dna``: ``supercoil tweezers --dna``, a study
under ``[units] preset = "dna"``, :meth:`supercoil.Tweezers.from_dna`) carries the
molecule's scales beside its nondimensional numbers: the contour length ``length_nm``,
the relaxed link ``relaxed_link`` (Lk0 = N_bp / 10.5), the torque unit
``torque_scale_pN_nm`` (A/L) and the force unit ``force_scale_pN`` (A/L²).
:class:`DNAScales` reads them; the figures then draw the extension in nm (with z/L on
the right-hand axis), the torque in pN·nm, forces in pN and the end's rotation in turns
(with σ = turns / Lk0 on the top axis), title the figure with the force, the salt and
the length, and state the athermal caveat once, under the axes (:data:`CAVEAT`).

Plotting never computes: a DNA key missing from a point (``extension_nm`` of a run
stopped before its summary was written) is its nondimensional value times the unit, the
same product the JSON holds.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from supercoil.plotting import style

# the nondimensional key -> (its key in DNA units, the scale that converts it)
DNA_KEYS = {
    "extension": ("extension_nm", "length_nm"),
    "extension_after": ("extension_after_nm", "length_nm"),
    "torque": ("torque_pN_nm", "torque_scale_pN_nm"),
    "torque_after": ("torque_after_pN_nm", "torque_scale_pN_nm"),
    "tension": ("force_pN", "force_scale_pN"),
}

CAVEAT = ("Athermal elastic model (zero temperature): the extension is the full contour "
          "length L before buckling, and the buckling torque is above measured ones.")
CAVEAT_WIDTH = 95  # characters per line of the caveat under a figure


def _finite(value) -> float | None:
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


@dataclass(frozen=True)
class DNAScales:
    """The scales of a result in DNA units (see the module docstring)."""

    base_pairs: float
    length_nm: float
    relaxed_link: float
    torque_scale_pN_nm: float
    force_scale_pN: float
    force_pN: float | None = None
    salt_mM: float | None = None
    diameter_nm: float | None = None

    @classmethod
    def of(cls, data: Mapping) -> DNAScales | None:
        """The scales in ``data`` (a ``branch.json`` payload, or a result file's attributes
        and summary); None for a result not in DNA units or without them."""
        if data.get("units", "dna") != "dna":
            return None
        needed = {k: _finite(data.get(k)) for k in ("base_pairs", "length_nm", "relaxed_link",
                                                    "torque_scale_pN_nm", "force_scale_pN")}
        if any(v is None or v <= 0 for v in needed.values()):
            return None
        return cls(**needed, force_pN=_finite(data.get("force_pN")),
                   salt_mM=_finite(data.get("salt_mM")),
                   diameter_nm=_finite(data.get("diameter_nm")))

    def scale(self, key: str) -> float:
        return getattr(self, DNA_KEYS[key][1])

    def in_dna_units(self, point: Mapping) -> dict:
        """``point`` (numbers, or arrays of a branch's rows) with its DNA keys: those it
        has are kept, the missing ones are the nondimensional values times the units."""
        out = dict(point)
        for key, (dna_key, _) in DNA_KEYS.items():
            if dna_key not in out and out.get(key) is not None:
                out[dna_key] = _times(out[key], self.scale(key))
        if "superhelical_density" not in out and out.get("turns") is not None:
            out["superhelical_density"] = _times(out["turns"], 1.0 / self.relaxed_link)
        return out

    def title(self, n_nodes=None) -> str:
        """``DNA in magnetic tweezers: 3000 bp (1020 nm), N = 239`` over ``F = 1 pN, 150 mM
        salt (D = 4.3 nm)``: the force, the salt and the length."""
        first = (f"DNA in magnetic tweezers: {self.base_pairs:g} bp ({self.length_nm:.4g} nm)"
                 + ("" if n_nodes is None else f", N = {n_nodes}"))
        second = []
        if self.force_pN is not None:
            second.append(f"F = {self.force_pN:.4g} pN")
        diameter = None if self.diameter_nm is None else f"D = {self.diameter_nm:.3g} nm"
        if self.salt_mM is not None:
            second.append(f"{self.salt_mM:g} mM salt" + (f" ({diameter})" if diameter else ""))
        elif diameter:
            second.append(diameter)
        return first + ("\n" + ", ".join(second) if second else "")

    def axes(self, x: str, y: str) -> tuple[str, str, dict]:
        """The keys drawn for the nondimensional ``x`` and ``y`` and the secondary axes of
        :func:`~supercoil.plotting.figures.diagram_figure`: σ beside turns, z/L beside
        the extension in nm."""
        secondary = {}
        for axis, key in (("x", x), ("y", y)):
            if key == "turns":
                secondary[axis] = (style.LABELS["superhelical_density"],
                                   1.0 / self.relaxed_link)
            elif key == "extension":
                secondary[axis] = (style.LABELS["extension"], 1.0 / self.length_nm)
        return DNA_KEYS.get(x, (x,))[0], DNA_KEYS.get(y, (y,))[0], secondary


def _times(value, factor: float):
    a = np.asarray(value, float) * factor
    return float(a) if a.ndim == 0 else a


def caveat_text() -> str:
    """:data:`CAVEAT` in lines of :data:`CAVEAT_WIDTH` characters (a figure's caption)."""
    return textwrap.fill(CAVEAT, CAVEAT_WIDTH)
