"""Progress of long commands: a rich live line on a terminal, plain log lines otherwise.

:class:`Progress` receives messages (a branch starts, a note) and points (the
branch, its parameter value, the step, the number of points). On a terminal
(standard output is a TTY) it shows a spinner line with those numbers,
updated in place; otherwise it prints one plain line per message and one every
``every`` points (and the first point of each branch) to standard error, so
logs stay short. ``quiet`` silences both. Messages, and the first point of each branch,
also go to the ``supercoil.cli.progress`` logger (the ``--log`` file's headings).
"""

from __future__ import annotations

import logging
import sys
import time
from typing import Self

log = logging.getLogger(__name__)


class Progress:
    """``with Progress(quiet=False) as progress: progress.message(...); progress.point(...)``."""

    def __init__(self, quiet: bool = False, *, live: bool | None = None, every: int = 10,
                 stream=None):
        self.quiet = quiet
        self.stream = stream if stream is not None else sys.stderr
        self.live = (sys.stdout.isatty() if live is None else live) and not quiet
        self.every = max(1, int(every))
        self._bar = None
        self._task = None
        self._last_branch = None
        self._start = time.perf_counter()

    def __enter__(self) -> Self:
        if self.live:
            from rich.progress import Progress as RichProgress
            from rich.progress import SpinnerColumn, TextColumn, TimeElapsedColumn

            self._bar = RichProgress(SpinnerColumn(), TextColumn("{task.description}"),
                                     TextColumn("{task.fields[numbers]}"), TimeElapsedColumn(),
                                     transient=True)
            self._bar.start()
            self._task = self._bar.add_task("starting", total=None, numbers="")
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None

    def message(self, text: str) -> None:
        """A line that stays (a branch starts, a note)."""
        line = " ".join(str(text).split())
        log.info("%s", line)
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.console.print(line, highlight=False)
            self._bar.update(self._task, description=line[:60])
        else:
            print(line, file=self.stream, flush=True)

    def point(self, branch: str, parameter: str, value: float, step: float | None,
              n_points: int) -> None:
        """A new point of ``branch``: ``parameter = value`` after a step ``step``."""
        first = branch != self._last_branch
        self._last_branch = branch
        step_text = "" if step is None else f", step {step:.3g}"
        numbers = f"{parameter} = {value:.6g}{step_text}, {n_points} points"
        if first:
            log.info("%s: %s", branch, numbers)
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.update(self._task, description=branch, numbers=numbers)
            return
        if first or n_points % self.every == 0:
            elapsed = time.perf_counter() - self._start
            print(f"  {branch}: {numbers} ({elapsed:.0f} s)", file=self.stream, flush=True)

    def on_point(self, branch) -> None:
        """The ``on_point`` of the verbs: :meth:`point` of the branch's last point."""
        k = len(branch)
        step = float(branch.arclength[-1] - branch.arclength[-2]) if k >= 2 else None
        self.point(branch.name, branch.parameter, float(branch.parameter_values[-1]), step, k)
