"""``supercoil ring --json/--out``: one ring equilibrium's JSON document, and its folder
(``result.h5`` with the one-point branch ``ring`` of
:func:`~supercoil.api.ring_result.ring_branch`, and ``ring.json``)."""

from __future__ import annotations

from pathlib import Path

from supercoil.api.ring_result import ring_branch, ring_payload

ENVELOPE_KEYS = ("schema_version", "units", "conventions", "provenance")


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
    if preset is not None:  # the scales that export, plot and view read
        from supercoil.units.tweezers import dna_attributes

        attributes.update(dna_attributes(preset))
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
