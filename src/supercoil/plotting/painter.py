"""Figures drawn by a helper process that imports matplotlib during the computation.

A command that ends by drawing figures pays matplotlib's import (0.3 s) and
the drawing (0.1 s a figure) after its computation, one after the other. A
:class:`Painter` started before the computation runs ``python -m
supercoil.plotting.painter``, which imports matplotlib and draws a small
figure (the fonts and the mathtext parser loaded) on another core while the
command computes, then waits for the figures
(:func:`supercoil.plotting.tweezers.figure_jobs`, pickled on its standard
input) and draws them. The command's own process never imports matplotlib,
so the helper adds only its interpreter and numpy (about 0.15 s of CPU).
The helper runs at the lowest priority (``nice 19``): on a machine whose other
cores are busy it takes no time from the computation and does its work while
the command waits for it; at normal priority it slowed the computation by
about as much as it saved. One helper, not one per figure: two would import
matplotlib twice, and on the two-core benchmark machine, with another
process busy, two made the figures slower, not faster (docs/benchmarks.md,
"Session 8").

The files are the same as drawn in the command's own process (the same
builders, style and save options). Whatever the helper did not draw (it
could not start, failed or timed out) is reported back and drawn by the caller.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Self

PROCESSES = 1  # helpers (module doc)
TIMEOUT = 300.0  # seconds a helper may take for its figures before it is killed


def usable_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


class Painter:
    """Helper processes that draw figure jobs (module doc); a context manager.

    ``processes``: how many helpers (default :data:`PROCESSES`; none on a
    single core, where a helper would only take turns with the computation).
    """

    def __init__(self, processes: int | None = None):
        count = PROCESSES if processes is None else int(processes)
        if usable_cores() < 2:
            count = 0
        self._helpers: list[subprocess.Popen] = []
        env = dict(os.environ)
        # the helpers import this very package, wherever it was imported from
        source = str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (source, env.get("PYTHONPATH", "")) if p)
        for _ in range(count):
            try:
                self._helpers.append(subprocess.Popen(
                    [sys.executable, "-m", "supercoil.plotting.painter"],
                    stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL, env=env))
            except OSError:
                break

    def draw(self, jobs: Sequence) -> list:
        """Hand ``jobs`` round-robin to the helpers and wait for them; returns the jobs
        that were not drawn (all of them without helpers), for the caller to draw."""
        helpers, self._helpers = self._helpers, []
        if not helpers:
            return list(jobs)
        shares = [list(jobs[i::len(helpers)]) for i in range(len(helpers))]
        sent = []
        for helper, share in zip(helpers, shares, strict=True):
            try:
                helper.stdin.write(pickle.dumps(share))
                helper.stdin.close()
                sent.append(True)
            except OSError:  # the helper is gone (a broken pipe)
                with contextlib.suppress(OSError):
                    helper.stdin.close()  # closes the pipe even when its flush fails
                sent.append(False)
        left = []
        for helper, share, ok in zip(helpers, shares, sent, strict=True):
            try:
                helper.wait(timeout=TIMEOUT)
            except subprocess.TimeoutExpired:
                helper.kill()
                helper.wait()
                ok = False
            if not ok or helper.returncode != 0:
                left += share
        return left

    def close(self) -> None:
        """End helpers that got no jobs (the command failed or was interrupted): they
        have written nothing, and would otherwise first finish importing matplotlib."""
        helpers, self._helpers = self._helpers, []
        for helper in helpers:
            with contextlib.suppress(OSError):
                helper.kill()
            helper.wait()
            with contextlib.suppress(OSError):
                helper.stdin.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _warm_up() -> None:
    """Draw and encode a small figure in the house style (fonts, mathtext, PNG)."""
    import io

    from supercoil.plotting.tweezers import SAVE_OPTIONS, diagram_figure

    fig = diagram_figure([{"name": "a", "turns": [0.0, 1.0], "extension": [1.0, 0.5],
                           "stable": [True, False]}],
                         [{"kind": "fold", "turns": 1.0, "extension": 0.5}],
                         title="warm-up", x="turns", y="extension")
    fig.savefig(io.BytesIO(), format="png", **SAVE_OPTIONS)


def main() -> int:
    """The helper: warm up, read the pickled jobs from standard input, draw them."""
    try:
        with contextlib.suppress(AttributeError, OSError):
            # the lowest priority: the helper takes only a core the command leaves idle
            os.nice(19)
        _warm_up()
        data = sys.stdin.buffer.read()
        if not data:
            return 0  # closed without jobs
        from supercoil.plotting.tweezers import draw_job

        for job in pickle.loads(data):
            draw_job(job)
    except KeyboardInterrupt:  # Ctrl-C reaches the whole process group
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
