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

from supercoil import checks
from supercoil.errors import InputError


class CurveFileError(InputError):
    """A curve file that is missing, unreadable or malformed (one-line message)."""


def read_curve(path: str | os.PathLike) -> np.ndarray:
    """Vertices ``(n_vertices, 3)`` of the curve file at ``path``.

    At most :data:`~supercoil.checks.MAX_CURVE_BYTES` bytes are read (a larger
    file, or an endless one such as ``/dev/zero``, is refused at that point) and
    at most :data:`~supercoil.checks.MAX_CURVE_VERTICES` vertices accepted.
    Raises :class:`CurveFileError` naming the file (and the line) and what a
    valid file looks like.
    """
    path = Path(path)
    limit = checks.MAX_CURVE_BYTES
    try:
        with open(path, "rb") as stream:
            data = stream.read(limit + 1)
    except FileNotFoundError:
        raise CurveFileError(
            f"curve file {path}: no such file; give a text file with one vertex 'x y z' per line"
        ) from None
    except IsADirectoryError:
        raise CurveFileError(
            f"curve file {path}: is a folder; give a text file with one vertex 'x y z' per line"
        ) from None
    except OSError as exc:
        raise CurveFileError(f"curve file {path}: cannot be read ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise CurveFileError(
            f"curve file {path}: larger than {limit // (1024 * 1024)} MiB; a curve file holds "
            f"at most {checks.MAX_CURVE_VERTICES} vertices 'x y z', one per line"
        )
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise CurveFileError(
            f"curve file {path}: not a UTF-8 text file; give a text file "
            "with one vertex 'x y z' per line"
        ) from None
    if "\0" in text:
        raise CurveFileError(
            f"curve file {path}: holds NUL bytes, not text; give a text file with one vertex "
            "'x y z' per line"
        )
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        content = line.split("#", 1)[0].replace(",", " ").split()
        if not content:
            continue
        where = f"curve file {path}, line {number}"
        if len(rows) == checks.MAX_CURVE_VERTICES:
            raise CurveFileError(
                f"{where}: more than {checks.MAX_CURVE_VERTICES} vertices; a curve file holds "
                f"at most {checks.MAX_CURVE_VERTICES}"
            )
        if len(content) != 3:
            raise CurveFileError(
                f"{where}: expected 3 numbers 'x y z', got {len(content)} ({_shown(line)})"
            )
        try:
            vertex = [float(word) for word in content]
        except ValueError:
            raise CurveFileError(
                f"{where}: {_shown(line)} is not three numbers 'x y z'"
            ) from None
        if not all(math.isfinite(x) for x in vertex):
            raise CurveFileError(
                f"{where}: non-finite coordinate in {_shown(line)}; "
                "all coordinates must be finite numbers"
            )
        rows.append(vertex)
    if not rows:
        raise CurveFileError(f"curve file {path}: no vertices; give one vertex 'x y z' per line")
    return np.array(rows, dtype=float)


def _shown(line: str, width: int = 60) -> str:
    """The line as quoted in a message, cut to ``width`` characters."""
    text = line.strip()
    return repr(text if len(text) <= width else text[:width] + "...")
