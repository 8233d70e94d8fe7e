"""Errors shared by every layer of supercoil.

:class:`InputError` is raised by the constructors of options and problems (and by
the readers of study, curve and result files) when an input is invalid. Its
message names the input, says what is wrong and what would be valid; the
``supercoil`` command prints it as its ``error:`` line and exits with status 2.
It is a :class:`ValueError`, so code that catches ``ValueError`` keeps working.
"""

from __future__ import annotations


class InputError(ValueError):
    """An invalid input: which one, what is wrong, and what would be valid."""


__all__ = ["InputError"]
