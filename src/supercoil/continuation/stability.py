"""Stability at a point of a branch: inertia count, zero modes, determinant sign.

``unstable_count`` is the exact number of negative eigenvalues of the Hessian
of the Lagrangian on the tangent space of the constraints (and of the phase
conditions, if any), from the inertia of the KKT matrix on the free DOFs
(:class:`~supercoil.solvers.kkt.KKTFactor`; the problem's pins remove rigid
motions and gauges). Eigenvalues of ``H v = mu M v`` nearest zero come from
the eigenproblem of :mod:`supercoil.stability.analysis` (gauge pins
released, the problem's symmetry and near-symmetry modes removed as
constraints; the near-symmetries are removed from the inertia count as
there): dense below 100 unknowns, shift-invert Lanczos above (measured at
N = 200 on a contact state: 10 ms against 81 ms dense, same eigenvalues). Those with ``|mu| <= zero_tolerance``
are ``zero_modes`` and never signed, so ``unstable_count = max(found below
-tol, inertia - zero_modes)`` (as :func:`~supercoil.stability.analysis.analyse`).
``determinant_sign`` is the sign of ``det(Z^T H Z)``, the test of
Chamekh, Mani-Aouadi & Moakher 2014: it is
the parity of the inertia and misses eigenvalues that cross in pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from supercoil.continuation.system import ExtendedSystem
from supercoil.solvers.csr import csr_from_arrays
from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.kkt import KKTFactor
from supercoil.stability.analysis import (
    count_sliding_modes,
    eigen_system,
    sliding_phase_modes,
    stiff_sliding_modes,
)
from supercoil.stability.eigen import dense_constrained_eigenpairs, lowest_pairs
from supercoil.stability.sliding_count import (
    sliding_left_out,
    without_sliding_pairs,
)

_DENSE_BELOW = 100


@dataclass(frozen=True)
class PointStability:
    unstable_count: int
    zero_modes: int
    negative_count: int  # raw inertia of the constrained Hessian
    determinant_sign: int
    eigenvalues: np.ndarray  # (k,) ascending, the computed ones nearest zero
    modes: np.ndarray  # (k, n_dofs) M-orthonormal full DOF vectors

    @property
    def nearest_eigenvalue(self) -> float:
        if self.eigenvalues.size == 0:
            return float("nan")
        return float(self.eigenvalues[np.argmin(np.abs(self.eigenvalues))])

    def critical_modes(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` eigenpairs nearest zero: ``(values (k,), modes (k, n_dofs))``."""
        idx = np.argsort(np.abs(self.eigenvalues))[:k]
        return self.eigenvalues[idx], self.modes[idx]


def count_rows(system: ExtendedSystem, x: np.ndarray) -> np.ndarray:
    """The rows ``(r, system.n)`` that remove the approximate symmetries from the count
    at ``x``: one integral phase row ``(M g)^T v = 0`` per approximate symmetry ``g``
    (:func:`~supercoil.stability.analysis.sliding_phase_modes`, M-orthogonal to the
    exact ones) that the system's own phase rows do not already remove (a continuation
    started with ``near_symmetry_gauge``: one row per mode, coupled to it).

    The count is then on the subspace of the eigenvalues (the symmetries projected
    out M-orthogonally), as in :func:`~supercoil.stability.analysis.analyse`. Pinning
    the DOF where ``|g|`` is largest instead counts on another subspace, with the same
    inertia only while the sliding is nearly free: along a plectoneme in contact the
    discrete contact gives the sliding a clear curvature of either sign (at L/D = 40,
    F L^2/A = 320, N = 123 from 3.97 to 4.45 turns the sliding's Rayleigh quotient near
    -1400 against a next eigenvalue of 600-950), and the pinned count stayed one above
    the eigenvalues, which N = 82 did not (its quotient there positive).
    """
    problem = system.problem_at(x[-1])
    q = system.q(x)
    modes = sliding_phase_modes(problem, q)
    if modes.size == 0:
        return np.zeros((0, system.n))
    g = modes[:, system.free]
    if system.r:
        coupling = np.abs(system.P @ g.T) / np.outer(np.linalg.norm(system.P, axis=1),
                                                      np.linalg.norm(g, axis=1))
        g = g[coupling.max(axis=0) <= 0.1 / np.sqrt(system.n)]
    return g * system.mass[None, :] if g.size else np.zeros((0, system.n))


