"""One ring equilibrium as a result: its JSON document, and a one-point branch ``ring``
in a result folder (``supercoil ring --json/--out`` and ``supercoil run`` of a ``ring``
study)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

RECORD_KEYS = ("excess_link", "writhe", "twist", "energy", "link_error",
               "min_gap_over_diameter", "n_contact_points", "n_contact_intervals")
ENVELOPE_KEYS = ("schema_version", "units", "conventions", "provenance")


def ring_branch(state, summary: dict):
    """The :class:`supercoil.Equilibrium` ``state`` as a one-point
    :class:`~supercoil.continuation.Branch` named ``ring``, with the numbers of
    ``summary`` as records."""
    from supercoil.continuation import Branch, ContinuationStatus

    q = np.asarray(state.points, float).ravel()
    mu = np.asarray(state.tensions, float).ravel()
    records = {k: np.array([summary[k]], dtype=float) for k in RECORD_KEYS
               if isinstance(summary.get(k), (int, float)) and not isinstance(summary[k], bool)}
    stability = state.stability
    eig = np.asarray(stability.eigenvalues, float)
    return Branch(
        name="ring", parent=None, origin=None, parameter="excess_link",
        parameter_values=np.array([state.excess_link], float), states=q[None, :],
        multipliers=mu[None, :], unstable_count=np.array([stability.unstable_count]),
        zero_modes=np.array([stability.zero_modes]),
        determinant_sign=np.array([stability.determinant_sign]),
        nearest_eigenvalue=np.array([eig[np.argmin(np.abs(eig))] if eig.size else math.nan]),
        tangents=np.zeros((1, q.size + mu.size + 1)), arclength=np.zeros(1),
        special_points=(),
        status=(ContinuationStatus.MAX_POINTS if state.converged
                else ContinuationStatus.START_FAILED),
        message=f"one state (a single solve, not a continuation): {state.message}",
        records=records)


def ring_payload(summary: dict, curvature) -> dict:
    """``ring.json``'s payload: the summary, the curvature form and the one point."""
    return {**summary, "curvature_form": curvature, "branch": "ring",
            "points": [{"branch": "ring", "index": 0, **{k: v for k, v in summary.items()
                                                         if not isinstance(v, dict)}}]}


def ring_document(state, summary: dict, preset=None, *, initial: str | None = None) -> dict:
    """``supercoil ring --json``'s document: ``summary`` (the state's record, in DNA units
    with a :class:`~supercoil.units.dna.DNAPreset` ``preset``), the curvature form and,
    with contact, the ``initial`` curve's file; in the JSON envelope."""
    from supercoil.io.results import envelope

    problem = state.problem
    payload = {**summary, "curvature_form": problem.rod.curvature}
    treatment = "none"
    if problem.contact is not None:
        treatment = problem.contact.treatment
        payload["initial_curve"] = initial
    data = envelope(payload, n_nodes=problem.rod.nodes, tolerances=dict(state.tolerances),
                    contact_treatment=treatment,
                    units="nondimensional" if preset is None else preset.name)
    if preset is not None:
        data["conventions"].update(preset.conventions())
        data["provenance"]["units_preset"] = preset.record()
    return data


def write_ring_folder(out: Path, state, summary: dict, data: dict, preset=None) -> None:
    """``supercoil ring --out DIR``: result.h5 and ring.json (``data``, the --json
    document, with the one point)."""
    problem = state.problem
    lod = None if problem.contact is None else problem.contact.length_over_diameter
    data = {**{k: v for k, v in data.items() if k not in ENVELOPE_KEYS},
            **{k: v for k, v in ring_payload(summary, problem.rod.curvature).items()
               if k in ("branch", "points")},
            **{k: data[k] for k in ENVELOPE_KEYS}}
    attributes = {"twist_ratio": problem.rod.twist_ratio, "n_nodes": problem.rod.nodes,
                  "closed": True}
    if lod is not None:
        attributes.update(length_over_diameter=lod, diameter=1.0 / lod)
    settings = {"command": "ring", "twist_ratio": problem.rod.twist_ratio,
                "excess_link": problem.excess_link, "length_over_diameter": lod,
                "nodes": problem.rod.nodes, "contact": data["provenance"]["contact_treatment"],
                "initial": data.get("initial_curve"),
                "dna": None if preset is None else preset.record()}
    write_ring(out, ring_branch(state, summary), data, settings=settings,
               attributes=attributes, provenance=data["provenance"], units=data["units"],
               converged=bool(summary["converged"]))


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
