"""The verb of the knotted-ring diagram: :func:`knot_diagram`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

from supercoil.api.recording import RESULT_FILE
from supercoil.errors import InputError

DIAGRAM_JSON = "diagram.json"


@dataclasses.dataclass(frozen=True)
class KnotDiagramResult:
    """What :func:`knot_diagram` returns: the branches (``knot_up``, ``knot_down``), the
    summary (``diagram.json``'s data, with the JSON envelope) and the computed diagram
    (:class:`~supercoil.problems.knot_diagram.KnotDiagram`)."""

    branches: tuple
    summary: dict
    computed: object

    @property
    def ok(self) -> bool:
        return bool(self.summary["ok"])


def knot_diagram(knot: str, twist_ratio: float, length_over_diameter: float,
                 excess_link: tuple[float, float], *, nodes: int = 60,
                 max_points: int = 150, start: float | None = None, deflation: int = 3,
                 out=None, overwrite: bool = False,
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
    & Funke 2015) and by relaxing the knot anew, and each new one is followed both ways (docs/knots.md, "A knotted
    ring's diagram"). ``out``: a folder (created if missing) for ``result.h5`` (the two
    branches with their states, readable by :func:`supercoil.load`) and
    ``diagram.json`` (the summary); an existing result there is refused unless
    ``overwrite``. Invalid input raises :class:`supercoil.errors.InputError` before
    anything is computed or written.
    """
    from supercoil.io.results import envelope, write_json
    from supercoil.io.store import save
    from supercoil.problems.knot_diagram import KnotDiagramOptions, compute_knot_diagram

    options = KnotDiagramOptions(knot, twist_ratio, length_over_diameter,
                                 tuple(excess_link) if isinstance(excess_link, (list, tuple))
                                 else excess_link, nodes, max_points, start, deflation)
    folder = None if out is None else Path(out)
    if folder is not None:
        if folder.exists() and not folder.is_dir():
            raise InputError(f"out {folder}: is a file, not a folder; give a folder",
                             name="out")
        if (folder / RESULT_FILE).exists() and not overwrite:
            raise InputError(f"out {folder}: holds a {RESULT_FILE} already; give another "
                             "folder or overwrite=True", name="out")
    diagram = compute_knot_diagram(options, progress=progress, on_point=on_point)
    summary = envelope(diagram.payload(), n_nodes=options.n_nodes,
                       tolerances=options.tolerances, contact_treatment="barrier")
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        settings = {"command": "diagram knot",
                    "options": {k: v for k, v in dataclasses.asdict(options).items()}}
        save(folder / RESULT_FILE, diagram.branches, problem="knot_diagram",
             settings=settings, summary=summary, overwrite=True,
             attributes={"twist_ratio": options.twist_ratio, "n_nodes": options.n_nodes,
                         "closed": True, "diameter": options.diameter,
                         "length_over_diameter": options.length_over_diameter,
                         "knot_type": diagram.knot.name},
             status="complete" if diagram.ok else "incomplete")
        write_json(summary, folder / DIAGRAM_JSON)
    return KnotDiagramResult(diagram.branches, summary, diagram)
