"""``supercoil run STUDY.toml``: run a study file, saving as it goes (the running itself
is :func:`supercoil.api.study_run.run_study`; this command adds the progress display,
SIGTERM handled as Ctrl-C, the messages and the exit status).

Writes into ``--out DIR`` (default: the study file's name without ``.toml``,
in the current folder):

* ``result.h5``: the result file (:mod:`supercoil.io.store`, ``docs/results.md``),
  written point by point where the problem reports points, so an interrupted
  or killed run leaves every point computed so far;
* the JSON summary (``[outputs] json``): ``diagram.json`` for a ring diagram
  (the keys of ``supercoil diagram ring``), ``ring.json`` for a single ring;
* the figures (``[outputs] figures``), drawn from the result file by
  :mod:`supercoil.plotting.figures`.

Exit status: 0 done; 1 computed but incomplete (a branch stopped early, or
the run was interrupted: the file says where, ``--resume`` continues); 2 bad
input (the study file, the folder, a result file that does not match).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from supercoil.api.recording import RESULT_FILE
from supercoil.cli._common import EXIT_NOT_CONVERGED, checked_path, fail, warn
from supercoil.cli._options import overwrite_option, quiet_option

Quiet = quiet_option("No progress output, and no list of the files written.")
Overwrite = overwrite_option("Write into an existing non-empty DIR, replacing its result.h5, "
                             "summary and figures (other files are left alone).")


def run_command(
    study: Annotated[Path, typer.Argument(metavar="STUDY.toml", help="The study file (TOML): "
                                          "rod, units, problem, continuation, outputs; "
                                          "see examples/*.toml.", show_default=False,
                                          callback=checked_path)],
    out: Annotated[Path | None, typer.Option(
        "--out", metavar="DIR", help="Output folder (default: the study's file name without "
        ".toml); an existing non-empty DIR is refused unless --overwrite or --resume.",
        show_default=False, callback=checked_path)] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue the interrupted run in DIR (its result.h5): completed "
        "branches are kept. The study must be the same (presentation keys aside).")] = False,
    quiet: Quiet = False,
    overwrite: Overwrite = False,
    json_path: Annotated[str | None, typer.Option(
        "--json", metavar="PATH", help="Also write the JSON summary to PATH, replaced if it "
        "exists ('-' = standard output, which silences the other output).",
        show_default=False)] = None,
    overrides: Annotated[list[str] | None, typer.Option(
        "--set", metavar="TABLE.KEY=VALUE", help="Override one key of the study (a TOML "
        "value), e.g. --set rod.nodes=48; repeatable.", show_default=False)] = None,
) -> None:
    """Run a study file (TOML): result file, JSON summary and figures.

    The result file (result.h5, read with supercoil.load) is saved as the run goes;
    Ctrl-C stops it and keeps every point computed so far, --resume continues it."""
    from supercoil.api.study_run import run_study
    from supercoil.cli._common import check_json_target, write_json_or_fail
    from supercoil.cli.progress import Progress
    from supercoil.cli.saving import figures_interrupted, terminate_as_interrupt
    from supercoil.io.study import StudyError, load_study

    quiet = quiet or json_path == "-"
    check_json_target(json_path)
    try:
        spec = load_study(study, overrides or ())
    except StudyError as exc:
        fail(str(exc))
    if resume and overwrite:
        fail("--resume and --overwrite exclude each other: --resume continues DIR's result, "
             "--overwrite replaces it")
    out = Path(study.stem) if out is None else out
    result_path = out / RESULT_FILE
    stored = _prepare_folder(out, spec, resume, overwrite)
    if stored is not None and stored.status in ("complete", "incomplete"):
        # every branch ended (an incomplete one by its point limit): resuming changes nothing
        if not quiet:
            print(f"nothing to resume: {result_path} is {stored.status} ({stored.message})")
        if json_path is not None and stored.summary is not None:
            write_json_or_fail(stored.summary, json_path)
        if stored.status != "complete":
            raise typer.Exit(EXIT_NOT_CONVERGED)
        return
    from supercoil.io.store import ResultFileError

    try:
        with Progress(quiet=quiet) as progress, terminate_as_interrupt():
            outcome = run_study(spec, out, resume=resume, progress=progress.message,
                                on_point=progress.on_point)
    except ResultFileError as exc:  # the result file is locked by another run
        fail(str(exc))
    if outcome["status"] == "interrupted" and not outcome.get("resumable", True):
        figures_interrupted(out)
    if json_path is not None and outcome.get("summary") is not None:
        write_json_or_fail(outcome["summary"], json_path)
    for note in outcome.get("notes", ()):
        warn(f"note: {note}")
    if not quiet:
        print(f"wrote {', '.join(outcome['files'])} to {out.resolve()}")
    if outcome["status"] != "complete":
        # --resume continues interrupted branches; an incomplete run's branches all
        # ended (a branch stopped early), and resuming would change nothing
        hint = (f"; continue with 'supercoil run {study} --out {out} --resume'"
                if outcome["status"] == "interrupted" and outcome.get("resumable", True)
                else "")
        warn(f"{outcome['status']}: {outcome['message']} (saved in {result_path}{hint})")
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _prepare_folder(out: Path, spec, resume: bool, overwrite: bool):
    """The folder checks of :func:`supercoil.cli.saving.prepare_folder` (one-line errors,
    nothing written before they pass); with ``resume`` the stored result (a
    :class:`~supercoil.io.store.Result`) computed from the same study, else None."""
    from supercoil.api.studies import study_mismatch
    from supercoil.cli.saving import prepare_folder

    stored = prepare_folder(out, overwrite=overwrite, resume=resume, what="its results")
    if stored is not None:
        mismatch = study_mismatch(stored, spec)
        if mismatch:
            fail(f"--resume: {out / RESULT_FILE} was computed with another study ({mismatch}); "
                 "resume with the same study, or start anew with --overwrite or another "
                 "--out")
    return stored
