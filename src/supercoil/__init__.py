"""supercoil: equilibria, branches, bifurcations and stability of self-avoiding elastic rods."""

from supercoil._version import __version__

__all__ = ["__version__"]
