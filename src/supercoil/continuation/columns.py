"""Per-point columns that grow with a branch, read as views without copying.

A branch followed point by point is handed to the caller at every accepted point
(``continuation(on_point=...)``, which the result files use to store each point as it
comes). Stacking the points' states and tangents into new arrays at every point costs
O(k n) at the k-th point, O(k^2 n) over the run: at k = 20000 points of a rod with
n = 1230 unknowns, 1.1 s a point (measured), against 30-300 ms for the point itself.

:class:`Columns` keeps each quantity in one array that doubles its capacity when full,
so a point costs O(n) amortised, and hands out read-only views of the first k rows.
A view handed out never changes: a row that one covers and that is written again
(the tracer replaces its last point after a regauge) is written into a copy of the
column, which the later views share.
"""

from __future__ import annotations

import numpy as np


class Columns:
    """Named per-point arrays, rows written by index and read as read-only views."""

    def __init__(self):
        self._data: dict[str, np.ndarray] = {}
        self._shared: dict[str, int] = {}  # rows of the current array inside a handed-out view
        self._ragged: dict[str, list] = {}  # columns whose rows differ in shape: kept as lists

    def __contains__(self, name: str) -> bool:
        return name in self._data or name in self._ragged

    def put(self, name: str, i: int, value) -> None:
        """Write row ``i`` of column ``name`` (rows ``0..i-1`` written before)."""
        if name in self._ragged:
            rows = self._ragged[name]
            rows[i:i + 1] = [np.asarray(value)]
            return
        value = np.asarray(value)
        column = self._data.get(name)
        if column is None:
            column = np.empty((max(16, 2 * i + 2),) + value.shape, dtype=value.dtype)
            self._data[name], self._shared[name] = column, 0
        elif column.shape[1:] != value.shape:
            # rows of another shape: stacked on demand as np.array(list) would
            self._ragged[name] = [column[j] for j in range(i)] + [value]
            del self._data[name], self._shared[name]
            return
        if not np.can_cast(value.dtype, column.dtype, "safe"):
            column = column.astype(np.result_type(column.dtype, value.dtype))
            self._data[name], self._shared[name] = column, 0
        if i >= column.shape[0]:
            grown = np.empty((max(2 * column.shape[0], i + 1),) + column.shape[1:],
                             dtype=column.dtype)
            kept = min(i, column.shape[0])
            grown[:kept] = column[:kept]
            column = grown
            self._data[name], self._shared[name] = column, 0
        elif i < self._shared[name]:
            column = column.copy()  # a handed-out view covers row i: it keeps the old row
            self._data[name], self._shared[name] = column, 0
        column[i] = value

    def fill(self, name: str, rows) -> None:
        """Write rows ``0..len(rows)-1`` of a new column ``name`` at once."""
        rows = np.asarray(rows)
        column = np.empty((max(16, 2 * len(rows)),) + rows.shape[1:], dtype=rows.dtype)
        column[:len(rows)] = rows
        self._data[name], self._shared[name] = column, 0

    def get(self, name: str, i: int):
        """Row ``i`` of column ``name``."""
        if name in self._ragged:
            return self._ragged[name][i]
        return self._data[name][i]

    def view(self, name: str, k: int) -> np.ndarray:
        """The first ``k`` rows of column ``name``, read-only, shared with the column
        until a row they cover is written again."""
        if name in self._ragged:
            return np.array(self._ragged[name][:k])
        view = self._data[name][:k]
        view.flags.writeable = False
        self._shared[name] = max(self._shared[name], k)
        return view
