"""Running a study (:class:`~supercoil.io.study.Study`) into a folder: what
:func:`supercoil.run`, ``supercoil run`` and each task of ``supercoil sweep`` do.

:func:`run_study` writes ``result.h5`` point by point: a ring diagram and a tweezers
study are computed by :func:`supercoil.ring_diagram` and :func:`supercoil.tweezers`,
which store every point as it comes; a ``ring`` study is solved through
:func:`supercoil.equilibrium`. Then the JSON summary and the figures the study asks for.
It reports through the callbacks it is given and through :mod:`logging`, and never
prints or exits: the command line adds its progress display and its handling of
signals around it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from supercoil.api.recording import RESULT_FILE, from_interrupt

log = logging.getLogger(__name__)

SUMMARY_FILES = {"ring_diagram": "diagram.json", "ring": "ring.json",
                 "tweezers": "branch.json"}
FIGURE_FORMATS = ("png",)


def run_study(spec, out: Path, *, resume: bool = False,
              progress: Callable[[str], None] | None = None,
              on_point: Callable | None = None) -> dict:
    """Run ``spec`` (a :class:`~supercoil.io.study.Study`) into the existing folder ``out``;
    with ``resume``, continue the interrupted result there.

    ``progress(message)`` receives the lines worth showing (a branch starts, a note);
    ``on_point(branch)`` is called after every accepted point, once it is stored, with
    its branch so far. Returns ``{"status", "message", "files", "notes"}`` (and the
    ``summary`` once computed); the result file's status is ``complete``,
    ``incomplete``, ``interrupted`` (KeyboardInterrupt, from Ctrl-C or a callback:
    caught, the file closed) or ``failed`` (an exception: recorded, then re-raised).
    ``resumable`` is False when the interrupt came while the figures were drawn (the
    data are complete).
    """
    from supercoil.io.store import ResultWriter

    progress = progress or _silent
    result_path = out / RESULT_FILE
    if resume:
        writer = ResultWriter.reopen(result_path)
    else:
        writer = ResultWriter.create(result_path, problem=spec.kind, settings=spec.settings,
                                     units=spec.units, provenance=_provenance(spec),
                                     attributes=_attributes(spec), study_text=spec.text,
                                     overwrite=True)
    saved = {"points": 0}
    counted = _point_counter(on_point, saved)
    try:
        if spec.kind == "ring_diagram":
            outcome = _run_ring_diagram(spec, writer, progress, counted, resume)
        elif spec.kind == "tweezers":
            outcome = _run_tweezers(spec, writer, progress, counted, resume)
        else:
            outcome = _run_ring(spec, writer, progress)
    except BaseException as exc:
        if from_interrupt(exc):  # Ctrl-C, even inside a compiled kernel
            message = (f"interrupted by the user; {saved['points']} continuation points "
                       "saved so far")
            if writer.status == "running":  # the verbs close their result themselves
                writer.set_status("interrupted", message)
                writer.close()
            return {"status": "interrupted", "message": message, "files": [RESULT_FILE],
                    "notes": []}
        if writer.status == "running":
            writer.set_status("failed", f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            writer.close()
        raise
    summary = outcome["summary"]
    writer.set_summary(summary)
    writer.set_status(outcome["status"], outcome["message"])
    writer.close()
    files = [RESULT_FILE]
    if spec.settings["outputs"]["json"]:
        from supercoil.io.results import write_json

        name = SUMMARY_FILES[spec.kind]
        write_json(summary, out / name)
        files.append(name)
    if spec.settings["outputs"]["figures"]:
        try:
            files += _figures(result_path, out, outcome["notes"])
        except KeyboardInterrupt:
            log.info("interrupted while drawing the figures: the data are complete in %s",
                     result_path.resolve())
            return {**outcome, "status": "interrupted", "files": files, "resumable": False,
                    "message": "interrupted while drawing the figures (the data are complete)"}
    return {**outcome, "files": files}


def _attributes(spec) -> dict:
    rod, problem = spec.settings["rod"], spec.settings["problem"]
    out = {"twist_ratio": rod["twist_ratio"], "n_nodes": rod["nodes"],
           "closed": spec.kind != "tweezers", "study_name": spec.name}
    for key in ("tension", "end_distance"):
        if key in problem:
            out[key] = problem[key]
    if "length_over_diameter" in rod:
        out["length_over_diameter"] = rod["length_over_diameter"]
        out["diameter"] = 1.0 / rod["length_over_diameter"]
    preset = spec.dna_preset()
    if preset is not None:
        from supercoil.units.tweezers import dna_attributes

        out.update(dna_attributes(preset, problem.get("force_pN")))
    return out


def _treatment(spec) -> str:
    if spec.kind == "tweezers":
        return "barrier" if "length_over_diameter" in spec.settings["rod"] else "none"
    return spec.settings["problem"].get("contact", "none")


def _provenance(spec) -> dict:
    out = {"study_file": spec.source, "contact_treatment": _treatment(spec),
           "n_nodes": spec.settings["rod"]["nodes"]}
    preset = spec.dna_preset()
    if preset is not None:
        out["units_preset"] = preset.record()
    return out


def _envelope(spec, payload: dict, tolerances: dict) -> dict:
    from supercoil.io.results import envelope

    preset = spec.dna_preset()
    data = envelope(payload, n_nodes=spec.settings["rod"]["nodes"], tolerances=tolerances,
                    contact_treatment=_treatment(spec),
                    units=spec.units)
    data["provenance"]["study_file"] = spec.source
    if preset is not None:
        data["conventions"].update(preset.conventions())
        data["provenance"]["units_preset"] = preset.record()
    return data


def _silent(message: str) -> None:
    """The ``progress`` of a run given none."""


def _point_counter(on_point, saved: dict):
    """``on_point`` of the verbs (which store each point): counted, then passed on."""
    def counted(branch) -> None:
        saved["points"] += 1
        if on_point is not None:
            on_point(branch)

    return counted


def _outcome(ok: bool, payload: dict, summary: dict, notes: list) -> dict:
    """Status, message, summary and notes of a branch computation's run."""
    if ok:
        status, message = "complete", f"{len(payload['branches'])} branches computed"
    else:
        failed = [b["name"] for b in payload["branches"] if not b["ok"]]
        status = "incomplete"
        message = (f"branch(es) {', '.join(failed)} stopped early" if failed else
                   "a step failed (see notes)")
    return {"status": status, "message": message, "summary": summary,
            "notes": notes + list(payload["notes"])}


