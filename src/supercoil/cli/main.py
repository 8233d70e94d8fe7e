"""The ``supercoil`` command: builds the typer application from the commands' modules
and runs it, turning every failure into one line on standard error.

Each command lives in its own module (``supercoil.cli.ring``, ``.demo``, ...): it
parses its options and constructs the library's options and problems, which
validate them; an :class:`~supercoil.errors.InputError` becomes the command's
``error:`` line (exit 2), with the library's name of the input replaced by the option.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, NoReturn

import typer
from typer.core import TyperGroup

from supercoil import __version__
from supercoil.cli import (
    demo,
    diagram,
    export,
    knot,
    plot,
    ring,
    sweep,
    tighten,
    tweezers,
    view,
    writhe,
)
from supercoil.cli import (
    run as run_study_command,
)
from supercoil.cli._common import EXIT_BAD_INPUT, EXIT_NOT_CONVERGED, fail, raised_while_solving
from supercoil.errors import InputError

UNITS_NOTE = (
    "Units are nondimensional: bending stiffness A = 1 and rod length L = 1, so energies are "
    "E*L/A, forces F*L^2/A, torques M*L/A; the twist ratio is C/A; link, twist and writhe "
    "are in turns (positive = right-handed). 'ring --dna' and 'tweezers --dna' take DNA units "
    "instead (base pairs, superhelical density or force in pN, salt in mM) and add nm, kT "
    "and pN to their output."
)
# the order a new user meets the commands in, which --help lists them in
COMMANDS = ("demo", "ring", "diagram", "tweezers", "run", "sweep", "plot", "view", "export",
            "writhe", "knot", "tighten")
# the commands that call the compiled kernels: a first run of one says it compiles them
COMPUTING_COMMANDS = ("demo", "ring", "diagram", "tweezers", "run", "sweep", "writhe", "knot",
                      "tighten")
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS")
COMPILE_TIME = "under a minute, longer on a busy machine"  # measured: 45 s (demo, load 0.6)


class _InUsersOrder(TyperGroup):
    """The commands listed in the order of :data:`COMMANDS` (typer lists groups last)."""

    def list_commands(self, ctx) -> list[str]:
        rank = {name: i for i, name in enumerate(COMMANDS)}
        return sorted(super().list_commands(ctx), key=lambda name: rank.get(name, len(rank)))


app = typer.Typer(
    name="supercoil",
    cls=_InUsersOrder,
    help="Equilibria and stability of elastic rods (Kirchhoff rods, closed rings, writhe). "
    + UNITS_NOTE
    + " Exit status: 0 done, 1 computed but not converged, 2 bad input.",
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version_callback(value: bool) -> None:
    if value:
        print(f"supercoil {__version__}")
        raise typer.Exit()


LOG_HELP = (
    "Write the computation's log to FILE (overwritten): each continuation step accepted, "
    "with its length, parameter and corrector iterations, or refused and why; the "
    "gauge's moves; the solvers' messages. A run that stops early ends its log with the "
    "steps that led there. The log of this process only: a sweep's workers keep theirs."
)


def _log_to(ctx: typer.Context, path: Path) -> None:
    """Send the library's log records (DEBUG and up) to ``path`` for the command; the file
    is opened at the first record, so a command refused for bad input writes nothing."""
    if path.is_dir():
        fail(f"--log {str(path)!r} is a directory: give a file in an existing folder")
    if not path.parent.is_dir():
        fail(f"--log {str(path)!r}: the folder {str(path.parent)!r} does not exist")
    handler = logging.FileHandler(path, mode="w", encoding="utf-8", delay=True)
    handler.setFormatter(logging.Formatter(
        "%(asctime)s.%(msecs)03d %(levelname)s %(name)s: %(message)s", "%H:%M:%S"))
    handler.setLevel(logging.DEBUG)
    logger = logging.getLogger("supercoil")
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)

    def restore() -> None:
        logger.removeHandler(handler)
        logger.setLevel(level)
        handler.close()

    ctx.call_on_close(restore)


def _help_without_command(ctx: typer.Context) -> None:
    """A group called without a command: its help, exit status 2."""
    if ctx.invoked_subcommand is None:
        print(ctx.get_help())
        raise typer.Exit(EXIT_BAD_INPUT)


@app.callback(invoke_without_command=True)
def _root(
    ctx: typer.Context,
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_version_callback,
            is_eager=True,
            help="Print the supercoil version and exit.",
        ),
    ] = False,
    log: Annotated[
        Path | None,
        typer.Option("--log", metavar="FILE", help=LOG_HELP),
    ] = None,
) -> None:
    """Equilibria and stability of elastic rods."""
    if log is not None:
        _log_to(ctx, log)
    _help_without_command(ctx)


app.command("demo", help=demo.DEMO_HELP)(demo.demo)
app.command("ring")(ring.ring)
diagram.register(app, _help_without_command)
app.command("tweezers")(tweezers.tweezers)
app.command("run")(run_study_command.run_command)
app.command("sweep")(sweep.sweep_command)
app.command("plot")(plot.plot)
app.command("view")(view.view)
app.command("export")(export.export_command)
app.command("writhe")(writhe.writhe)
app.command("knot")(knot.knot)
app.command("tighten")(tighten.tighten)


def _one_blas_thread():
    """One BLAS/LAPACK thread for the command, unless the user's environment sets the
    count (OPENBLAS_NUM_THREADS, MKL_NUM_THREADS or OMP_NUM_THREADS).

    The solves of one rod call LAPACK on many small blocks; threads only add
    contention there, and a solve may land on another state with two threads than
    with one. numpy is loaded by ``import supercoil`` before the command runs, so the
    environment variables would come too late: threadpoolctl limits the loaded
    libraries.
    """
    if any(name in os.environ for name in BLAS_THREAD_VARIABLES):
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def _compiling() -> None:
    print(f"supercoil: first run: compiling the numerical kernels ({COMPILE_TIME}; "
          "cached for later runs)", file=sys.stderr, flush=True)


def _computes(args: Sequence[str]) -> bool:
    """Whether ``args`` ask for a command that runs numerical kernels (not for a help,
    the version, or a figure, page or file drawn from a result)."""
    return bool(args) and args[0] in COMPUTING_COMMANDS \
        and not {"-h", "--help", "--version"} & set(args)


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def _internal_error(exc: BaseException) -> int:
    print(f"error: internal error: {type(exc).__name__}: {_one_line(exc)} (please report)",
          file=sys.stderr, flush=True)
    return EXIT_NOT_CONVERGED


def run(argv: Sequence[str] | None = None) -> int:
    """Run the command on ``argv`` (default: ``sys.argv[1:]``) and return the exit status.

    Parse errors of typer/click, bad input and unexpected exceptions all end as
    one line on standard error (docs/model.md, "Files and exit statuses"):
    ``error: ...`` with status 2 for bad input, ``error: internal error: ...`` with
    status 1 for a bug. RuntimeWarnings (numpy's overflow and invalid-value
    warnings) are silenced. ``SUPERCOIL_DEBUG=1`` re-raises unexpected exceptions
    with their traceback and shows the warnings.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    if _computes(args):
        from supercoil._numba import cache_is_cold

        if cache_is_cold():
            _compiling()
    debug = os.environ.get("SUPERCOIL_DEBUG", "") not in ("", "0")
    try:
        with warnings.catch_warnings():
            if not debug:
                # numpy's overflow/invalid-value warnings from trial steps that a
                # solver then rejects: the result's status and message say what
                # happened, so they would only break the one-line stderr contract
                warnings.simplefilter("ignore", RuntimeWarning)
            with _one_blas_thread():
                status = app(args=args, prog_name="supercoil", standalone_mode=False)
    except typer.TyperException as exc:  # typer's parse errors (click's, in typer's copy)
        ctx = getattr(exc, "ctx", None)
        command = ctx.command_path if ctx is not None else "supercoil"
        print(f"error: {_one_line(exc.format_message())} (see '{command} --help')",
              file=sys.stderr, flush=True)
        return exc.exit_code
    except typer.Abort:
        print("error: aborted", file=sys.stderr, flush=True)
        return 1
    except InputError as exc:
        if debug:
            raise
        if raised_while_solving(exc):  # a failure of the numerics, not of the input
            return _internal_error(exc)
        print(f"error: {_one_line(exc)}", file=sys.stderr, flush=True)
        return EXIT_BAD_INPUT
    except OSError as exc:
        if debug:
            raise
        if exc.errno in (errno.ENAMETOOLONG, errno.ELOOP):  # a path the user gave
            print(f"error: {exc.filename}: {exc.strerror}; give a shorter, valid path",
                  file=sys.stderr, flush=True)
            return EXIT_BAD_INPUT
        return _internal_error(exc)
    except Exception as exc:
        if debug:
            raise
        return _internal_error(exc)
    return status if isinstance(status, int) else 0


def main(argv: Sequence[str] | None = None) -> NoReturn:
    """Entry point of the ``supercoil`` console script."""
    sys.exit(run(argv))


if __name__ == "__main__":
    main()