def count_system(system: ExtendedSystem, x: np.ndarray, hessian=None, rows=None):
    """``(H, J)`` of the count at ``x``: the system's, with the rows that remove the
    approximate symmetries below ``J`` (``hessian``: ``system.hessian(x)`` if already
    known; ``rows``: ``count_rows(system, x)`` if already known)."""
    J = system.jacobian(x)
    H = system.hessian(x) if hessian is None else hessian
    rows = count_rows(system, x) if rows is None else rows
    if rows.shape[0]:
        J = with_dense_rows(sp.csr_matrix(J), rows)
    return H, J


def with_dense_rows(J: sp.csr_matrix, rows: np.ndarray) -> sp.csr_matrix:
    """``J`` ``(m, n)`` with the nonzero entries of the dense ``rows`` ``(r, n)`` below it:
    ``scipy.sparse.vstack([J, csr_matrix(rows)])`` made as one matrix from the arrays."""
    nonzero = rows != 0
    columns = np.nonzero(nonzero)[1].astype(J.indices.dtype, copy=False)
    counts = np.cumsum(nonzero.sum(axis=1)).astype(J.indptr.dtype, copy=False)
    return csr_from_arrays(np.concatenate([J.data, rows[nonzero]]),
                           np.concatenate([J.indices, columns]),
                           np.concatenate([J.indptr, J.indptr[-1] + counts]),
                           (J.shape[0] + rows.shape[0], J.shape[1]),
                           canonical=bool(J.has_canonical_format))


def inertia(system: ExtendedSystem, x: np.ndarray, zero_tolerance: float | None = None,
            hessian=None) -> tuple[int, int]:
    """``(negative count, determinant sign)`` of the constrained Hessian at ``x``.

    Near-symmetry directions are removed from the count as in
    :func:`~supercoil.stability.analysis.analyse` (:func:`count_rows`). With
    ``zero_tolerance``, an exactly singular Hessian (a special point located
    exactly) is handled: the count is then that of the eigenvalues below
    ``-zero_tolerance / 2`` (the inertia of ``H + M zero_tolerance / 2``) and
    the determinant sign is 0. ``hessian``: ``system.hessian(x)`` if already known.
    """
    negative, sign, _factor, _dofs, _left_out = inertia_with_factor(system, x, zero_tolerance,
                                                                     hessian)
    return negative, sign


def factor_count(system: ExtendedSystem, x: np.ndarray, hessian=None) -> int:
    """The negative count of the constrained Hessian at ``x`` as the factor of
    :func:`inertia` counts it, before :func:`stiff_sliding` leaves anything out: one
    sparse factorisation, no eigenproblem. Raises on a singular matrix."""
    return count_factor(system, x, hessian).reduced_negative_count


def count_factor(system: ExtendedSystem, x: np.ndarray, hessian=None) -> KKTFactor:
    """The factor whose count :func:`factor_count` reads, its inertia computed; given to
    :func:`point_stability` at the same ``x``, Hessian and phase rows, it spares the
    same factorisation. Raises on a singular matrix."""
    H, J = count_system(system, x, hessian)
    factor = KKTFactor(H, J)
    factor.reduced_negative_count  # noqa: B018 (the inertia, computed once: it may raise)
    return factor


def inertia_with_factor(system: ExtendedSystem, x: np.ndarray, zero_tolerance: float | None,
                        hessian, factor: KKTFactor | None = None
                        ) -> tuple[int, int, KKTFactor, np.ndarray, int]:
    """:func:`inertia` with the factor it counted with, that factor's DOFs (indices
    into the problem's DOFs, ``(n_count,)``: its unknowns are those DOFs, then the
    rows of ``system.jacobian(x)``, then the :func:`count_rows`) and the number of
    eigenvalues that :func:`stiff_sliding` left out of the factor's count (0 or 1; more
    only as the contact's ripple), whose signs the determinant's then leaves out too
    (the parity of the count returned).
    ``factor``: :func:`count_factor` at ``x`` with the Hessian ``hessian``, if made."""
    if factor is not None:
        negative = factor.reduced_negative_count
        left_out = stiff_sliding(system, x, hessian, negative)
        sign = int(factor.determinant_sign * (-1) ** (factor.m + left_out))
        return negative - left_out, sign, factor, system.free, left_out
    H, J = count_system(system, x, hessian)
    dofs = system.free
    try:
        factor = KKTFactor(H, J)
        negative = factor.reduced_negative_count
        left_out = stiff_sliding(system, x, H, negative)
        sign = int(factor.determinant_sign * (-1) ** (J.shape[0] + left_out))
        return negative - left_out, sign, factor, dofs, left_out
    except (SingularMatrixError, InertiaError):
        if zero_tolerance is None:
            raise
        shift = -0.5 * zero_tolerance
        factor = KKTFactor(H, J, shift=shift, mass=system.mass)
        negative = factor.reduced_negative_count
        left_out = stiff_sliding(system, x, H, negative, shift)
        return negative - left_out, 0, factor, dofs, left_out


