"""One ring equilibrium as a result: a one-point branch ``ring`` (``supercoil ring --out``
and ``supercoil run`` of a ``ring`` study)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

RECORD_KEYS = ("excess_link", "writhe", "twist", "energy", "link_error",
               "min_gap_over_diameter", "n_contact_points", "n_contact_intervals")


def ring_branch(result, excess_link: float, summary: dict):
    """The solve ``result`` (:class:`~supercoil.problems.ring.RingResult` or its contact
    counterpart) as a one-point :class:`~supercoil.continuation.Branch` named ``ring``,
    with the numbers of ``summary`` as records."""
    from supercoil.continuation import Branch, ContinuationStatus

    q = np.asarray(result.points, float).ravel()
    mu = np.asarray(result.multipliers, float).ravel()
    records = {k: np.array([summary[k]], dtype=float) for k in RECORD_KEYS
               if isinstance(summary.get(k), (int, float)) and not isinstance(summary[k], bool)}
    eig = np.asarray(result.lowest_eigenvalues, float)
    return Branch(
        name="ring", parent=None, origin=None, parameter="excess_link",
        parameter_values=np.array([excess_link], float), states=q[None, :],
        multipliers=mu[None, :], unstable_count=np.array([result.unstable_count]),
        zero_modes=np.array([result.zero_modes]),
        determinant_sign=np.array([result.determinant_sign]),
        nearest_eigenvalue=np.array([eig[np.argmin(np.abs(eig))] if eig.size else math.nan]),
        tangents=np.zeros((1, q.size + mu.size + 1)), arclength=np.zeros(1),
        special_points=(),
        status=(ContinuationStatus.MAX_POINTS if result.converged
                else ContinuationStatus.START_FAILED),
        message=f"one state (a single solve, not a continuation): {result.message}",
        records=records)


def ring_payload(summary: dict, curvature) -> dict:
    """``ring.json``'s payload: the summary, the curvature form and the one point."""
    return {**summary, "curvature_form": curvature, "branch": "ring",
            "points": [{"branch": "ring", "index": 0, **{k: v for k, v in summary.items()
                                                         if not isinstance(v, dict)}}]}


def write_ring(out: Path, branch, data: dict, *, settings: dict, attributes: dict,
               provenance: dict, units: str, converged: bool) -> None:
    """``out/result.h5`` (the branch, ``data`` as its summary) and ``out/ring.json``."""
    from supercoil.cli.saving import create_folder, open_writer
    from supercoil.io.results import write_json

    create_folder(out)
    writer = open_writer(out, resume=False, problem="ring", settings=settings,
                         attributes=attributes, provenance=provenance, units=units)
    writer.write_branch(branch, complete=True, contact="diameter" in attributes)
    writer.set_summary(data)
    writer.set_status("complete" if converged else "incomplete",
                      "converged" if converged else "not converged")
    writer.close()
    write_json(data, out / "ring.json")
