"""Continuation of any energy: the generic layer under the rod problems, for a user's model.

:class:`Energy` describes an energy ``E(q; lambda)`` by its callables (value, gradient,
Hessian, optional equality constraints); :func:`continuation` follows its equilibria
in ``lambda`` with the same pseudo-arclength predictor-corrector, stability (the
inertia of the KKT matrix) and events (folds, bifurcations) as the rod problems
(Keller 1977; Allgower & Georg 1990), and :func:`switch_branch` leaves a branch at
a bifurcation along its critical mode (Seydel 2010).

The parameter is an explicit argument: each call builds its own numerical problem,
so a branch depends only on the arguments of the call that computed it.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil.continuation import Branch, ContinuationOptions, SpecialPoint
from supercoil.continuation import continuation as follow
from supercoil.continuation import switch_branch as switch
from supercoil.errors import InputError
from supercoil.solvers.carried import Carried
from supercoil.solvers.parameters import Parametrised, problem_at
from supercoil.solvers.problem import HessianParts

Array = np.ndarray


@dataclass(frozen=True, eq=False)
class Energy:
    """An energy ``E(q; lambda)`` of ``n_dofs`` unknowns, to be made stationary.

    ``energy(q, lam) -> float``, ``gradient(q, lam) -> (n_dofs,)``,
    ``hessian(q, lam) -> (n_dofs, n_dofs)`` (dense or scipy sparse, symmetric).
    ``fixed``: indices of unknowns held at their starting values. ``mass`` (n_dofs,):
    the positive metric of arclength and eigenvalues (default ones). Optional
    equality constraints ``c(q) = 0`` of ``n_constraints`` rows:
    ``constraints(q) -> (m,)``, ``constraint_jacobian(q) -> (m, n_dofs)`` and
    ``constraint_hessian(q, mu) -> sum_k mu_k d^2 c_k / dq^2``.
    ``parameter_gradient(q, lam) -> d gradient / d lam`` (default: central
    differences of the gradient).
    """

    energy: Callable[[Array, float], float]
    gradient: Callable[[Array, float], Array]
    hessian: Callable[[Array, float], object]
    n_dofs: int
    fixed: tuple[int, ...] = ()
    mass: Array | None = dataclasses.field(default=None, repr=False)
    n_constraints: int = 0
    constraints: Callable[[Array], Array] | None = None
    constraint_jacobian: Callable[[Array], object] | None = None
    constraint_hessian: Callable[[Array, Array], object] | None = None
    parameter_gradient: Callable[[Array, float], Array] | None = None

    def __post_init__(self) -> None:
        for name in ("energy", "gradient", "hessian"):
            if not callable(getattr(self, name)):
                raise InputError(f"{name}: expected a callable f(q, lam), got "
                                 f"{getattr(self, name)!r}")
        if isinstance(self.n_dofs, bool) or int(self.n_dofs) != self.n_dofs or self.n_dofs < 1:
            raise InputError(f"n_dofs: got {self.n_dofs!r}; valid: a positive integer")
        fixed = tuple(int(i) for i in self.fixed)
        if any(not 0 <= i < self.n_dofs for i in fixed) or len(set(fixed)) != len(fixed):
            raise InputError(f"fixed: got {self.fixed!r}; valid: distinct indices in "
                             f"[0, {self.n_dofs})")
        object.__setattr__(self, "fixed", fixed)
        if self.mass is not None:
            mass = np.array(self.mass, float)
            if mass.shape != (self.n_dofs,) or not (np.isfinite(mass).all() and (mass > 0).all()):
                raise InputError(f"mass: expected {self.n_dofs} positive finite numbers")
            mass.setflags(write=False)
            object.__setattr__(self, "mass", mass)
        if self.n_constraints:
            missing = [n for n in ("constraints", "constraint_jacobian", "constraint_hessian")
                       if getattr(self, n) is None]
            if missing:
                raise InputError(f"n_constraints = {self.n_constraints} needs "
                                 f"{', '.join(missing)}")


class _EnergyAt(Parametrised, Carried):
    """An :class:`Energy` at the parameter value ``self.parameter``: the protocol of the
    numerical layers (:class:`~supercoil.solvers.problem.ConstrainedEnergy`)."""

    parameters = ("parameter",)

    def __init__(self, model: Energy, value: float):
        self.model = model
        self.parameter = float(value)
        self.n_dofs = int(model.n_dofs)
        self.n_constraints = int(model.n_constraints)
        self.fixed = np.array(model.fixed, dtype=np.int64)
        self.mass = np.ones(self.n_dofs) if model.mass is None else np.array(model.mass)

    def energy(self, q):
        return float(self.model.energy(q, self.parameter))

    def gradient(self, q):
        return np.asarray(self.model.gradient(q, self.parameter), float)

    def hessian(self, q):
        return HessianParts(sp.csr_matrix(self.model.hessian(q, self.parameter)),
                            np.zeros((0, self.n_dofs)), np.zeros(0))

    def constraints(self, q):
        if not self.n_constraints:
            return np.zeros(0)
        return np.asarray(self.model.constraints(q), float)

    def constraint_jacobian(self, q):
        if not self.n_constraints:
            return sp.csr_matrix((0, self.n_dofs))
        return sp.csr_matrix(self.model.constraint_jacobian(q))

    def constraint_hessian(self, q, multipliers):
        if not self.n_constraints:
            return sp.csr_matrix((self.n_dofs, self.n_dofs))
        return sp.csr_matrix(self.model.constraint_hessian(q, multipliers))

    def parameter_derivative(self, q, multipliers, name):
        """``d(gradient, c)/d lambda``, or None for the layer's central differences."""
        if self.model.parameter_gradient is None:
            return None
        dg = np.asarray(self.model.parameter_gradient(q, self.parameter), float)
        return np.concatenate([dg, np.zeros(self.n_constraints)])

    def accept(self, q):
        pass


