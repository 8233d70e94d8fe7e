"""Figures drawn by a helper process that imports matplotlib during the computation.

A command that ends by drawing figures pays matplotlib's import (0.3 s) and
the drawing (0.1 s a figure) after its computation, one after the other. A
:class:`Painter` started before the computation runs ``python -m
supercoil.plotting.painter``, which imports matplotlib and draws a small
figure (the fonts and the mathtext parser loaded) on another core while the
command computes, says so on its standard output, then waits for the
figures (:func:`supercoil.plotting.tweezers.figure_jobs`, or the ring diagram's
jobs of :mod:`supercoil.plotting.ring_diagram`, pickled on its
standard input) and draws them. The command's own process then never
imports matplotlib.

The helper runs at the lowest priority (``nice 19``), so that it takes no
time from the computation when the machine's other cores are busy; at
normal priority, with another job on the two-core machine, it slowed the
computation by about as much as it saved. A helper that is not ready when
the figures are due (it was starved) is ended and the caller draws them
itself, as without a painter: its interpreter and numpy imports are then
the only cost. One helper, not one per figure: two would import matplotlib
twice, and with another job on the machine two made the figures slower,
not faster (docs/benchmarks.md, "Session 8"). When the figures come, the
helper forks (Linux): the fork shares its warmed-up matplotlib and the two
draw the jobs side by side (:func:`draw_shared`), while the command's own
process waits on the other core.

The files are the same as drawn in the command's own process (the same
builders, style and save options). Whatever the helper did not draw (it
could not start, was not ready, failed or timed out) is reported back and
drawn by the caller.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import select
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Self

from supercoil._fork import can_fork as _can_fork
from supercoil._fork import usable_cores

PROCESSES = 1  # helpers (module doc)
TIMEOUT = 300.0  # seconds a helper may take for its figures before it is killed
READY = b"ready\n"  # what a helper writes on its standard output once warmed up


class Painter:
    """Helper processes that draw figure jobs (module doc); a context manager.

    ``processes``: how many helpers (default :data:`PROCESSES`; none on a
    single core, where a helper would only take turns with the computation).
    """

    def __init__(self, processes: int | None = None):
        count = PROCESSES if processes is None else int(processes)
        if usable_cores() < 2 or os.name == "nt":  # Windows: no select() on pipes
            count = 0
        self._helpers: list[subprocess.Popen] = []
        self._ready: set[int] = set()
        env = dict(os.environ)
        # the helpers import this very package, wherever it was imported from
        source = str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (source, env.get("PYTHONPATH", "")) if p)
        for _ in range(count):
            try:
                self._helpers.append(subprocess.Popen(
                    [sys.executable, "-m", "supercoil.plotting.painter"],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                    stderr=subprocess.DEVNULL, env=env))
            except OSError:
                break

    def _warmed_up(self, helper: subprocess.Popen, timeout: float) -> bool:
        """Whether ``helper`` said it is warmed up, waiting up to ``timeout`` seconds."""
        if helper.pid in self._ready:
            return True
        try:
            readable, _, _ = select.select([helper.stdout], [], [], timeout)
        except (OSError, ValueError):
            return False
        if readable and helper.stdout.read(len(READY)) == READY:  # b"" if it ended
            self._ready.add(helper.pid)
            return True
        return False

    def ready(self, timeout: float = 0.0) -> bool:
        """Whether every helper has imported matplotlib and warmed up (it says so on
        its standard output), waiting up to ``timeout`` seconds; False without helpers."""
        deadline = time.monotonic() + timeout
        return bool(self._helpers) and all(
            self._warmed_up(h, max(0.0, deadline - time.monotonic())) for h in self._helpers)

    def draw(self, jobs: Sequence) -> list:
        """Hand ``jobs`` round-robin to the helpers that are ready and wait for them;
        returns the jobs that were not drawn, for the caller to draw.

        A helper that is not ready (the machine's other cores were busy, and at
        its priority it waited) is ended: drawing its share here needs only
        matplotlib's import, the helper still its interpreter's, numpy's and
        matplotlib's."""
        return self.wait(self.submit(jobs))

    def submit(self, jobs: Sequence) -> list:
        """The first half of :meth:`draw`: hand ``jobs`` to the helpers that are ready,
        without waiting; returns what :meth:`wait` takes (the caller can work meanwhile,
        e.g. write its data files while the figures are drawn)."""
        helpers = [h for h in self._helpers if self._warmed_up(h, 0.0)]
        self.close(keep=helpers)
        if not helpers:
            return [(None, list(jobs), False)]
        shares = [list(jobs[i::len(helpers)]) for i in range(len(helpers))]
        sent = []
        for helper, share in zip(helpers, shares, strict=True):
            try:
                helper.stdin.write(pickle.dumps(share))
                helper.stdin.close()
                sent.append((helper, share, True))
            except OSError:  # the helper is gone (a broken pipe)
                with contextlib.suppress(OSError):
                    helper.stdin.close()  # closes the pipe even when its flush fails
                sent.append((helper, share, False))
        return sent

    def wait(self, submitted: list) -> list:
        """The second half of :meth:`draw`: wait for the helpers given jobs by
        :meth:`submit`; returns the jobs that were not drawn, for the caller to draw."""
        left = []
        for helper, share, ok in submitted:
            if helper is None:
                left += share
                continue
            try:
                helper.wait(timeout=TIMEOUT)
            except subprocess.TimeoutExpired:
                helper.kill()
                helper.wait()
                ok = False
            helper.stdout.close()
            if not ok or helper.returncode != 0:
                left += share
        return left

    def close(self, keep: Sequence[subprocess.Popen] = ()) -> None:
        """End the helpers (but those in ``keep``) that got no jobs: the command failed
        or was interrupted, or they were not ready. They have written nothing."""
        helpers, self._helpers = self._helpers, []
        for helper in helpers:
            if any(helper is k for k in keep):
                continue
            with contextlib.suppress(OSError):
                helper.kill()
            helper.wait()
            for pipe in (helper.stdin, helper.stdout):
                with contextlib.suppress(OSError):
                    pipe.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _warm_up() -> None:
    """Draw and encode a small figure in the house style (fonts, mathtext, PNG)."""
    import io

    import matplotlib

    from supercoil.plotting.tweezers import LINE_DIAGRAM, SAVE_OPTIONS, save_png

    # as draw_job draws a line diagram, on the figure it then draws them on
    with matplotlib.rc_context({"figure.dpi": SAVE_OPTIONS["dpi"]}):
        fig = LINE_DIAGRAM([{"name": "a", "turns": [0.0, 1.0], "extension": [1.0, 0.5],
                             "stable": [True, False]}],
                           [{"kind": "fold", "turns": 1.0, "extension": 0.5}],
                           title="warm-up", x="turns", y="extension")
    save_png(fig, io.BytesIO())


