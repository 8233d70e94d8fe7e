"""Checks of inputs, shared by the constructors of options and problems.

Each check raises :class:`~supercoil.errors.InputError` with a message that
names the input, says what is wrong and what is valid, e.g. ``twist_ratio
(C/A) must be a number above 0 and up to 1e6, got -2``. The message starts
with the input's name, which the error carries as ``name`` so that a command
line or a study file can put its own name for the input in its place.

The bounds below are the stated limits of every size and magnitude: beyond
them a computation would exhaust memory (a rod of 1e9 nodes) or overflow (an
excess link of 1e300), so the inputs are refused before any work.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence

from supercoil.errors import InputError

MIN_NODES = 8  # nodes of a closed rod
MIN_CLAMPED_NODES = 12  # nodes of a clamped rod
MAX_NODES = 100_000
MAX_MAGNITUDE = 1e6  # |excess link| (turns), C/A, L/D, forces F L^2/A
MAX_POINTS = 100_000  # points of one branch, steps of one quasi-static path
MAX_TURNS = 1000.0  # turns of the tweezers' end
MIN_BASE_PAIRS = 12
MAX_BASE_PAIRS = 10_000_000
MAX_CURVE_VERTICES = MAX_NODES  # vertices of a curve file
MAX_CURVE_BYTES = 16 * 1024 * 1024  # size of a curve file


def _text(value: float) -> str:
    """``1e6`` rather than ``1000000.0``, ``3.1416`` for pi, ``0.5`` as it is."""
    if value == math.pi:
        return "pi (3.1416)"
    if isinstance(value, numbers.Integral):
        return str(value)
    value = float(value)
    if value.is_integer() and abs(value) < 1e5:
        return str(int(value))
    text = f"{value:g}"
    return text.replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


def interval_text(low: float, high: float, low_open: bool = False,
                  high_open: bool = False) -> str:
    """``"from 0 to 1e6"``, ``"above 0 and up to 1e6"``, ``"strictly between 0 and 1"``."""
    if low == -math.inf and high == math.inf:
        return "finite"
    if low == -math.inf:
        return f"{'below' if high_open else 'up to'} {_text(high)}"
    if high == math.inf:
        return f"{'above' if low_open else 'at least'} {_text(low)}"
    if low_open and high_open:
        return f"strictly between {_text(low)} and {_text(high)}"
    if low_open:
        return f"above {_text(low)} and up to {_text(high)}"
    if high_open:
        return f"from {_text(low)} to below {_text(high)}"
    return f"from {_text(low)} to {_text(high)}"


def refuse(name: str, message: str) -> InputError:
    """The :class:`InputError` ``"{name} {message}"`` (to be raised), carrying ``name``."""
    return InputError(f"{name} {message}", name=name)


def _label(name: str, meaning: str) -> str:
    return f"{name} ({meaning})" if meaning else name


def number(name: str, value, low: float = -math.inf, high: float = math.inf, *,
           low_open: bool = False, high_open: bool = False, meaning: str = "") -> float:
    """``value`` as a float if it is a finite real number in the interval; else InputError.

    ``meaning`` says what the input is (``"C/A"``), shown after the name.
    """
    valid = f"a number {interval_text(low, high, low_open, high_open)}"
    if valid.endswith("finite"):
        valid = "a finite number"
    label = _label(name, meaning)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{label} must be {valid}, got {value!r}", name=name)
    x = float(value)
    if not math.isfinite(x):
        raise InputError(f"{label} must be {valid}, got {value!r} (not a finite number)",
                         name=name)
    if not ((x > low if low_open else x >= low) and (x < high if high_open else x <= high)):
        raise InputError(f"{label} must be {valid}, got {value!r}", name=name)
    return x


def optional_number(name: str, value, *args, **kwargs) -> float | None:
    """``None`` passes; anything else as :func:`number`."""
    return None if value is None else number(name, value, *args, **kwargs)


def integer(name: str, value, low: int, high: int, *, meaning: str = "") -> int:
    """``value`` as an int if it is a whole number from ``low`` to ``high``; else InputError."""
    label = _label(name, meaning)
    valid = f"a whole number from {low} to {high}"
    whole = (not isinstance(value, bool) and isinstance(value, numbers.Real)
             and math.isfinite(float(value)) and float(value).is_integer())
    if not whole or not low <= int(value) <= high:
        raise InputError(f"{label} must be {valid}, got {value!r}", name=name)
    return int(value)


def choice(name: str, value, options: Sequence[str], *, meaning: str = "") -> str:
    """``value`` if it is one of ``options``; else InputError listing them."""
    if not isinstance(value, str) or value not in options:
        raise InputError(f"{_label(name, meaning)} must be one of {', '.join(options)}, got "
                         f"{value!r}", name=name)
    return value


def flag(name: str, value) -> bool:
    """``value`` if it is a bool; else InputError."""
    if not isinstance(value, bool):
        raise InputError(f"{name} must be true or false, got {value!r}", name=name)
    return value


def distinct_integers(name: str, values: Iterable, low: int, high: int, *,
                      meaning: str = "") -> tuple[int, ...]:
    """A non-empty tuple of distinct whole numbers from ``low`` to ``high``, sorted."""
    label = _label(name, meaning)
    valid = f"distinct whole numbers from {low} to {high}, at least one"
    try:
        items = tuple(values)
    except TypeError:
        raise InputError(f"{label} must be {valid}, got {values!r}", name=name) from None
    good = items and all(not isinstance(v, bool) and isinstance(v, numbers.Real)
                         and math.isfinite(float(v)) and float(v).is_integer()
                         and low <= int(v) <= high for v in items)
    if not good or len({int(v) for v in items}) != len(items):
        raise InputError(f"{label} must be {valid}, got {values!r}", name=name)
    return tuple(sorted(int(v) for v in items))


__all__ = ["MAX_BASE_PAIRS", "MAX_CURVE_BYTES", "MAX_CURVE_VERTICES", "MAX_MAGNITUDE",
           "MAX_NODES", "MAX_POINTS", "MAX_TURNS", "MIN_BASE_PAIRS", "MIN_CLAMPED_NODES",
           "MIN_NODES", "choice", "distinct_integers", "flag", "integer", "interval_text",
           "number", "optional_number", "refuse"]
