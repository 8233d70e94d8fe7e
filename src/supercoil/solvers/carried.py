"""What a problem carries from state to state, as a value: ``frames``, ``with_frames``,
``carried_to``.

A rod's energy depends on reference frames carried along a branch by parallel
transport (and on the reference link that goes with them); a Cosserat rod's on the
chart its rotations are measured in. :class:`Frames` is that carried state as an
immutable value (read-only arrays and numbers); ``problem.frames`` gives it,
``problem.with_frames(frames)`` is a new problem carrying it, and
``problem.carried_to(q)`` a new problem whose frames are transported to the state
``q`` (with the problem's own rules for jumps and rebuilds, its ``accept``). None
of them changes the problem they are called on.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from supercoil.errors import InputError


def _read_only(value):
    if isinstance(value, np.ndarray):
        out = np.array(value, copy=True)
        out.setflags(write=False)
        return out
    return value


@dataclass(frozen=True, eq=False)
class Frames:
    """The carried state of one problem: named read-only arrays and numbers.

    ``stored``: the frames are part of the state a branch's points need to be
    continued (a Cosserat rod's rotations, which its centreline does not give), so a
    result file keeps them with every point (:mod:`supercoil.io.branch_codec`);
    otherwise they are carried again along the stored states when read."""

    values: Mapping[str, object]
    stored: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "values", MappingProxyType(
            {name: _read_only(v) for name, v in dict(self.values).items()}))

    def equals(self, other: Frames) -> bool:
        """Whether ``other`` holds the same names and values, bit for bit."""
        if set(self.values) != set(other.values):
            return False
        return all(np.array_equal(self.values[k], other.values[k]) for k in self.values)

    def __repr__(self) -> str:
        return f"Frames({', '.join(self.values)})"


class Carried:
    """Mixin: ``frames``, ``with_frames`` and ``carried_to`` from the class's in-place
    ``accept(q)`` and the attributes it carries (:attr:`frame_attributes`: pairs of the
    name in :class:`Frames` and the attribute)."""

    frame_attributes: tuple[tuple[str, str], ...] = ()
    # whether a result file keeps the frames with every point (Frames.stored)
    frames_stored: bool = False

    @property
    def frames(self) -> Frames:
        """The carried state (a copy: later changes of the problem do not reach it)."""
        return Frames({name: getattr(self, attribute)
                       for name, attribute in self.frame_attributes},
                      stored=self.frames_stored)

    def with_frames(self, frames: Frames):
        """A new problem carrying ``frames`` (from ``frames`` of a problem of this
        class and size); this one is unchanged."""
        names = [name for name, _ in self.frame_attributes]
        if set(frames.values) != set(names):
            raise InputError(f"frames: holds {', '.join(frames.values) or 'nothing'}; a "
                             f"{type(self).__name__} carries {', '.join(names) or 'nothing'}")
        new = copy.copy(self)
        new._restore_frames(frames)
        return new

    def _restore_frames(self, frames: Frames) -> None:
        """Set the carried attributes (rebinding; the read-only arrays are shared)."""
        for name, attribute in self.frame_attributes:
            setattr(self, attribute, frames.values[name])

    def carried_to(self, q: np.ndarray):
        """A new problem whose carried state is transported to ``q`` (``accept``'s
        rules); this one is unchanged."""
        new = copy.copy(self)
        new.accept(q)
        return new


def carried(problem, q: np.ndarray):
    """``problem.carried_to(q)``; for a protocol object without it (a caller's own), a
    shallow copy on which ``accept(q)`` is called, if it has ``accept`` (which must then
    rebind what it carries, never write into arrays the copy shares)."""
    carry = getattr(problem, "carried_to", None)
    if carry is not None:
        return carry(q)
    new = copy.copy(problem)
    accept = getattr(new, "accept", None)
    if accept is not None:
        accept(q)
    return new


def frames_of(problem) -> Frames | None:
    """``problem.frames``, or None for a protocol object that carries nothing."""
    return getattr(problem, "frames", None)


def with_frames(problem, frames: Frames | None):
    """``problem.with_frames(frames)``; the problem itself for ``frames`` None."""
    return problem if frames is None else problem.with_frames(frames)
