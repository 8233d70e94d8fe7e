"""Newton's method on the configuration manifold of a Cosserat rod.

Solves ``r(x, R) = gradient(x, R) - loads = 0`` on the free tangent DOFs, with the
update ``x <- x + alpha dx``, ``R <- exp(alpha hat(w)) R`` (:func:`~supercoil.cosserat.rod.retract`)
and the linear system ``K dv = -r`` of one of two tangents:

* ``"consistent"``: the linearisation ``K_c`` of the residual (nonsymmetric);
  Newton's quadratic convergence follows from it directly;
* ``"symmetric"``: its symmetric part ``H0`` (Chamekh, Mani-Aouadi & Moakher 2009,
  after Simo 1985). ``K_c - H0 = -blockdiag(hat(m_i)) / 2``, ``m_i`` the nodal moments
  of the internal forces; when the applied loads are conservative and carry no
  moment on the free nodes, ``m_i`` is part of the residual, so the error of the
  tangent is ``O(|r|)`` and the convergence stays quadratic (Crisfield 1990,
  "consistent linearization using projectors"). A dead moment on a free node in
  three dimensions (not conservative on SO(3), Argyris 1982) keeps ``m_i != 0`` at the
  solution: the error stays ``O(1)`` and the convergence becomes linear.

``loads`` ``(n_nodes, 6)`` are dead nodal forces and spatial moments. The step is
shortened by backtracking on the residual norm (sufficient decrease
``|r(alpha)| <= (1 - 1e-4 alpha) |r(0)|``), which serves both tangents and loads
without a potential (``line_search="monotone"``). A stiff rod (large EA, GA) defeats
any monotone test: the linear step from a straight rod bends it along a parabola whose
stretch energy grows as ``EA theta^4``, so the first full step raises the residual a
thousandfold although the next one converges (the cantilever rolled up by an end
moment, EA = GA = 1e4 A/L^2). The default ``"watchdog"`` (Chamberlain, Powell,
Lemarechal & Pedersen 1982) therefore takes a full step that does not decrease the
residual once, and goes back to backtrack from its start only if the following step
does not bring the residual below that start's.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse.linalg as spla

from supercoil.cosserat.rod import CosseratRod, retract
from supercoil.errors import InputError
from supercoil.solvers.newton import Status

TANGENTS = ("symmetric", "consistent")
LINE_SEARCHES = ("watchdog", "monotone", "none")


@dataclass(frozen=True)
class ManifoldNewtonOptions:
    """Options of :func:`solve_equilibrium`; validated on construction."""

    tangent: str = "symmetric"
    tolerance: float = 1e-10
    max_iterations: int = 50
    line_search: str = "watchdog"
    min_step: float = 1e-8

    def __post_init__(self) -> None:
        if self.tangent not in TANGENTS:
            raise InputError(f"tangent must be one of {TANGENTS}, got {self.tangent!r}")
        if not (self.tolerance > 0):
            raise InputError(f"tolerance must be positive, got {self.tolerance!r}")
        if self.line_search not in LINE_SEARCHES:
            raise InputError(f"line_search must be one of {LINE_SEARCHES}, got "
                             f"{self.line_search!r}")
        if not (isinstance(self.max_iterations, int) and self.max_iterations >= 1):
            raise InputError(f"max_iterations must be an integer >= 1, got "
                             f"{self.max_iterations!r}")


@dataclass(frozen=True)
class ManifoldNewtonResult:
    positions: np.ndarray  # (n_nodes, 3)
    rotations: np.ndarray  # (n_nodes, 3, 3)
    status: Status
    message: str
    iterations: int
    residual_history: tuple[float, ...] = field(default_factory=tuple)

    @property
    def converged(self) -> bool:
        return self.status.ok

    @property
    def convergence_orders(self) -> np.ndarray:
        """``log(r_{k+1} / r_k) / log(r_k / r_{k-1})`` along the iteration: 2 for quadratic,
        1 for linear convergence."""
        r = np.log(np.asarray(self.residual_history))
        return (r[2:] - r[1:-1]) / (r[1:-1] - r[:-2])


def residual(rod: CosseratRod, positions, rotations, loads) -> np.ndarray:
    """``gradient - loads``, ``(6 n_nodes,)``: out-of-balance forces and moments."""
    return rod.gradient(positions, rotations) - np.asarray(loads, dtype=float).ravel()


def solve_equilibrium(rod: CosseratRod, positions: np.ndarray, rotations: np.ndarray,
                      fixed=(), loads: np.ndarray | None = None,
                      options: ManifoldNewtonOptions | None = None) -> ManifoldNewtonResult:
    """Equilibrium from ``(positions, rotations)`` with the tangent DOFs ``fixed`` held
    (indices into the ``(6 n_nodes,)`` tangent vector) under dead ``loads``."""
    opts = options or ManifoldNewtonOptions()
    x = np.array(positions, dtype=float)
    R = np.array(rotations, dtype=float)
    loads = np.zeros(rod.n_dofs) if loads is None else np.asarray(loads, dtype=float).ravel()
    if loads.size != rod.n_dofs:
        raise InputError(f"loads must have {rod.n_dofs} entries (6 per node), got {loads.size}")
    free = np.setdiff1d(np.arange(rod.n_dofs), np.asarray(fixed, dtype=np.int64))
    history: list[float] = []

    def done(status, message, it):
        return ManifoldNewtonResult(x, R, status, message, it, tuple(history))

    def tangent(x, R):
        K = (rod.symmetric_tangent(x, R) if opts.tangent == "symmetric"
             else rod.consistent_tangent(x, R))
        return K[free][:, free].tocsc()

    def newton_step(K, r):
        dv = np.zeros(rod.n_dofs)
        dv[free] = spla.spsolve(K, -r)
        return dv

    r = residual(rod, x, R, loads)[free]
    # watchdog (Chamberlain, Powell, Lemarechal & Pedersen 1982): the reference state
    # from which a full step was taken without a decrease of the residual
    reference = None
    for it in range(opts.max_iterations + 1):
        if not np.all(np.isfinite(r)):
            return done(Status.NONFINITE, f"non-finite residual at iteration {it}", it)
        norm = float(np.linalg.norm(r))
        history.append(norm)
        largest = float(np.max(np.abs(r)))
        if largest <= opts.tolerance:
            return done(Status.CONVERGED, f"converged in {it} iterations", it)
        K = tangent(x, R)
        # forces of stiffness ||K|| are known to eps ||K|| |x| at best
        floor = np.finfo(float).eps * float(abs(K).sum(axis=1).max()) \
            * max(float(np.max(np.abs(x))), rod.length)
        if largest <= floor:
            return done(Status.ROUNDOFF_LIMITED,
                        f"converged to the round-off floor eps ||K|| |x| = {floor:.1e} in {it} "
                        f"iterations", it)
        if it == opts.max_iterations:
            break
        relaxed = False
        if reference is not None and reference[5]:
            # two steps since the reference: keep them if the residual fell below the
            # reference's, else go back there and backtrack along its step
            if norm <= (1 - 1e-4) * reference[3]:
                reference = None
            else:
                x, R, r, norm, dv, _ = reference
                reference = None
                alpha = 0.5
                relaxed = None
        elif reference is not None:
            reference = reference[:5] + (True,)
            relaxed = True  # the step after the relaxed one is taken in full
        if relaxed is not None:
            dv = newton_step(K, r)
            if not np.all(np.isfinite(dv)):
                return done(Status.SINGULAR, f"iteration {it}: singular tangent", it)
            alpha = 1.0
        while True:
            xt, Rt = retract(x, R, alpha * dv)
            rt = residual(rod, xt, Rt, loads)[free]
            finite = bool(np.all(np.isfinite(rt)))
            if finite and (opts.line_search == "none" or relaxed
                           or np.linalg.norm(rt) <= (1 - 1e-4 * alpha) * norm):
                break
            if (opts.line_search == "watchdog" and finite and alpha == 1.0
                    and reference is None):
                reference = (x, R, r, norm, dv, False)  # one more step decides
                break
            alpha *= 0.5
            if alpha < opts.min_step:
                return done(Status.LINE_SEARCH_FAILED,
                            f"iteration {it}: no step length reduced the residual "
                            f"({norm:.2e})", it)
        x, R, r = xt, Rt, rt
    return done(Status.MAX_ITERATIONS,
                f"no convergence in {opts.max_iterations} iterations (residual {history[-1]:.2e})",
                opts.max_iterations)


def clamp_dofs(n_nodes: int, node: int, positions: bool = True, rotations: bool = True,
               components=(0, 1, 2)) -> list[int]:
    """Tangent indices of ``node``'s position and/or spin ``components``."""
    node = node % n_nodes
    out = []
    if positions:
        out += [6 * node + c for c in components]
    if rotations:
        out += [6 * node + 3 + c for c in components]
    return out