def _computed(spec, options, writer, progress, on_point, resume: bool):
    """The computed branches of ``options`` on the study's rod (the ring diagram's or the
    tweezers'), saved by ``writer``."""
    from supercoil.api.verbs import diagram_of

    rod = spec.rod()
    return diagram_of(options, rod=rod if rod.model == "cosserat" else None,
                      progress=progress, on_point=on_point, out=writer, resume=resume).computed


def _run_ring_diagram(spec, writer, progress, on_point, resume: bool) -> dict:
    options = spec.diagram_options()
    notes = []
    s = spec.settings
    progress(f"ring diagram: C/A = {s['rod']['twist_ratio']:.6g}, L/D = "
                     f"{s['rod']['length_over_diameter']:.6g}, N = {s['rod']['nodes']}, modes "
                     f"{', '.join(map(str, s['problem']['modes']))}, dLk <= "
                     f"{s['problem']['max_excess_link']:.6g}")
    diagram = _computed(spec, options, writer, progress, on_point, resume)
    payload = diagram.payload()
    preset = spec.dna_preset()
    if preset is not None:
        payload = diagram_in_dna_units(payload, preset, s["problem"]["max_superhelical_density"])
    summary = _envelope(spec, payload, options.tolerances)
    return _outcome(diagram.ok, payload, summary, notes)


def diagram_in_dna_units(payload: dict, preset, max_sigma: float) -> dict:
    """``diagram.json``'s payload with DNA keys added (the nondimensional ones unchanged):
    plasmid constants at the top, ``superhelical_density`` and ``energy_kT`` per point and
    per special point, ``force_pN`` / ``force_per_length_pN_per_nm`` in contact lists."""
    out = dict(payload)
    out.update(base_pairs=preset.base_pairs, length_nm=preset.length_nm,
               diameter_nm=preset.effective_diameter_nm,
               salt_mM=None if preset.salt_mM is None else float(preset.salt_mM),
               temperature_K=float(preset.temperature_K), kT_pN_nm=preset.kT_pN_nm,
               relaxed_link=preset.relaxed_link, max_superhelical_density=max_sigma,
               michell_superhelical_density={
                   m: preset.superhelical_density_of(v)
                   for m, v in payload["michell_excess_link"].items()})

    def point(p: dict) -> dict:
        q = dict(p)
        if "excess_link" in p:
            q["superhelical_density"] = preset.superhelical_density_of(p["excess_link"])
        if isinstance(p.get("energy"), (int, float)):
            q["energy_kT"] = preset.energy_to_kT(p["energy"])
        if "contact_points" in p:
            q["contact_points"] = [{**c, "force_pN": preset.force_to_pN(c["force"])}
                                   for c in p["contact_points"]]
        if "contact_intervals" in p:
            q["contact_intervals"] = [
                {**c, "force_per_length_pN_per_nm":
                 preset.force_per_length_to_pN_per_nm(c["force_per_length"])}
                for c in p["contact_intervals"]]
        return q

    out["points"] = [point(p) for p in payload["points"]]
    out["special_points"] = [point(p) for p in payload["special_points"]]
    return out


