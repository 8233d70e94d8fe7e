"""The rod's fused kernels against the steps they replaced.

* ``kernels.gradient_terms``: the bending and reference-twist gradients of
  ``bending_terms`` / ``twist_terms`` at order 1 on ``q[dofs]``, scattered with
  ``np.bincount`` (``StencilPattern.scatter_vector``), and the twists;
* ``kernels.edge_length_terms``: ``(np.sum(e * e, axis=1) - h * h) / (2 * h)`` and
  ``take_along_axis([-e / h, e / h], order)``;
* ``RodEnergy.gradient`` / ``constraints`` / ``constraint_jacobian``: the former numpy
  code on closed and clamped rods, for all curvature forms, bit for bit, also after
  the frames move (``accept``) and for repeated states (the memos);
* ``ExtendedSystem.jacobian`` (no phase rows): ``csr_columns`` of the problem's Jacobian.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.continuation.system import ExtendedSystem
from supercoil.geometry.curves import circle
from supercoil.rod import kernels
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.solvers.csr import csr_columns


def _bent_ring(n: int, form: str):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = circle(n)
    x[:, 2] += 0.05 * np.sin(2 * t)
    return ClosedRodEnergy(Rod(n_nodes=n, twist_stiffness=2 / 3, curvature=form), x, 1.3), x


def _buckled_clamped(n: int, form: str):
    x = straight_rod(n)
    s = np.linspace(0, 1, n)
    x[2:-2, 0] += 0.02 * np.sin(np.pi * s[2:-2]) ** 2
    x[2:-2, 1] += 0.01 * np.sin(2 * np.pi * s[2:-2])
    rod = Rod(n_nodes=n, twist_stiffness=4 / 3, curvature=form, closed=False)
    return ClampedRodEnergy(rod, straight_rod(n), turns=0.7, tension=3.0), x


def _former_gradient(energy, q):
    """RodEnergy.gradient before residual13 (its numpy steps), on the same frames."""
    stencils = energy._stencils(q)
    g = energy._pattern.scatter_vector(
        kernels.bending_terms(stencils, energy._bend_weight, energy._curvature, 1)[1])
    values, local, _ = kernels.twist_terms(stencils, energy._frame_data, 1)
    phi = float(values.sum())
    twist_gradient = energy._pattern.scatter_vector(local)
    tw = energy.twist_offset() + phi / (2 * np.pi)
    out = g + (energy._twist_coefficient * tw / (2 * np.pi)) * twist_gradient
    if isinstance(energy, ClampedRodEnergy):
        out[2] += energy.tension
        out[-1] -= energy.tension
    return out, phi


def _former_constraints(energy, q):
    e = energy._edge_vectors(q)[energy._constrained]
    h = energy.rod.edge_length
    return (np.sum(e * e, axis=1) - h * h) / (2 * h)


def _former_jacobian_data(energy, q):
    e = energy._edge_vectors(q)[energy._constrained] / energy.rod.edge_length
    order = energy._jacobian_layout_of_constrained()[1]
    return np.take_along_axis(np.concatenate([-e, e], axis=1), order, axis=1).ravel()


@pytest.mark.parametrize("form", ["angle", "tan", "sin"])
@pytest.mark.parametrize("make", [_bent_ring, _buckled_clamped])
def test_gradient_constraints_and_jacobian_equal_the_former_steps(form, make):
    energy, x = make(40, form)
    rng = np.random.default_rng(5)
    q = x.ravel()
    for step in range(4):
        for _ in range(2):  # the second call at a state from the memos
            g = energy.gradient(q)
            expected, phi = _former_gradient(energy, q)
            assert g.tobytes() == expected.tobytes()
            assert energy.reference_twist_total(q) == phi
            c = energy.constraints(q)
            assert c.tobytes() == _former_constraints(energy, q).tobytes()
            c[:] = 1.0  # the caller's copy: the memo keeps its values
            assert energy.constraints(q).tobytes() == _former_constraints(energy, q).tobytes()
            J = energy.constraint_jacobian(q)
            data = _former_jacobian_data(energy, q)
            assert J.data.tobytes() == data.tobytes()
            assert np.array_equal(np.signbit(J.data), np.signbit(data))
        q = q + 2e-3 * rng.standard_normal(q.size)
        if step == 1:
            energy.accept(q)  # new frames: nothing remembered may be reused


def test_gradient_terms_and_edge_length_terms_refuse_wrong_shapes():
    energy, x = _bent_ring(12, "angle")
    with pytest.raises(ValueError, match="curvature form"):
        kernels.gradient_terms(x.ravel(), energy._pattern.dofs, energy._bend_weight, "bad",
                               energy._frame_data, energy.n_dofs)
    with pytest.raises(ValueError, match=r"\(n, 9\)"):
        kernels.gradient_terms(x.ravel(), energy._pattern.dofs[:-1], energy._bend_weight,
                               "angle", energy._frame_data, energy.n_dofs)
    values, data = kernels.edge_length_terms(x, np.zeros((0, 2), np.int64), 0.1,
                                             np.zeros((0, 6), np.int64))
    assert values.shape == (0,) and data.shape == (0,)


def test_free_jacobian_equals_csr_columns_of_the_problems_jacobian():
    energy, x = _buckled_clamped(30, "angle")
    system = ExtendedSystem(energy, "turns", x.ravel())
    rng = np.random.default_rng(2)
    for k in range(5):
        state = system.pack(x.ravel() + 1e-3 * k * rng.standard_normal(x.size),
                            np.zeros(system.m), energy.turns)
        J_free = system.jacobian(state)
        ref = csr_columns(energy.constraint_jacobian(system.q(state)), system.free)
        for mine, theirs in ((J_free.indptr, ref.indptr), (J_free.indices, ref.indices),
                             (J_free.data, ref.data)):
            assert mine.dtype == theirs.dtype and mine.tobytes() == theirs.tobytes()
        assert J_free.shape == ref.shape
    # another constrained set (another pattern): the map is made again
    energy.set_constrained_edges(np.arange(3, 20))
    system = ExtendedSystem(energy, "turns", x.ravel())
    J_free = system.jacobian(system.pack(x.ravel(), np.zeros(system.m), energy.turns))
    ref = csr_columns(energy.constraint_jacobian(x.ravel()), system.free)
    assert J_free.shape == ref.shape and J_free.data.tobytes() == ref.data.tobytes()
    assert J_free.indices.tobytes() == ref.indices.tobytes()