def _options(options: ContinuationOptions | None, bounds) -> ContinuationOptions:
    opts = options or ContinuationOptions()
    if not isinstance(opts, ContinuationOptions):
        raise InputError(f"options: expected a supercoil.ContinuationOptions, got {opts!r}")
    if bounds is not None:
        low, high = (float(v) for v in bounds)
        try:
            opts = dataclasses.replace(opts, parameter_bounds=(low, high))
        except ValueError as exc:
            raise InputError(f"bounds: {exc}") from None
    return opts


def _problem(problem, parameter: str, start: float):
    if isinstance(problem, Energy):
        return _EnergyAt(problem, start), "parameter"
    if not hasattr(problem, parameter):
        raise InputError(f"parameter: the problem has no attribute {parameter!r}")
    # a deep copy: the continuation carries the copy's reference frames along (accept);
    # then the parameter's value by ``at``, or, on an object without it, set on the copy
    return problem_at(copy.deepcopy(problem), **{parameter: float(start)}), parameter


def continuation(problem, q0, *, start: float, bounds: tuple[float, float] | None = None,
                 parameter: str = "parameter", options: ContinuationOptions | None = None,
                 multipliers=None, name: str = "branch", records=None,
                 events=()) -> Branch:
    """The branch of equilibria of ``problem`` through ``q0`` at ``lambda = start``.

    ``problem``: an :class:`Energy`, or an object with the protocol of
    :class:`~supercoil.solvers.problem.ConstrainedEnergy` whose attribute
    ``parameter`` is the continuation parameter. It is copied, never changed: the
    continuation evaluates ``problem.at(**{parameter: value})`` where the object has
    ``at`` (:class:`~supercoil.solvers.parameters.Parametrised`), else a shallow copy
    with the attribute set on the copy, so the attribute must hold the parameter's
    whole effect (a property whose setter rebinds what depends on it, never writes
    into arrays it shares).
    ``q0`` (n_dofs,): a near-equilibrium at ``start`` (corrected first);
    ``bounds``: ``(low, high)`` of the parameter, where the run stops.
    ``records(q, multipliers, lam) -> dict`` adds named per-point values (a function
    that also takes the keyword ``problem`` gets the problem at the point);
    ``events``: :class:`~supercoil.continuation.UserEvent` s located on the branch.
    Returns a :class:`~supercoil.continuation.Branch` whose ``status`` says how the
    run ended (numerical failures never raise).
    """
    opts = _options(options, bounds)
    work, name_of_parameter = _problem(problem, parameter, start)
    q0 = np.array(q0, dtype=float)
    if q0.shape != (work.n_dofs,) or not np.isfinite(q0).all():
        raise InputError(f"q0: expected {work.n_dofs} finite numbers, got shape {q0.shape}")
    return follow(work, q0, multipliers, name_of_parameter, opts, name=name,
                  records=records, events=tuple(events))


def switch_branch(problem, branch: Branch, point: SpecialPoint, *,
                  parameter: str = "parameter", options: ContinuationOptions | None = None,
                  bounds: tuple[float, float] | None = None, side: int = 1, mode: int = 0,
                  name: str | None = None, records=None, events=()) -> Branch:
    """The branch that bifurcates from ``point`` of ``branch``, followed from the
    bifurcation along ``side`` (+1 or -1) times its critical mode number ``mode``."""
    if point.kind != "bifurcation":
        raise InputError(f"point: a {point.kind!r} point; switching needs a bifurcation")
    if side not in (1, -1):
        raise InputError(f"side: got {side!r}; valid: +1 or -1")
    opts = _options(options, bounds)
    work, name_of_parameter = _problem(problem, parameter, point.parameter)
    if name_of_parameter != branch.parameter and isinstance(problem, Energy):
        branch = dataclasses.replace(branch, parameter=name_of_parameter)
    return switch(work, branch, point, opts, side=side, mode=mode, name=name,
                  records=records, events=tuple(events))
