"""Phase conditions of a branch: which rows fix its symmetries, and moving them.

A problem with continuous symmetries (a closed rod's rotations and material
sliding) has a family of equilibria at every parameter value; continuation
follows one member by adding phase rows to the extended system (Doedel's
integral phase condition ``<M g, q - q_0> = 0``, or a node gauge). The rows are
chosen at the start of a branch (:func:`branch_phase_modes`), may be moved to
those of the last point when a step fails (:func:`regauged`, the ``regauge``
option) and are re-anchored at every point (:func:`rephased_tangent`, the
``rephase`` option).
"""

from __future__ import annotations

import numpy as np

from supercoil.continuation.bordered import BorderedFactor
from supercoil.continuation.corrector import correct, tangent
from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.errors import SingularMatrixError
from supercoil.solvers.problem import ConstrainedEnergy
from supercoil.stability.analysis import (
    goldstone_modes,
    near_symmetry_gauge,
    sliding_phase_modes,
)


def branch_phase_modes(problem: ConstrainedEnergy, q: np.ndarray,
                       options: ContinuationOptions) -> np.ndarray | None:
    """Phase-condition modes of a branch started at ``q`` (None when there are none).

    ``phase_conditions``: the symmetry modes (:func:`phase_modes`).
    ``near_symmetry_gauge``: one row per approximate symmetry that is not a
    combination of the exact ones at ``q`` (a closed rod's material sliding
    off the circle): with ``gauge="node"`` a unit row on the DOF of
    :func:`~supercoil.stability.analysis.near_symmetry_gauge` (``q_i =
    q_i(start)``), with ``gauge="integral"`` the mode itself, M-orthogonal to
    the exact symmetries (:func:`~supercoil.stability.analysis.sliding_phase_modes`;
    the condition ``<M g, q - q_start> = 0``). Either keeps Newton and the tangent off the
    nearly singular direction; its multiplier is the small force that the
    discretisation's ripple exerts along the sliding, which the stored
    points' residual (without it) shows.
    """
    rows = []
    if options.phase_conditions:
        rows.append(phase_modes(problem, q))
    if options.near_symmetry_gauge and options.gauge == "integral":
        modes = sliding_phase_modes(problem, q)
        if modes.size:
            rows.append(modes / np.linalg.norm(modes, axis=1, keepdims=True))
    elif options.near_symmetry_gauge:
        dofs = near_symmetry_gauge(problem, q)
        gauge = np.zeros((dofs.size, problem.n_dofs))
        gauge[np.arange(dofs.size), dofs] = 1.0 / np.asarray(problem.mass, float)[dofs]
        rows.append(gauge)
    modes = np.vstack(rows) if rows else np.zeros((0, problem.n_dofs))
    return modes if modes.shape[0] else None


def phase_modes(problem: ConstrainedEnergy, q: np.ndarray, relative: float = 1e-8) -> np.ndarray:
    """The problem's symmetry modes at ``q`` that do not vanish there, ``(r, n_dofs)``."""
    getter = getattr(problem, "symmetry_modes", None)
    if getter is None:
        return np.zeros((0, problem.n_dofs))
    modes = np.atleast_2d(np.asarray(getter(q), dtype=float))
    if modes.size == 0:
        return np.zeros((0, problem.n_dofs))
    scale = max(1.0, float(np.max(np.abs(q))))
    norms = np.linalg.norm(modes, axis=1)
    return modes[norms > relative * scale]


