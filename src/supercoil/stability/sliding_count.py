"""The sliding's eigenvalue left out of the unstable count, where the sliding is stiff.

The count leaves out an approximate symmetry ``g`` (the material sliding of a ring,
the sliding of a localised loop or plectoneme along a long open rod) by counting on
the M-orthogonal complement of ``g`` (:func:`~supercoil.continuation.stability.count_rows`,
or the branch's own phase row). That is the count with the sliding's eigenvalue left out
only while ``g`` is an eigenvector of the constrained Hessian, as in the continuum. In
self-contact the discrete contact's ripple gives the sliding an eigenvalue of either
sign much larger than the gap to the next ones (``-1e4`` to ``-1e5`` against a next
eigenvalue of ``500-2000`` along the tweezers' plectoneme at L/D = 200, F L^2/A = 100,
C/A = 1, N = 202 and 303), and the discrete sliding mode ``v_s`` is ``g`` only to
an overlap of ``0.82-0.9``: on the complement of ``g`` the rest of ``v_s`` (odd under
the half-turn, as ``g``) still has a negative curvature, and the count was one where
the constrained Hessian's only negative eigenvalue is the sliding's. That count came
and went with the ripple: at N = 202 from 3.27 to 3.90 and from 4.82 turns, at N = 303
from 3.12 to 4.12 and from 4.57 turns; the fold-bounded instability between 2.20 and
2.50 turns (an even mode) the same at both.

With ``b = M g`` the bordered inertia gives ``n_g = n_f - 1 + [b^T H^-1 b > 0]``
(``n_g`` the count on the complement of ``g``, ``n_f`` the count without the
row): where ``n_g < n_f`` the row removed a negative eigenvalue, the sliding's. Where
``n_g = n_f >= 1``, :func:`sliding_left_out` finds the ``n_f`` negative eigenpairs of
the constrained Hessian without the row and leaves one out when ``g`` lies mostly in
their span (``sum (v_i^T M g)^2 >= g^T M g / 2``, the v_i M-orthonormal): the
sliding's eigenvalue is then one of them, and the count is ``n_f - 1``, as on the
complement of ``v_s``. The branches' count (:mod:`supercoil.continuation.stability`)
and a state's own report (:func:`~supercoil.stability.analysis.analyse`) both apply it,
where a contact acts (:func:`contact_acts`).

Where the sliding is no approximate symmetry (a plectoneme that reaches towards the
clamps, its tail ratio above the contact branch's threshold: no phase row, the count on
all of ``ker J``), the ripple can still set its eigenvalue: at L/D = 100, lambda = 80,
C/A = 1.5 from 21.7 turns (tail ratio 0.26) to the spanning ply, -2.2e5 to -1.6e5 at
N = 243 while N = 364 had it positive up to 23.9 turns, against next eigenvalues of
130-210 that agree between the two, and the counts differed at 71 states. There the
eigenvalue is left out only as the ripple's, ``RIPPLE_RATIO`` times the other lowest
eigenvalues at least (``ratio`` of :func:`sliding_left_out`): a structure that the
clamps make unstable along its sliding does so on the elastic scale, and stays counted.

The sliding is not the ripple's only mode. Where the ply fills the rod (L/D = 200,
lambda = 150, C/A = 1.5, N = 678, past 44.9 turns, the hard-core ply spanning the rod at
44.05), the four eigenvalues nearest zero were positive (135 to 2.9e4) and the same at
N = 1017, but two were far below them: the sliding's (-1.9e6 to -3.2e6, overlap 0.94-0.96
with ``g``) and a second (-4.6e4 to -7.7e5, overlap 0.17-0.25 with ``g``); both move the
nodes along the centreline (0.94-0.98 and 0.91-0.97 of the mode's M-norm along the
tangents, ``tangent_rows``, against 0.11-0.14 for the elastic mode nearest zero), the
second with an amplitude that varies along the rod, once and a quarter over it (a
harmonic of the sliding). A motion ``u t`` of an inextensible rod along its own centreline is a
change of parametrisation where ``u`` is constant; a varying ``u`` bends the curve only
by ``w = u' / kappa`` (``t . x' = 1`` kept), little on a tightly curved ply, so the
continuum gives such a mode a small eigenvalue, and the discrete contact (which pairs
of nodes touch, and where between them) a large one of either sign. With ``tangents``
(the far case), a negative eigenpair of the ``negative + 1`` lowest that is mostly the
sliding or mostly along the centreline (``TANGENTIAL_SHARE`` of its M-norm at least) is
left out where its eigenvalue lies below ``-ratio`` times the largest magnitude among
those not left out: on that mesh, at eight states from 41.95 to 47.76 turns, the count
was 1-2 from 45.1 turns with the sliding's mode alone left out, 0 at all eight with
both, as N = 1017's.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil.solvers.errors import InertiaError, SingularMatrixError
from supercoil.solvers.kkt import KKTFactor
from supercoil.stability.eigen import dense_path, lowest_dense_pairs, lowest_pairs

# the share of |g|_M^2 in the span of the negative eigenvectors above which the sliding's
# eigenvalue is one of them (more than half: at most one eigenvector of an orthonormal
# set can carry it)
SLIDING_SHARE = 0.5
# where the sliding is no approximate symmetry (its tails not straight: a plectoneme that
# reaches towards the clamps), its negative eigenvalue is the contact's ripple, left out
# of the count, only where it exceeds the next eigenvalues by this factor: measured at
# L/D = 100, lambda = 80, C/A = 1.5 beyond 21.7 turns (tail ratio 0.26-0.98), -1.6e5 to
# -2.2e5 at N = 243 and -7.2e4 at N = 364 against next eigenvalues of 130-210 that agree
# between the meshes, while the sliding's sign did not (module doc); an instability of
# the structure's position against the clamps is on the elastic scale, the next ones'
RIPPLE_RATIO = 10.0
# the share of a mode's M-norm along the centreline at or above which it is mostly a
# motion of the material along its own curve (module doc: 0.91-0.98 for the ripple's
# modes of a spanning ply, 0.11-0.14 for the elastic mode nearest zero, which changes
# the curve's shape and moves the nodes across it)
TANGENTIAL_SHARE = 0.5
# shifts tried below the spectrum for the lowest eigenpairs: -1, -10, ..., -1e12
_SHIFTS = -(10.0 ** np.arange(0, 13))


def contact_acts(problem, q: np.ndarray) -> bool:
    """Whether a contact acts on ``problem`` at ``q`` (its contact energy positive): only
    there does the sliding carry the contact's stiff part that the complement of ``g``
    keeps (measured on the ring diagram of ``supercoil demo``: 30 of the 40 eigen-solves
    of :func:`sliding_left_out` were on its contact-free branches, none leaving one out)."""
    energy = getattr(problem, "contact_energy", None)
    return energy is not None and bool(energy(q) > 0.0)


def without_sliding_pairs(values: np.ndarray, modes: np.ndarray, sliding: np.ndarray,
                          mass: np.ndarray, tangents: sp.csr_matrix | None = None,
                          count: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The eigenpairs ``(values (k,), modes (k, n))`` (M-orthonormal, ascending) less those
    that are mostly one of the approximate symmetries ``sliding`` ``(r, n)`` (``(v^T M
    g)^2 >= SLIDING_SHARE g^T M g``) or, with ``tangents`` (``(nodes, n)``,
    :func:`sliding_left_out`), mostly along the centreline; with ``count``, only the
    ``count`` lowest negative ones of those (the eigenvalues a count left out)."""
    if sliding.size == 0 or values.size == 0:
        return values, modes
    drop = _ripple_like(modes.T, sliding, mass, tangents)
    if count is not None:
        drop &= values < 0.0
        drop &= np.cumsum(drop) <= count
    return values[~drop], modes[~drop]


