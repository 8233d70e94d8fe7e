"""Stability of a constrained equilibrium: inertia, zero modes, lowest modes.

An equilibrium ``(q, lambda)`` is stable when the Hessian of the Lagrangian
``H_L`` is positive definite on the tangent space ``ker J`` of the
constraints, after the rigid motions (fixed DOFs) are removed. We report

* ``negative_count``: the exact number of negative eigenvalues of ``Z^T H_L Z``
  from the inertia of the KKT matrix (Sylvester; see
  :mod:`supercoil.solvers.kkt`);
* ``lowest_eigenvalues``/``lowest_modes``: the eigenpairs of
  ``H_L v = mu M v`` on ``ker J`` nearest zero (``M`` the lumped mass, so
  that eigenvalues converge under refinement), by shift-invert Lanczos with
  KKT solves;
* ``zero_modes``: eigenvalues with ``|mu| <= zero_tolerance``, never given a
  sign; ``unstable_count``: the eigenvalues below ``-zero_tolerance``
  (``max(found below, negative_count - zero_modes)``);
* approximate symmetries (``near_symmetry_modes``: a closed rod's material
  sliding off the circle) are projected out of the eigenvalues and, by an
  integral phase row, out of the count (:func:`_reduced_system`): the unstable
  count is that of the state modulo its continuous symmetries (docs/model.md,
  "Stability");
* ``determinant_sign``: the sign of ``det(Z^T H_L Z)`` — Chamekh et al.'s test
  (Chamekh, Mani-Aouadi & Moakher 2014), which only sees the parity of ``negative_count``: when
  eigenvalues cross zero in pairs (symmetric bifurcations) the determinant
  keeps its sign while the count changes by two.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.csr import csr_columns
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.newton import lagrangian_hessian
from supercoil.solvers.problem import ConstrainedEnergy, free_dofs
from supercoil.stability.eigen import lowest_pairs
from supercoil.stability.sliding_count import (
    RIPPLE_RATIO,
    contact_acts,
    sliding_left_out,
    without_sliding_pairs,
)

DEFAULT_ZERO_TOLERANCE = 1e-6
@dataclass(frozen=True)
class StabilityReport:
    unstable_count: int
    zero_modes: int
    negative_count: int
    determinant_sign: int
    lowest_eigenvalues: np.ndarray  # (k,), ascending
    lowest_modes: np.ndarray  # (k, n_dofs), full DOF vectors, M-orthonormal
    zero_tolerance: float
    certified: bool = True  # inertia consistent with the eigenvalues and the determinant
    message: str = ""

    @property
    def stable(self) -> bool:
        return self.unstable_count == 0 and self.zero_modes == 0


def _reduced_system(problem: ConstrainedEnergy, q: np.ndarray, multipliers: np.ndarray):
    """``(dofs, H, J)`` of the count: the free DOFs, ``J`` the constraints' rows and one
    integral phase row ``(M g)^T v = 0`` per approximate symmetry ``g``
    (:func:`sliding_phase_modes`, M-orthogonal to the rigid motions).

    That is the subspace of the eigenvalues (the rigid motions and ``g`` projected
    out) and of the continuation's count with the integral gauge. Pinning a DOF
    instead (:func:`near_symmetry_gauge`) counts on another subspace, which gives the
    same inertia only while the sliding is nearly free: on contact states, where the
    discretisation gives it a clear curvature (Rayleigh quotient -1102 at a state of
    the ring's beta_II, N = 204), the pinned count was off by one from the
    eigenvalues and from a dense null-space count at 17 of 143 hard-contact states
    and 18 of 158 barrier states of beta and beta_II at N = 132
    (``python benchmarks/bench_hard_contact_check.py --all``;
    benchmarks/results/beta_stability.md).
    """
    free = free_dofs(problem)
    H = lagrangian_hessian(problem, q, multipliers).restrict(free)
    J = problem.constraint_jacobian(q)[:, free] if problem.n_constraints else None
    modes = sliding_phase_modes(problem, q)
    if modes.size:
        rows = sp.csr_matrix(modes[:, free] * np.asarray(problem.mass, dtype=float)[free])
        J = rows if J is None else sp.vstack([sp.csr_matrix(J), rows], format="csr")
    return free, H, J


def goldstone_modes(problem: ConstrainedEnergy, q: np.ndarray,
                    relative: float = 1e-6) -> np.ndarray:
    """The approximate-symmetry motions left once the exact ones are gauged, ``(r, n_dofs)``.

    Each ``near_symmetry_modes`` vector ``s`` (a closed rod's material
    sliding) minus the exact-symmetry motion that brings the gauge pins back
    to zero (least squares on ``gauge_dofs``; M-orthogonal projection when
    there are none): the direction along which the *pinned* system is nearly
    singular. Modes smaller than ``relative`` times ``s`` lie in the span of
    the exact symmetries (sliding on the circle is a rotation) and are left out.
    """
    near = _modes(problem, q, "near_symmetry_modes")
    if near.size == 0:
        return np.zeros((0, problem.n_dofs))
    exact = _modes(problem, q, "symmetry_modes")
    gauge = np.asarray(getattr(problem, "gauge_dofs", ()), dtype=np.int64)
    mass = problem.mass
    out = []
    for s in near:
        g = s.copy()
        if exact.size and gauge.size:
            g -= np.linalg.lstsq(exact[:, gauge].T, s[gauge], rcond=None)[0] @ exact
        elif exact.size:
            basis = _symmetry_basis(problem, q, np.arange(problem.n_dofs), near=False)
            g -= basis @ (basis.T @ (mass * s))
        if np.sqrt(g @ (mass * g)) > relative * np.sqrt(s @ (mass * s)):
            out.append(g)
    return np.array(out).reshape(-1, problem.n_dofs)


def sliding_phase_modes(problem: ConstrainedEnergy, q: np.ndarray,
                        relative: float = 1e-6, kind: str = "near_symmetry_modes"
                        ) -> np.ndarray:
    """The approximate-symmetry motions M-orthogonal to the exact ones, ``(r, n_dofs)``.

    Each ``near_symmetry_modes`` vector ``s`` minus its M-orthogonal projection on
    the ``symmetry_modes`` (a closed rod's sliding less the rigid motion it
    contains). As the row of an integral phase condition its reaction ``nu M g``
    has no net force or torque, so the rigid pins carry none and a symmetric
    state stays symmetric; :func:`goldstone_modes` (the rigid motion fitted on
    the pins) made the reaction depend on where the pins are: measured on the
    ring's beta branch (L/D 122, N = 204) it broke D_3 slowly, and the
    bifurcation at dLk 5.149 (Coleman & Swigon 2002's P) unfolded into a fold.
    ``kind="far_sliding_modes"``: the same of the sliding where it is no approximate
    symmetry (:func:`stiff_sliding_modes`).
    """
    near = _modes(problem, q, kind)
    if near.size == 0:
        return np.zeros((0, problem.n_dofs))
    basis = _symmetry_basis(problem, q, np.arange(problem.n_dofs), near=False)
    mass = problem.mass
    out = []
    for s in near:
        g = s - basis @ (basis.T @ (mass * s))
        if np.sqrt(g @ (mass * g)) > relative * np.sqrt(s @ (mass * s)):
            out.append(g)
    return np.array(out).reshape(-1, problem.n_dofs)


def near_symmetry_gauge(problem: ConstrainedEnergy, q: np.ndarray,
                        exclude: np.ndarray | None = None) -> np.ndarray:
    """DOFs whose pinning removes the approximate symmetries from the count (sorted).

    The unstable count leaves out the continuous symmetries of the state
    (docs/model.md, "Stability"), the material sliding of a closed rod off the circle
    included, although the discretisation breaks it weakly: the pinned
    Hessian then has a near-null eigenvalue (measured at round-off level,
    1e-9 against 3e4, on the alpha branch of the ring at N = 40) whose
    computed sign is noise. Counting it, or removing it through a Schur
    complement of the nearly singular KKT matrix, made the count flicker by
    one between neighbouring points. Pinning, for each :func:`goldstone_modes`
    vector ``g``, the free DOF where ``|g|`` is largest (not in ``exclude``)
    removes that direction as the rigid pins remove the rigid motions: the
    KKT matrix becomes regular and banded, and the count is that of the
    other eigenvalues whenever the near-null one is small against their gap
    (checked against the eigenvalues with ``g`` projected out, in
    :func:`analyse`).
    """
    modes = goldstone_modes(problem, q)
    if modes.size == 0:
        return np.zeros(0, dtype=np.int64)
    allowed = np.zeros(problem.n_dofs, dtype=bool)
    allowed[free_dofs(problem)] = True
    if exclude is not None:
        allowed[np.asarray(exclude, dtype=np.int64)] = False
    chosen: list[int] = []
    previous: list[np.ndarray] = []
    for g in modes:
        g = g.copy()
        for i, h in zip(chosen, previous):  # zero on the DOFs already pinned
            g -= (g[i] / h[i]) * h
        weights = np.where(allowed, np.abs(g), -1.0)
        i = int(np.argmax(weights))
        if weights[i] <= 0:
            continue
        chosen.append(i)
        previous.append(g)
        allowed[i] = False
    return np.array(sorted(chosen), dtype=np.int64)


def eigen_dofs(problem: ConstrainedEnergy) -> np.ndarray:
    """DOFs of the eigenproblem: the free ones plus the gauge pins.

    Fixed DOFs are either boundary conditions (clamps) or ``gauge_dofs`` that
    only remove continuous symmetries (rigid motions of a ring, rotation of a
    clamped rod about its axis). The count uses the pinned system (same
    inertia at an equilibrium); the eigenvalues release the gauge pins and
    project the symmetry modes out M-orthogonally, so that they do not depend
    on which DOFs were pinned.
    """
    mask = np.zeros(problem.n_dofs, dtype=bool)
    mask[free_dofs(problem)] = True
    mask[np.asarray(getattr(problem, "gauge_dofs", ()), dtype=np.int64)] = True
    return np.flatnonzero(mask)


def _modes(problem: ConstrainedEnergy, q: np.ndarray, name: str) -> np.ndarray:
    getter = getattr(problem, name, None)
    modes = np.zeros((0, problem.n_dofs)) if getter is None else np.asarray(getter(q), float)
    return modes.reshape(-1, problem.n_dofs)


def _symmetry_basis(problem: ConstrainedEnergy, q: np.ndarray, dofs: np.ndarray,
                    near: bool = True) -> np.ndarray:
    """M-orthonormal basis ``(len(dofs), r)`` of the symmetry modes on ``dofs``.

    ``near``: include the approximate symmetries (``near_symmetry_modes``, e.g.
    a closed rod's material sliding), which the unstable count leaves out.
    """
    modes = _modes(problem, q, "symmetry_modes")
    if near:
        modes = np.vstack([modes, _modes(problem, q, "near_symmetry_modes")])
    if modes.size == 0:
        return np.zeros((dofs.size, 0))
    root = np.sqrt(problem.mass[dofs])
    qmat, rfac = np.linalg.qr(root[:, None] * modes[:, dofs].T)
    keep = np.abs(np.diag(rfac)) > 1e-10 * np.max(np.abs(np.diag(rfac)))
    return qmat[:, keep] / root[:, None]


def eigen_system(problem: ConstrainedEnergy, q: np.ndarray, multipliers: np.ndarray,
                 full_hessian=None, near: bool = True):
    """``(dofs, H, J, mass, symmetry)`` of the constrained eigenproblem at ``(q,
    multipliers)``: its DOFs (:func:`eigen_dofs`), the Hessian of the Lagrangian and
    the constraint Jacobian on them, their masses, and the M-orthonormal symmetry
    modes projected out.

    ``full_hessian``: the Hessian of the Lagrangian at ``(q, multipliers)`` on all
    DOFs (:func:`~supercoil.solvers.newton.lagrangian_hessian`) if already assembled.
    ``near``: the approximate symmetries projected out too.
    """
    dofs = eigen_dofs(problem)
    H = (lagrangian_hessian(problem, q, multipliers) if full_hessian is None
         else full_hessian).restrict(dofs)
    # csr_columns: scipy's column slicing, the same arrays from a gather remembered per
    # pattern (checked equal along the tweezers benchmark: 135 of 135; 0.4 ms a call)
    J = None
    if problem.n_constraints:
        J = problem.constraint_jacobian(q)
        J = csr_columns(J, dofs) if getattr(J, "format", None) == "csr" else J[:, dofs]
    return dofs, H, J, problem.mass[dofs], _symmetry_basis(problem, q, dofs, near)


def negative_count(problem: ConstrainedEnergy, q: np.ndarray, multipliers: np.ndarray) -> int:
    """Exact number of negative eigenvalues of the constrained Hessian (inertia only)."""
    _dofs, H, J = _reduced_system(problem, q, multipliers)
    return KKTFactor(H, J).reduced_negative_count


def eigenvalue_nearest_zero(problem: ConstrainedEnergy, q: np.ndarray,
                            multipliers: np.ndarray) -> float:
    """The signed eigenvalue of ``H_L v = mu M v`` (constrained, symmetry removed) nearest 0."""
    dofs, H, J, mass, sym = eigen_system(problem, q, multipliers)
    m = J.shape[0] if J is not None else 0
    values, _ = lowest_pairs(H, J, mass, n_wanted=4, n=dofs.size, m=m, symmetry=sym,
                             force_sparse=True)
    return float(values[np.argmin(np.abs(values))])


def analyse(problem: ConstrainedEnergy, q: np.ndarray, multipliers: np.ndarray,
            n_modes: int = 6, zero_tolerance: float = DEFAULT_ZERO_TOLERANCE) -> StabilityReport:
    """Full stability report at an equilibrium (see module docstring)."""
    free, H, J = _reduced_system(problem, q, multipliers)
    factor = KKTFactor(H, J)
    neg = factor.reduced_negative_count
    left_out = _stiff_sliding(problem, q, free, H, neg)
    neg -= left_out
    det_sign = int(factor.determinant_sign
                   * (-1) ** ((J.shape[0] if J is not None else 0) + left_out))
    # where the stiff sliding's eigenvalue is left out, its own eigenpair is, not g's
    # direction (supercoil.stability.sliding_count)
    dofs, H_e, J_e, mass_e, sym = eigen_system(problem, q, multipliers, near=not left_out)
    values, vectors = lowest_pairs(H_e, J_e, mass_e, n_wanted=neg + left_out + n_modes,
                                   n=dofs.size, m=J_e.shape[0] if J_e is not None else 0,
                                   symmetry=sym)
    if left_out:
        sliding, tangents = count_sliding_modes(problem, q)
        values, modes_t = without_sliding_pairs(
            values, vectors.T, sliding[:, dofs], mass_e,
            None if tangents is None else tangents[:, dofs], count=left_out)
        vectors = modes_t.T
    zero = int(np.sum(np.abs(values) <= zero_tolerance))
    below = int(np.sum(values < -zero_tolerance))
    # Approximate symmetries (a closed rod's material sliding) are projected out
    # of the eigenvalues above and, by an integral phase row, out of the inertia
    # (_reduced_system).
    # Eigenvalues within the tolerance are zero modes, whatever sign the
    # inertia gave them; the count of clearly negative ones is at least what
    # the eigensolver found and at least the inertia minus the zero modes.
    unstable = max(below, neg - zero)
    # Cross-checks of the inertia: the determinant's sign is its parity, and the
    # eigensolver cannot find more clearly negative eigenvalues than it counts.
    problems = []
    if det_sign != (-1) ** neg:
        problems.append(f"determinant sign {det_sign:+d} contradicts {neg} negative eigenvalues")
    if below > neg:
        problems.append(f"{below} negative eigenvalues found but the inertia counts {neg}")
    message = ("inertia not certified: " + "; ".join(problems)) if problems else ""
    if below > neg:
        # The inertia is the verified method (tests up to N = 20 000); on very fine
        # meshes the shift-invert eigenvalues lose accuracy first. Report the
        # inertia count and keep the warning.
        unstable = neg
    modes = np.zeros((len(values), problem.n_dofs))
    modes[:, dofs] = vectors.T
    return StabilityReport(
        unstable_count=unstable,
        zero_modes=zero,
        negative_count=neg,
        determinant_sign=det_sign,
        lowest_eigenvalues=values,
        lowest_modes=modes,
        zero_tolerance=zero_tolerance,
        certified=not problems,
        message=message,
    )


def stiff_sliding_modes(problem: ConstrainedEnergy, q: np.ndarray, negative: int
                        ) -> tuple[np.ndarray, float | None, sp.csr_matrix | None] | None:
    """``(modes, ratio, tangents)`` where a count of ``negative`` may include the stiff
    sliding's eigenvalue (:mod:`supercoil.stability.sliding_count`): a positive count, a
    contact acting at ``q`` and a sliding present; None otherwise (no eigen-solve
    needed). ``modes``: the approximate symmetries (:func:`sliding_phase_modes`,
    ``ratio`` and ``tangents`` None) or, where the sliding is none (its tails not
    straight), the sliding itself (``far_sliding_modes``), whose eigenvalue is left out
    only where it is the contact's ripple, ``ratio``
    (:data:`~supercoil.stability.sliding_count.RIPPLE_RATIO`) times the next
    eigenvalues at least, and with it those of the modes along the centreline
    (``tangents``: the problem's ``tangent_rows(q)``, an empty matrix if it has none)."""
    if negative <= 0 or not contact_acts(problem, q):
        return None
    modes, tangents = count_sliding_modes(problem, q)
    if not modes.size:
        return None
    return (modes, None, None) if tangents is None else (modes, RIPPLE_RATIO, tangents)


def count_sliding_modes(problem: ConstrainedEnergy, q: np.ndarray
                        ) -> tuple[np.ndarray, sp.csr_matrix | None]:
    """``(modes, tangents)``: the sliding whose eigenpairs a count leaves out
    (:func:`stiff_sliding_modes`): the approximate symmetries (``tangents`` None), else
    the sliding where it is none, with the problem's ``tangent_rows(q)`` (``(nodes,
    n_dofs)``; an empty one if the problem has none)."""
    modes = sliding_phase_modes(problem, q)
    if modes.size:
        return modes, None
    far = sliding_phase_modes(problem, q, kind="far_sliding_modes")
    rows = getattr(problem, "tangent_rows", None)
    tangents = (sp.csr_matrix(rows(q)) if rows is not None
                else sp.csr_matrix((0, problem.n_dofs)))
    return far, tangents


def _stiff_sliding(problem: ConstrainedEnergy, q: np.ndarray, free: np.ndarray, H,
                   negative: int) -> int:
    """1 where the ``negative`` eigenvalues counted on the complement of the approximate
    symmetries include the stiff sliding's (:mod:`supercoil.stability.sliding_count`),
    as the branches' count leaves it out, else 0. ``H``: the count's Hessian on the
    ``free`` DOFs."""
    found = stiff_sliding_modes(problem, q, negative)
    if found is None:
        return 0
    modes, ratio, tangents = found
    J = (sp.csr_matrix(problem.constraint_jacobian(q))[:, free] if problem.n_constraints
         else sp.csr_matrix((0, free.size)))
    return sliding_left_out(H, J, modes[:, free], np.asarray(problem.mass, float)[free],
                            negative, ratio=ratio,
                            tangents=None if tangents is None else tangents[:, free])