def stiff_sliding(system: ExtendedSystem, x: np.ndarray, H, negative: int,
                  shift: float = 0.0) -> int:
    """How many of the ``negative`` eigenvalues counted on the complement of the
    approximate symmetries (:func:`count_rows` or the system's own phase rows) are the
    stiff sliding's, which that complement does not take out, or, where the sliding is no
    symmetry, the contact's ripple (:mod:`~supercoil.stability.sliding_count`): 0, 1
    or, in the ripple's case, more. ``H``: the count's Hessian."""
    found = stiff_sliding_modes(system.problem_at(x[-1]), system.q(x), negative)
    if found is None:
        return 0
    modes, ratio, tangents = found
    g = modes[:, system.free]
    J = sp.csr_matrix(system.jacobian(x))
    keep = np.arange(J.shape[0])
    if system.r:  # the phase rows that hold the sliding are left out
        coupling = np.abs(system.P @ g.T) / np.outer(np.linalg.norm(system.P, axis=1),
                                                      np.linalg.norm(g, axis=1))
        held = coupling.max(axis=1) > 0.1 / np.sqrt(system.n)
        keep = np.concatenate([keep[:J.shape[0] - system.r],
                               keep[J.shape[0] - system.r:][~held]])
    return sliding_left_out(H, J[keep], g, system.mass, negative, shift, ratio,
                            None if tangents is None else tangents[:, system.free])


def related_order(order: np.ndarray, dofs: np.ndarray, rows: int, new_dofs: np.ndarray,
                  new_rows: int, pattern) -> np.ndarray | None:
    """A banded ordering of a KKT matrix on ``new_dofs`` with ``new_rows`` constraint rows,
    from the ordering ``order`` of one on ``dofs`` with ``rows`` rows (its unknowns: the
    DOFs, then the rows); ``dofs`` must lie in ``new_dofs`` and the new rows be the
    first ``new_rows`` of the old ones, else None. The old unknowns keep their relative
    order (the rows beyond ``new_rows`` are left out); each new DOF goes midway between
    the first and the last placed unknowns it couples to in ``pattern`` (the new sparse
    Hessian, ``(n_new, n_new)``, a CSR matrix or its arrays), at the end if none: its
    own band is half their distance, the others' grow by one.

    What for: the shift-invert factor of the eigenproblem (the gauge pins released,
    the dense phase rows left out) needs a banded ordering of its own pattern, which
    :func:`~supercoil.solvers.ordering.kkt_order` computed anew (reverse Cuthill-McKee,
    1-2 ms at N = 100) at every new contact pattern: 64 of its 135 calls along the
    tweezers benchmark; the count's factor of the same point has an ordering already.
    The ordering only decides the band LU's band (partial pivoting: solves equal to
    round-off whatever the order). Measured, half-bandwidths against the fresh
    ordering's: the same at every point of the tweezers benchmark; on the ring's (N =
    200) narrower at 180 of 186 points (e.g. 43 against 55), wider at 5 (43 against 39).
    """
    n_new = new_dofs.size
    where = np.minimum(np.searchsorted(new_dofs, dofs), max(n_new - 1, 0))
    if n_new == 0 or not np.array_equal(new_dofs[where], dofs) or new_rows > rows:
        return None  # not a smaller system's ordering: the caller orders afresh
    mapped = np.full(dofs.size + rows, -1, dtype=np.int64)
    mapped[:dofs.size] = where
    mapped[dofs.size:dofs.size + new_rows] = n_new + np.arange(new_rows)
    sequence = mapped[np.asarray(order, dtype=np.int64)]
    sequence = list(sequence[sequence >= 0])
    placed = np.zeros(n_new + new_rows, dtype=bool)
    placed[sequence] = True
    for dof in np.flatnonzero(~placed[:n_new]):
        neighbours = pattern.indices[pattern.indptr[dof]:pattern.indptr[dof + 1]]
        neighbours = neighbours[placed[neighbours]]
        if neighbours.size:
            rank = np.empty(n_new + new_rows, dtype=np.int64)
            rank[sequence] = np.arange(len(sequence))
            sequence.insert((int(np.min(rank[neighbours])) + int(np.max(rank[neighbours]))) // 2
                            + 1, dof)
        else:
            sequence.append(dof)
        placed[dof] = True
    return np.asarray(sequence, dtype=np.int64)


