"""The tweezers' rod problem and its first state; per-point records of its branches.

Per point the branches' ``records`` hold (docs/model.md, "Nondimensional
units" and "Contacts in the output"): ``turns``, ``extension`` (end-to-end
distance along the axis over L), ``torque`` (axial moment at the turned end,
``M L / A = 2 pi (C/A) Tw`` for the reduced twist), ``twist`` (excess twist
from the reference frames, turns), ``writhe`` (the double sum of the rod
closed by straight tails along the axis), ``closure_error`` = ``|Tw + Wr -
turns|`` (Fuller's closure; above 1/2 the rod has wrapped around a tail, or,
without self-contact, passed through itself: ``closure_failed``), ``energy``
(elastic only), ``load_potential`` (``-F z``, zero under displacement
control), ``tension`` (the axial force: the dead load, or the reaction at the
end under displacement control), ``azimuth_pin``, ``n_contact_points``,
``n_contact_intervals``, ``min_gap_over_diameter`` and ``sliding_residual`` (the KKT
residual without the continuation's phase rows: the force the sliding's phase row
holds, docs/continuation.md, "Long open rods"); the contact-free and contact
branches also record ``run_start``, the index of the first point of the continuation
run that computed the point (:class:`~supercoil.problems.segments.RunRecords`).
"""

from __future__ import annotations

import math

import numpy as np

from supercoil.contact.report import COUNT_KEYS, contact_summary
from supercoil.problems.ring_diagram.records import kkt_residual
from supercoil.problems.tweezers.options import TweezersOptions, segment_length
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.topology import writhe

TAIL_WRAP = 0.5  # |Tw + Wr - turns| above this: the closure failed (a tail or a self-crossing)


def clamped_problem(options: TweezersOptions) -> tuple[ClampedRodEnergy, np.ndarray]:
    """The rod problem at ``turns = start`` and its first state ``(n_nodes * 3,)``.

    Load control: the straight rod. Displacement control: the planar clamped
    Euler buckle at the end distance (module doc), before Newton.
    """
    opts = options
    rod = Rod(opts.n_nodes, twist_stiffness=opts.twist_ratio, closed=False)
    if opts.load_control:
        pts = straight_rod(opts.n_nodes)
        problem = ClampedRodEnergy(rod, pts, opts.turns[0], tension=opts.tension)
    else:
        pts = clamped_buckle(opts.n_nodes, opts.end_distance)
        problem = ClampedRodEnergy(rod, pts, opts.turns[0], end_distance_control=True)
    if not opts.loop_slides:
        problem.sliding_tail = None  # the sliding is never an approximate symmetry
    # with self-contact, the contact-free branches must not pass through the rod
    problem.impenetrable = opts.length_over_diameter is not None
    return problem, pts.ravel()


def clamped_buckle(n_nodes: int, end_distance: float) -> np.ndarray:
    """Planar clamped buckle ``(n_nodes, 3)`` in the x-z plane with the given end distance.

    Edges of exact length ``h = L/(n - 2)`` at tangent angles
    ``a sin(2 pi s)`` (``s`` the edge midpoints, so the first and last edges
    lie along the axis); ``a`` solves ``sum h cos(theta) = z`` (Brent). The
    shape is symmetric, so the far end lies on the axis.
    """
    from scipy.optimize import brentq

    h = segment_length(n_nodes)
    s = (np.arange(n_nodes - 1)) * h  # edge midpoints: edge k spans [(k - 1/2) h, (k + 1/2) h]

    def distance(a):
        return float(np.sum(h * np.cos(a * np.sin(2 * np.pi * s)))) - h - end_distance

    a = brentq(distance, 0.0, 2.4, xtol=1e-15)  # J0(2.4) ~ 0: below any z/L > 0 here
    theta = a * np.sin(2 * np.pi * s)
    steps = h * np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    pts = np.vstack([[0.0, 0.0, -0.5 * h], -0.5 * h * np.array([0, 0, 1.0]) + np.cumsum(
        steps, axis=0)])
    pts[[0, 1, -2, -1], 0] = 0.0  # round-off of the symmetric sum
    return pts


def tweezers_records(whole, rod: ClampedRodEnergy, contact: bool, probe=None):
    """Per-point records (module doc) for ``continuation(records=)``."""

    def records(q: np.ndarray, multipliers: np.ndarray, turns: float, problem=None) -> dict:
        # the problem at the point (the continuation's, with its frames), else this one
        # at the point's load
        point = whole.at(turns=float(turns)) if problem is None else problem
        rod_at = point if rod is whole else point.base
        x = q.reshape(-1, 3)
        wr = writhe(x, closure="axis", self_crossing="nan")
        tw = rod_at.twist(q)
        error = abs(tw + wr - turns)
        out = {"turns": float(turns), "extension": rod_at.extension(q),
               "torque": 2 * math.pi * rod_at.rod.twist_ratio * tw, "twist": tw, "writhe": wr,
               "closure_error": error,
               "closure_failed": bool(not error <= TAIL_WRAP),  # a crossing: NaN, failed
               "energy": rod_at.elastic_energy(q), "load_potential": rod_at.load_potential(q),
               "tension": axial_force(rod_at, multipliers),
               # the azimuth pin the point was computed with (a resumed run keeps it)
               "azimuth_pin": int(rod_at.gauge_dofs[0]) if rod_at.gauge_dofs.size == 1 else -1,
               "sliding_residual": kkt_residual(point, q, multipliers)}
        if contact:
            summary = contact_summary(point, q, multipliers, COUNT_KEYS)
            gap = summary["min_gap_over_diameter"]
            out.update(n_contact_points=summary["n_contact_points"],
                       n_contact_intervals=summary["n_contact_intervals"],
                       min_gap_over_diameter=float("inf") if gap is None else gap)
        else:
            gap = float("inf") if probe is None else probe.min_distance(q) / probe.diameter
            out.update(n_contact_points=0, n_contact_intervals=0,
                       min_gap_over_diameter=float(gap))
        return out

    return records


def axial_force(rod: ClampedRodEnergy, multipliers: np.ndarray) -> float:
    """The axial force at the turned end: the dead load, or the last edge's tension."""
    if not rod.end_distance_control:
        return float(rod.tension)
    mu = np.asarray(multipliers, dtype=float)
    return float(mu[rod.n_constraints - 1]) if mu.size >= rod.n_constraints else float("nan")
