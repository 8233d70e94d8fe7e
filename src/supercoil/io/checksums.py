"""Checksums of result data: SHA-256 of decoded arrays and of plain metadata values.

A digest covers what a reader gets back, not the bytes on disk: an array's
dtype, shape and C-ordered bytes; a metadata mapping's keys and values in a
canonical text form (floats by :meth:`float.hex`, so every bit counts). The
result file (:mod:`supercoil.io.store_write`) and its journal
(:mod:`supercoil.io.journal`) store these digests; the readers recompute and
compare them, so damaged data is refused rather than returned altered.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping

import numpy as np


def array_digest(array: np.ndarray) -> str:
    """Hex SHA-256 of ``array``'s dtype, shape and values (C order)."""
    a = np.asarray(array, order="C")
    h = hashlib.sha256()
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def bytes_digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def canonical(value) -> object:
    """A plain, exactly comparable form of a metadata value (str, bool, int, float,
    or a small array)."""
    if isinstance(value, bytes):
        return ["s", value.decode("utf-8")]
    if isinstance(value, str):
        return ["s", value]
    if isinstance(value, (bool, np.bool_)):
        return ["b", bool(value)]
    if isinstance(value, (int, np.integer)):
        return ["i", int(value)]
    if isinstance(value, (float, np.floating)):
        f = float(value)
        return ["f", f.hex() if math.isfinite(f) else repr(f)]
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return canonical(value[()])
        return ["a", array_digest(value)]
    raise TypeError(f"metadata value of type {type(value).__name__} has no canonical form")


def mapping_digest(values: Mapping) -> str:
    """Hex SHA-256 of a mapping of metadata values (keys sorted)."""
    text = json.dumps({str(k): canonical(v) for k, v in values.items()}, sort_keys=True,
                      separators=(",", ":"))
    return bytes_digest(text.encode("utf-8"))
