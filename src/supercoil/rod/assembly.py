"""Scatter local stencil gradients and Hessians into global vectors and sparse matrices."""

from __future__ import annotations

import numpy as np

from supercoil._numba import njit
from supercoil.solvers.csr import CSRArrays


@njit()
def _accumulate(slot, values, out):
    """``out[slot[k]] += values[k]`` in the order of ``k`` (as ``np.bincount``)."""
    for k in range(slot.size):
        out[slot[k]] += values[k]


class StencilPattern:
    """Precomputed global indices for 3-vertex stencils.

    ``vertex_nodes`` has shape ``(n_stencils, 3)`` (node indices of
    ``x_{i-1}, x_i, x_{i+1}``). Degrees of freedom are the flattened node
    coordinates ``q = points.ravel()`` (node ``a`` owns ``3a, 3a+1, 3a+2``).
    """

    def __init__(self, vertex_nodes: np.ndarray, n_dofs: int):
        self.vertex_nodes = np.asarray(vertex_nodes, dtype=np.int64)
        self.n_dofs = n_dofs
        dofs = (3 * self.vertex_nodes[:, :, None] + np.arange(3)[None, None, :]).reshape(-1, 9)
        self.dofs = dofs  # (n_stencils, 9)
        rows = np.repeat(dofs, 9, axis=1)  # (n_stencils, 81), row-major over the 9x9 block
        cols = np.tile(dofs, (1, 9))
        # Map every local entry onto its slot in a fixed CSR pattern.
        key = rows.ravel() * n_dofs + cols.ravel()
        unique_keys, self._slot = np.unique(key, return_inverse=True)
        urows = unique_keys // n_dofs
        ucols = unique_keys % n_dofs
        indptr = np.zeros(n_dofs + 1, dtype=np.int64)
        np.add.at(indptr, urows + 1, 1)
        # scipy keeps 32-bit indices when they fit; store them so, to save a
        # conversion per matrix.
        index_type = np.int32 if max(n_dofs, unique_keys.size) < 2**31 - 1 else np.int64
        self._indptr = np.cumsum(indptr).astype(index_type)
        self._indices = ucols.astype(index_type)
        self._nnz = unique_keys.size

    def gather(self, q: np.ndarray) -> np.ndarray:
        """Stencil coordinates, shape ``(n_stencils, 9)``."""
        return q[self.dofs]

    def scatter_vector(self, local: np.ndarray) -> np.ndarray:
        """Sum local gradients ``(n_stencils, 9)`` into a global vector ``(n_dofs,)``."""
        return np.bincount(self.dofs.ravel(), weights=np.asarray(local).ravel(),
                           minlength=self.n_dofs)

    def scatter_matrix(self, local: np.ndarray) -> CSRArrays:
        """Sum local Hessians ``(n_stencils, 9, 9)`` into the arrays of a CSR matrix
        ``(n_dofs, n_dofs)`` of the stencils' pattern.

        Entries are summed in stencil order, so symmetric local Hessians give an
        exactly symmetric matrix. The arrays are canonical (the pattern's keys are
        sorted and unique), which spares the sums that take them scipy's check; the
        index arrays are the pattern's, shared (a matrix made from them copies them,
        :meth:`~supercoil.solvers.csr.CSRArrays.tocsr`).
        """
        values = np.ascontiguousarray(local, dtype=np.float64).ravel()
        if values.size != self._slot.size:
            raise ValueError(f"local Hessians must have shape ({len(self.dofs)}, 9, 9)")
        data = np.zeros(self._nnz)
        _accumulate(self._slot, values, data)
        return CSRArrays(data, self._indices, self._indptr, (self.n_dofs, self.n_dofs),
                         canonical=True)
