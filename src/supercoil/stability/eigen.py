"""The lowest eigenpairs of the constrained Hessian, ``H v = mu M v`` on ``ker J`` with
symmetry modes projected out: shift-invert Lanczos on the KKT factor
(:func:`lowest_pairs`), the dense reference (:func:`dense_constrained_eigenpairs`) and
its faster form for the lowest few (:func:`lowest_dense_pairs`), all on one BLAS thread
so that the eigenpairs do not depend on the thread count."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla
from scipy.linalg import eigh, lu, null_space, solve_triangular
from threadpoolctl import ThreadpoolController

from supercoil.solvers.kkt import KKTFactor

_CONTROLLER: ThreadpoolController | None = None


def _one_blas_thread():
    """A context with BLAS on one thread: LAPACK's ``eigh`` and ARPACK's dot products
    split their sums over the threads, so eigenvectors (their sign, and the basis of a
    double eigenvalue) and the last bits of eigenvalues would depend on the thread count.
    The controller is made once per process (a new one re-scans the loaded libraries)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")


def lowest_pairs(H, J, mass, n_wanted, n, m, symmetry=None, force_sparse=False,
                 factor_order=None, sigma: float = -1e-3):
    """The eigenpairs of ``H v = mu M v`` on ``ker J`` (the symmetry modes projected
    out) nearest zero, ``(values, vectors)``: the method of
    :func:`_lowest_pairs_threads`, computed with one BLAS thread (the same eigenpairs,
    bit for bit, whatever the thread count of the process). ``sigma``: the shift of
    the sparse path (the eigenpairs nearest it; below the spectrum: the lowest)."""
    with _one_blas_thread():
        return _lowest_pairs_threads(H, J, mass, n_wanted, n, m, symmetry, force_sparse,
                                     factor_order, sigma)


def dense_path(dim: int, k: int) -> bool:
    """Whether :func:`lowest_pairs` takes the dense path for ``k`` eigenpairs on a
    constrained space of dimension ``dim`` (small, or a large share of it wanted)."""
    return dim <= 400 or k >= dim // 4


def _lowest_pairs_threads(H, J, mass, n_wanted, n, m, symmetry=None, force_sparse=False,
                          factor_order=None, sigma: float = -1e-3):
    """Eigenpairs of ``H v = mu M v`` on ``ker J`` (minus symmetry modes) nearest zero.

    ``symmetry`` is an M-orthonormal basis ``(n, r)`` of modes to project out.
    The sparse path (shift-invert Lanczos) solves the problem constrained by
    ``J v = 0`` and ``S^T M v = 0`` exactly, as the dense reference does: the
    ``r`` dense symmetry rows are eliminated by a Schur complement
    (:func:`_constrained_shift_invert`), so that the KKT factorisation keeps
    its banded pattern. (Projecting ``v`` onto the M-complement of ``S``
    instead agrees only when ``S`` spans an invariant subspace of ``H``, which
    an approximate symmetry does not: measured 3606 against the dense 3630 for
    the lowest eigenvalue on a contact branch at N = 200.)

    Lanczos runs in ARPACK's standard mode on the symmetrically scaled operator
    ``M^(1/2) (H - sigma M)^-1 M^(1/2)`` (constrained as above), whose eigenvalues
    are ``1 / (mu - sigma)``: one operator application per Lanczos step (the
    generalised mode needs two or three). ``factor_order``: the KKT factor's
    ordering (``KKTFactor(order=...)``), if known.
    """
    r = 0 if symmetry is None else symmetry.shape[1]
    dim = n - m - r
    k = int(min(n_wanted, dim - 2))
    if not force_sparse and dense_path(dim, k):
        values, vectors = dense_constrained_eigenpairs(H, J, mass, symmetry)
        return values[:k], vectors[:, :k]
    opinv = _constrained_shift_invert(H, J, mass, symmetry, sigma, factor_order)
    root = np.sqrt(mass)
    scaled = spla.LinearOperator((n, n), matvec=lambda y: root * opinv(root * np.ravel(y)),
                                 dtype=float)
    rng = np.random.default_rng(12345)
    y0 = root * opinv(mass * rng.standard_normal(n))  # M^(1/2) of a shift-inverted start
    # ncv: 12 Lanczos vectors (ARPACK's default 20) took 17 solves instead of 23 per
    # call at the ring's points (N = 200), with the same eigenvalues to 2e-12 relative
    try:
        nu, y = spla.eigsh(scaled, k=k, v0=y0, which="LM", tol=1e-12,
                           ncv=min(n, max(2 * k + 1, 12)))
    except spla.ArpackNoConvergence:
        # ARPACK may give up (measured: after 8951 iterations with 1 of 2 pairs, in the
        # stiff sliding's count on the tweezers' contact branch at lambda = 150,
        # N = 302; the spectrum there was not examined); the dense reference has them all
        values, vectors = dense_constrained_eigenpairs(H, J, mass, symmetry)
        nearest = np.sort(np.argsort(np.abs(values - sigma), kind="stable")[:k])
        return values[nearest], vectors[:, nearest]
    values, vectors = sigma + 1.0 / nu, y / root[:, None]
    order = np.argsort(values)
    return values[order], vectors[:, order]


