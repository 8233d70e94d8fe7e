"""What ``supercoil tweezers`` writes: the branches and the summary in ``result.h5``,
``branch.json`` (with the JSON envelope), the figures of :mod:`supercoil.plotting.tweezers`,
and a few lines on what was computed."""

from __future__ import annotations

from pathlib import Path

import typer

from supercoil.cli._common import EXIT_NOT_CONVERGED, warn


def tweezers_attributes(options, preset) -> dict:
    out = {"twist_ratio": options.twist_ratio, "n_nodes": options.n_nodes, "closed": False}
    for key in ("tension", "end_distance", "length_over_diameter"):
        value = getattr(options, key)
        if value is not None:
            out[key] = value
    if options.length_over_diameter is not None:
        out["diameter"] = 1.0 / options.length_over_diameter
    if preset is not None:
        from supercoil.units.tweezers import dna_attributes

        out.update(dna_attributes(preset, preset.force_to_pN(options.tension)))
    return out


def write_tweezers(result, out: Path, writer, path=None, preset=None) -> dict:
    """Store the branches and the summary in ``writer`` (then closed), write branch.json
    (with the envelope), then the figures; return the payload. The data are complete
    before the first figure is drawn: an interrupt while drawing leaves them whole.

    ``path``: the quasi-static path (:class:`~supercoil.problems.tweezers_protocol.PathResult`)
    of the up-down protocol, written as the list ``path`` with its jumps among the special
    points, and its states as the result's extra ``path`` (``states``, ``turns``).
    ``preset``: a :class:`~supercoil.units.dna.DNAPreset`; its suffixed keys are added to
    every point, special point and path point, and ``units`` is ``dna``.
    """
    from supercoil.cli.saving import figures_interrupted
    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.tweezers import pick_configurations, write_figures
    from supercoil.problems.tweezers_output import (
        TWEEZERS_CONVENTIONS,
        add_contact_lists,
        result_payload,
    )

    payload = result_payload(result, contacts=False)
    states = {b.name: b.states for b in result.branches}
    if path is not None:
        import numpy as np

        payload["path"] = list(path.points)
        payload["path_ok"] = path.ok
        payload["path_message"] = path.message
        payload["special_points"] += list(path.jumps)
        writer.set_extra("path", {"states": np.asarray(path.states, float),
                                  "turns": np.array([p["turns"] for p in path.points],
                                                    float)})
    add_contact_lists(result, payload["points"])
    data = dict(payload)
    if preset is not None:
        from supercoil.units.tweezers import tweezers_payload_in_dna_units

        data = tweezers_payload_in_dna_units(data, preset,
                                             preset.force_to_pN(result.options.tension))
    configurations = pick_configurations(data, states)
    data = envelope(data, n_nodes=result.options.n_nodes, tolerances=result.options.tolerances,
                    units="nondimensional" if preset is None else preset.name,
                    contact_treatment="barrier" if result.contact_problem else "none")
    data["conventions"].update(TWEEZERS_CONVENTIONS)
    if preset is not None:
        data["conventions"].update(preset.conventions())
        data["provenance"]["units_preset"] = preset.record()
    for branch in result.branches:
        writer.write_branch(branch, complete=True, contact=branch.name in result.contact_branches)
    for name in set(writer.branch_names()) - {b.name for b in result.branches}:
        writer.remove_branch(name)
    writer.set_summary(data)
    complete = payload["ok"] and (path is None or path.ok)
    writer.set_status("complete" if complete else "incomplete",
                      f"{len(result.branches)} branches computed" if complete else
                      "; ".join([b["message"] for b in payload["branches"] if not b["ok"]]
                                + ([] if path is None or path.ok else [path.message])))
    writer.close()
    write_json(data, out / "branch.json")
    try:
        write_figures(data, configurations, out)
    except KeyboardInterrupt:
        figures_interrupted(out)
        raise typer.Exit(EXIT_NOT_CONVERGED) from None
    payload = data
    for b in payload["branches"]:
        specials = [p for p in payload["special_points"] if p["branch"] == b["name"]
                    and p["kind"] != "fold"]
        folds = sum(p["kind"] == "fold" for p in payload["special_points"]
                    if p["branch"] == b["name"])
        kinds = ", ".join(f"{p['kind']} at {p['turns']:.4f} turns" for p in specials[:6])
        if len(specials) > 6:
            kinds += f", ... ({len(specials)} in all)"
        print(f"  {b['name']}: {b['n_points']} points, {b['seconds']:.1f} s, "
              f"{b['status'].lower()}" + (f"; {kinds}" if kinds else "")
              + (f"; {folds} folds" if folds else ""))
    if payload.get("greenhill_turns") is not None:
        print(f"  exact buckling of the straight rod (clamped Greenhill with tension): "
              f"{payload['greenhill_turns']:.6f} turns")
    ply = payload.get("hard_core_ply")
    if ply is not None:
        print(f"  hard-core ply (Neukirch & van der Heijden 2002): torque {ply['torque']:.4g} A/L, "
              f"extension {ply['extension_per_turn']:.4g} L per turn, spans the rod at "
              f"{ply['spanning_turns']:.4g} turns")
    if path is not None:
        jumps = ", ".join(f"{j['turns']:.3f} ({'up' if j['direction'] > 0 else 'down'}, "
                          f"z/L {j['extension']:.3f} -> {j['extension_after']:.3f})"
                          for j in path.jumps)
        print(f"  path: {len(path.points)} quasi-static steps; jumps at {jumps or 'none'}")
    if preset is not None:
        last = payload["points"][-1]
        print(f"  DNA: {preset.base_pairs} bp = {preset.length_nm:.4g} nm, F = "
              f"{payload['force_pN']:.4g} pN, D = {preset.effective_diameter_nm:.3g} nm; last "
              f"state: extension {last['extension_nm']:.4g} nm, torque "
              f"{last['torque_pN_nm']:.4g} pN nm")
        warn(f"note: {payload['conventions']['athermal']}")
    print(f"wrote result.h5, branch.json and figures to {out.resolve()}", flush=True)
    for note in payload["notes"]:
        warn(f"note: {note}")
    return payload
