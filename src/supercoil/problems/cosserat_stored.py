"""A Cosserat branch as it is stored and shown, and back: :func:`centreline_branch`,
:func:`cosserat_branch`.

The outputs, the viewer and the result files read a branch's states as centrelines
(``(k, 3 N)``, as a Kirchhoff ring's). A Cosserat branch's unknowns are each node's
position and rotation coordinates (``q[6i:6i+3]``, ``q[6i+3:6i+6]``), which mean a
configuration only with the chart the run carried at the point (its frames:
:mod:`supercoil.cosserat.problem`). At an accepted point the chart is re-based there,
so its frames hold the point's own rotations, chart-free: ``reference_rotations``
``(N, 3, 3)`` (each section's rotation matrix) and ``centres`` ``(N, 3)`` (its rotation
coordinates, equal to the point's). The stored branch keeps the centrelines as its
states and those frames with every point (:class:`~supercoil.solvers.carried.Frames`
``stored``: ``frames/reference_rotations`` and ``frames/centres`` in the result
file); its tangents, phase conditions and special points stay in the rod's unknowns.
:func:`cosserat_branch` rebuilds the branch in the unknowns from it, bit for bit the
branch the run computed, so that it can be continued (``resume``) and switched from.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.continuation import Branch
from supercoil.cosserat.rod import DOFS_PER_NODE


def centreline_branch(branch: Branch) -> Branch:
    """The branch with its states as centrelines ``(k, 3 n)`` (module doc); the rest,
    its frames included, as computed."""
    k = len(branch)
    if not k or branch.states.shape[1] % DOFS_PER_NODE:  # no point, or centrelines already
        return branch
    states = np.asarray(branch.states, float).reshape(k, -1, DOFS_PER_NODE)[:, :, :3]
    return dataclasses.replace(branch, states=states.reshape(k, -1))


def cosserat_branch(stored: Branch) -> Branch:
    """The branch in the Cosserat unknowns of a stored one (:func:`centreline_branch`'s,
    or read from a result file): each state ``[x_i, centres_i]`` per node, from its
    centreline and its frames. A branch without points is returned as it is; one
    without stored frames cannot be rebuilt (ValueError)."""
    k = len(stored)
    if not k:
        return stored
    if stored.states.shape[1] % 3 or not stored.frames \
            or "centres" not in stored.frames[0].values:
        raise ValueError(f"branch {stored.name!r}: stored without the sections' frames, "
                         "so its Cosserat states cannot be rebuilt")
    x = np.asarray(stored.states, float).reshape(k, -1, 3)
    theta = np.asarray([f.values["centres"] for f in stored.frames], float)
    if theta.shape != x.shape:
        raise ValueError(f"branch {stored.name!r}: frames of {theta.shape[1]} nodes for "
                         f"centrelines of {x.shape[1]}")
    states = np.concatenate([x, theta], axis=2).reshape(k, -1)
    return dataclasses.replace(stored, states=states)


def cosserat_stored(stored: dict) -> dict:
    """``name -> (branch, complete)`` of a stored result with every branch that has
    points rebuilt in the Cosserat unknowns (:func:`cosserat_branch`)."""
    return {name: (cosserat_branch(b), complete) for name, (b, complete) in stored.items()}
