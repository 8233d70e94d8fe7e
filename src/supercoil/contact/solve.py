"""Equilibria with self-contact: the four treatments behind one call.

* ``barrier``: one Newton minimisation of ``E + sum psi``.
* ``penalty``: Newton minimisations of ``E + sum psi``, the stiffness raised
  between them until the largest penetration is below ``penalty_tolerance * D``
  (Chamekh, Mani-Aouadi & Moakher 2009): a pair carries its force ``F`` through
  the penetration ``F / k``, so at the reached forces the stiffness is multiplied
  by twice the ratio of penetration to tolerance (between 2 and
  ``PENALTY_GROWTH``), at most to ``MAX_PENALTY`` times its default.
* ``augmented``: Newton on the augmented Lagrangian, then the multiplier
  update ``lam <- max(lam - k g, 0)``, repeated until the largest
  penetration is below ``penetration_tolerance * D`` (the scheme of
  Chamekh, Mani-Aouadi & Moakher 2014 with a finite penalty; the penalty
  grows tenfold, at most to 1000 times its default, whenever an update
  fails to cut the penetration fourfold).
* ``exact``: an active-set method on the inequality constraints ``g >= 0``.
  The augmented-Lagrangian solution gives the first active set (or the
  previous solve's active set when there is one): a maximal set of its
  touching pairs with linearly independent gap gradients (greedy Gram–Schmidt,
  strongest force first; along a line contact the pairs' gradients are
  dependent and LICQ fails). Newton in stationary mode then solves the
  equality-constrained problem exactly (the multipliers are minus the
  contact forces); the contact that pulls hardest is released, pairs that
  penetrate are added, and the solve is repeated until the forces are
  non-negative and nothing penetrates. An active set that repeats stops the
  loop; the augmented-Lagrangian state is then returned, not converged.

Every step of every Newton iteration is bounded by continuous collision
detection (:meth:`ContactProblem.step_bound`), so segments never pass
through each other. The result says whether the state is admissible (gap
within tolerance) and the solve converged; nothing is returned silently.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil.contact import potentials
from supercoil.contact.problem import ContactProblem
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.solvers.problem import free_dofs

log = logging.getLogger(__name__)

PENALTY_GROWTH = 100.0  # largest factor of one raise of the penalty stiffness
MAX_PENALTY = 1e6  # largest penalty stiffness over its default


@dataclass(frozen=True)
class ContactSolveResult:
    q: np.ndarray
    multipliers: np.ndarray
    converged: bool
    admissible: bool  # no penetration beyond the tolerance, forces >= 0
    status: str
    message: str
    newton_iterations: int
    outer_iterations: int
    residual: float
    max_penetration_over_diameter: float  # max(0, 1 - d_min / D)


def max_penetration(problem: ContactProblem, q: np.ndarray) -> float:
    """``max(0, 1 - d_min / D)`` over non-neighbour segment pairs."""
    st = problem.pair_state(q, problem.diameter)
    if len(st.pairs) == 0:
        return 0.0
    return float(max(0.0, 1.0 - st.distance.min() / problem.diameter))


def _feature_keys(problem: ContactProblem, pairs, s, t, eps: float = 1e-9):
    """Closest-feature key of each pair: a node when the closest point is an end."""
    keys = []
    for (i, j), si, tj in zip(pairs, s, t):
        def feature(seg, u):
            if u <= eps:
                return ("node", int(problem.segments[seg, 0]))
            if u >= 1 - eps:
                return ("node", int(problem.segments[seg, 1]))
            return ("edge", int(seg))
        keys.append(tuple(sorted((feature(i, si), feature(j, tj)))))
    return keys


def solve_contact(problem: ContactProblem, q0: np.ndarray,
                  options: NewtonOptions | None = None) -> ContactSolveResult:
    """Equilibrium of ``problem`` (a :class:`ContactProblem`) from ``q0``."""
    opts = options or NewtonOptions(mode="minimize", max_iterations=200)
    if opts.mode == "minimize" and opts.inertia_test is None:
        # the exact inertia costs a block factorisation per iteration; the
        # final state's stability is analysed separately anyway
        opts = dataclasses.replace(opts, inertia_test="curvature")
    treatment = problem.treatment
    d0 = problem.min_distance(q0)
    if treatment == "barrier" and not d0 > problem.diameter:
        return _result(problem, q0, np.zeros(problem.n_constraints), False, "inadmissible start",
                       f"the initial state touches or penetrates (d_min/D = "
                       f"{d0 / problem.diameter:.6f}); the barrier needs a gap", 0, 0, np.nan)
    if treatment == "barrier":
        res = newton(problem, q0, opts)
        return _finish(problem, res, 1, "")
    if treatment == "penalty":
        return _penalty(problem, q0, opts)
    if treatment == "augmented":
        return _augmented(problem, q0, opts)
    return _exact(problem, q0, opts)


def _result(problem, q, lam, converged, status, message, its, outer, residual):
    pen = max_penetration(problem, q)
    admissible = pen <= problem.options.tolerance
    return ContactSolveResult(q, lam, converged, admissible, status, message, its, outer,
                              residual, pen)


def _finish(problem, res, outer, extra):
    pen = max_penetration(problem, res.q)
    tol = problem.options.tolerance
    message = res.message + extra
    admissible = pen <= tol
    if not admissible:
        message += (f"; warning: penetration {pen:.2e} D exceeds the tolerance {tol:.0e} D"
                    + (" (the penalty reached its largest stiffness: use 'augmented')"
                       if problem.treatment == "penalty" else ""))
    return ContactSolveResult(res.q, res.multipliers, res.converged, admissible,
                              res.status.value, message, res.iterations, outer, res.residual, pen)


def _penalty(problem: ContactProblem, q0, opts):
    """The penalty raised until the penetration is within tolerance (module docstring)."""
    tol = problem.options.tolerance
    k0 = problem.default_stiffness
    q, total, pen = np.asarray(q0, float), 0, np.inf
    for outer in range(1, problem.options.max_outer_iterations + 1):
        res = newton(problem, q, opts)
        total += res.iterations
        if not res.converged:
            return dataclasses.replace(
                _finish(problem, res, outer, f" (penalty {problem.stiffness / k0:g} x the "
                        f"default, solve {outer})"), newton_iterations=total)
        q, pen = res.q, max_penetration(problem, res.q)
        if pen <= tol or problem.stiffness >= MAX_PENALTY * k0:
            break
        factor = min(max(2.0 * pen / tol, 2.0), PENALTY_GROWTH)
        problem.stiffness = min(problem.stiffness * factor, MAX_PENALTY * k0)
        problem.invalidate()
        log.debug("penalty: penetration %.3g D, stiffness raised to %.3g x the default",
                  pen, problem.stiffness / k0)
    extra = (f"; penalty {problem.stiffness / k0:g} x the default after {outer} solve(s): "
             f"penetration {pen:.2e} D (tolerance {tol:.0e} D)")
    return dataclasses.replace(_finish(problem, res, outer, extra), newton_iterations=total)


def _augmented(problem: ContactProblem, q0, opts, max_outer=None):
    tol = problem.options.penetration_tolerance
    D = problem.diameter
    q, lam = np.asarray(q0, float), None
    total = 0
    max_outer = max_outer or problem.options.max_outer_iterations
    res = None
    k0, pen_prev = problem.default_stiffness, np.inf
    # The multipliers belong to segment pairs: on a closed rod, sliding the
    # material along itself (nearly free) would carry the contacts away from
    # them, so the outer iterations run with the sliding gauge and the last
    # ones without it (the gauge's reaction must vanish at an equilibrium).
    pinned = problem.closed and problem._slide_pin is None
    if pinned:
        problem.pin_sliding(q)
    for outer in range(1, max_outer + 1):
        if lam is not None and len(lam) != problem.n_constraints:
            lam = None  # the gauge was released: fresh least-squares multipliers
        res = newton(problem, q, opts, multipliers=lam)
        total += res.iterations
        q, lam = res.q, res.multipliers
        if not res.converged:
            if problem._slide_pin is not None:  # a failed state is not held by the gauge either
                problem.release_sliding()
            return _finish(problem, res, outer, f" (augmented Lagrangian, outer iteration {outer})")
        st = problem.pair_state(q, problem._cutoff())
        gap = st.distance - D
        old = problem._multipliers_of(st.pairs)
        new = potentials.augmented_update(gap, old, problem.stiffness)
        problem.pair_multipliers = {(int(i), int(j)): float(f)
                                    for (i, j), f in zip(st.pairs, new) if f > 0}
        problem.invalidate()  # the multipliers set the reach of the pair data
        pen = max(0.0, -float(gap.min()) / D) if gap.size else 0.0
        if pen <= tol and problem._slide_pin is None:
            break
        if pen <= 10 * tol and problem._slide_pin is not None:
            problem.release_sliding()
            continue
        # Penalty growth (Conn, Gould & Toint 1991; Bertsekas 1982): when an
        # update did not cut the penetration fourfold, the rod is stiffer than
        # the penalty at the contacts and first-order updates crawl.
        if pen > 0.25 * pen_prev and problem.stiffness < 1e3 * k0:
            problem.stiffness *= 10.0
            problem.invalidate()
        pen_prev = pen
    if problem._slide_pin is not None:  # never return a state held by the gauge
        problem.release_sliding()
        res = newton(problem, q, opts)
        total += res.iterations
    extra = (f"; augmented Lagrangian: {outer} outer iterations, {total} Newton iterations, "
             f"penalty {problem.stiffness / k0:g} x the default")
    return dataclasses.replace(_finish(problem, res, outer, extra), newton_iterations=total)


def _exact(problem: ContactProblem, q0, opts):
    """Active-set solve of the inequality-constrained problem (see module docstring)."""
    stationary = dataclasses.replace(opts, mode="stationary")
    if len(problem.active):
        # A neighbouring solve left its active set (continuation, a small load
        # step): start the active-set loop from it; a contact that releases or
        # forms on the way is handled by the loop. Start over if that fails.
        out = _active_set_loop(problem, np.asarray(q0, float), problem.active, None,
                               stationary, 0, 0, max_cycles=3)
        if out.converged and out.admissible:
            return dataclasses.replace(out, message=out.message + " (from the previous "
                                       "active set)")
        problem.active = np.zeros((0, 2), dtype=np.int64)
    # The augmented-Lagrangian warm start keeps its multipliers (and penalty)
    # from the previous solve of this problem: from a nearby state it then
    # needs one or two outer iterations.
    warm = problem.__dict__.get("_warm")
    if warm is None or warm.base is not problem.base:
        warm = ContactProblem(problem.base, dataclasses.replace(problem.options,
                                                                 treatment="augmented"))
        problem.__dict__["_warm"] = warm
    warm.invalidate()
    start = _augmented(warm, q0, opts)
    if not start.converged:
        return dataclasses.replace(start, message="warm start failed: " + start.message)
    st, force = warm.pair_forces(start.q)
    active, forces = independent_pairs(problem, start.q, st.pairs, force)
    lam = np.concatenate([start.multipliers[: problem.n_equalities], -forces])
    # a polish from next to the solution
    out = _active_set_loop(problem, start.q, active, lam, stationary, start.newton_iterations,
                           start.outer_iterations, problem.options.max_outer_iterations)
    if out.converged and out.admissible:
        return out
    if start.admissible:
        # The polish failed (its active set cycled or Newton stopped): return
        # the augmented-Lagrangian state (an equilibrium within the penetration
        # tolerance), not converged for this treatment, saying so.
        problem.active = np.zeros((0, 2), dtype=np.int64)
        return dataclasses.replace(
            start, converged=False, status="exact polish failed",
            message=start.message + "; exact contact: the active-set polish did not settle ("
            + out.message + "); the state is the augmented-Lagrangian solution (use "
            "--contact augmented for it)")
    return out


def _active_set_loop(problem: ContactProblem, q, active, lam, opts, total, outer, max_cycles):
    """Newton on the active contacts; release negative forces, add penetrating pairs; repeat."""
    D = problem.diameter
    tol = problem.options.penetration_tolerance
    m0 = problem.n_equalities
    scale = max(float(np.max(np.abs(lam))) if lam is not None and lam.size else 1.0, 1.0)
    res = None
    seen: set[frozenset] = set()
    for cycle in range(1, max_cycles + 1):
        key = frozenset(map(tuple, np.asarray(active).tolist()))
        if key in seen:  # the active set cycles: stop (the caller falls back)
            problem.active = active
            return _result(problem, q, lam, False, "active set cycled",
                           f"exact contact: the active set returned to an earlier one after "
                           f"{cycle - 1} cycles", total, outer + cycle, res.residual)
        seen.add(key)
        problem.active = active
        problem.invalidate()
        if lam is not None and len(lam) != problem.n_constraints:
            lam = None
        res = newton(problem, q, opts, multipliers=lam)
        total += res.iterations
        if not res.converged:
            return _finish(problem, res, outer + cycle, f" (exact contact, active-set cycle {cycle})")
        q, lam = res.q, res.multipliers
        scale = max(scale, float(np.max(np.abs(lam))) if lam.size else 1.0)
        contact_force = -lam[m0:]
        changed = False
        if contact_force.size and contact_force.min() < -problem.options.force_tolerance * scale:
            # release the contact that pulls hardest, one at a time (releasing
            # all at once was measured to cycle)
            keep = np.ones(len(active), dtype=bool)
            keep[int(np.argmin(contact_force))] = False
            active, lam = active[keep], np.concatenate([lam[:m0], lam[m0:][keep]])
            changed = True
        st = problem.pair_state(q, D * (1 - tol))
        if len(st.pairs):
            have = {tuple(p) for p in active.tolist()}
            new_keys = set(_feature_keys(problem, *_params(problem, q, active)))
            add = []
            for pair, key in zip(st.pairs, _feature_keys(problem, st.pairs, st.s, st.t)):
                if tuple(pair) not in have and key not in new_keys:
                    add.append(pair)
                    new_keys.add(key)
            if add:
                grown = np.concatenate([active, np.array(add, dtype=np.int64)])
                kept, _ = independent_pairs(problem, q, grown,
                                             np.concatenate([-lam[m0:], np.zeros(len(add))]))
                if len(kept) > len(active):
                    old_lam = {tuple(p): v for p, v in zip(active.tolist(), lam[m0:])}
                    active = kept
                    lam = np.concatenate([lam[:m0], [old_lam.get(tuple(p), 0.0)
                                                     for p in kept.tolist()]])
                    changed = True
        log.debug("active-set cycle %d: %d active, min force %.3g, %d penetrating, changed %s",
                  cycle, len(active), float(contact_force.min()) if contact_force.size else 0.0,
                  len(st.pairs), changed)
        if not changed:
            break
    else:
        problem.active = active
        return _result(problem, q, lam, False, "active set did not settle",
                       f"exact contact: the active set changed in each of {max_cycles} cycles",
                       total, outer + max_cycles, res.residual)
    problem.active = active
    problem.invalidate()
    message = res.message + f"; exact contact: {len(active)} active constraints, {cycle} cycles"
    out = _finish(problem, res, outer + cycle, "")
    return dataclasses.replace(out, message=message + out.message[len(res.message):],
                               newton_iterations=total)


def independent_pairs(problem: ContactProblem, q, pairs, force, rtol: float = 1e-3):
    """A maximal set of ``pairs`` with linearly independent constraint gradients.

    Along a line contact every segment touches two or three segments of the
    other strand, and the gradients of those pairs' gaps are (nearly)
    dependent: constraining all of them makes the KKT matrix singular (LICQ
    fails and the forces are not unique). Greedy Gram–Schmidt of the gradients
    on the free DOFs near the contacts (after removing what the rod's own
    constraints fix), strongest force first, keeps a maximal independent
    subset (a gradient is kept when more than ``rtol`` of its norm is new);
    holding those at zero gap holds the others to first order. Returns
    ``(pairs, forces)``.
    """
    if len(pairs) == 0:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    order = np.argsort(-np.asarray(force), kind="stable")
    pairs, force = np.asarray(pairs)[order], np.asarray(force)[order]
    _d, grad, _hess, dofs = problem._pair_derivatives(q, pairs)
    # Work on the DOFs near the contacts only (cost independent of N): the
    # free DOFs of the pair nodes and of the rod constraints touching them.
    free = np.zeros(problem.n_dofs, dtype=bool)
    free[free_dofs(problem)] = True
    near = np.zeros(problem.n_dofs, dtype=bool)
    near[dofs.ravel()] = True
    J = (problem.base.constraint_jacobian(q).tocsr() if problem.base.n_constraints
         else sp.csr_matrix((0, problem.n_dofs)))
    rows = np.unique(J[:, near].nonzero()[0]) if J.shape[0] else np.zeros(0, dtype=np.int64)
    if len(rows):
        near[J[rows].nonzero()[1]] = True
    local = np.flatnonzero(near & free)
    index = np.full(problem.n_dofs, -1)
    index[local] = np.arange(len(local))
    G = np.zeros((len(local), len(pairs)))
    cols = np.repeat(np.arange(len(pairs))[:, None], dofs.shape[1], axis=1)
    inside = index[dofs] >= 0
    np.add.at(G, (index[dofs][inside], cols[inside]), grad[inside])
    # the rod's own constraints come first: contact gradients are judged
    # relative to what inextensibility already fixes
    Jl = J[rows][:, local].toarray() if len(rows) else np.zeros((0, len(local)))
    basis = np.linalg.qr(Jl.T)[0] if len(Jl) else np.zeros((len(local), 0))
    G = G - basis @ (basis.T @ G)
    keep = []
    for k in range(G.shape[1]):  # greedy Gram–Schmidt in force order
        v = G[:, k].copy()
        for u in keep:
            v -= (G[:, u] @ v) * G[:, u]
        norm = np.linalg.norm(v)
        if norm > rtol * max(np.linalg.norm(G[:, k]), 1e-300):
            G[:, k] = v / norm
            keep.append(k)
    return pairs[keep].astype(np.int64), force[keep]


def _params(problem, q, pairs):
    """``(pairs, s, t)``: closest parameters of the pairs at ``q`` on the contact curve."""
    _d, s, t = problem.pair_distances(q, pairs)
    return pairs, s, t


def solved_contact_report(problem, res: ContactSolveResult, note: str):
    """``(contact, message, converged)`` of a relaxed contact state ``res``: the
    contact summary (:func:`supercoil.contact.report.contact_summary`) with the
    largest penetration and its tolerance, ``note`` and the solver's message with
    warnings for negative contact forces and an inadmissible state, and whether the
    state is an admissible equilibrium (converged, admissible, no negative force)."""
    from supercoil.contact.report import contact_summary

    contact = contact_summary(problem, res.q, res.multipliers)
    contact.update(max_penetration_over_diameter=max_penetration(problem, res.q),
                   penetration_tolerance=problem.options.tolerance)
    message = note + "; " + res.message
    if contact["negative_contact_forces"]:
        message += (f"; warning: {contact['negative_contact_forces']} contact force(s) are "
                    "negative: not an admissible equilibrium")
    if not res.admissible:
        message += "; warning: the state is not admissible (penetration beyond tolerance)"
    converged = bool(res.converged and res.admissible and not contact["negative_contact_forces"])
    return contact, message, converged