def _ripple_like(vectors: np.ndarray, sliding: np.ndarray, mass: np.ndarray,
                 tangents: sp.csr_matrix | None) -> np.ndarray:
    """``(k,)`` bool: the columns of ``vectors`` ``(n, k)`` mostly one of ``sliding`` or,
    with ``tangents``, mostly along the centreline (``TANGENTIAL_SHARE``)."""
    norms = np.sum(vectors * (mass[:, None] * vectors), axis=0)
    share = (vectors.T @ (mass * sliding).T) ** 2 / np.sum(sliding * mass * sliding,
                                                           axis=1)[None, :]
    like = share.max(axis=1) / norms >= SLIDING_SHARE
    if tangents is not None:
        along = np.sum(np.asarray(tangents @ (np.sqrt(mass)[:, None] * vectors)) ** 2,
                       axis=0)
        like |= along / norms >= TANGENTIAL_SHARE
    return like


def sliding_left_out(H, J: sp.csr_matrix, sliding: np.ndarray, mass: np.ndarray,
                     negative: int, shift: float = 0.0, ratio: float | None = None,
                     tangents: sp.csr_matrix | None = None) -> int:
    """1 if the sliding's negative eigenvalue is among the ``negative`` that the count on
    the complement of ``sliding`` found, else 0 (module doc); with ``ratio`` and
    ``tangents``, the number of the ripple's negative eigenvalues among them.

    ``H``: the Hessian of the Lagrangian on the count's DOFs (``(n, n)``,
    :class:`~supercoil.assembly.HessianParts`), ``J``: the constraint rows without
    the sliding's (``(m, n)``), ``sliding``: the approximate symmetry's generators on
    those DOFs (``(r, n)``), ``mass``: ``(n,)``, ``shift``: the count's (the count of
    eigenvalues below ``shift``). ``ratio``: for a sliding that is no approximate
    symmetry (module doc), 1 only where the eigenvector mostly the sliding (its share
    ``(v^T M g)^2 >= SLIDING_SHARE g^T M g``) has an eigenvalue below ``-ratio`` times
    the largest magnitude among the others of the ``negative + 1`` lowest (those left
    out with it excepted, :func:`_ripple`). ``tangents``
    (``(nodes, n)``, the rod's ``tangent_rows`` on those DOFs): with ``ratio``, the
    eigenpairs mostly along the centreline are the ripple's too (module doc)."""
    if negative <= 0 or sliding.shape[0] == 0:
        return 0
    try:
        full = KKTFactor(H, J, shift=shift, mass=mass).reduced_negative_count
    except (SingularMatrixError, InertiaError):
        return 0
    if full != negative:
        return 0  # the row took out a negative eigenvalue: the sliding's
    if ratio is not None:
        return _ripple(H, J, sliding, mass, full, shift, ratio, tangents)
    values, vectors = _lowest(H, J, mass, full)
    vectors = vectors[:, values < shift]
    share = 0.0
    for g in sliding:
        norm = float(g @ (mass * g))
        if norm > 0.0:
            share = max(share, float(np.sum((vectors.T @ (mass * g)) ** 2)) / norm)
    return int(share >= SLIDING_SHARE)


