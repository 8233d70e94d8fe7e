"""Helpers of the ``supercoil`` command: input checks, one-line errors, JSON output.

Exit statuses (docs/model.md, "Files and exit statuses"): 0 done; 1 computed but not
converged (what was done is saved, and the message says where); 2 bad input. Errors
are one line on standard error starting with ``error:``, never a traceback.
"""

from __future__ import annotations

import math
import os
import re
import sys
from collections.abc import Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

import typer

from supercoil.errors import InputError

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2

FORMULATION_HELP = ("How the contact potential is summed: integral (default: a double "
                    "integral over the strands, which counts a contact once wherever it lies; "
                    "best with --contact-curve spline) or pairs (over segment pairs, whose "
                    "count of one contact depends on the mesh).")


def fail(message: str) -> NoReturn:
    """Print ``error: message`` as one line on standard error and exit with status 2."""
    line = " ".join(str(message).split())
    print(f"error: {line}", file=sys.stderr, flush=True)
    raise typer.Exit(EXIT_BAD_INPUT)


@contextmanager
def refused(names: Mapping[str, str] | None = None, prefix: str = ""):
    """Turn an :class:`~supercoil.errors.InputError` raised in the block into the command's
    ``error:`` line (exit 2): the input's library name is replaced by ``names[name]`` (the
    option, e.g. ``"twist_ratio"`` -> ``"--twist-ratio"``), ``prefix`` put before it.

    An InputError raised inside a solve (Newton, stability, continuation) is a failure of
    the numerics, not of the input: it is raised on, and reported as an internal error.
    """
    try:
        yield
    except InputError as exc:
        if raised_while_solving(exc):
            raise
        fail(prefix + exc.renamed(dict(names or {})))


def path_kind(option: str, path: Path) -> str:
    """``"missing"``, ``"folder"``, ``"file"`` or ``"other"`` for ``path``; a one-line error
    (exit 2) when the path cannot be looked at (a name too long, a loop of links, ...)."""
    try:
        if path.is_dir():
            return "folder"
        if path.is_file():
            return "file"
        return "other" if path.exists() else "missing"
    except OSError as exc:
        fail(f"{option} {_short(path)}: cannot be used ({exc.strerror or exc}); give a "
             "shorter, valid path")


MAX_NAME_BYTES = 255  # one file or folder name (the usual file systems' limit)
MAX_PATH_BYTES = 4096  # a whole path (Linux's PATH_MAX)


def checked_path(value: Path | None) -> Path | None:
    """The ``callback`` of a path argument or option: a path with a name longer than 255
    bytes, or longer than 4096 bytes in all, is refused with click's one-line error."""
    if value is None:
        return value
    text = os.fsencode(str(value))
    if len(text) > MAX_PATH_BYTES or any(len(os.fsencode(part)) > MAX_NAME_BYTES
                                         for part in Path(value).parts):
        raise typer.BadParameter(f"{_short(value)}: a name is longer than {MAX_NAME_BYTES} "
                                 f"bytes or the path longer than {MAX_PATH_BYTES}; give a "
                                 "shorter path")
    return value


def _short(path: Path, width: int = 80) -> str:
    """The path as quoted in a message, cut to ``width`` characters."""
    text = str(path)
    return text if len(text) <= width else text[:width] + "..."


def warn(message: str) -> None:
    """One line on standard error (for a computed but unconverged result)."""
    print(" ".join(str(message).split()), file=sys.stderr, flush=True)


_WARNING_WORD = re.compile(r"\bwarning\b", re.IGNORECASE)
_WARNING_PREFIX = re.compile(r"^\s*warning\s*:?\s*", re.IGNORECASE)


def warning_in(message: str | None) -> str | None:
    """The ``warning: ...`` line for a result message that contains the word warning."""
    if not message or not _WARNING_WORD.search(message):
        return None
    # Only the warning parts of a "status; warning: ...; warning: ..." message.
    parts = [part for part in str(message).split("; ") if _WARNING_WORD.search(part)]
    text = "; ".join(" ".join(_WARNING_PREFIX.sub("", part, count=1).split()) for part in parts)
    return f"warning: {text}"


