"""The frames a problem carries at a branch's points, restored rather than re-accepted.

A rod's reference frames (a Cosserat rod's chart) are carried from point to point
along a branch (:mod:`supercoil.solvers.carried`); a state means the same
configuration only with the frames it was computed with. The tracer keeps them per
point (``Branch.frames``) and at each special point (``SpecialPoint.frames``), and
switching, the consistency check and resumption start from those. A branch read
from a file has none (unless its problem stores them with its points,
``Frames.stored``: a Cosserat rod's chart): its frames are carried again along its
stored states from the branch's start, in order, as the run that computed it carried
them; from the same problem that gives the same frames whatever was computed before.
"""

from __future__ import annotations

import numpy as np

from supercoil.continuation.branch import Branch
from supercoil.solvers.carried import carried, frames_of, with_frames


def carried_along(problem, states) -> tuple[object, list]:
    """``(problem carried along states in order, the frames at each)``; ``problem`` is
    unchanged."""
    frames = []
    for q in states:
        problem = carried(problem, np.asarray(q, dtype=float))
        frames.append(frames_of(problem))
    return problem, frames


def frames_at(problem, branch: Branch, index: int):
    """``problem`` carrying the frames of point ``index`` of ``branch``: the stored
    ones, else carried along its states ``0 .. index`` (module doc)."""
    if branch.frames:
        return with_frames(problem, branch.frames[index])
    return carried_along(problem, branch.states[:index + 1])[0]


def branch_frames(problem, branch: Branch) -> tuple:
    """The frames of every point of ``branch``: the stored ones, else carried along
    its states from ``problem`` (module doc)."""
    if branch.frames:
        return branch.frames
    return tuple(carried_along(problem, branch.states)[1])
