"""Errors shared by every layer of supercoil.

:class:`InputError` is raised by the constructors of options and problems (and by
the readers of study, curve and result files) when an input is invalid. Its
message names the input, says what is wrong and what would be valid; the
``supercoil`` command prints it as its ``error:`` line and exits with status 2.
It is a :class:`ValueError`, so code that catches ``ValueError`` keeps working.
"""

from __future__ import annotations

import re


class InputError(ValueError):
    """An invalid input: which one, what is wrong, and what would be valid.

    ``name``: the input's name as the raising code knows it (``"twist_ratio"``),
    when the message starts with it; :meth:`renamed` puts a caller's name for the
    same input in its place (a command-line option, a key of a study file).
    """

    def __init__(self, message: str, *, name: str | None = None) -> None:
        super().__init__(message)
        self.name = name

    def renamed(self, names: dict[str, str]) -> str:
        """The message with its leading input name replaced by ``names[name]``, if given
        (and later mentions of a name with an underscore, such as ``base_pairs``)."""
        message = str(self)
        label = names.get(self.name) if self.name else None
        if label is None or not message.startswith(self.name):
            return message
        rest = message[len(self.name):]
        if "_" in self.name and " " not in label:
            rest = re.sub(rf"\b{re.escape(self.name)}\b", label, rest)
        return label + rest


__all__ = ["InputError"]