def _constrained_shift_invert(H, J, mass, symmetry, sigma: float,
                              order: np.ndarray | None = None):
    """``x -> v`` solving ``(H - sigma M) v + J^T a + M S b = x, J v = 0, S^T M v = 0``.

    One sparse KKT factorisation of ``[[H - sigma M, J^T], [J, 0]]``; the ``r``
    dense rows ``C = S^T M`` by block elimination: with ``K w = [x; 0]`` and
    ``K W = [C^T; 0]``, ``b = (C W_v)^-1 C w_v`` and ``v = w_v - W_v b``. ``order``:
    the factor's ordering (``KKTFactor(order=...)``; None: ``kkt_order``).
    """
    n = mass.size
    m = J.shape[0] if J is not None else 0
    factor = KKTFactor(H, J, shift=sigma, mass=mass, order=order)
    r = 0 if symmetry is None else symmetry.shape[1]
    if r:
        C = (mass[:, None] * symmetry).T  # (r, n)
        rhs = np.zeros((n + m, r))
        rhs[:n] = C.T
        W = factor.solve(rhs)[:n]
        schur = C @ W

    def opinv(x):
        rhs = np.zeros(n + m)
        rhs[:n] = np.ravel(x)
        w = factor.solve(rhs)[:n]
        if r:
            w = w - W @ np.linalg.solve(schur, C @ w)
        return w

    return opinv


def dense_constrained_eigenpairs(H, J, mass, symmetry=None):
    """Dense reference: all eigenpairs of ``Z^T H Z y = mu Z^T M Z y`` (ascending).

    ``Z`` spans ``ker J`` intersected with the M-orthogonal complement of
    ``symmetry`` (``(n, r)`` or None). Returns eigenvalues ``(d,)`` and
    M-orthonormal vectors ``(n, d)``. O(n^3): an oracle for tests and small systems.
    """
    Hd = H.dense()
    rows = []
    if J is not None and J.shape[0]:
        rows.append(J.toarray())
    if symmetry is not None and symmetry.shape[1]:
        rows.append((mass[:, None] * symmetry).T)
    with _one_blas_thread():
        Z = null_space(np.vstack(rows)) if rows else np.eye(Hd.shape[0])
        A = Z.T @ Hd @ Z
        B = Z.T @ (mass[:, None] * Z)
        values, y = eigh(0.5 * (A + A.T), 0.5 * (B + B.T))
        return values, Z @ y


# lowest_dense_pairs gives way to the reference where J^T's LU shows J nearly rank
# deficient (a pivot below this fraction of the largest) or the basis of ker J grows
# (an entry of L1^-T L2^T above GROWTH_LIMIT: partial pivoting bounds those of L by 1)
PIVOT_FLOOR = 1e-10
GROWTH_LIMIT = 1e6


def lowest_dense_pairs(H, J, mass: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` lowest eigenpairs of ``H v = mu M v`` on ``ker J``, dense: ``(values (k,),
    M-orthonormal vectors (n, k))``, the reference's
    (:func:`dense_constrained_eigenpairs`) to round-off at about a third of its cost.

    ``H``: :class:`~supercoil.solvers.problem.HessianParts` (or anything with
    ``matmat``), ``J``: ``(m, n)`` sparse, of full rank. The basis of ``ker J`` comes
    from the LU factors of ``J^T`` with partial pivoting instead of an SVD: with
    ``J^T = P L U`` and ``L = [L1; L2]`` (``L1`` unit lower triangular, ``(m, m)``),
    ``ker J = P ker L^T``, spanned by the columns of ``P [-L1^-T L2^T; I]``; the
    identity block makes the products with it cheap, and only the ``k`` lowest
    eigenpairs of the projected pencil are computed (LAPACK's ``sygvx``). Where
    the LU shows ``J`` nearly rank deficient, or the basis badly scaled, the reference
    is used. One BLAS thread, as :func:`lowest_pairs`."""
    n = mass.size
    m = J.shape[0]
    if k <= 0:
        return np.zeros(0), np.zeros((n, 0))
    with _one_blas_thread():
        if m == 0:
            Z = None
        else:
            p, L, U = lu(J.toarray().T, p_indices=True)  # J^T = L[p] U
            pivots = np.abs(np.diag(U))
            if pivots.min() <= PIVOT_FLOOR * pivots.max():
                Z = None  # nearly rank deficient: the SVD's null space
            else:
                X = -solve_triangular(L[:m], L[m:].T, trans="T", lower=True,
                                      unit_diagonal=True, check_finite=False)
                if not np.abs(X).max(initial=0.0) <= GROWTH_LIMIT:
                    Z = None
                else:
                    Z = np.vstack([X, np.eye(n - m)])[p]  # L[p]^T Z = 0: J Z = 0
        if Z is None:
            values, vectors = dense_constrained_eigenpairs(H, J, mass)
            return values[:k], vectors[:, :k]
        order = np.argsort(p)  # rows of Z back into [X; I]
        HZ = H.matmat(Z)[order]
        A = X.T @ HZ[:m] + HZ[m:]
        Mp = mass[order]
        B = X.T @ (Mp[:m, None] * X)
        B[np.diag_indices(n - m)] += Mp[m:]
        k = min(k, n - m)
        values, y = eigh(0.5 * (A + A.T), 0.5 * (B + B.T), subset_by_index=[0, k - 1],
                         check_finite=False)
        return values, Z @ y
