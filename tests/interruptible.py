"""Child processes that a test interrupts as a user's Ctrl-C would.

A shell starts a background job (``cmd &`` without job control, ``nohup``) with SIGINT
ignored, and a child inherits that: Python then installs no KeyboardInterrupt handler,
and a test's SIGINT does nothing. The tests that send SIGINT start their child with
SIGINT at its default disposition, so that it behaves as a command run in a terminal
whatever the test runner was started from.
"""

from __future__ import annotations

import signal
import subprocess


def popen(args, **kwargs) -> subprocess.Popen:
    """``subprocess.Popen(args, **kwargs)`` with SIGINT not ignored in the child: an
    ignored SIGINT of this process is set to Python's default handler while the child
    starts (a handler becomes the default disposition across ``exec``; an ignored
    signal stays ignored), then restored."""
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.SIG_IGN:
        return subprocess.Popen(args, **kwargs)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return subprocess.Popen(args, **kwargs)
    finally:
        signal.signal(signal.SIGINT, previous)
