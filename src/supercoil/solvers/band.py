"""LAPACK's band LU of a reordered sparse matrix: where its entries go in band storage.

After a bandwidth-reducing ordering (:func:`bandwidth_order`, reverse
Cuthill–McKee) a sparse matrix of half-bandwidths ``kl``, ``ku`` is factorised
by LAPACK's band LU with partial pivoting (``dgbtrf``) in ``O(n kl (kl + ku))``;
the row interchanges stay within ``kl`` more diagonals. :class:`BandLayout`
says where each stored entry goes in LAPACK's band storage, so that a matrix
of a known pattern is poured into it by one scatter (the layout is remembered
per pattern by the callers). The exact inertia of symmetric band matrices is
in :mod:`supercoil.solvers.inertia`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.csgraph import reverse_cuthill_mckee

from supercoil._numba import njit


def band_lu(size: int, rows: np.ndarray, cols: np.ndarray, values: np.ndarray,
            max_fraction: float = 0.25):
    """LAPACK's band LU (``dgbtrf``) of the ``(size, size)`` matrix with entries ``values``
    at ``(rows, cols)`` (no duplicates): ``(lub, piv, kl, ku, info)``, or None when the
    band ``kl + ku + 1`` is wider than ``max_fraction`` of ``size`` (a sparse LU pays
    then). ``info > 0``: a pivot is exactly zero; ``info < 0``: a bad argument.
    The same as :func:`band_layout` then :func:`band_factor`."""
    layout = band_layout(size, rows, cols, max_fraction)
    return None if layout is None else band_factor(layout, values)


class BandLayout:
    """Where the entries at ``(rows, cols)`` go in LAPACK's band storage of a
    ``(size, size)`` matrix: the half-bandwidths ``kl``, ``ku`` and the offsets
    ``positions`` of the entries in the Fortran-ordered ``(2 kl + ku + 1, size)``
    array ``ab`` (``ab[kl + ku + i - j, j] = a_ij``). It depends on the pattern only:
    callers remember it per pattern and fill it with each matrix's values.
    ``dropped``: entries outside the band (None: none), which must be zero
    (:func:`band_layout_of_nonzeros`); their offsets point past ``ab``."""

    __slots__ = ("dropped", "kl", "ku", "positions", "size")

    def __init__(self, size: int, kl: int, ku: int, positions: np.ndarray,
                 dropped: np.ndarray | None = None):
        self.size, self.kl, self.ku, self.positions = size, kl, ku, positions
        self.dropped = dropped

    @property
    def storage_size(self) -> int:
        """Length of the flat band storage: ``ab`` ``(2 kl + ku + 1, size)``, and one slot
        past it for the dropped entries."""
        return (2 * self.kl + self.ku + 1) * self.size + (self.dropped is not None)

    @property
    def nbytes(self) -> int:  # for PatternMemo's memory bound
        return int(self.positions.nbytes) + (0 if self.dropped is None
                                             else int(self.dropped.nbytes))

    def holds(self, values: np.ndarray) -> bool:
        """Whether the matrix with ``values`` at the entries is within the band (every
        dropped entry is zero)."""
        return self.dropped is None or not np.any(values[self.dropped])


def band_layout(size: int, rows: np.ndarray, cols: np.ndarray,
                max_fraction: float = 0.25) -> BandLayout | None:
    """The :class:`BandLayout` of the entries at ``(rows, cols)``, or None when the
    band ``kl + ku + 1`` is wider than ``max_fraction`` of ``size`` (:func:`band_lu`)."""
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    compiled = rows.ndim == 1 and rows.shape == cols.shape and rows.size > 0
    if compiled:
        kl, ku = _band_widths(rows, cols)
    else:  # numpy's broadcasting and errors (an empty pattern), as before
        kl = int(max(0, np.max(rows - cols)))
        ku = int(max(0, np.max(cols - rows)))
    if kl + ku + 1 > size * max_fraction:
        return None
    positions = _band_positions(rows, cols, kl, ku) if compiled \
        else cols * (2 * kl + ku + 1) + (kl + ku + rows - cols)
    positions.flags.writeable = False  # shared by the factors of one pattern
    return BandLayout(size, kl, ku, positions)


@njit()
def _band_widths(rows, cols):
    """``(max(0, max(rows - cols)), max(0, max(cols - rows)))`` in one compiled pass
    (numpy's temporaries were half of a new pattern's layout at N = 100)."""
    kl = ku = 0
    for i in range(rows.size):
        kl = max(kl, rows[i] - cols[i])
        ku = max(ku, cols[i] - rows[i])
    return kl, ku


@njit()
def _band_positions(rows, cols, kl, ku):
    """``cols * (2 kl + ku + 1) + (kl + ku + rows - cols)``: the offsets in ``ab``."""
    positions = np.empty(rows.size, dtype=np.int64)
    for i in range(rows.size):
        positions[i] = cols[i] * (2 * kl + ku + 1) + (kl + ku + rows[i] - cols[i])
    return positions


def band_layout_of_nonzeros(size: int, rows: np.ndarray, cols: np.ndarray,
                            values: np.ndarray, max_fraction: float = 0.25
                            ) -> BandLayout | None:
    """:func:`band_layout` of the band of the entries whose ``values`` are not zero; the
    stored zeros outside it are ``dropped`` (the layout then :meth:`BandLayout.holds`
    only values that are zero there too). A straight rod's Hessian and Jacobian store
    zeros that couple far unknowns (the lateral DOFs at rest): the stored band of its
    bordered matrix is 769 wide at N = 100 (388 unknowns), its nonzero band 7 to 13,
    and SuperLU, which takes stored zeros for fill, needed 3-5 ms against 0.1 ms."""
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    nonzero = np.asarray(values) != 0.0
    if not np.any(nonzero):
        return None
    kl = int(max(0, np.max((rows - cols)[nonzero])))
    ku = int(max(0, np.max((cols - rows)[nonzero])))
    if kl + ku + 1 > size * max_fraction:
        return None
    outside = (rows - cols > kl) | (cols - rows > ku)
    if not np.any(outside):
        return band_layout(size, rows, cols, max_fraction)
    positions = cols * (2 * kl + ku + 1) + (kl + ku + rows - cols)
    positions[outside] = (2 * kl + ku + 1) * size  # the slot past ab
    positions.flags.writeable = False
    dropped = np.flatnonzero(outside)
    dropped.flags.writeable = False
    return BandLayout(size, kl, ku, positions, dropped)


def band_factor(layout: BandLayout, values: np.ndarray):
    """``dgbtrf`` of the matrix with ``values`` at ``layout``'s entries:
    ``(lub, piv, kl, ku, info)`` as :func:`band_lu` (the values of dropped entries,
    zeros, go to a slot past ``ab``).

    ``ab`` is made in Fortran order and factorised in place (``overwrite_ab``): the
    C-ordered array made before was copied by the wrapper first (measured at
    n = 795, ``kl = ku = 43``: 0.57 ms against 0.48 ms a factorisation with the
    factors kept alive; the same LAPACK call on the same numbers, the same result
    bit for bit)."""
    flat = np.zeros(layout.storage_size)
    flat[layout.positions] = values
    return factor_band_storage(layout, flat)


def factor_band_storage(layout: BandLayout, flat: np.ndarray):
    """:func:`band_factor` of the band storage already filled: ``flat``
    (``layout.storage_size``, float64) holds ``ab`` in Fortran order, then the slot of
    the dropped entries if any; it is factorised in place."""
    kl, ku, size = layout.kl, layout.ku, layout.size
    ab = flat[:(2 * kl + ku + 1) * size].reshape((2 * kl + ku + 1, size), order="F")
    lub, piv, info = lapack.dgbtrf(ab, kl, ku, overwrite_ab=1)
    return lub, piv, kl, ku, info


def bandwidth_order(A: sp.spmatrix) -> np.ndarray:
    """Reverse Cuthill–McKee ordering of a symmetric sparse matrix."""
    n = A.shape[0]
    pattern = sp.csr_matrix(A, copy=True)
    pattern.eliminate_zeros()
    pattern = (abs(pattern) + sp.identity(n)).tocsr()
    return np.asarray(reverse_cuthill_mckee(pattern, symmetric_mode=True), dtype=np.int64)
