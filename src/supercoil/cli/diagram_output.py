"""Run and write branch computations of the CLI (``diagram ring``, ``demo``, ``tweezers``).

No numerics: :func:`run_saving` runs a computation it is given with a
progress display and saves its branches as they come; :func:`run_diagram`
computes a ring diagram and writes it; :func:`write_diagram`
saves a ring diagram's branches, puts the payload of
:meth:`~supercoil.problems.ring_diagram.RingDiagram.payload` into
``diagram.json`` (with the JSON envelope) and draws the three figures of
:mod:`supercoil.plotting.ring_diagram` from it.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from supercoil.cli._common import warn

DIAGRAM_FILES = ("diagram.json", "link_writhe.png", "contact_map.png", "configurations.png")
# Points between saves of a branch in progress: a save rewrites the branch (53 ms
# for 126 points at N = 128, measured, compressed; in-progress saves are now
# written uncompressed, 29 ms for 559 points at N = 100), so saving every point
# would cost as much as computing it on long branches; 'supercoil run' appends
# every point instead.
SAVE_EVERY = 10
# ... and not sooner than this many seconds after the previous in-progress save: on a
# short run the saves were overhead on the critical path (issue 5's benchmark: 9 saves of
# the contact branch, about 0.1 s of its 3-4 s under py-spy), while a kill without an
# interrupt now loses at most this long or SAVE_EVERY points, whichever is more
SAVE_INTERVAL = 2.0


def save_branch(branch, folder: Path, compressed: bool = True) -> None:
    """Write ``branch`` to ``folder/<name>.npz`` atomically (a temporary file renamed):
    an interrupt or a crash leaves the previous file or the new one, never a part."""
    target = folder / f"{branch.name}.npz"
    temporary = folder / f".{branch.name}.partial.npz"
    branch.save(temporary, compressed)
    os.replace(temporary, target)


def run_saving(compute, out: Path, quiet: bool = False, saved: dict | None = None,
               compress_final: bool = True):
    """Run ``compute(message, on_point, on_branch)`` with a progress display, saving
    branches into ``out/branches`` as they come.

    Every branch is written to ``out/branches/<name>.npz`` when it is final,
    and a branch in progress every ``SAVE_EVERY`` points but at most once per
    ``SAVE_INTERVAL`` seconds (atomically: a temporary file renamed) and when an
    interrupt (Ctrl-C) ends the run, so that the interrupt loses no point computed
    (a kill without an interrupt loses at most ``SAVE_EVERY`` points or
    ``SAVE_INTERVAL`` seconds of points, whichever is more). ``saved`` (a dict, if given) gets ``name -> branch`` for every final
    branch written, so that a later writer need not write it again. Returns what
    ``compute`` returns, or None after an interrupt (the message says what was kept).
    ``compress_final=False`` writes the final branches without deflating them too, for a
    caller that compresses them later, off its critical path (``supercoil tweezers``,
    while its figures are drawn: the deflation of issue 5's three branches took 0.05 s of
    the command, the plain writes 0.01 s).
    """
    from supercoil.cli.progress import Progress

    folder = out / "branches"
    folder.mkdir(parents=True, exist_ok=True)

    def save(branch, compressed: bool = True) -> None:
        save_branch(branch, folder, compressed)

    unsaved = {}  # name -> the last state of each branch in progress
    saved_at = {}  # name -> the number of points of its last in-progress save
    last_save = [time.monotonic()]  # when the last in-progress save was written

    with Progress(quiet) as progress:
        def on_point(branch) -> None:
            unsaved[branch.name] = branch
            k = len(branch)
            step = float(branch.arclength[-1] - branch.arclength[-2]) if k >= 2 else None
            progress.point(branch.name, branch.parameter, float(branch.parameter_values[-1]),
                           step, k)
            if k - saved_at.get(branch.name, 0) >= SAVE_EVERY and \
                    time.monotonic() - last_save[0] >= SAVE_INTERVAL:
                # uncompressed: deflating a long branch's arrays took most of a save
                # (the final save, below, is compressed)
                save(branch, compressed=False)
                saved_at[branch.name] = k
                last_save[0] = time.monotonic()

        def on_branch(branch, contact) -> None:
            save(branch, compressed=compress_final)
            unsaved.pop(branch.name, None)
            if saved is not None:
                saved[branch.name] = branch

        try:
            return compute(progress.message, on_point, on_branch)
        except KeyboardInterrupt:
            for branch in unsaved.values():  # every point computed so far
                save(branch, compressed=False)
            kept = sorted(p.name for p in folder.glob("*.npz") if not p.name.startswith("."))
            warn(f"interrupted: kept {', '.join(kept) or 'no branch'} in {folder.resolve()} "
                 f"(branches in progress up to their last point); the "
                 "summary and the figures were not written")
            return None


def compute_diagram(options, out: Path, quiet: bool = False, saved: dict | None = None):
    """:func:`ring_diagram` through :func:`run_saving` (None after an interrupt)."""
    from supercoil.problems.ring_diagram import ring_diagram

    return run_saving(lambda message, on_point, on_branch: ring_diagram(
        options, progress=message, on_point=on_point, on_branch=on_branch), out, quiet, saved)


def run_diagram(options, out: Path, quiet: bool = False) -> dict | None:
    """:func:`compute_diagram` then :func:`write_diagram`; the payload, or None after an
    interrupt."""
    saved: dict = {}
    diagram = compute_diagram(options, out, quiet, saved)
    if diagram is None:
        return None
    return write_diagram(diagram, out, options.contact, saved)


def write_diagram(diagram, out: Path, contact: str, saved: dict | None = None) -> dict:
    """Save ``diagram`` (a RingDiagram) into ``out``, print a summary; return the payload.
    Branches that ``saved`` holds (:func:`run_saving`'s record) are already written."""
    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.figures import through_special_points
    from supercoil.plotting.ring_diagram import draw_jobs
    from supercoil.plotting.style import generation_style

    options = diagram.options
    (out / "branches").mkdir(parents=True, exist_ok=True)
    for branch in diagram.branches:
        if saved is None or saved.get(branch.name) is not branch:
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
    draw_jobs(jobs)
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


def incomplete_message(payload: dict, out: Path) -> str | None:
    """The warning for branches that stopped early, or None when every branch is ok."""
    if payload["ok"]:
        return None
    failed = [b["name"] for b in payload["branches"] if not b["ok"]]
    return (f"incomplete: branch(es) {', '.join(failed)} stopped early (see 'message' in "
            f"{out.resolve() / 'diagram.json'})")
