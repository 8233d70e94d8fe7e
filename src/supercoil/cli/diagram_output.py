"""Run and write ring diagrams of the CLI (``diagram ring``, ``demo``).

No numerics: :func:`run_diagram` computes a ring diagram with
:func:`supercoil.ring_diagram` through :func:`~supercoil.cli.saving.run_saving`
(every accepted point appended to ``result.h5`` as it comes), and :func:`write_diagram` stores the final
branches and the summary, closes the result, writes ``diagram.json`` (the
payload of :meth:`~supercoil.problems.ring_diagram.RingDiagram.payload` with
the JSON envelope) and then draws the three figures of
:mod:`supercoil.plotting.ring_diagram` from it.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import typer

from supercoil.api.recording import RESULT_FILE
from supercoil.cli._common import EXIT_NOT_CONVERGED, warn
from supercoil.cli.saving import figures_interrupted

DIAGRAM_FILES = (RESULT_FILE, "diagram.json", "link_writhe.png", "contact_map.png",
                 "configurations.png")


def diagram_settings(options, command: str, rod=None) -> dict:
    """What a resumed run must share with the stored one: the command and its options,
    and for a Cosserat ``rod`` its model's keys (a Kirchhoff rod's add none)."""
    from supercoil.cli.model_options import model_record

    model = {} if rod is None else {"rod": model_record(rod)}
    return {"command": command, "options": dataclasses.asdict(options), **model}


def diagram_attributes(options) -> dict:
    return {"twist_ratio": options.twist_ratio, "n_nodes": options.n_nodes, "closed": True,
            "length_over_diameter": options.length_over_diameter,
            "diameter": options.diameter}


def run_diagram(options, out: Path, quiet: bool = False, *, resume=None,
                command: str = "diagram ring", resume_hint: str = "",
                rod=None) -> dict | None:
    """Compute ``options``' ring diagram into ``out`` (``result.h5``, ``diagram.json``, the
    figures) with :func:`supercoil.ring_diagram`; the payload, or None after an interrupt.
    ``resume``: the stored :class:`~supercoil.io.store.Result` to continue. ``rod``: a
    :class:`~supercoil.CosseratRod` for the Cosserat model's diagram, None for the
    Kirchhoff rod's."""
    from supercoil.api.verbs import diagram_of
    from supercoil.cli.saving import open_writer, run_saving

    writer = open_writer(out, resume=resume is not None, problem="ring_diagram",
                         settings=diagram_settings(options, command, rod),
                         attributes=diagram_attributes(options),
                         provenance={"contact_treatment": options.contact,
                                     "n_nodes": options.n_nodes})

    def compute(message, on_point):
        return diagram_of(options, rod=rod, progress=message, on_point=on_point, out=writer,
                          resume=resume is not None)

    diagram = run_saving(compute, writer, quiet, resume_hint)
    if diagram is None:
        return None
    return write_diagram(diagram.computed, out, options.contact, writer)


def store_diagram(diagram, writer, summary: dict) -> None:
    """Store the final branches of ``diagram`` and ``summary`` (``diagram.json``'s data)
    in ``writer``, set the run's status and close it."""
    for branch in diagram.branches:
        writer.write_branch(branch, complete=True,
                            contact=branch.name in diagram.contact_branches)
    for name in set(writer.branch_names()) - {b.name for b in diagram.branches}:
        writer.remove_branch(name)
    writer.set_summary(summary)
    if diagram.ok:
        writer.set_status("complete", f"{len(diagram.branches)} branches computed")
    else:
        failed = [b.name for b in diagram.branches if not diagram.branch_ok(b)]
        writer.set_status("incomplete", f"branch(es) {', '.join(failed)} stopped early"
                          if failed else next(n for n in diagram.notes
                                              if n.startswith("failed:")))
    writer.close()


