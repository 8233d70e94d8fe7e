"""The rod model's keys of a run's JSON payload: ``model`` (``"kirchhoff"`` or
``"cosserat"``, with the Cosserat rod's stiffnesses) and the largest stretch and shear
strains over every point of every branch (0 for the inextensible, unshearable
Kirchhoff rod)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

KIRCHHOFF = {"model": "kirchhoff"}


def model_keys(model: Mapping, branches: Iterable) -> dict:
    """``model`` with ``max_stretch_strain`` and ``max_shear_strain`` over ``branches``
    (their records of the same names; 0 where no branch records them)."""
    out = dict(model)
    for key in ("max_stretch_strain", "max_shear_strain"):
        values = [np.max(np.abs(b.records[key])) for b in branches
                  if key in b.records and len(b.records[key])]
        out[key] = float(max(values)) if values else 0.0
    return out
