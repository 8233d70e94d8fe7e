"""The per-point stability against fresh and dense computations.

``point_stability`` computes the Hessian of the Lagrangian once on all DOFs and
restricts it for the count and for the eigenproblem, and orders the eigenproblem's
shift-invert factor from the count's. Oracles: the restricted Hessian equals
``ExtendedSystem.hessian`` bit for bit; the count and determinant sign equal those of
the dense matrix's eigenvalues; the eigenvalues equal the dense constrained
eigenproblem's and those of a freshly ordered factor to round-off.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import null_space

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation.options import ContinuationOptions
from supercoil.continuation.phase import branch_phase_modes
from supercoil.continuation.stability import (
    count_system,
    eigenpairs,
    inertia,
    point_stability,
)
from supercoil.continuation.system import ExtendedSystem
from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.lu import BandLU


def contact_ring_system(n: int = 60, amplitude: float = 0.03, excess_link: float = 2.5):
    """A bent, twisted ring with integral barrier contact and the integral phase row."""
    x = circle(n)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x[:, 2] += amplitude * np.sin(2 * t)
    x[:, 0] *= 1.0 + 0.1 * np.cos(2 * t)
    rod = ClosedRodEnergy(Rod(n_nodes=n, twist_stiffness=2 / 3), x, excess_link)
    problem = ContactProblem(rod, ContactOptions(diameter=0.05, formulation="integral"))
    q = x.ravel()
    modes = branch_phase_modes(problem, q, ContinuationOptions(gauge="integral"))
    assert modes is not None and modes.shape[0] == 1
    system = ExtendedSystem(problem, "excess_link", q, modes, q)
    mu = np.linspace(-1.0, 1.0, problem.n_constraints)
    return system, system.pack(q, mu, excess_link)


@pytest.mark.parametrize("excess_link", [0.5, 2.5, 6.0])
def test_point_stability_equals_the_fresh_count_and_eigenpairs(excess_link):
    system, x = contact_ring_system(excess_link=excess_link)
    full = system.full_hessian(x)
    fresh = system.hessian(x)
    restricted = full.restrict(system.free)
    for a, b in ((restricted.sparse.data, fresh.sparse.data),
                 (restricted.sparse.indices, fresh.sparse.indices),
                 (restricted.sparse.indptr, fresh.sparse.indptr),
                 (restricted.vectors, fresh.vectors),
                 (restricted.coefficients, fresh.coefficients)):
        assert np.array_equal(a, b)

    tol, n_modes = 1e-6, 6
    stab = point_stability(system, x, tol, n_modes)
    # the count on a freshly assembled Hessian, and the dense oracle
    H, J = count_system(system, x)
    assert isinstance(KKTFactor(H, J)._lu, BandLU)  # a narrow band: LAPACK's band LU
    neg, det_sign = inertia(system, x, tol)
    assert stab.negative_count == neg
    assert stab.determinant_sign == det_sign
    Z = null_space(J.toarray())
    values = np.linalg.eigvalsh(Z.T @ H.dense() @ Z)
    assert neg == int(np.sum(values < 0))
    assert det_sign == int(np.prod(np.sign(values)))


@pytest.mark.parametrize("excess_link", [0.5, 2.5, 6.0])
def test_eigenpairs_equal_the_dense_constrained_eigenpairs_to_round_off(excess_link):
    """Band LU and standard-mode Lanczos on the scaled shift-invert operator; the
    oracle: the dense constrained eigenproblem's eigenvalues nearest the shift, and
    its residual for the modes (``H v - mu M v`` orthogonal to the constrained space)."""
    from supercoil.stability.analysis import eigen_system

    system, x = contact_ring_system(excess_link=excess_link)
    values, modes = eigenpairs(system, x, 8)
    scale = np.max(np.abs(values))
    np.testing.assert_allclose(values, _dense_nearest(system, x, values.size), rtol=0,
                               atol=1e-9 * scale)
    dofs, H, J, mass, sym = eigen_system(system.problem, system.q(x), system.multipliers(x))
    Z = null_space(np.vstack([J.toarray(), (mass[:, None] * sym).T]))
    Hd = H.dense()
    for mu, mode in zip(values, modes[:, dofs], strict=True):
        residual = Z.T @ (Hd @ mode - mu * mass * mode)
        assert np.max(np.abs(residual)) <= 1e-6 * scale * np.max(np.abs(mode))


def test_the_hessian_before_accept_serves_the_point_after_it():
    """add_point passes the converged correction's Hessian, assembled before the accept
    that carries the reference frames to the point: the accept changes it by round-off,
    and the count and eigenvalues from it equal the fresh ones."""
    system, x = contact_ring_system(excess_link=2.5)
    rng = np.random.default_rng(5)
    problem = system.problem
    n = problem.n_dofs // 3
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    bump = np.stack([np.cos(3 * t), np.sin(2 * t), np.cos(t + rng.uniform())], axis=1)
    x2 = x.copy()
    x2[:system.n] += 0.02 * bump.ravel()[system.free]  # the frames turn by a few degrees
    before = system.full_hessian(x2)
    problem.accept(system.q(x2))
    after = system.full_hessian(x2)
    scale = np.max(np.abs(after.sparse.data))
    assert np.max(np.abs((before.sparse - after.sparse).data), initial=0.0) <= 1e-13 * scale
    np.testing.assert_allclose(before.vectors, after.vectors, rtol=0,
                               atol=1e-13 * np.max(np.abs(after.vectors)))
    np.testing.assert_allclose(before.coefficients, after.coefficients, rtol=1e-13)
    reused = point_stability(system, x2, 1e-6, 6, before)
    fresh = point_stability(system, x2, 1e-6, 6)
    assert (reused.negative_count, reused.unstable_count, reused.zero_modes,
            reused.determinant_sign) == (fresh.negative_count, fresh.unstable_count,
                                         fresh.zero_modes, fresh.determinant_sign)
    np.testing.assert_allclose(reused.eigenvalues, fresh.eigenvalues, rtol=0,
                               atol=1e-9 * np.max(np.abs(fresh.eigenvalues)))


def _dense_nearest(system, x, k):
    """The ``k`` eigenvalues nearest the shift-invert's shift (-1e-3), from the dense
    constrained eigenproblem (the oracle of the sparse paths), ascending."""
    from supercoil.stability.analysis import eigen_system
    from supercoil.stability.eigen import dense_constrained_eigenpairs

    problem = system.problem
    _dofs, H, J, mass, sym = eigen_system(problem, system.q(x), system.multipliers(x))
    values, _ = dense_constrained_eigenpairs(H, J, mass, sym)
    return np.sort(values[np.argsort(np.abs(values + 1e-3))[:k]])


@pytest.mark.parametrize("excess_link", [0.5, 2.5, 6.0])
def test_eigen_factor_ordered_from_the_count_equals_the_fresh_ordering(excess_link):
    """point_stability orders the shift-invert factor from the count's
    (related_order: the six rigid gauge pins inserted, the dense phase row left out):
    the same eigenvalues as with a fresh kkt_order and as the dense oracle, to round-off,
    the same modes, and a band no wider than the fresh ordering's."""
    from supercoil.continuation.stability import inertia_with_factor, related_order
    from supercoil.stability.analysis import eigen_system

    system, x = contact_ring_system(excess_link=excess_link)
    tol, n_modes = 1e-6, 6
    stab = point_stability(system, x, tol, n_modes)
    fresh_values, fresh_modes = eigenpairs(system, x, stab.negative_count + n_modes)
    scale = np.max(np.abs(fresh_values))
    np.testing.assert_allclose(stab.eigenvalues, fresh_values, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(stab.eigenvalues, _dense_nearest(system, x, fresh_values.size),
                               rtol=0, atol=1e-9 * scale)
    overlap = np.abs(np.einsum("ij,ij->i", stab.modes * system.problem.mass, fresh_modes))
    assert np.all(overlap > 1 - 1e-8)

    _neg, _sign, factor, dofs, _left_out = inertia_with_factor(system, x, tol, None)
    problem = system.problem
    eigen_dofs, H, J, mass, _sym = eigen_system(problem, system.q(x), system.multipliers(x))
    assert eigen_dofs.size == dofs.size + 6 and factor.m == J.shape[0] + system.r
    order = related_order(factor.order, dofs, factor.m, eigen_dofs, J.shape[0], H.sparse)
    assert np.array_equal(np.sort(order), np.arange(eigen_dofs.size + J.shape[0]))
    derived = KKTFactor(H, J, shift=-1e-3, mass=mass, order=order)._lu
    fresh = KKTFactor(H, J, shift=-1e-3, mass=mass)._lu
    assert isinstance(derived, BandLU) and isinstance(fresh, BandLU)
    assert derived._kl <= fresh._kl and derived._ku <= fresh._ku


def test_related_order_keeps_the_old_sequence_and_places_new_dofs_between_neighbours():
    """Exact: a path graph 0-1-2-3-4 whose DOF 2 is new; the old ordering of DOFs
    (0, 1, 3, 4) and rows (r0, r1, a third row dropped) is kept; DOF 2 couples to 1 and
    3 and goes midway between them; an uncoupled new DOF goes last."""
    import scipy.sparse as sp

    from supercoil.continuation.stability import related_order

    dofs = np.array([0, 1, 3, 4])
    # old unknowns: DOFs 0, 1, 3, 4 (indices 0-3), rows 4, 5, 6
    old_order = np.array([0, 4, 1, 5, 6, 2, 3])
    path = sp.diags([np.ones(4), np.ones(5), np.ones(4)], [-1, 0, 1], format="csr")
    order = related_order(old_order, dofs, 3, np.arange(5), 2, path)
    # new unknowns: DOFs 0-4 (indices 0-4), rows 5, 6; DOF 2 between 1 (rank 2) and 3
    assert order.tolist() == [0, 5, 1, 6, 2, 3, 4]
    with_lonely = sp.block_diag((path, sp.identity(1)), format="csr")
    order = related_order(old_order, dofs, 3, np.arange(6), 2, with_lonely)
    assert order.tolist() == [0, 6, 1, 7, 2, 3, 4, 5]
    # not a subsystem (an old DOF missing from the new ones, or more rows): None
    assert related_order(old_order, dofs, 3, np.array([0, 1, 2, 4]), 2, path[:4, :4]) is None
    assert related_order(old_order, dofs, 3, np.arange(5), 4, path) is None


def test_eigen_system_jacobian_equals_scipy_column_slicing():
    """eigen_system takes the constraint Jacobian's eigen-DOF columns by csr_columns:
    the arrays of scipy's ``J[:, dofs]``, bit for bit (pattern, explicit zeros, order)."""
    from supercoil.stability.analysis import eigen_system

    system, x = contact_ring_system(excess_link=2.5)
    problem = system.problem
    q = system.q(x)
    dofs, _H, J, _mass, _sym = eigen_system(problem, q, system.multipliers(x))
    reference = problem.constraint_jacobian(q)[:, dofs]
    assert J.shape == reference.shape and J.format == reference.format == "csr"
    for a, b in ((J.indptr, reference.indptr), (J.indices, reference.indices),
                 (J.data, reference.data)):
        assert a.dtype == b.dtype and np.array_equal(a, b)
