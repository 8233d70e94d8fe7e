"""Plain-text curve files: one vertex ``x y z`` per line.

Format: each non-blank line holds three numbers separated by spaces, tabs or
commas; ``#`` starts a comment (a whole line or the end of a line). Each vertex
appears once: a closed polygon does not repeat its first vertex at the end.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np


class CurveFileError(ValueError):
    """A curve file that is missing, unreadable or malformed (one-line message)."""


def read_curve(path: str | os.PathLike) -> np.ndarray:
    """Vertices ``(n_vertices, 3)`` of the curve file at ``path``.

    Raises :class:`CurveFileError` naming the file (and the line) and what a
    valid file looks like.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CurveFileError(
            f"curve file {path}: no such file; give a text file with one vertex 'x y z' per line"
        ) from None
    except IsADirectoryError:
        raise CurveFileError(
            f"curve file {path}: is a folder; give a text file with one vertex 'x y z' per line"
        ) from None
    except UnicodeDecodeError:
        raise CurveFileError(
            f"curve file {path}: not a UTF-8 text file; give a text file "
            "with one vertex 'x y z' per line"
        ) from None
    except OSError as exc:
        raise CurveFileError(f"curve file {path}: cannot be read ({exc.strerror})") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        content = line.split("#", 1)[0].replace(",", " ").split()
        if not content:
            continue
        where = f"curve file {path}, line {number}"
        if len(content) != 3:
            raise CurveFileError(
                f"{where}: expected 3 numbers 'x y z', got {len(content)} ({line.strip()!r})"
            )
        try:
            vertex = [float(word) for word in content]
        except ValueError:
            raise CurveFileError(
                f"{where}: {line.strip()!r} is not three numbers 'x y z'"
            ) from None
        if not all(math.isfinite(x) for x in vertex):
            raise CurveFileError(
                f"{where}: non-finite coordinate in {line.strip()!r}; "
                "all coordinates must be finite numbers"
            )
        rows.append(vertex)
    if not rows:
        raise CurveFileError(f"curve file {path}: no vertices; give one vertex 'x y z' per line")
    return np.array(rows, dtype=float)
