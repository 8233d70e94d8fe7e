"""Starting a continuation at a singular point: a fold or a bifurcation point.

There the constrained Hessian is singular: the plain start of
:func:`~supercoil.continuation.continuation` (the point corrected at its
parameter value, its tangent bordered by ``e_lambda``) fails. :func:`start_branch`
tries the plain start and, when it fails without a point, starts again off the
point along its critical mode ``phi`` (the constrained Hessian's eigenvector
nearest zero there, :func:`~supercoil.continuation.stability.eigenpairs`):

1. on the hyperplane through the point orthogonal to ``phi`` (``guess``
   ``(phi, 0)``). At a fold the branch's tangent is ``phi`` and that bordered
   matrix is regular (Keller 1977): the start is the fold itself and the branch
   leaves it along ``+phi`` or ``-phi``, the two halves of the fold;
2. on the hyperplane at the distance of the first step (``initial_step``, the
   arclength metric) along ``+phi`` or ``-phi`` from it and orthogonal to
   ``phi``. At a simple bifurcation point the bordered matrix of 1. is singular
   too (the two branches' tangents span the kernel of ``[K, F_lambda]``); this
   hyperplane cuts the branch tangent to ``phi``, as a switch does
   (:func:`~supercoil.continuation.switch_branch`).

The start is taken as singular when the plain start fails without a point,
leaves the parameter bounds at once (fewer than two points: at a fold both halves
of the branch lie on one side of the start), or gives a tangent along which the
parameter does not change (``|dlambda|`` below :data:`FOLD_TANGENT` of the unit
tangent in the arclength metric; the plain tangent's orientation is then
arbitrary). The side tried first is ``+phi`` with ``direction`` +1, ``-phi`` with
-1, so that the two calls of a diagram that follows a start both ways take the
two sides; ``bounds`` widens the parameter bounds of the starts off the point
(both halves of a fold run to the same side of it). A note says which start was
used and why.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation.branch import Branch
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.pseudo_arclength import continuation
from supercoil.continuation.stability import eigenpairs
from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.newton import least_squares_multipliers
from supercoil.solvers.parameters import problem_at

# a plain start whose tangent changes the parameter by less than this (the parameter's
# part of the unit tangent, arclength metric) is at a fold: a fold located by the
# continuation lies within 1e-10 of the arclength from the exact one, its tangent's
# parameter part as small; elsewhere it is of order one
FOLD_TANGENT = 1e-6


def critical_mode(problem, q0: np.ndarray, parameter: str, start: float,
                  options: ContinuationOptions) -> tuple[float, np.ndarray] | None:
    """``(eigenvalue, mode)`` of the constrained Hessian at ``q0`` nearest zero (the mode on
    all DOFs, M-normalised), with the phase rows a run started there would have; None
    when none is found."""
    at = problem_at(problem, **{parameter: start})
    modes = branch_phase_modes(at, q0, options)
    system = ExtendedSystem(problem, parameter, q0, modes, q0, options.parameter_weight,
                            options.finite_difference_step)
    mu = least_squares_multipliers(at, q0, system.free)
    try:
        values, vectors = eigenpairs(system, system.pack(q0, mu, start), 2)
    except (SingularMatrixError, InertiaError, ValueError, np.linalg.LinAlgError):
        return None
    if values.size == 0:
        return None
    k = int(np.argmin(np.abs(values)))
    return float(values[k]), vectors[k]


def singular(branch: Branch, options: ContinuationOptions) -> bool:
    """Whether the plain start of ``branch`` was at a singular point (module doc)."""
    if len(branch) == 0:
        return branch.status is ContinuationStatus.START_FAILED
    if len(branch) < 2:  # left the bounds at once; a first step that failed is not this
        return branch.status is ContinuationStatus.PARAMETER_BOUND
    t = np.asarray(branch.tangents[0], dtype=float)
    return abs(t[-1]) * options.parameter_weight < FOLD_TANGENT


def start_branch(problem, q0: np.ndarray, multipliers0: np.ndarray | None = None, *,
                 parameter: str, start: float, options: ContinuationOptions,
                 bounds: tuple[float, float] | None = None,
                 **kwargs) -> tuple[Branch, str | None]:
    """``(branch, note)``: :func:`~supercoil.continuation.continuation` from ``q0`` at
    ``start``; if the start is singular (:func:`singular`), started again off the point
    along its critical mode (module doc), ``note`` saying so (None for the plain
    start). ``bounds``: the parameter bounds of the starts off the point (default
    ``options``'). ``kwargs`` go to ``continuation`` (records, events, on_point, stop,
    name, ...). The plain start is first tried with one step only (without ``on_point``)
    to tell. When every start off the point fails, that trial's branch and a note."""
    q0 = np.asarray(q0, dtype=float)
    quiet = {k: v for k, v in kwargs.items() if k != "on_point"}
    plain = continuation(problem, q0, multipliers0, parameter=parameter,
                         options=dataclasses.replace(options, max_points=2), start=start,
                         **quiet)  # the start and one step, to tell
    if not singular(plain, options):
        return continuation(problem, q0, multipliers0, parameter=parameter, options=options,
                            start=start, **kwargs), None
    found = critical_mode(problem, q0, parameter, start, options)
    if found is None:
        return plain, (f"the start at {parameter} = {start:.6g} failed ({plain.message}) and "
                       "no critical mode was found there")
    value, mode = found
    mass = np.asarray(problem.mass, dtype=float)
    size = float(np.sqrt(mode @ (mass * mode)))
    phi = mode / size if size > 0 else mode
    m = int(problem.n_constraints)
    first = 1.0 if options.direction >= 0 else -1.0
    off = options if bounds is None else dataclasses.replace(options, parameter_bounds=bounds)
    for offset in (0.0, options.initial_step):
        for sign in (first, -first):
            guess = np.concatenate([sign * phi, np.zeros(m), [0.0]])
            branch = continuation(problem, q0 + offset * sign * phi, None, parameter=parameter,
                                  options=off, start=start, guess=guess, **kwargs)
            if len(branch) >= 2:
                where = ("on the hyperplane through it orthogonal to its critical mode (a "
                         "fold's tangent)" if offset == 0.0 else
                         f"{offset:.3g} along its critical mode (arclength metric), on the "
                         "hyperplane orthogonal to it")
                return branch, (f"the start at {parameter} = {start:.6g} is a singular point "
                                f"(the plain start: {plain.message}; the constrained "
                                f"Hessian's eigenvalue nearest zero is {value:.3g}): started "
                                f"{where}, side {'+' if sign > 0 else '-'}")
    return plain, (f"the start at {parameter} = {start:.6g} failed ({plain.message}); "
                   f"starts off it along its critical mode (eigenvalue {value:.3g}) failed "
                   "too")
