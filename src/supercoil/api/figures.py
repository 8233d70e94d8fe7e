"""Figures of a stored result from Python: the figures ``supercoil plot`` draws.

The result is read from its file (``result.h5``, written by any command or by
:func:`supercoil.save`) or its output folder, so a figure shows exactly what was
stored.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from supercoil.errors import InputError


def plot(result, kind: str | None = None, out: str | Path = ".",
         formats: Sequence[str] = ("png",)) -> list[Path]:
    """Draw the figures of ``result`` (a ``result.h5``, an output folder, a
    ``diagram.json`` / ``branch.json``, :func:`supercoil.load`'s result, or a Diagram or
    Equilibrium just computed) into the folder ``out``; returns the files.

    ``kind``: one figure (``diagram``, ``contact-map``, ``configurations``,
    ``hat-curve``, ...); by default every kind the result has data for. ``formats``:
    ``png`` and/or ``svg``.
    """
    from supercoil.api.outputs import stored
    from supercoil.plotting.result_data import load_result

    with stored(result) as source:
        return _draw(load_result(source), kind, out, formats)


def _draw(data, kind: str | None, out, formats: Sequence[str]) -> list[Path]:
    from supercoil.plotting import style
    from supercoil.plotting.figures import plot_result, supported_kinds

    kinds = supported_kinds(data)
    if kind is not None and kind not in kinds:
        raise InputError(f"kind: {kind!r} is not drawn for this result; valid: "
                         f"{', '.join(kinds)}")
    unknown = [f for f in formats if f not in style.FORMATS]
    if not formats or unknown:
        raise InputError(f"formats: got {list(formats)!r}; valid: any of "
                         f"{', '.join(style.FORMATS)}")
    folder = Path(out)
    if not folder.is_dir():
        raise InputError(f"out: {folder} is not an existing folder")
    written: list[Path] = []
    for name in ([kind] if kind is not None else kinds):
        written += [Path(p) for p in plot_result(data, name, folder, formats=tuple(formats))]
    return written