def _ripple(H, J: sp.csr_matrix, sliding: np.ndarray, mass: np.ndarray, negative: int,
            shift: float, ratio: float, tangents: sp.csr_matrix | None = None) -> int:
    """:func:`sliding_left_out` with ``ratio``: how many of the ``negative`` eigenvalues
    below ``shift`` are the ripple's: of the ``negative + 1`` lowest eigenpairs, those
    below ``shift`` mostly the sliding (or, with ``tangents``, mostly along the
    centreline) and below ``-ratio`` times the largest magnitude among the rest, the
    rest grown by each that fails until none does."""
    values, vectors = _lowest(H, J, mass, negative + 1)
    if values.size < 2:
        return 0
    ripple = _ripple_like(vectors, sliding, mass, tangents) & (values < shift)
    while ripple.any():
        scale = float(np.abs(values[~ripple]).max()) if (~ripple).any() else 0.0
        stiff = ripple & (np.abs(values) >= ratio * scale)
        if np.array_equal(stiff, ripple):
            break
        ripple = stiff
    if tangents is None or tangents.shape[0] == 0:
        return int(min(ripple.sum(), 1))  # the sliding's eigenvalue alone
    return int(ripple.sum())


def _lowest(H, J: sp.csr_matrix, mass: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` lowest eigenpairs of ``H v = mu M v`` on ``ker J`` (M-orthonormal
    vectors ``(n, k)``): shift-invert below the spectrum, at the first shift of
    ``_SHIFTS`` below which no eigenvalue lies; dense, without a shift, for small
    systems (:func:`~supercoil.stability.eigen.dense_path`), the ``k`` lowest only
    (:func:`~supercoil.stability.eigen.lowest_dense_pairs`)."""
    n, m = mass.size, J.shape[0]
    if dense_path(n - m, min(k, n - m - 2)):  # no shift to search for
        return lowest_dense_pairs(H, J, mass, k)
    for sigma in _SHIFTS:
        try:
            below = KKTFactor(H, J, shift=float(sigma), mass=mass).reduced_negative_count
        except (SingularMatrixError, InertiaError):
            continue
        if below == 0:
            return lowest_pairs(H, J, mass, n_wanted=k, n=n, m=m, sigma=float(sigma))
    return np.zeros(0), np.zeros((n, 0))
