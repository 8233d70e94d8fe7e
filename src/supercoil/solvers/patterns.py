"""Memos keyed by sparsity patterns, and the fingerprints of patterns.

Along a branch the Hessian and the KKT matrices are assembled many times per
point on the same few sparsity patterns (rod + contact + constraint curvature,
restricted to the free DOFs). What depends on a pattern only (orderings, band
layouts, index maps of sums and restrictions) is computed once per pattern and
kept in a :class:`PatternMemo`; :func:`pattern_words` makes the key of a pattern
in one compiled pass.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from supercoil._numba import njit


class PatternMemo:
    """A small first-in-first-out memo of per-pattern index maps, bounded in size.

    Keys and values are tuples of bytes, arrays and numbers; the oldest entries
    are dropped beyond ``max_entries`` or ``max_bytes`` (keys and values
    together), so that large problems (N = 10 000: tens of MB per pattern) keep
    one or two patterns rather than exhausting memory.
    """

    def __init__(self, max_entries: int = 16, max_bytes: int = 64 * 2**20):
        self.max_entries, self.max_bytes = max_entries, max_bytes
        self._items: dict[tuple, tuple] = {}
        self._sizes: dict[tuple, int] = {}
        self._total = 0

    @staticmethod
    def _size(item) -> int:
        if isinstance(item, tuple):
            total = 0
            for part in item:
                total += PatternMemo._size(part)
            return total
        if isinstance(item, bytes):
            return len(item)
        nbytes = getattr(item, "nbytes", None)
        return 8 if nbytes is None else int(nbytes)

    def get(self, key: tuple):
        return self._items.get(key)

    def put(self, key: tuple, value: tuple) -> None:
        size = self._size(key) + self._size(value)
        if size > self.max_bytes:
            return
        if key in self._items:  # replaced: its size no longer counts
            del self._items[key]
            self._total -= self._sizes.pop(key)
        while self._items and (len(self._items) >= self.max_entries
                               or self._total + size > self.max_bytes):
            oldest = next(iter(self._items))
            del self._items[oldest]
            self._total -= self._sizes.pop(oldest)
        self._items[key] = value
        self._sizes[key] = size
        self._total += size

    def clear(self) -> None:
        self._items.clear()
        self._sizes.clear()
        self._total = 0

    def __len__(self) -> int:
        return len(self._items)

    def values(self):
        return self._items.values()


def pattern_words(A: sp.csr_matrix, B: sp.csr_matrix, u: np.ndarray, v: np.ndarray
                  ) -> tuple[np.ndarray, int]:
    """What a per-pattern memo needs to know of two CSR matrices and two vectors, as one
    int64 array, and a 64-bit hash of it: ``(words, hash)``.

    The words are the lengths of the six arrays, ``A.indptr``, ``2 A.indices + (A.data
    != 0)``, the same of ``B``, then ``u != 0`` and ``v != 0``: equal words, equal stored
    patterns, zeros and shapes' rows (the caller keys the columns). A memo keys on
    ``(hash, shapes)`` and compares the words of a hit (:func:`same_words`): exact, a
    collision is a miss. Made in one compiled pass (with four interleaved polynomial
    hashes): 11 µs for the 12 200 words of a contact state at N = 100 (10 400 entries
    of ``S``), and 7 µs for the comparison, where Python's hash of ``S.indices``' bytes
    alone took 25 µs (and the bordered factor's memos hashed them twice, ``J``'s
    three times)."""
    return _pattern_words(A.indptr, A.indices, A.data, B.indptr, B.indices, B.data,
                          np.asarray(u), np.asarray(v))


@njit()
def _pattern_words(a_ptr, a_idx, a_data, b_ptr, b_idx, b_data, u, v):
    words = np.empty(6 + a_ptr.size + a_idx.size + b_ptr.size + b_idx.size + u.size
                     + v.size, dtype=np.int64)
    words[0], words[1], words[2] = a_ptr.size, a_idx.size, b_ptr.size
    words[3], words[4], words[5] = b_idx.size, u.size, v.size
    w = 6
    for i in range(a_ptr.size):
        words[w] = a_ptr[i]
        w += 1
    for i in range(a_idx.size):
        words[w] = 2 * np.int64(a_idx[i]) + (a_data[i] != 0.0)
        w += 1
    for i in range(b_ptr.size):
        words[w] = b_ptr[i]
        w += 1
    for i in range(b_idx.size):
        words[w] = 2 * np.int64(b_idx[i]) + (b_data[i] != 0.0)
        w += 1
    for i in range(u.size):
        words[w] = u[i] != 0.0
        w += 1
    for i in range(v.size):
        words[w] = v[i] != 0.0
        w += 1
    # four polynomial hashes (base an odd 64-bit constant, wrapping) over the words
    # interleaved, so that the multiplications do not wait on each other
    base = np.int64(-7046029254386353131)  # 0x9E3779B97F4A7C15
    h0, h1, h2, h3 = np.int64(1), np.int64(2), np.int64(3), np.int64(4)
    quads = words.size // 4
    for q in range(quads):
        h0 = h0 * base + words[4 * q]
        h1 = h1 * base + words[4 * q + 1]
        h2 = h2 * base + words[4 * q + 2]
        h3 = h3 * base + words[4 * q + 3]
    for w in range(4 * quads, words.size):
        h0 = h0 * base + words[w]
    h = ((h0 * base + h1) * base + h2) * base + h3
    return words, h ^ (h >> 29)


@njit()
def same_words(a, b) -> bool:
    """``np.array_equal`` of two int64 arrays, compiled (no temporaries)."""
    if a.size != b.size:
        return False
    for i in range(a.size):
        if a[i] != b[i]:
            return False
    return True
