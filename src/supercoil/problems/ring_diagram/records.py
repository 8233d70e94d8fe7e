"""Per-point records of the ring diagram's branches.

Per point the branches' ``records`` hold ``excess_link``, ``writhe`` (double
sum), ``twist`` (material frames), ``energy`` (elastic only), ``link_error``
= ``|Tw + Wr - dLk|`` (:func:`~supercoil.problems.ring_branches.ring_records`),
``n_contact_points``, ``n_contact_intervals`` and ``min_gap_over_diameter``,
and on contact branches ``sliding_residual`` (:func:`kkt_residual`); the
contact lists with positions are recomputed from the stored states by
:meth:`~supercoil.problems.ring_diagram.RingDiagram.points`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.contact.report import COUNT_KEYS, contact_summary
from supercoil.continuation import Branch
from supercoil.continuation.carry import branch_frames
from supercoil.solvers.csr import transpose_matvec
from supercoil.solvers.problem import free_dofs


def contact_records(contact: ContactProblem, base_records, free: bool):
    """Per-point records: the ring's plus the contact counts and the closest approach
    (``contact``'s, a probe on a contact-free branch)."""

    def records(q, multipliers, excess_link, problem=None):
        # the contact problem at the point (the continuation's), else this one there
        # the problem at the point (the continuation's: the contact problem, or the rod on
        # a contact-free branch), else this one there
        if problem is None:
            problem = contact.at(excess_link=excess_link)
            problem = problem.base if free else problem
        out = dict(base_records(q, multipliers, excess_link,
                                problem=getattr(problem, "base", problem)))
        if free:
            d_min = contact.min_distance(q)
            out.update(n_contact_points=0, n_contact_intervals=0,
                       min_gap_over_diameter=float(d_min / contact.diameter))
        else:
            summary = contact_summary(problem, q, multipliers, COUNT_KEYS)
            gap = summary["min_gap_over_diameter"]
            out.update(n_contact_points=summary["n_contact_points"],
                       n_contact_intervals=summary["n_contact_intervals"],
                       min_gap_over_diameter=float("inf") if gap is None else gap,
                       sliding_residual=kkt_residual(problem, q, multipliers))
        return out

    return records


def kkt_residual(problem, q: np.ndarray, multipliers: np.ndarray) -> float:
    """``max |grad E + J^T mu|, |c|`` on the free DOFs, without any continuation gauge.

    On a contact branch followed with the material sliding pinned this is the
    sliding force that the pin holds (:mod:`~supercoil.problems.ring_diagram.contact_branches`,
    "Material sliding").
    """
    free = free_dofs(problem)
    g = problem.gradient(q)
    if problem.n_constraints:
        g = g + transpose_matvec(problem.constraint_jacobian(q), multipliers)
        c = np.abs(problem.constraints(q))
    else:
        c = np.zeros(0)
    return float(max(np.max(np.abs(g[free]), initial=0.0), np.max(c, initial=0.0)))


def with_records(branch: Branch, problem, records) -> Branch:
    """The branch with its records recomputed by ``records``, given the problem at each
    point (the branch's frames, :mod:`supercoil.continuation.carry`; ``problem``
    unchanged)."""
    rows = []
    frames = branch_frames(problem, branch)
    for q, mu, lam, carried in zip(branch.states, branch.multipliers, branch.parameter_values,
                                   frames):
        point = problem.with_frames(carried).at(excess_link=float(lam))
        rows.append(records(q, mu, float(lam), problem=point))
    merged = {k: np.array([r[k] for r in rows]) for k in rows[0]} if rows else {}
    return dataclasses.replace(branch, records=merged)