def write_diagram(diagram, out: Path, contact: str, writer) -> dict:
    """Store ``diagram`` (a RingDiagram) in ``writer`` (then closed) and ``diagram.json``,
    print a summary, draw the figures; return the payload. The data are complete
    before the first figure is drawn: an interrupt while drawing leaves them whole
    (exit status 1, with a hint to draw them with ``supercoil plot``)."""
    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.figures import through_special_points
    from supercoil.plotting.ring_diagram import draw_jobs
    from supercoil.plotting.style import generation_style

    options = diagram.options
    payload = diagram.payload()
    data = envelope(payload, n_nodes=options.n_nodes, tolerances=options.tolerances,
                    contact_treatment=contact)
    store_diagram(diagram, writer, data)
    write_json(data, out / "diagram.json")
    points = payload["points"]
    by_branch = {b["name"]: [p for p in points if p["branch"] == b["name"]]
                 for b in payload["branches"]}
    title = (f"twisted ring, C/A = {options.twist_ratio:.4g}, "
             f"L/D = {options.length_over_diameter:g}, N = {options.n_nodes}")
    shown = []
    for b in payload["branches"]:
        rows = by_branch[b["name"]]
        if not b["contact"] and b["parent"] is not None and rows:
            rows = rows[:-1]  # the last contact-free point lies beyond the contact onset
        shown.append({"name": b["name"], "linestyle": generation_style(b["generation"]),
                      "writhe": [r["writhe"] for r in rows],
                      "excess_link": [r["excess_link"] for r in rows],
                      "stable": [r["stable"] for r in rows],
                      "contact_points": [r["contact_points"] for r in rows],
                      "contact_intervals": [r["contact_intervals"] for r in rows]})
    lines = [through_special_points(b, payload["special_points"], ("writhe", "excess_link"))
             for b in shown]
    jobs = [(out / "link_writhe.png", "ring:link_writhe",
             {"branches": lines, "special_points": payload["special_points"], "title": title}),
            (out / "contact_map.png", "ring:contact_map",
             {"branches": [b for b, e in zip(shown, payload["branches"]) if e["contact"]],
              "title": title})]
    configurations = []
    for branch in diagram.branches:
        if branch.name not in diagram.contact_branches or len(branch) == 0:
            continue
        for index in sorted({len(branch) // 3, 2 * len(branch) // 3, len(branch) - 1}):
            configurations.append({
                "label": f"{branch.name}, dLk = {branch.parameter_values[index]:.3f}, "
                         f"Wr = {float(branch.records['writhe'][index]):.3f}",
                "points": branch.states[index].reshape(-1, 3)})
    jobs.append((out / "configurations.png", "ring:configurations",
                 {"configurations": configurations, "diameter": options.diameter,
                  "title": title}))
    try:
        draw_jobs(jobs)
    except KeyboardInterrupt:
        figures_interrupted(out)
        raise typer.Exit(EXIT_NOT_CONVERGED) from None
    where = out.resolve()
    for b in payload["branches"]:
        specials = [p for p in payload["special_points"] if p["branch"] == b["name"]]
        kinds = ", ".join(f"{p['kind']} at dLk {p['excess_link']:.4f}" for p in specials)
        print(f"  {b['name']}: {b['n_points']} points, {b['seconds']:.1f} s, "
              f"{b['status'].lower()}" + (f"; {kinds}" if kinds else ""))
    print(f"wrote {', '.join(DIAGRAM_FILES)} to {where}", flush=True)
    for note in payload["notes"]:
        warn(f"note: {note}")
    return payload


def incomplete_message(payload: dict, out: Path) -> str | None:
    """The warning for branches that stopped early, or None when every branch is ok."""
    if payload["ok"]:
        return None
    failed = [b["name"] for b in payload["branches"] if not b["ok"]]
    return (f"incomplete: branch(es) {', '.join(failed)} stopped early (see 'message' in "
            f"{out.resolve() / 'diagram.json'})")
