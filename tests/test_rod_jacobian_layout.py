"""ClosedRodEnergy's edge-length Jacobian from its remembered CSR layout against
scipy's COO assembly (the former code): the same matrix bit for bit (indices,
index dtype, values, the sign of stored zeros), on bent and planar rings."""

import numpy as np
import pytest
import scipy.sparse as sp

from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod


def _coo_jacobian(rod, q):
    m = rod.n_constraints
    e = rod._edge_vectors(q)[rod._constrained] / rod.rod.edge_length
    nodes = rod.edge_nodes[rod._constrained]
    a = 3 * nodes[:, :1] + np.arange(3)
    b = 3 * nodes[:, 1:] + np.arange(3)
    return sp.csr_matrix((np.concatenate([-e, e], axis=1).ravel(),
                          (np.repeat(np.arange(m), 6), np.concatenate([a, b], axis=1).ravel())),
                         shape=(m, rod.n_dofs))


@pytest.mark.parametrize("n", [8, 37, 200])
def test_edge_length_jacobian_equals_the_coo_assembly_bit_for_bit(n):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    bent = circle(n)
    bent[:, 2] += 0.03 * np.sin(2 * t)
    rod = ClosedRodEnergy(Rod(n_nodes=n, twist_stiffness=2 / 3), bent, 1.0)
    rng = np.random.default_rng(n)
    for q in (bent.ravel(), circle(n).ravel(), bent.ravel() + 1e-3 * rng.standard_normal(3 * n)):
        for J in (rod.constraint_jacobian(q),  # the states after the first: the remembered layout
                  rod.constraint_jacobian_arrays(q).tocsr()):
            ref = _coo_jacobian(rod, q)
            assert J.has_canonical_format and ref.has_canonical_format
            for mine, theirs in ((J.indptr, ref.indptr), (J.indices, ref.indices)):
                assert mine.dtype == theirs.dtype and np.array_equal(mine, theirs)
            assert np.array_equal(J.data, ref.data)
            assert np.array_equal(np.signbit(J.data), np.signbit(ref.data))
