"""``supercoil demo``: the bifurcation diagram of a DNA-like ring with self-contact.

Coleman & Swigon's DNA example (Coleman & Swigon 2000; its diagram in Coleman &
Swigon 2002, Figures 1-4): C/A = 2/3, L/D = 122. Computes
:func:`supercoil.ring_diagram` with the settings below and writes its files with
:mod:`supercoil.cli.diagram_output`. No numerics here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.cli._common import EXIT_NOT_CONVERGED, checked_path, fail, warn
from supercoil.cli._options import overwrite_option, quiet_option

TWIST_RATIO = 2.0 / 3.0  # C/A of DNA
LENGTH_OVER_DIAMETER = 122.0  # Coleman & Swigon's DNA example
# 132 nodes: segments (L/132 = 0.92 D) shorter than the tube diameter, as contact
# lines need, and a multiple of 4 and 3, so that the mesh has the D_2 and D_3
# symmetries of the alpha and beta branches (at N = 128 the pinned sliding gauge
# breaks beta's D_3 before contact, which then comes at dLk 1.51 instead of 1.40).
# dLk <= 3: one and two contact points on alpha, three on beta (Coleman & Swigon
# 2002); further up, beta's contact branch stalls and alpha reaches contact
# intervals (supercoil diagram ring --max-excess-link 3.5).
N_NODES = 132
MODES = (2, 3)
MAX_EXCESS_LINK = 3.0
CONTACT_MAX_POINTS = 300
# The double-integral contact on the B-spline: alpha's contact branch to dLk 3 with
# its physical folds only, where the pair sum adds artefact folds (docs/contact.md,
# "Contact energy: pair sum or double integral"). The demo draws primary branches
# only, where the two formulations agree on the contacts.
CONTACT_FORMULATION = "integral"
CONTACT_CURVE = "spline"
DEFAULT_FOLDER = "supercoil-demo"

DEMO_HELP = (
    "The bifurcation diagram of a DNA-like ring with self-contact (Coleman & Swigon 2002)."
    "\n\n"
    f"C/A = 2/3 and L/D = {LENGTH_OVER_DIAMETER:g}, Coleman & Swigon's DNA example, at "
    f"N = {N_NODES} nodes: the circle and its Michell bifurcations, the alpha and beta "
    "branches without contact up to their first contact, then with self-contact up to "
    f"dLk = {MAX_EXCESS_LINK:g} turns (at most {CONTACT_MAX_POINTS} points each). Writes "
    "what 'supercoil diagram ring' writes (result.h5, diagram.json, link_writhe.png, "
    "contact_map.png, configurations.png) into a new folder and says where. Exit status 1 "
    f"when a branch stopped before dLk = {MAX_EXCESS_LINK:g}: what was computed is written "
    "all the same, and --resume continues it."
)

Quiet = quiet_option()
Overwrite = overwrite_option("Write into an existing non-empty --out DIR, replacing the demo's "
                             "own files (other files are left alone).")


def demo(
    out: Annotated[Path | None, typer.Option(
        "--out", metavar="DIR", help="Folder for the result and figures. Default: "
        f"./{DEFAULT_FOLDER}, or ./{DEFAULT_FOLDER}-2, -3, ... if that exists. An existing "
        "non-empty DIR is refused unless --overwrite or --resume.", show_default=False,
        callback=checked_path)] = None,
    overwrite: Overwrite = False,
    resume: Annotated[bool, typer.Option(
        "--resume", help=f"Continue the interrupted demo in --out DIR (default "
        f"./{DEFAULT_FOLDER}) from its result.h5: finished branches are kept.")] = False,
    quiet: Quiet = False,
) -> None:
    from supercoil.cli.saving import nothing_to_resume

    folder, stored = prepare_folder(out, overwrite, resume)
    if nothing_to_resume(stored):
        return
    if not run_demo(folder, quiet, stored):
        raise typer.Exit(EXIT_NOT_CONVERGED)


def prepare_folder(out: Path | None, overwrite: bool, resume: bool = False):
    """``(folder, stored)``: the output folder, created (or, with ``overwrite``, reused),
    and with ``resume`` the stored result to continue (None otherwise); exit 2 if it
    is refused."""
    from supercoil.cli.diagram_output import diagram_settings
    from supercoil.cli.saving import prepare_folder as prepare

    if out is None and resume:
        out = Path(DEFAULT_FOLDER)
    if out is None:
        for index in range(1, 10_000):
            candidate = Path(DEFAULT_FOLDER if index == 1 else f"{DEFAULT_FOLDER}-{index}")
            try:
                candidate.mkdir()
            except FileExistsError:
                continue
            except OSError as exc:
                fail(
                    f"cannot create the demo folder {candidate.resolve()} ({exc.strerror}); "
                    "run from a writable folder or give --out DIR"
                )
            return candidate, None
        fail(f"too many {DEFAULT_FOLDER}-* folders here; give --out DIR")
    stored = prepare(out, overwrite=overwrite, resume=resume, problem="ring_diagram",
                     settings=diagram_settings(demo_options(), "demo"),
                     what="the demo's files", same_as="this version of the demo")
    return out, stored


def demo_options():
    """The demo's :class:`~supercoil.problems.ring_diagram.DiagramOptions`."""
    from supercoil.problems.ring_diagram import DiagramOptions

    return DiagramOptions(TWIST_RATIO, LENGTH_OVER_DIAMETER, n_nodes=N_NODES, modes=MODES,
                          max_excess_link=MAX_EXCESS_LINK,
                          contact_max_points=CONTACT_MAX_POINTS,
                          contact_formulation=CONTACT_FORMULATION, contact_curve=CONTACT_CURVE)


def run_demo(folder: Path, quiet: bool = False, stored=None) -> bool:
    """Compute the diagram, write it into ``folder`` and say where; True if every branch
    ended as asked (False after an interrupt too: what was saved is kept). ``stored``:
    the interrupted result to continue (``--resume``)."""
    from supercoil.cli.diagram_output import incomplete_message, run_diagram

    options = demo_options()
    print(f"supercoil demo: bifurcation diagram of a twisted ring with self-contact, "
          f"C/A = 2/3, L/D = {LENGTH_OVER_DIAMETER:g} (Coleman & Swigon's DNA example), "
          f"N = {N_NODES}, "
          f"modes {', '.join(map(str, MODES))}, dLk <= {MAX_EXCESS_LINK:g}", flush=True)
    payload = run_diagram(options, folder, quiet, resume=stored, command="demo",
                          resume_hint=f"continue with 'supercoil demo --out {folder} "
                          "--resume'")
    if payload is None:
        return False
    message = incomplete_message(payload, folder)
    if message is not None:
        warn(message)
        return False
    return True
