"""The verb of the knotted-ring diagram: :func:`knot_diagram`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

DIAGRAM_JSON = "diagram.json"


@dataclasses.dataclass(frozen=True)
class KnotDiagramResult:
    """What :func:`knot_diagram` returns: the branches (``knot_up``, ``knot_down``, ...), the
    summary (``diagram.json``'s data, with the JSON envelope) and the computed diagram
    (:class:`~supercoil.problems.knot_diagram.KnotDiagram`)."""

    branches: tuple
    summary: dict
    computed: object

    @property
    def ok(self) -> bool:
        return bool(self.summary["ok"])

    def __repr__(self) -> str:
        names = ", ".join(f"{b.name} ({len(b)})" for b in self.branches)
        kinds: dict[str, int] = {}
        for point in self.summary.get("special_points", ()):
            kinds[point["kind"]] = kinds.get(point["kind"], 0) + 1
        special = ", ".join(f"{n} {k}" for k, n in kinds.items()) or "none"
        low, high = self.summary["excess_link"]
        return (f"KnotDiagramResult({self.summary['knot_type']}, dLk {low:g} to {high:g}, "
                f"{'complete' if self.ok else 'incomplete'}: {len(self.branches)} branches\n"
                f"  points per branch: {names}\n  special points: {special})")


def knot_diagram(knot: str, twist_ratio: float, length_over_diameter: float,
                 excess_link: tuple[float, float], *, nodes: int = 60,
                 max_points: int = 150, start: float | None = None, deflation: int = 3,
                 branch_depth: int = 1, secondary_max_points: int = 60,
                 secondary_max_branches: int = 12, out=None, resume=None, overwrite: bool = False,
                 progress: Callable[[str], None] | None = None,
                 on_point: Callable | None = None) -> KnotDiagramResult:
    """The diagram of a knotted ring in its excess link, with self-contact (Coleman &
    Swigon 2000, Figure 5).

    ``knot`` (``"3_1"``, ``"5_2*"``, ``"T(2,5)"``, as for :class:`supercoil.Ring`) is
    relaxed with the barrier contact of tube diameter ``1/length_over_diameter`` at
    ``start`` (default: the middle of ``excess_link = (dLk_min, dLk_max)``) and
    followed both ways to the ends of the range, ``max_points`` points each way;
    the knot type is kept at every step. At ``deflation`` computed points spread
    over the range further equilibria are sought by deflation (Farrell, Birkisson
    & Funke 2015) and by relaxing the knot anew, and each new one is followed both
    ways (docs/knots.md, "A knotted ring's diagram"). ``branch_depth`` 2 also follows
    the half-branches switched from the located bifurcation points of those branches
    (``knot_I+``, ``knot_II-``, ...: at most ``secondary_max_points`` points each,
    ``secondary_max_branches`` in all), 3 those switched from theirs too.

    ``out``: a folder (created if missing): every accepted point is appended to
    ``out/result.h5`` as it comes, before ``on_point(branch)`` sees it, so a run
    stopped by Ctrl-C, a signal or a crash keeps every point reported (the result is
    then closed as ``interrupted`` or ``failed``); at the end the file gets the final
    branches, the summary and the status, and ``diagram.json`` (the summary) is
    written beside it. An existing result there is refused unless ``overwrite``.
    ``out`` may also be an open :class:`supercoil.io.store.ResultWriter`: the points
    and final branches are stored in it, and the caller adds the summary and status
    and closes it. ``resume``: ``True`` continues the result in ``out``; a result
    (:func:`supercoil.load`'s, or its file or folder) is continued from: its finished
    branches are kept, the others continued from their last point, and the stored
    options must be these, but for a point limit, which may be raised (as for
    :func:`supercoil.ring_diagram`). Invalid input
    raises :class:`supercoil.errors.InputError` before anything is computed or
    written.
    """
    from supercoil.api.verbs import _computed
    from supercoil.io.results import envelope, write_json
    from supercoil.problems.knot_diagram import KnotDiagramOptions, compute_knot_diagram

    options = KnotDiagramOptions(knot, twist_ratio, length_over_diameter,
                                 tuple(excess_link) if isinstance(excess_link, (list, tuple))
                                 else excess_link, nodes, max_points, start, deflation,
                                 branch_depth=branch_depth,
                                 secondary_max_points=secondary_max_points,
                                 secondary_max_branches=secondary_max_branches)

    def compute(settings, say, *, on_point, on_branch, resume):
        return compute_knot_diagram(settings, progress=say, on_point=on_point,
                                    on_branch=on_branch, resume=resume)

    diagram, writer, owned = _computed(
        "knot_diagram", options, compute, progress, on_point, out, resume, overwrite,
        attributes={"twist_ratio": options.twist_ratio, "n_nodes": options.n_nodes,
                    "closed": True, "diameter": options.diameter,
                    "length_over_diameter": options.length_over_diameter},
        provenance={"contact_treatment": "barrier", "n_nodes": options.n_nodes},
        contact=lambda name: True)
    summary = envelope(diagram.payload(), n_nodes=options.n_nodes,
                       tolerances=options.tolerances, contact_treatment="barrier")
    if writer is not None:
        writer.set_attribute("knot_type", diagram.knot.name)
    if owned:
        finish(writer, diagram, summary)
        write_json(summary, writer.path.parent / DIAGRAM_JSON)
    return KnotDiagramResult(diagram.branches, summary, diagram)


def finish(writer, diagram, summary: dict) -> None:
    """Store ``summary`` (``diagram.json``'s data) and the run's status in ``writer`` (which
    holds ``diagram``'s final branches), and close it."""
    writer.set_summary(summary)
    stopped = [b.name for b in diagram.branches if not b.status.complete]
    writer.set_status("complete" if diagram.ok else "incomplete",
                      f"{len(diagram.branches)} branches computed" if diagram.ok else
                      f"branch(es) {', '.join(stopped)} stopped early")
    writer.close()
