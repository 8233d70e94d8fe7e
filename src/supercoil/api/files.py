"""Saving results of the API in the one result format (HDF5), readable by :func:`supercoil.load`.

A :class:`~supercoil.api.results.Diagram` is stored with every branch (states,
records, special points), its settings, its JSON payload as summary and its
status; an :class:`~supercoil.api.results.Equilibrium` as a one-point branch
``ring``, as ``supercoil ring --out`` stores it. The files are those the command
line writes (``result.h5``), so ``supercoil plot``, ``view`` and ``export`` read them.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from supercoil.api.results import Diagram, Equilibrium
from supercoil.continuation import Branch, ContinuationStatus
from supercoil.errors import InputError


def _plain(value):
    """Settings as JSON data: tuples as lists, infinities as strings."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def _dna(result):
    """The DNA preset of a result in DNA units (a tweezers problem made by
    ``Tweezers.from_dna``), else None."""
    return getattr(getattr(result, "problem", None), "dna", None)


def _attributes(twist_ratio: float, n_nodes: int, closed: bool,
                length_over_diameter: float | None, **loads) -> dict:
    """The scalar attributes the readers of a result file use (``n_nodes``, ``closed``,
    the tube's diameter, the load), as the command line stores them."""
    out = {"twist_ratio": twist_ratio, "n_nodes": n_nodes, "closed": closed}
    out.update({k: v for k, v in loads.items() if v is not None})
    if length_over_diameter is not None:
        out.update(length_over_diameter=length_over_diameter,
                   diameter=1.0 / length_over_diameter)
    return out


def options_attributes(options, *, closed: bool) -> dict:
    """The attributes of a result computed with ``options`` (a ring diagram's or the
    tweezers' options)."""
    return _attributes(options.twist_ratio, options.n_nodes, closed,
                       options.length_over_diameter,
                       tension=getattr(options, "tension", None),
                       end_distance=getattr(options, "end_distance", None))


def _equilibrium_branch(eq: Equilibrium) -> Branch:
    q = np.asarray(eq.points, float).reshape(1, -1)
    records = {k: np.array([eq.record[k]], dtype=float)
               for k in ("excess_link", "writhe", "twist", "energy", "link_error",
                         "min_gap_over_diameter", "n_contact_points", "n_contact_intervals")
               if isinstance(eq.record.get(k), (int, float))
               and not isinstance(eq.record[k], bool)}
    eig = np.asarray(eq.stability.eigenvalues, float)
    nearest = eig[np.argmin(np.abs(eig))] if eig.size else np.nan
    return Branch(name="ring", parent=None, origin=None, parameter="excess_link",
                  parameter_values=np.array([eq.excess_link]), states=q,
                  multipliers=np.asarray(eq.tensions, float).reshape(1, -1),
                  unstable_count=np.array([eq.stability.unstable_count]),
                  zero_modes=np.array([eq.stability.zero_modes]),
                  determinant_sign=np.array([eq.stability.determinant_sign]),
                  nearest_eigenvalue=np.array([nearest]),
                  tangents=np.zeros((1, q.shape[1] + eq.tensions.size + 1)),
                  arclength=np.zeros(1), special_points=(),
                  status=ContinuationStatus.PARAMETER_BOUND if eq.converged
                  else ContinuationStatus.START_FAILED,
                  message=eq.message, records=records)


def save(result: Diagram | Equilibrium, path: str | Path, *, overwrite: bool = False) -> Path:
    """Write ``result`` to the HDF5 file ``path``; returns the path.

    An existing file is refused unless ``overwrite``. Read it back with
    :func:`supercoil.load`.
    """
    from supercoil.io.store import ResultWriter

    path = Path(path)
    if path.exists() and not overwrite:
        raise InputError(f"save: {path} exists; give another path or overwrite=True")
    if not path.parent.is_dir():
        raise InputError(f"save: the folder {path.parent} does not exist")
    if isinstance(result, Diagram):
        settings = _plain(dataclasses.asdict(result.settings))
        branches = list(result.branches.values())
        contact = getattr(result.computed, "contact_branches", frozenset())
        summary = result.summary
        status = "complete" if result.ok else "incomplete"
        kind = result.kind
        options = result.settings
        attributes = options_attributes(options, closed=kind != "tweezers")
        if _dna(result) is not None:
            from supercoil.units.tweezers import dna_attributes

            attributes.update(dna_attributes(_dna(result), result.problem.force_pN))
    elif isinstance(result, Equilibrium):
        ring = result.problem
        settings = {"twist_ratio": ring.rod.twist_ratio, "nodes": ring.rod.nodes,
                    "excess_link": ring.excess_link,
                    "contact": None if ring.contact is None else ring.contact.treatment,
                    "length_over_diameter": None if ring.contact is None
                    else ring.contact.length_over_diameter}
        branches, contact = [_equilibrium_branch(result)], frozenset()
        summary = _plain(dict(result.record))
        status = "complete" if result.converged else "incomplete"
        kind = "ring"
        attributes = _attributes(ring.rod.twist_ratio, ring.rod.nodes, True,
                                 settings["length_over_diameter"])
    else:
        raise InputError(f"save: expected a supercoil.Diagram or Equilibrium, got "
                         f"{type(result).__name__}")
    units = "nondimensional" if _dna(result) is None else _dna(result).name
    with ResultWriter.create(path, problem=kind, settings=settings, attributes=attributes,
                             units=units, overwrite=overwrite) as w:
        for branch in branches:
            w.write_branch(branch, complete=branch.ok, contact=branch.name in contact)
        w.set_summary(summary)
        w.set_status(status, getattr(result, "message", ""))
    return path
