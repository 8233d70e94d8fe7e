"""supercoil: equilibria, branches, bifurcations and stability of self-avoiding elastic rods."""

from supercoil._version import __version__

__all__ = ["__version__", "load"]


def load(path):
    """Read a result -- ``result.h5``, or the output folder of any command that computes
    (``demo``, ``diagram ring``, ``tweezers``, ``run``, ``ring --out``) -- into a
    :class:`supercoil.io.store.Result`: ``.branches`` maps names to ``Branch`` objects,
    with the settings, status and summary (see ``docs/results.md``). A damaged or
    truncated file raises :class:`supercoil.errors.InputError`."""
    from supercoil.io.store import load as _load

    return _load(path)
