"""Figures of a stored result or sweep from Python: the figures ``supercoil plot`` draws.

The result is read from its file (``result.h5``, written by any command or by
:func:`supercoil.save`) or its output folder, a sweep from its folder (``supercoil
sweep --out``) or its ``sweep.nc``, so a figure shows exactly what was stored.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from supercoil.errors import InputError


def plot(result, kind: str | None = None, out: str | Path = ".",
         formats: Sequence[str] = ("png",), variable: str | None = None) -> list[Path]:
    """Draw the figures of ``result`` (a ``result.h5``, an output folder, a
    ``diagram.json`` / ``branch.json``, :func:`supercoil.load`'s result, or a Diagram or
    Equilibrium just computed; or a sweep's folder or ``sweep.nc``) into the folder
    ``out``; returns the files.

    ``kind``: one figure (``diagram``, ``contact-map``, ``configurations``,
    ``hat-curve``, ...; of a sweep ``hat-curves``, ``curve-map``, ``map``,
    ``buckling-torque``); by default every kind the result has data for.
    ``formats``: ``png`` and/or ``svg``. ``variable``: the dataset's number a sweep's
    ``map`` draws (default: the problem's, e.g. ``end_extension`` for tweezers).
    """
    from supercoil.api.outputs import stored
    from supercoil.plotting import style
    from supercoil.plotting.result_data import load_result
    from supercoil.plotting.sweep import is_sweep

    unknown = [f for f in formats if f not in style.FORMATS]
    if not formats or unknown:
        raise InputError(f"formats: got {list(formats)!r}; valid: any of "
                         f"{', '.join(style.FORMATS)}")
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"out: {folder} is a file, not a folder; give a folder")
    if isinstance(result, (str, Path)) and is_sweep(result):
        return _plot_sweep(Path(result), kind, folder, tuple(formats), variable)
    if variable is not None:
        raise InputError(f"variable: only a sweep's map takes it; {result} is not a sweep")
    with stored(result) as source:
        data = load_result(source)
        _make_folder(folder)
        return _draw(data, kind, folder, formats)


def _make_folder(folder: Path) -> None:
    """Create ``folder`` (and its parents), as ``supercoil plot --out`` does."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"out: cannot create the folder {folder} ({exc.strerror}); give a "
                         "folder in a writable location") from None


def _draw(data, kind: str | None, folder: Path, formats: Sequence[str]) -> list[Path]:
    from supercoil.plotting.figures import plot_result, supported_kinds

    kinds = supported_kinds(data)
    if kind is not None and kind not in kinds:
        raise InputError(f"kind: {kind!r} is not drawn for this result; valid: "
                         f"{', '.join(kinds)}")
    written: list[Path] = []
    for name in ([kind] if kind is not None else kinds):
        written += [Path(p) for p in plot_result(data, name, folder, formats=tuple(formats))]
    return written


def _plot_sweep(path: Path, kind, folder: Path, formats: tuple, variable) -> list[Path]:
    from supercoil.plotting.sweep import plot_sweep, sweep_kinds
    from supercoil.sweeps.dataset import load_sweep

    kinds = sweep_kinds(load_sweep(path))
    if kind is not None and kind not in kinds:
        raise InputError(f"kind: {kind!r} is not drawn for this sweep; valid: "
                         f"{', '.join(kinds)}")
    _make_folder(folder)
    written: list[Path] = []
    for name in ([kind] if kind is not None else kinds):
        try:
            written += plot_sweep(path, name, folder, formats, variable)
        except ValueError as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(str(exc)) from None
    return written
