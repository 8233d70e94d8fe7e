"""Output folders and result files of the computing commands (``demo``, ``diagram ring``,
``tweezers``, ``run``, ``ring --out``).

:func:`prepare_folder` checks ``--out``, ``--overwrite`` and ``--resume``
before anything is written (one-line errors, exit 2); :func:`open_writer`
starts or continues the folder's ``result.h5``; :func:`run_saving` runs a
verb (:func:`supercoil.ring_diagram`, :func:`supercoil.tweezers`) that appends
every accepted point to the result as it comes (one write to the operating
system per point) with a progress display, and turns SIGTERM into Ctrl-C: an
``interrupted`` result that ``--resume`` continues.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from pathlib import Path

from supercoil.api.recording import (
    RESULT_FILE,
    from_interrupt,
    kept,
    plain,
    raise_limits,
    settings_mismatch,
)
from supercoil.cli._common import MAX_NAME_BYTES, fail, path_kind, warn


@contextlib.contextmanager
def terminate_as_interrupt():
    """Within the block, SIGTERM raises KeyboardInterrupt as Ctrl-C does (main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def prepare_folder(out: Path, *, overwrite: bool, resume: bool, problem: str | None = None,
                   settings: dict | None = None, what: str = "this command's files",
                   same_as: str = "the same options", create: bool = True):
    """Check ``--out`` before anything is written; with ``resume`` return the stored
    :class:`~supercoil.io.store.Result` (refused when its ``problem`` or ``settings``
    differ from the given ones), else None. One-line errors, exit 2. The folder is
    created (and tried for writing) unless ``create`` is False: call it after every
    other input passed, so that a refused input leaves nothing behind."""
    if resume and overwrite:
        fail("--resume and --overwrite exclude each other: --resume continues DIR's result, "
             "--overwrite replaces it")
    if any(len(part.encode()) > MAX_NAME_BYTES for part in out.parts):
        fail(f"--out {str(out)[:80]}...: a folder name is longer than {MAX_NAME_BYTES} bytes; "
             "give a shorter name")
    if path_kind("--out", out) not in ("missing", "folder"):
        fail(f"--out {out}: is a file, not a folder; give a new folder")
    result_path = out / RESULT_FILE
    if path_kind("--out", result_path) not in ("missing", "file"):
        fail(f"--out {out}: {result_path} is not a file; remove it or give another folder")
    if resume:
        from supercoil.io.store import ResultFileError, load

        if not result_path.is_file():
            fail(f"--resume: {result_path} does not exist; nothing to resume (run without "
                 "--resume to start)")
        try:
            stored = load(result_path)
        except ResultFileError as exc:
            fail(f"--resume: {exc}")
        if problem is not None and stored.problem != problem:
            fail(f"--resume: {result_path} holds a {stored.problem!r} result, not a "
                 f"{problem!r} one; give its folder to the command that wrote it")
        if settings is not None:
            mismatch = settings_mismatch(stored.settings, plain(settings))
            if mismatch:
                fail(f"--resume: {result_path} was computed with other settings ({mismatch});"
                     f" resume with {same_as}, or start anew with --overwrite or another "
                     "--out")
        return stored
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        fail(f"--out {out}: folder exists and is not empty; give a new folder, add --resume "
             f"to continue its result, or --overwrite to replace {what} in it")
    if create:
        create_folder(out)
    return None


def create_folder(out: Path) -> None:
    """Create ``--out`` and try writing in it; a one-line error (exit 2) if it cannot be."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".supercoil-write-test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        fail(f"--out {out}: cannot write there ({exc.strerror or exc}); give a folder in a "
             "writable location")


def open_writer(out: Path, *, resume: bool, problem: str, settings: dict,
                attributes: dict | None = None, provenance: dict | None = None,
                units: str = "nondimensional"):
    """The folder's result writer: ``result.h5`` continued (``resume``) or started anew
    (replacing one left by an earlier run). A result another process writes is a
    one-line error."""
    from supercoil.io.store import ResultFileError, ResultWriter

    path = out / RESULT_FILE
    try:
        if resume:
            writer = ResultWriter.reopen(path)
            raise_limits(writer, plain(settings))
            return writer
        return ResultWriter.create(path, problem=problem, settings=plain(settings),
                                   units=units, attributes=attributes, provenance=provenance,
                                   overwrite=True)
    except ResultFileError as exc:
        fail(str(exc))


def _close_as(writer, status: str, message: str) -> None:
    writer.set_status(status, message)
    writer.close()


def run_saving(compute, writer, quiet: bool = False, resume_hint: str = ""):
    """Run ``compute(message, on_point)`` -- a verb (:func:`supercoil.ring_diagram`,
    :func:`supercoil.tweezers`) storing every accepted point in ``writer`` as it comes,
    called with ``out=writer`` -- with a progress display; SIGTERM is turned into Ctrl-C.

    Returns what ``compute`` returns (the writer still open), or None after Ctrl-C or
    SIGTERM: the result then has status ``interrupted`` and is closed, and a warning says
    what was kept and how to continue (``resume_hint``). Another exception closes the
    result with status ``failed`` and propagates.
    """
    from supercoil.cli.progress import Progress

    with Progress(quiet) as progress, terminate_as_interrupt():
        try:
            return compute(progress.message, progress.on_point)
        except BaseException as exc:
            if from_interrupt(exc):  # Ctrl-C, or SIGTERM, even inside a compiled kernel
                interrupted(writer, resume_hint)
                return None
            if writer.status == "running":
                _close_as(writer, "failed",
                          f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            raise


def interrupted(writer, resume_hint: str = "") -> None:
    """Close ``writer`` as ``interrupted`` (unless the verb did) and say what was kept."""
    what = kept(writer)
    if writer.status == "running":
        _close_as(writer, "interrupted", f"interrupted; kept {what}")
    warn(f"interrupted: kept {what} in {writer.path.resolve()}"
         + (f"; {resume_hint}" if resume_hint else ""))


def figures_interrupted(out: Path) -> None:
    """The warning for Ctrl-C while the figures are drawn (the data are complete)."""
    warn(f"interrupted while drawing the figures: the data are complete in "
         f"{(out / RESULT_FILE).resolve()}; draw the figures with 'supercoil plot {out} "
         f"--out {out}'")


def nothing_to_resume(stored) -> bool:
    """True (and says so) when the stored result of ``--resume`` is already complete."""
    if stored is None or stored.status != "complete":
        return False
    print(f"nothing to resume: {stored.path} is complete ({stored.message})")
    return True
