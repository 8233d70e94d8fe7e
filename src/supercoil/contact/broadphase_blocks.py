"""Prefilters of the broad phase (:mod:`supercoil.contact.broadphase`): the block pairs
that may hold a segment pair within the cutoff.

Methods. ``"kdtree"`` groups the segments, in order of arc length, into blocks
of 8, bounds each block by a sphere, asks a `scipy.spatial.cKDTree` on the
block centres for all block pairs within ``cutoff + 2 max(ρ)``
(``query_pairs``, returned as an array) and drops, vectorised, the block pairs
that fail the sphere test or whose segments are all closer along the rod than
the exclusion; one compiled loop (numba) then applies the exact per-pair tests
to the segment pairs of the remaining block pairs. ``"brute"`` tests all pairs,
vectorised over blocks of rows so that memory stays bounded (about ``2**20``
pairs at a time), then applies the same compiled exact tests; it is the
reference the tests compare against. Both apply the same exact tests to a
superset of the answer, so they return the same array.

Why blocks. When the cutoff is many segment lengths (a tube of diameter ``D``
resolved by ``h ≪ D``), most pairs within the cutoff are neighbours along the
rod that the exclusion drops. On the plectonemic ring of
``benchmarks/bench_contact.py`` at N = 10000 (``D/h ≈ 95``), a tree on the
segment midpoints returns 1.27 million pairs of which 0.28 million are kept;
blocks drop the neighbours a block at a time before any segment pair is formed,
and blocks of 8 segments made the call several times faster than the plain tree
there (and were the fastest, or within 15 % of it, on a random walk and a tight
helix). A block is only compact if consecutive arc lengths are close in space,
as on any rod; a block much wider than the median (a gap in the data) is split
into single segments.

Why a KD tree and not a cell list: a cell list in vectorised numpy returned the
same pairs but needs per-cell-pair temporaries and was an order of magnitude
slower than the compiled tree search on that ring; the tree also needs no cell
size. Its radius uses the largest block sphere, so one very long segment makes
every query wider; rods with comparable segment lengths (every discretisation in
this package) do not suffer from that.

Small rods. Up to 32 blocks (256 segments) the block pairs are all tested at
once in numpy instead (the same pairs: both keep a pair at most the radius
apart), so that a small rod never imports ``scipy.spatial``. Up to 128 segments
the compiled exact tests run on all pairs without any prefilter (the same tests,
so the same array).
"""

from __future__ import annotations

import functools

import numpy as np

# The loose prefilters (tree radius, brute-force blocks) are wider still, so
# that they never drop a pair the exact test keeps.
PREFILTER_SLACK = 1e-9


# Pairs tested at once by the brute-force reference.
_BRUTE_BLOCK_PAIRS = 1 << 20


# Segments per block of the KD tree (measured, see the module docstring).
_BLOCK_SIZE = 8


# A block whose sphere is this many times wider than the median one is split.
_WIDE_BLOCK = 2.0


# Up to this many blocks (256 segments) their pairs are all tested at once instead of
# asking a KD tree (module docstring, "Small rods").
_TREE_ABOVE_BLOCKS = 32


