"""The computed branches of a study, looked up by name (:class:`BranchSet`).

The ring diagram's and the tweezers' results hold their branches in order in a
``branches`` tuple; this base gives them the lookups they share.
"""

from __future__ import annotations

from supercoil.continuation import Branch, SpecialPoint


class BranchSet:
    """Lookups of a result that holds its branches, in order, as ``self.branches``."""

    def branch(self, name: str) -> Branch:
        """The branch called ``name`` (KeyError otherwise)."""
        for b in self.branches:
            if b.name == name:
                return b
        raise KeyError(name)

    def special_points(self) -> list[SpecialPoint]:
        """The special points of every branch, branch by branch."""
        return [p for b in self.branches for p in b.special_points]