_SOLVING_PACKAGES = ("supercoil.solvers", "supercoil.stability", "supercoil.continuation")


def raised_while_solving(exc: BaseException) -> bool:
    """True if ``exc`` was raised inside a solve (Newton, stability, continuation).

    The API raises ValueError for bad input while it sets a problem up; a
    ValueError from inside the numerics is a failure of theirs (a solve should
    return a status), which the command must not report as bad input.
    """
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_globals.get("__name__", "")
        if any(name == p or name.startswith(p + ".") for p in _SOLVING_PACKAGES):
            return True
        tb = tb.tb_next
    return False


def require_count(option: str, value: int, low: int, high: int) -> None:
    """Refuse an integer option outside ``[low, high]`` (a count of points, sides, ...)."""
    if not low <= value <= high:
        fail(f"{option} {value}: give an integer from {low} to {high}")


def parse_ratio(text: str) -> float:
    """A number written as a decimal (``0.6667``) or a fraction (``2/3``), as papers
    quote twist ratios; a typer ``parser``. Other text raises ``typer.BadParameter``
    (a ``ValueError`` would lose its message in some typer releases), which the
    command line reports as an invalid value of the option, with the reason."""
    words = str(text).split("/")
    if len(words) > 2:
        raise typer.BadParameter(f"{text!r} is not a number or a fraction like 2/3")
    try:
        values = [float(word) for word in words]
    except ValueError:
        raise typer.BadParameter(f"{text!r} is not a number or a fraction like 2/3") from None
    if len(values) == 1:
        return values[0]
    if values[1] == 0:
        raise typer.BadParameter(f"{text!r} divides by zero")
    return values[0] / values[1]


def parse_span(option: str, text: str, valid: str) -> tuple[float, float]:
    """``"A:B"`` -> ``(a, b)``; a one-line error ``OPTION TEXT: give VALID`` unless two
    numbers (their range is checked by the options the command builds)."""
    words = text.split(":")
    try:
        if len(words) != 2:
            raise ValueError
        return float(words[0]), float(words[1])
    except ValueError:
        fail(f"{option} {text!r}: give {valid}")


def parse_vector(option: str, text: str) -> tuple[float, float, float]:
    """Three finite numbers separated by commas or spaces, not all zero."""
    words = text.replace(",", " ").split()
    try:
        values = tuple(float(word) for word in words)
    except ValueError:
        fail(f'{option} {text!r} is not three numbers; give a direction like "0,0,1"')
    if len(values) != 3:
        fail(f'{option} {text!r} has {len(values)} numbers; give three, like "0,0,1"')
    if not all(math.isfinite(v) for v in values):
        fail(f'{option} {text!r} has a non-finite component; give finite numbers like "0,0,1"')
    if not any(values):
        fail(f'{option} {text!r} is the zero vector; give a non-zero direction like "0,0,1"')
    return values  # type: ignore[return-value]


def check_json_target(path: str | None) -> None:
    """Refuse a ``--json`` path that cannot be written, before any computation."""
    if path is None or path == "-":
        return
    target = Path(path)
    folder = target.parent
    if len(target.name.encode()) > 255:
        fail(f"--json {_short(target)}: the file name is longer than 255 bytes; give a "
             "shorter name")
    if path_kind("--json", target) == "folder":
        fail(f"--json {path}: is a folder; give a file path, or - for standard output")
    if path_kind("--json", folder) != "folder":
        fail(
            f"--json {path}: folder {folder} does not exist; give a path in an existing "
            "folder, or - for standard output"
        )
    if not os.access(folder, os.W_OK | os.X_OK):
        fail(
            f"--json {path}: folder {folder} is not writable; give a path in a writable "
            "folder, or - for standard output"
        )


def write_json_or_fail(data: dict, path: str) -> None:
    from supercoil.io.results import write_json

    try:
        write_json(data, path)
    except OSError as exc:
        fail(
            f"--json {path}: cannot write ({exc.strerror or exc}); give a path in a "
            "writable folder, or - for standard output"
        )