def kdtree_prefilter(
    midpoints: np.ndarray,
    radii: np.ndarray,
    arc_start: np.ndarray,
    arc_end: np.ndarray,
    cutoff: float,
    separation_floor: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block pairs (A, B) holding every segment pair that may pass the exact tests.

    The segments, sorted by ``arc_start``, are grouped in blocks of
    ``_BLOCK_SIZE``; block ``A`` gets the centre ``c_A`` (mean of its midpoints) and the
    radius ``ρ_A = max_{i∈A} |m_i − c_A| + radii[i]``, so every pair (i ∈ A, j ∈ B) with
    ``|m_i − m_j| ≤ cutoff + radii[i] + radii[j]`` has ``|c_A − c_B| ≤ cutoff + ρ_A + ρ_B``.
    Its arc-length separation is at most ``max(0, max_B arc_start − min_A arc_end,
    max_A arc_start − min_B arc_end)`` (for a closed rod too: the gap around the loop is
    never longer than the gap along ``[0, P)``). Block pairs failing either bound are
    dropped whole; the others, and every block with itself, are returned with the member
    table (n_blocks, _BLOCK_SIZE) (padding −1) for `_exact_tests`. Blocks much wider than
    the typical one (a gap in the data, e.g. two rods in one call) are split into single
    segments so that they do not widen every query.
    """
    n_segments = midpoints.shape[0]
    order = np.argsort(arc_start, kind="stable")
    n_blocks = -(-n_segments // _BLOCK_SIZE)
    members = np.full(n_blocks * _BLOCK_SIZE, -1, dtype=np.int64)
    members[:n_segments] = order
    members = members.reshape(n_blocks, _BLOCK_SIZE)
    centres, block_radii = _block_spheres(members, midpoints, radii)
    wide = block_radii > _WIDE_BLOCK * np.median(block_radii)
    if np.any(wide):
        singles = members[wide].ravel()
        singles = singles[singles >= 0]
        single_members = np.full((singles.size, _BLOCK_SIZE), -1, dtype=np.int64)
        single_members[:, 0] = singles
        members = np.concatenate([members[~wide], single_members])
        centres = np.concatenate([centres[~wide], midpoints[singles]])
        block_radii = np.concatenate([block_radii[~wide], radii[singles]])
    filled = _filled(members)
    latest_start = arc_start[filled].max(axis=1)
    earliest_end = arc_end[filled].min(axis=1)

    reach = (cutoff + 2.0 * float(np.max(block_radii))) * (1.0 + PREFILTER_SLACK)
    block_a, block_b = _close_block_pairs(centres, reach)
    widest_gap = np.maximum(
        latest_start[block_b] - earliest_end[block_a], latest_start[block_a] - earliest_end[block_b]
    )
    keep = np.maximum(widest_gap, 0.0) >= separation_floor
    block_a, block_b = block_a[keep], block_b[keep]
    difference = centres[block_a] - centres[block_b]
    reach = (cutoff + block_radii[block_a] + block_radii[block_b]) * (1.0 + PREFILTER_SLACK)
    keep = np.einsum("ij,ij->i", difference, difference) <= reach * reach
    block_a, block_b = block_a[keep], block_b[keep]
    # Pairs inside one block: the block paired with itself.
    inner = np.flatnonzero(np.maximum(latest_start - earliest_end, 0.0) >= separation_floor)
    return np.concatenate([block_a, inner]), np.concatenate([block_b, inner]), members


def _close_block_pairs(centres: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """``(a, b)``, ``a < b``: the pairs of ``centres`` (n, 3) at most ``reach`` apart.

    Up to ``_TREE_ABOVE_BLOCKS`` centres every pair is tested (numpy); beyond,
    `scipy.spatial.cKDTree.query_pairs` (O(n log n)). Both keep a pair when the
    distance is at most ``reach``; the order of the pairs is not specified (the
    caller sorts its answer).
    """
    n = centres.shape[0]
    if n > _TREE_ABOVE_BLOCKS:
        # imported here: scipy.spatial takes ~0.05 s to import, and small rods never use it
        from scipy.spatial import cKDTree

        pairs = cKDTree(centres).query_pairs(reach, output_type="ndarray")
        return pairs[:, 0], pairs[:, 1]
    a, b = upper_pairs(n)
    difference = centres[a] - centres[b]
    keep = np.einsum("ij,ij->i", difference, difference) <= reach * reach
    return a[keep], b[keep]


@functools.lru_cache(maxsize=8)
def upper_pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.triu_indices(n, 1)`` as int64, read-only (shared between calls)."""
    a, b = (np.ascontiguousarray(v, dtype=np.int64) for v in np.triu_indices(n, 1))
    a.flags.writeable = False
    b.flags.writeable = False
    return a, b


@functools.lru_cache(maxsize=8)
def single_members(n: int) -> np.ndarray:
    """The member table ``(n, 1)`` of one segment a block, read-only (shared)."""
    members = np.arange(n, dtype=np.int64)[:, None]
    members.flags.writeable = False
    return members


def _filled(members: np.ndarray) -> np.ndarray:
    """Block member table with the padding (−1) replaced by the block's first member."""
    return np.where(members >= 0, members, members[:, :1])


def _block_spheres(
    members: np.ndarray, midpoints: np.ndarray, radii: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n_blocks, 3) and radii (n_blocks,) of spheres holding every member segment."""
    filled = _filled(members)
    points = midpoints[filled]
    centres = points.mean(axis=1)
    reach = np.linalg.norm(points - centres[:, None, :], axis=2) + radii[filled]
    return centres, reach.max(axis=1)


def brute_prefilter(
    midpoints: np.ndarray, half_chords: np.ndarray, widened_cutoff: float
) -> tuple[np.ndarray, np.ndarray]:
    """Pairs i < j with ``|m_i − m_j| ≤ (widened_cutoff + r_i + r_j)(1 + slack)``, all pairs tested."""
    n_segments = midpoints.shape[0]
    rows_per_block = max(1, _BRUTE_BLOCK_PAIRS // n_segments)
    x, y, z = (np.ascontiguousarray(midpoints[:, axis]) for axis in range(3))
    found_first, found_second = [], []
    for row_start in range(0, n_segments - 1, rows_per_block):
        rows = np.arange(row_start, min(row_start + rows_per_block, n_segments - 1))
        column_start = row_start + 1
        dx = x[rows, None] - x[None, column_start:]
        dy = y[rows, None] - y[None, column_start:]
        dz = z[rows, None] - z[None, column_start:]
        squared = dx * dx + dy * dy + dz * dz
        reach = (widened_cutoff + half_chords[rows, None] + half_chords[None, column_start:]) * (
            1.0 + PREFILTER_SLACK
        )
        upper = np.arange(column_start, n_segments)[None, :] > rows[:, None]
        block_rows, block_columns = np.nonzero((squared <= reach * reach) & upper)
        found_first.append(rows[block_rows])
        found_second.append(block_columns + column_start)
    return (
        np.concatenate(found_first).astype(np.int64),
        np.concatenate(found_second).astype(np.int64),
    )