def regauged(system: ExtendedSystem, opts: ContinuationOptions, x: np.ndarray,
             t_old: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Move the phase rows to those :func:`branch_phase_modes` gives at the point ``x``
    (re-anchored there), correct ``x`` in the new gauge at its parameter value and
    recompute its tangent (oriented along ``t_old``): ``(x, t)`` in the new gauge, or
    None (gauge unchanged) if the rows are the same or the correction fails.

    ``x`` is an equilibrium of the old gauge: the new row's reaction differs (the
    discretisation's force along the sliding moves from one node or mode to another),
    so the state moves a little. A step from the uncorrected point could not
    converge, however short."""
    q = system.q(x)
    modes = branch_phase_modes(system.problem_at(x[-1]), q, opts)
    if modes is None or modes.shape != system.phase_modes.shape:
        return None
    if opts.gauge == "node" and np.array_equal(modes != 0, system.phase_modes != 0):
        return None
    if opts.gauge == "integral" and np.allclose(modes, system.phase_modes, rtol=0,
                                                atol=1e-12):
        return None
    old = (system.phase_modes, system.q_phase_full)
    system.set_phase(modes, q)
    e_lam = np.zeros(system.size)
    e_lam[-1] = 1.0
    corr = correct(system, x, e_lam, x, 0.0, opts.tolerance,
                   4 * opts.max_corrector_iterations)
    try:
        if not corr.ok:
            raise SingularMatrixError(corr.message)
        t = tangent(system, corr.x, orientation(system, corr.x, t_old))
    except SingularMatrixError:
        system.set_phase(*old)
        return None
    return corr.x, t


def rephased_tangent(system: ExtendedSystem, opts: ContinuationOptions, x: np.ndarray,
                     t_old: np.ndarray, full_hessian=None,
                     factor: BorderedFactor | None = None) -> np.ndarray | None:
    """Re-anchor the integral phase condition at the point ``x`` (``rephase``) and return
    its tangent in the new gauge, oriented along ``t_old`` (None: the rows keep their
    shape, nothing done).

    The point satisfies the new condition (``q - q_k = 0``); only its tangent is
    recomputed. ``full_hessian``: the Hessian on all DOFs at ``x`` if known. ``factor``: the
    bordered factor of the step's corrector (``ContinuationOptions.factor_refinement``):
    the tangent is then solved by iterative refinement with it, under its own border
    row (the kernel of ``[K, F_lambda]`` is one direction, whichever row normalises
    it), and oriented by the sign of its product with the orientation row; a new
    factor only when refinement does not converge.
    """
    q = system.q(x)
    modes = branch_phase_modes(system.problem_at(x[-1]), q, opts)
    if modes is None or modes.shape != system.phase_modes.shape:
        return None
    system.set_phase(modes, q)
    hessian = None if full_hessian is None else full_hessian.restrict(system.free)
    row = orientation(system, x, t_old)
    if factor is not None and hessian is not None:
        e_last = np.zeros(system.size)
        e_last[-1] = 1.0
        z = factor.refined_solve(hessian, system.jacobian_arrays(x),
                                 system.parameter_derivative(x), factor.row, e_last)
        if z is not None and np.all(np.isfinite(z)) and z @ row != 0.0:
            return np.sign(z @ row) * z / system.norm(z)
    return tangent(system, x, row, hessian)


def orientation(system: ExtendedSystem, x: np.ndarray, t_old: np.ndarray) -> np.ndarray:
    """The row that orients a tangent recomputed in a new gauge: ``W t_old`` with the
    approximate-symmetry motions (:func:`~supercoil.stability.analysis.goldstone_modes`
    at ``x``) projected out of its state part (M-orthogonally).

    Each gauge adds to the tangent the slide that keeps its own condition, so
    the two tangents can disagree along the slide while they agree on the
    rest: measured on the ring's alpha branch (N = 200, integral contact, node
    gauge, dLk 4.069), the plain product oriented the new tangent with dLk
    decreasing, and the branch turned back at a spurious fold, then snaked.
    """
    v = np.array(t_old, dtype=float)
    modes = goldstone_modes(system.problem_at(x[-1]), system.q(x))
    if modes.size:
        g = modes[:, system.free]
        mass = system.weights[:system.n]
        gram = (g * mass) @ g.T
        v[:system.n] -= g.T @ np.linalg.solve(gram, (g * mass) @ v[:system.n])
    return system.weights * v
