"""supercoil: equilibria, branches, bifurcations and stability of self-avoiding elastic rods."""

from supercoil._version import __version__

__all__ = ["__version__", "load"]


def load(path):
    """Read a result file (``supercoil run``'s ``result.h5``) into a
    :class:`supercoil.io.store.Result`: branches as ``Branch`` objects, settings,
    per-point records (see ``docs/results.md``)."""
    from supercoil.io.store import load as _load

    return _load(path)
