"""Write a computed ring diagram into a folder (``supercoil diagram ring`` and ``demo``).

No numerics: the branches are saved, the payload of
:meth:`~supercoil.problems.ring_diagram.RingDiagram.payload` goes into
``diagram.json`` (with the JSON envelope), and the three figures of
:mod:`supercoil.plotting.ring_diagram` are drawn from it.
"""

from __future__ import annotations

from pathlib import Path

from supercoil.cli._common import warn

DIAGRAM_FILES = ("diagram.json", "link_writhe.png", "contact_map.png", "configurations.png")


def write_diagram(diagram, out: Path, contact: str) -> dict:
    """Save ``diagram`` (a RingDiagram) into ``out``, print a summary; return the payload."""
    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.ring_diagram import (
        plot_configurations,
        plot_contact_map,
        plot_link_writhe,
    )

    options = diagram.options
    (out / "branches").mkdir(parents=True, exist_ok=True)
    for branch in diagram.branches:
        branch.save(out / "branches" / f"{branch.name}.npz")
    payload = diagram.payload()
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
        shown.append({"name": b["name"], "writhe": [r["writhe"] for r in rows],
                      "excess_link": [r["excess_link"] for r in rows],
                      "stable": [r["stable"] for r in rows],
                      "contact_points": [r["contact_points"] for r in rows],
                      "contact_intervals": [r["contact_intervals"] for r in rows]})
    lines = [_through_special_points(b, [p for p in payload["special_points"]
                                         if p["branch"] == b["name"]]) for b in shown]
    plot_link_writhe(out / "link_writhe.png", branches=lines,
                     special_points=payload["special_points"], title=title)
    plot_contact_map(out / "contact_map.png",
                     branches=[b for b, e in zip(shown, payload["branches"]) if e["contact"]],
                     title=title)
    configurations = []
    for branch in diagram.branches:
        if branch.name not in diagram.contact_branches or len(branch) == 0:
            continue
        for index in sorted({len(branch) // 3, 2 * len(branch) // 3, len(branch) - 1}):
            configurations.append({
                "label": f"{branch.name}, dLk = {branch.parameter_values[index]:.3f}, "
                         f"Wr = {float(branch.records['writhe'][index]):.3f}",
                "points": branch.states[index].reshape(-1, 3)})
    plot_configurations(out / "configurations.png", configurations=configurations,
                        diameter=options.diameter, title=title)
    write_json(envelope(payload, n_nodes=options.n_nodes, tolerances=options.tolerances,
                        contact_treatment=contact), out / "diagram.json")
    where = out.resolve()
    for b in payload["branches"]:
        specials = [p for p in payload["special_points"] if p["branch"] == b["name"]]
        kinds = ", ".join(f"{p['kind']} at dLk {p['excess_link']:.4f}" for p in specials)
        print(f"  {b['name']}: {b['n_points']} points, {b['seconds']:.1f} s, "
              f"{b['status'].lower()}" + (f"; {kinds}" if kinds else ""))
    print(f"wrote {', '.join(DIAGRAM_FILES)} and branches/*.npz to {where}", flush=True)
    for note in payload["notes"]:
        warn(f"note: {note}")
    return payload


def _through_special_points(line: dict, specials: list[dict]) -> dict:
    """The branch's polyline with its located special points inserted (ΔLk-Wr figure).

    Each special point enters twice at its place (after point ``index``): with
    the stability before it, then after it, so that a stable stretch is drawn
    heavy up to the located point (a bifurcation of the circle, a fold), not
    only up to the last stable sample.
    """
    k = len(line["writhe"])
    rows = [(float(i), line["writhe"][i], line["excess_link"][i], line["stable"][i])
            for i in range(k)]
    for p in specials:
        if "writhe" not in p or not 0 <= p["index"] < k:
            continue
        at = p["index"] + 0.5
        rows.append((at, p["writhe"], p["excess_link"], p["count_before"] == 0))
        rows.append((at + 1e-6, p["writhe"], p["excess_link"], p["count_after"] == 0))
    rows.sort(key=lambda r: r[0])
    return {"name": line["name"], "writhe": [r[1] for r in rows],
            "excess_link": [r[2] for r in rows], "stable": [r[3] for r in rows]}


def incomplete_message(payload: dict, out: Path) -> str | None:
    """The warning for branches that stopped early, or None when every branch is ok."""
    if payload["ok"]:
        return None
    failed = [b["name"] for b in payload["branches"] if not b["ok"]]
    return (f"incomplete: branch(es) {', '.join(failed)} stopped early (see 'message' in "
            f"{out.resolve() / 'diagram.json'})")