def main() -> int:
    """The helper: warm up, read the pickled jobs from standard input, draw them.

    The garbage collector as in the command's process (:mod:`supercoil._gc`), and
    the objects of the imports and the warm-up frozen once it is done, so that the
    collections while drawing do not go through matplotlib's modules again.
    """
    from supercoil._gc import collect_less, freeze

    collect_less()
    try:
        with contextlib.suppress(AttributeError, OSError):
            # the lowest priority: the helper takes only a core the command leaves idle
            os.nice(19)
        _warm_up()
        freeze()  # matplotlib's modules and caches: kept to the end
        sys.stdout.buffer.write(READY)
        sys.stdout.buffer.flush()
        data = sys.stdin.buffer.read()
        if not data:
            return 0  # closed without jobs
        draw_shared(pickle.loads(data))
        freeze()
    except KeyboardInterrupt:  # Ctrl-C reaches the whole process group
        return 130
    return 0


def _draw(job) -> None:
    """Draw one job of :func:`supercoil.plotting.tweezers.figure_jobs` or of the ring
    diagram (builders ``ring:...``)."""
    if str(job[1]).startswith("ring:"):
        from supercoil.plotting.ring_diagram import draw_job
    else:
        from supercoil.plotting.tweezers import draw_job
    draw_job(job)


def draw_shared(jobs: Sequence, fork: bool | None = None) -> None:
    """Draw ``jobs`` in this process and in a fork of it, side by side.

    The fork shares this process's warmed-up matplotlib (imports, fonts, mathtext:
    nothing is imported twice, unlike a second helper) and takes the jobs from
    the same queue: a pipe holding one byte per job index, each process reading
    one byte (a read of one byte from a pipe is atomic) and drawing that job,
    until the pipe is empty. A job is thus drawn once, whichever process is
    free first. Whatever the fork did not draw (it failed or was killed) is
    drawn here after it ended. ``fork``: None forks when :func:`_can_fork`
    and there are two jobs or more. In a process that has not imported matplotlib
    yet (the command's own, when its helper was not ready) the first job is drawn
    before the fork, so that the fork finds matplotlib imported.

    The command waits for these figures after its computation (0.5-0.8 s for the
    four of ``supercoil tweezers``, when its process is idle): two processes on
    the machine's two cores draw them in about half of that (docs/benchmarks.md,
    "Session 10 (fixed10)").
    """
    jobs = list(jobs)
    if fork is None:
        fork = len(jobs) >= 2 and _can_fork()
    if not fork or len(jobs) > 255:
        for job in jobs:
            _draw(job)
        return
    if "matplotlib.figure" not in sys.modules:
        _draw(jobs[0])
        jobs = jobs[1:]
        if len(jobs) < 2:
            for job in jobs:
                _draw(job)
            return
    read_end, write_end = os.pipe()
    os.write(write_end, bytes(range(len(jobs))))
    os.close(write_end)  # an empty pipe then reads as its end
    try:
        pid = os.fork()
    except OSError:  # no fork (out of processes or memory): this process takes every job
        pid = None
    if pid == 0:  # the fork: draw from the queue, then end without Python's exit handlers
        code = 1
        try:
            while index := os.read(read_end, 1):
                _draw(jobs[index[0]])
            code = 0
        finally:
            os._exit(code)
    drawn_here = set()
    try:
        while index := os.read(read_end, 1):
            drawn_here.add(index[0])
            _draw(jobs[index[0]])
    finally:
        os.close(read_end)
        fork_done = pid is not None and os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) == 0
    if not fork_done:
        for index, job in enumerate(jobs):
            if index not in drawn_here:
                _draw(job)


if __name__ == "__main__":
    sys.exit(main())
