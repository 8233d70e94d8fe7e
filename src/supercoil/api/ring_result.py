"""One ring equilibrium as a stored result: the one-point branch ``ring`` and the payload
of ``ring.json`` (a ``ring`` study, :func:`supercoil.run`; ``supercoil ring --out``)."""

from __future__ import annotations

import math

import numpy as np

RECORD_KEYS = ("excess_link", "writhe", "twist", "energy", "link_error",
               "min_gap_over_diameter", "n_contact_points", "n_contact_intervals")


def ring_branch(state, summary: dict):
    """The :class:`supercoil.Equilibrium` ``state`` as a one-point
    :class:`~supercoil.continuation.Branch` named ``ring``, with the numbers of
    ``summary`` as records."""
    from supercoil.continuation import Branch, ContinuationStatus

    q = np.asarray(state.points, float).ravel()
    mu = np.asarray(state.tensions, float).ravel()
    records = {k: np.array([summary[k]], dtype=float) for k in RECORD_KEYS
               if isinstance(summary.get(k), (int, float)) and not isinstance(summary[k], bool)}
    stability = state.stability
    eig = np.asarray(stability.eigenvalues, float)
    return Branch(
        name="ring", parent=None, origin=None, parameter="excess_link",
        parameter_values=np.array([state.excess_link], float), states=q[None, :],
        multipliers=mu[None, :], unstable_count=np.array([stability.unstable_count]),
        zero_modes=np.array([stability.zero_modes]),
        determinant_sign=np.array([stability.determinant_sign]),
        nearest_eigenvalue=np.array([eig[np.argmin(np.abs(eig))] if eig.size else math.nan]),
        tangents=np.zeros((1, q.size + mu.size + 1)), arclength=np.zeros(1),
        special_points=(),
        # the one point lies at the requested dLk: the parameter's bound is reached
        status=(ContinuationStatus.PARAMETER_BOUND if state.converged
                else ContinuationStatus.START_FAILED),
        message=f"one state (a single solve, not a continuation): {state.message}",
        records=records)


def ring_payload(summary: dict, curvature) -> dict:
    """``ring.json``'s payload: the summary, the curvature form and the one point, of the
    stored branch ``ring`` (the summary's own ``branch``, the route the solve took,
    ``circle`` or ``contact``, stays in its ``path``)."""
    return {**summary, "curvature_form": curvature, "branch": "ring",
            "points": [{**{k: v for k, v in summary.items() if not isinstance(v, dict)},
                        "branch": "ring", "index": 0}]}
