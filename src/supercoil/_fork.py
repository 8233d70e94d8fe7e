"""Work done in a fork of this process, on the other core, while this process goes on.

A fork copies the whole process as it is at that instant (every object, cache and
accepted state), so nothing has to be rebuilt there. A :class:`Worker` is such a fork
that then answers requests: a caller that sends it every change of its own state
(the continuation's tracer sends every accepted point) keeps it in step, and only
requests and answers cross the pipes. One fork per request is not used: on this
project's machine a fork makes the parent fault on every page it writes afterwards
(268 000 faults over 115 forks, measured: slower than computing in the process).

Forking is safe only where no other thread could hold a lock the fork would need:
:func:`can_fork` asks for Linux, at least two usable cores and a single thread in
the process, native ones included (``/proc/self/task``: a BLAS or XLA pool
counts). The ``supercoil`` command sets OpenBLAS to one thread before numpy is
imported, so its process has one thread; under pytest with JAX imported, or in a
user's threaded program, nothing forks and everything is computed in the process.

Point workers (:func:`point_workers`) are off in a library call unless
:func:`use_point_workers` turned them on; the command turns them on for its own
process (:func:`supercoil.cli.main.main`).
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import struct
import sys
from collections.abc import Callable

_point_workers = False


def usable_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


def can_fork() -> bool:
    """Whether a fork may compute beside this process: Linux (a fork of a process that
    imported numpy, scipy, numba or matplotlib is safe there; macOS's system libraries
    are not fork-safe), at least two cores, and no thread but this one, Python's or
    native (counted in ``/proc/self/task``: another thread, e.g. a BLAS or XLA pool,
    could hold a lock that the fork would then wait for forever)."""
    if not (sys.platform.startswith("linux") and hasattr(os, "fork") and usable_cores() >= 2):
        return False
    try:
        return len(os.listdir("/proc/self/task")) == 1
    except OSError:
        return False


def use_point_workers(enabled: bool = True) -> None:
    """Compute each accepted continuation point's stability, records and events in a
    fork while the next step is corrected (:class:`~supercoil.continuation.pseudo_arclength._Tracer`),
    where :func:`can_fork` allows it. The results are those of the serial computation."""
    global _point_workers
    _point_workers = bool(enabled)


def point_workers() -> bool:
    """Whether a continuation point may be handed to a fork now (see :func:`use_point_workers`)."""
    return _point_workers and can_fork()


class Worker:
    """A fork of this process that answers requests: ``serve(request)`` for each
    :meth:`submit`, in order, until :meth:`close`.

    The fork starts as this process is at the instant of the fork and then changes
    only by what ``serve`` does, so a caller that submits every change of its own
    state keeps the two in step. Requests and answers are pickled through two pipes
    (a length, then the bytes). The fork ignores interrupts (Ctrl-C reaches the
    whole process group: the parent decides what to do with the answer) and leaves
    with ``os._exit``, so it runs none of the parent's exit handlers and flushes
    none of its buffers.
    """

    def __init__(self, serve: Callable[[object], object]):
        requests_read, requests_write = os.pipe()
        answers_read, answers_write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the fork: answer every request, leave at the end of the requests
            try:
                os.close(requests_write)
                os.close(answers_read)
                signal.signal(signal.SIGINT, signal.SIG_IGN)
                while True:
                    request = _receive(requests_read)
                    if request is None:
                        break
                    try:
                        answer = pickle.dumps((True, serve(pickle.loads(request))),
                                              protocol=pickle.HIGHEST_PROTOCOL)
                    except BaseException as exc:  # noqa: BLE001 - every failure goes back
                        try:
                            answer = pickle.dumps((False, exc), protocol=pickle.HIGHEST_PROTOCOL)
                        except Exception:  # noqa: BLE001 - an exception that does not pickle
                            answer = pickle.dumps((False, RuntimeError(
                                f"{type(exc).__name__}: {exc}")),
                                protocol=pickle.HIGHEST_PROTOCOL)
                    _send(answers_write, answer)
            finally:
                os._exit(0)
        os.close(requests_read)
        os.close(answers_write)
        self.pid = pid
        self._requests = requests_write
        self._answers = answers_read
        self._partial = b""  # an answer read in part when an interrupt came
        self.capacity = _widen(requests_write)  # bytes the request pipe holds
        self._unanswered: list[int] = []  # sizes of the requests not answered yet

    @staticmethod
    def pack(request: object) -> bytes:
        return pickle.dumps(request, protocol=pickle.HIGHEST_PROTOCOL)

    def room(self, packed: bytes) -> bool:
        """Whether ``packed`` fits in the request pipe beside the unanswered requests. A
        caller that reads no answer before its next request must wait for answers
        until it does: the fork may be blocked writing an answer while the pipe is
        full, and a write would then wait forever."""
        return sum(self._unanswered) + len(packed) + _LENGTH.size <= self.capacity

    def submit(self, request: object) -> None:
        """Queue ``request`` (or its :meth:`pack`); to a fork that has died, nothing (its
        :meth:`result` says so)."""
        packed = request if isinstance(request, bytes) else self.pack(request)
        self._unanswered.append(len(packed) + _LENGTH.size)
        try:
            _send(self._requests, packed)
        except BrokenPipeError:
            pass  # the fork ended: result() answers (False, None) at the end of its answers

    def result(self) -> tuple[bool, object]:
        """The answer to the oldest request not yet answered: ``(True, value)``; the
        exception ``serve`` raised is raised here; ``(False, None)`` if the fork ended
        without answering (killed). An interrupt while waiting leaves the answer to a
        later call."""
        data = _receive(self._answers, self)
        if self._unanswered:
            del self._unanswered[0]
        if data is None:
            return False, None
        try:
            ok, value = pickle.loads(data)
        except Exception:  # noqa: BLE001 - a truncated answer: the fork was killed
            return False, None
        if not ok:
            raise value
        return True, value

    def close(self) -> None:
        """End the requests and wait for the fork to leave."""
        if self._requests is None:
            return
        for fd in (self._requests, self._answers):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._requests = self._answers = None
        with contextlib.suppress(ChildProcessError):
            os.waitpid(self.pid, 0)


_LENGTH = struct.Struct("<Q")
PIPE_BYTES = 1 << 20  # asked for the request pipe (Linux's default limit for a user)


def _widen(fd: int) -> int:
    """Ask for a pipe of ``PIPE_BYTES`` (Linux, ``F_SETPIPE_SZ``); the size it has."""
    try:
        import fcntl

        return fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, PIPE_BYTES)
    except (ImportError, AttributeError, OSError):
        return 1 << 16  # the usual default


def _send(fd: int, data: bytes) -> None:
    view = memoryview(_LENGTH.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _receive(fd: int, keeper: Worker | None = None) -> bytes | None:
    """One message from ``fd`` (None at its end or a truncated one); with ``keeper``,
    what was read before an interrupt is kept there and read on from next time."""
    data = keeper._partial if keeper is not None else b""
    try:
        while True:
            need = _LENGTH.size
            if len(data) >= need:
                need += _LENGTH.unpack_from(data)[0]
                if len(data) >= need:
                    break
            chunk = os.read(fd, min(1 << 20, need - len(data)))
            if not chunk:
                if keeper is not None:
                    keeper._partial = b""
                return None
            data += chunk
    except KeyboardInterrupt:
        if keeper is not None:
            keeper._partial = data
        raise
    if keeper is not None:
        keeper._partial = b""
    return data[_LENGTH.size:]
