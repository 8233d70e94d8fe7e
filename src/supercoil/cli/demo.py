"""``supercoil demo``: the bifurcation diagram of a DNA-like ring with self-contact.

Seed 001's DNA example (Coleman & Swigon, Figures 1-4): C/A = 2/3, L/D = 122.
Calls :func:`supercoil.problems.ring_diagram.ring_diagram` with the settings
below and writes its files with :mod:`supercoil.cli.diagram_output`. No
numerics here.
"""

from __future__ import annotations

from pathlib import Path

from supercoil.cli._common import fail, warn

TWIST_RATIO = 2.0 / 3.0  # C/A of DNA (seed 001)
LENGTH_OVER_DIAMETER = 122.0  # seed 001's DNA example
# 132 nodes: segments (L/132 = 0.92 D) shorter than the tube diameter, as contact
# lines need, and a multiple of 4 and 3, so that the mesh has the D_2 and D_3
# symmetries of the alpha and beta branches (at N = 128 the pinned sliding gauge
# broke beta's D_3 before contact, which came at dLk 1.51 instead of 1.40).
# dLk <= 3: one and two contact points on alpha, three on beta (seed 001); further
# up, beta's contact branch stalls (measured at dLk 3.09 at N = 120) and
# alpha reaches contact intervals (supercoil diagram ring --max-excess-link 3.5).
# alpha's contact branch needs about 220 points to dLk 3 (its folds near 2.3-2.7);
# the demo takes about 25 s on two cores.
N_NODES = 132
MODES = (2, 3)
MAX_EXCESS_LINK = 3.0
CONTACT_MAX_POINTS = 300
# The double-integral contact on the B-spline: alpha's contact branch to dLk 3 in 89
# points with 3 folds, against 220 points and 9 folds (most of them artefacts of the
# pair sum) with the diagram's default (docs/benchmarks.md, "Integral contact"). The
# demo draws primary branches only, where the two formulations agree on the contacts.
CONTACT_FORMULATION = "integral"
CONTACT_CURVE = "spline"
DEFAULT_FOLDER = "supercoil-demo"


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
          f"C/A = 2/3, L/D = {LENGTH_OVER_DIAMETER:g} (seed 001's DNA example), N = {N_NODES}, "
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
