"""Helpers of the ``supercoil`` command: input checks, one-line errors, JSON output.

Exit statuses (DESIGN.md): 0 done; 1 computed but not converged (what was
done is saved, and the message says where); 2 bad input. Errors are one line
on standard error starting with ``error:``, never a traceback.
"""

from __future__ import annotations

import math
import os
import re
import sys
from pathlib import Path
from typing import NoReturn

import typer

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2

# Bounds of the command-line inputs. The numerics would accept more, but beyond
# these the run either exhausts memory (N = 1e9 asked for 24 GB before being
# killed) or overflows (dLk = 1e300), so the command refuses them up front.
MAX_NODES = 100_000
CONTACT_CURVES = ("polygon", "spline", "quintic")  # supercoil.contact.problem.CURVES
CONTACT_FORMULATIONS = ("pairs", "integral")  # supercoil.contact.problem.FORMULATIONS
FORMULATION_HELP = ("How the contact potential is summed: integral (default: a double "
                    "integral over the strands, which counts a contact once wherever it lies; "
                    "best with --contact-curve spline) or pairs (over segment pairs, the "
                    "earlier default, whose count of one contact depends on the mesh; "
                    "docs/benchmarks.md).")
MIN_NODES = 8
MAX_MAGNITUDE = 1e6  # |excess link| in turns, twist ratio C/A
MAX_MAGNITUDE_TEXT = "1e6"


def fail(message: str) -> NoReturn:
    """Print ``error: message`` as one line on standard error and exit with status 2."""
    line = " ".join(str(message).split())
    print(f"error: {line}", file=sys.stderr, flush=True)
    raise typer.Exit(EXIT_BAD_INPUT)


def check_contact_choice(curve: str, formulation: str) -> None:
    """``--contact-curve`` and ``--contact-formulation``: a one-line error (exit 2) unless valid."""
    if curve not in CONTACT_CURVES:
        fail(f"--contact-curve {curve!r}: give one of {', '.join(CONTACT_CURVES)}")
    if formulation not in CONTACT_FORMULATIONS:
        fail(f"--contact-formulation {formulation!r}: give one of "
             f"{', '.join(CONTACT_FORMULATIONS)}")


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
    return a status, DESIGN.md), which the command must not report as bad input.
    """
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_globals.get("__name__", "")
        if any(name == p or name.startswith(p + ".") for p in _SOLVING_PACKAGES):
            return True
        tb = tb.tb_next
    return False


def require_finite(option: str, value: float, valid: str = "a finite number") -> None:
    if not math.isfinite(value):
        fail(f"{option} must be {valid}, got {value!r}")


def require_positive(option: str, value: float, valid: str) -> None:
    if not math.isfinite(value) or value <= 0:
        fail(f"{option} must be {valid}, got {value!r}")


def require_magnitude(option: str, value: float, valid: str) -> None:
    """A finite number with ``|value| <= MAX_MAGNITUDE``."""
    if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
        fail(f"{option} must be {valid}, got {value!r}")


def require_nodes(option: str, value: int) -> None:
    if not MIN_NODES <= value <= MAX_NODES:
        fail(
            f"{option} must be an integer from {MIN_NODES} to {MAX_NODES} "
            f"(nodes of the discrete rod), got {value}"
        )


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
    if target.is_dir():
        fail(f"--json {path}: is a folder; give a file path, or - for standard output")
    if not folder.is_dir():
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