def solve_incrementally(rod: CosseratRod, positions: np.ndarray, rotations: np.ndarray,
                        fixed=(), loads: np.ndarray | None = None,
                        options: ManifoldNewtonOptions | None = None,
                        first_fraction: float = 0.25, min_fraction: float = 1e-4
                        ) -> tuple[ManifoldNewtonResult, list[float]]:
    """Apply ``loads`` in increments, each solved by :func:`solve_equilibrium` from the
    last equilibrium (the incremental-iterative method of Simo & Vu-Quoc 1986).

    An increment that fails is halved (down to ``min_fraction`` of the load); one
    that converges in at most 4 iterations doubles the next. Returns the last result
    and the load fractions reached. By default each increment takes full Newton steps
    (``line_search="none"``): measured on the cantilever rolled up by an end moment
    (20 elements), that reached the full load in 4 to 16 increments for
    ``GA, EA`` from 3 to ``1e6 A/L^2``, where the watchdog needed up to 256 (the
    halving of the increment is the globalisation).
    """
    opts = options or ManifoldNewtonOptions(max_iterations=25, line_search="none")
    loads = np.zeros(rod.n_dofs) if loads is None else np.asarray(loads, dtype=float).ravel()
    x, R = np.array(positions, dtype=float), np.array(rotations, dtype=float)
    fraction, step = 0.0, float(first_fraction)
    reached = [0.0]
    result = None
    while fraction < 1.0:
        target = min(1.0, fraction + step)
        trial = solve_equilibrium(rod, x, R, fixed, target * loads, opts)
        if not trial.converged:
            step *= 0.5
            if step < min_fraction:
                return trial, reached
            continue
        result, fraction = trial, target
        x, R = trial.positions, trial.rotations
        reached.append(fraction)
        if trial.iterations <= 4:
            step *= 2.0
    if result is None:
        result = solve_equilibrium(rod, x, R, fixed, loads, opts)
    return result, reached