def _run_tweezers(spec, writer, progress, on_point, resume: bool) -> dict:
    from supercoil.problems.tweezers_output import TWEEZERS_CONVENTIONS, result_payload

    options = spec.tweezers_options()
    notes = []
    control = (f"F L^2/A = {options.tension:.6g}" if options.load_control
               else f"z/L = {options.end_distance:.6g}")
    progress(f"tweezers: C/A = {options.twist_ratio:.6g}, {control}, L/D = "
                     f"{options.length_over_diameter or 'no contact'}, N = {options.n_nodes}, "
                     f"turns {options.turns[0]:g} to {options.turns[1]:g}")
    result = _computed(spec, options, writer, progress, on_point, resume)
    payload = result_payload(result)
    preset = spec.dna_preset()
    if preset is not None:
        from supercoil.units.tweezers import tweezers_payload_in_dna_units

        payload = tweezers_payload_in_dna_units(payload, preset,
                                                spec.settings["problem"]["force_pN"])
    summary = _envelope(spec, payload, options.tolerances)
    summary["conventions"].update(TWEEZERS_CONVENTIONS)
    return _outcome(result.ok, payload, summary, notes)


def _run_ring(spec, writer, progress) -> dict:
    """A single ring solve (``supercoil ring``) through :func:`supercoil.equilibrium`,
    stored as a one-point branch ``ring``."""
    from supercoil import Ring, equilibrium
    from supercoil.api.model import contact_from_name
    from supercoil.api.ring_result import ring_branch, ring_payload

    s = spec.settings
    rod, problem = s["rod"], s["problem"]
    progress(f"ring: C/A = {rod['twist_ratio']:.6g}, dLk = "
                     f"{problem['excess_link']:.6g}, N = {rod['nodes']}")
    contact = None
    if "length_over_diameter" in rod:
        contact = contact_from_name(problem["contact"], rod["length_over_diameter"])
    state = equilibrium(Ring(spec.rod(), problem["excess_link"], contact=contact))
    # an inextensible, unshearable rod: no stretch and no shear
    summary = {"model": "kirchhoff", "max_stretch_strain": 0.0, "max_shear_strain": 0.0,
               **state.record}
    preset = spec.dna_preset()
    if preset is not None:
        from supercoil.units.dna import ring_summary_in_dna_units

        summary = ring_summary_in_dna_units(summary, preset)
    writer.write_branch(ring_branch(state, summary), complete=True, contact=contact is not None)
    data = _envelope(spec, ring_payload(summary, state.problem.rod.curvature),
                     dict(state.tolerances))
    status = "complete" if state.converged else "incomplete"
    message = ("converged" if state.converged else
               f"not converged: Newton stopped with status {summary['status']} "
               f"({state.message})")
    return {"status": status, "message": message, "summary": data, "notes": []}


def _figures(result_path: Path, out: Path, notes: list) -> list[str]:
    """PNG figures of every kind the result has data for (``supercoil plot``'s code)."""
    try:
        from supercoil.plotting.figures import plot_result, supported_kinds
        from supercoil.plotting.result_data import ResultError, load_result
    except ImportError:  # the figures module is not there: no figures
        notes.append("figures skipped: supercoil.plotting.figures is not available")
        return []
    try:
        data = load_result(result_path)
    except ResultError as exc:
        notes.append(f"figures skipped: {exc}")
        return []
    files = []
    for kind in supported_kinds(data):
        try:
            written = plot_result(data, kind, out, formats=FIGURE_FORMATS)
        except ValueError as exc:
            notes.append(f"figure {kind} skipped: {exc}")
            continue
        files += [Path(p).name for p in written]
    return files