def eigenpairs(system: ExtendedSystem, x: np.ndarray, n_wanted: int,
               full=None, count: tuple[np.ndarray, np.ndarray, int] | None = None,
               near: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of the constrained Hessian nearest zero: ``(values, (k, n_dofs) modes)``
    (:func:`~supercoil.stability.analysis.lowest_pairs`).

    ``full``: ``system.full_hessian(x)`` if already assembled. ``count``: ``(dofs, order, rows)`` of the count's
    factor at ``x`` (its DOFs, :attr:`~supercoil.solvers.kkt.KKTFactor.order` and
    number of rows, as :func:`inertia_with_factor` gives them): the shift-invert factor is then
    ordered by :func:`related_order` rather than by a new ``kkt_order`` (the same
    eigenpairs to round-off). ``near``: the approximate symmetries projected out (else
    only the exact ones)."""
    problem = system.problem_at(x[-1])
    dofs, H, J, mass, sym = eigen_system(problem, system.q(x), system.multipliers(x), full,
                                         near)
    m = J.shape[0] if J is not None else 0
    dim = dofs.size - m - sym.shape[1]
    if dim <= 0:
        return np.zeros(0), np.zeros((0, problem.n_dofs))
    if dim <= _DENSE_BELOW:
        values, vectors = dense_constrained_eigenpairs(H, J, mass, sym)
    else:
        order = None
        if count is not None:
            pattern = H.csr_arrays()  # the pattern's arrays only
            order = related_order(count[1], count[0], count[2], dofs, m,
                                  H.sparse.tocsr() if pattern is None else pattern)
        values, vectors = lowest_pairs(H, J, mass, n_wanted=min(n_wanted, dim - 2), n=dofs.size,
                                       m=m, symmetry=sym, force_sparse=True,
                                       factor_order=order)
    modes = np.zeros((values.size, problem.n_dofs))
    modes[:, dofs] = vectors.T
    return values, modes


def without_sliding(system: ExtendedSystem, x: np.ndarray, values: np.ndarray,
                    modes: np.ndarray, left_out: int) -> tuple[np.ndarray, np.ndarray]:
    """The eigenpairs ``(values, modes)`` (M-orthonormal full DOF modes) less the
    ``left_out`` lowest negative ones that are mostly an approximate symmetry ``g`` (``(v^T M g)^2 >=
    g^T M g / 2``, :data:`~supercoil.stability.sliding_count.SLIDING_SHARE`) or, where
    the sliding is none, mostly along the centreline
    (:func:`~supercoil.stability.sliding_count.without_sliding_pairs`)."""
    problem = system.problem_at(x[-1])
    sliding, tangents = count_sliding_modes(problem, system.q(x))
    return without_sliding_pairs(values, modes, sliding,
                                 np.asarray(problem.mass, dtype=float), tangents,
                                 count=left_out)


def point_stability(system: ExtendedSystem, x: np.ndarray, zero_tolerance: float,
                    n_modes: int, full=None, factor: KKTFactor | None = None
                    ) -> PointStability:
    """Stability report at the point ``x`` of the extended system (see module doc).

    ``full``: ``system.full_hessian(x)`` if already assembled (a converged
    correction's); ``factor``: :func:`count_factor` at ``x`` with that Hessian, if
    made. The shift-invert factor of the eigenpairs is ordered from the count's
    (``eigenpairs(count=...)``).
    """
    full = system.full_hessian(x) if full is None else full
    neg, det_sign, factor, dofs, left_out = inertia_with_factor(
        system, x, zero_tolerance, full.restrict(system.free), factor)
    count = (dofs, factor.order, factor.m)
    if left_out:  # the stiff sliding's: its own eigenpair left out, not the direction g
        values, modes = eigenpairs(system, x, neg + left_out + n_modes, full, count,
                                   near=False)
        values, modes = without_sliding(system, x, values, modes, left_out)
    else:
        values, modes = eigenpairs(system, x, neg + n_modes, full, count)
    zero = int(np.sum(np.abs(values) <= zero_tolerance))
    below = int(np.sum(values < -zero_tolerance))
    # as analyse: at least what the eigensolver found below -tol, at least the
    # inertia less zero modes; the inertia wins when the eigensolver finds more
    # negatives than it counts
    unstable = max(below, neg - zero) if below <= neg else neg
    return PointStability(unstable, zero, neg, det_sign, values, modes)
