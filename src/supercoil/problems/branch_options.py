"""Checks and constants shared by the options of the branch studies (ring diagram, tweezers).

Both follow a contact-free branch and then a branch with self-contact, with
the same kinds of steps and tolerances: :func:`check_steps` validates them,
:func:`branch_tolerances` reports them in a result's provenance, :func:`coarse_mesh_note`
says when the rod's mesh is too coarse for the tube.
"""

from __future__ import annotations

import numpy as np

from supercoil import checks
from supercoil.continuation import ContinuationOptions

PREDICTORS = ("tangent", "secant", "quadratic")
# Smallest arclength step of a contact branch. Where a contact forms, the branch
# turns within a gap range of about barrier_activation * D * K_rod / kappa
# (the barrier stiffness grows from zero like 6 kappa (g_hat - g) / g_hat):
# about 1e-8 L at N = 60, L/D = 122, so steps far below D are needed there.
CONTACT_MIN_STEP = 1e-12


def check_steps(options, points: tuple[str, ...] = ()) -> None:
    """The steps and tolerances shared by the ring diagram's and the tweezers' options:
    positive numbers, steps at most 1e3 (units of L or D), tolerances below 1; then the
    bounds on the points of a branch named in ``points``: integers from 2."""
    for name in ("free_max_step", "contact_max_step"):
        checks.number(name, getattr(options, name), 0.0, 1e3, low_open=True,
                      meaning="largest arclength step")
    for name in ("event_tolerance", "contact_event_tolerance", "contact_tolerance"):
        checks.number(name, getattr(options, name), 0.0, 1.0, low_open=True, high_open=True)
    for name in points:
        checks.integer(name, getattr(options, name), 2, checks.MAX_POINTS,
                       meaning="points of a branch")


def branch_tolerances(options) -> dict:
    """The provenance ``tolerances`` of options with ``event_tolerance``,
    ``contact_event_tolerance`` and ``contact_tolerance`` (ring diagram, tweezers)."""
    return {"corrector_residual": ContinuationOptions.tolerance,
            "zero_modes": ContinuationOptions.zero_tolerance,
            "event_arclength": options.event_tolerance,
            "contact_event_arclength": options.contact_event_tolerance,
            "contact_corrector_residual": options.contact_tolerance}


def coarse_mesh_note(rod, diameter: float, extra_nodes: int = 0) -> str | None:
    """A note when the segments of ``rod`` (its ``edge_length`` and ``length``) are longer
    than the tube ``diameter`` (a length), naming the node count that resolves it (plus
    ``extra_nodes``, e.g. a clamped rod's end nodes); None when they are not."""
    if rod.edge_length <= diameter:
        return None
    return (f"segments ({rod.edge_length:.3g} L) are longer than the tube diameter "
            f"({diameter:.3g} L): contact lines are under-resolved; use --nodes >= "
            f"{int(np.ceil(rod.length / diameter)) + extra_nodes}")
