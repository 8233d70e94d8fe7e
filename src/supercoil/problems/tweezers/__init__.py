"""A rod clamped at both ends, pulled and turned: the magnetic-tweezers experiment.

:func:`tweezers_branches` computes, for a rod of twist ratio ``C/A`` and tube
diameter ``D = L / (L/D)`` clamped on the ``z`` axis at both ends
(:class:`~supercoil.rod.open.ClampedRodEnergy`) and turned by ``turns``:

**Load control** (dead load ``F L^2/A``, the turned end slides along the axis):

1. the straight twisted rod in ``turns`` (branch ``straight``), its buckling
   located as a ``bifurcation`` (the unstable count jumps by 2: the rotation
   about the axis makes the critical eigenvalue double) and compared with the
   exact clamped condition (:mod:`supercoil.problems.greenhill`);
2. the buckled branch switched from it along the critical mode (branch
   ``buckled``), followed without contact until the closest approach of
   non-neighbouring points reaches ``D`` (a ``contact_onset``, located as a
   sign change of ``d_min/D - 1``; the branch is cut just after it);
3. from the last point of ``buckled`` that the barrier does not reach yet,
   the branch with self-contact (barrier treatment, ``buckled_contact``)
   through the plectoneme's growth up to the last requested turn.

**Displacement control** (end-to-end distance ``z/L < 1`` held): an
inextensible rod cannot be straight at ``z < L``, so there is no straight
branch: the branch starts from the clamped planar Euler buckle at
``turns = 0`` (tangent angle ``a sin(2 pi s / L)`` with ``a`` chosen for the
end distance, then Newton) and is followed in turns without, then with,
contact as above (branch ``clamped``, ``clamped_contact``).

The rotation about the axis is held by one pinned coordinate, picked again
along a branch where needed (:mod:`~supercoil.problems.tweezers.pins`); the
runs between are merged into one :class:`~supercoil.continuation.Branch`.
The per-point records are listed in :mod:`~supercoil.problems.tweezers.problem`.
The modules: ``options``, ``problem`` (the rod and the records), ``pins``,
``straight`` (Greenhill's straight rod), ``buckled`` (the contact-free
branch), ``contact`` (the branch with self-contact), ``result`` and
``compute`` (the driver); the quasi-static protocols are in
:mod:`supercoil.problems.tweezers_protocol`, the ``branch.json`` payload in
:mod:`supercoil.problems.tweezers_output`.
"""

from supercoil.problems.tweezers.compute import tweezers_branches
from supercoil.problems.tweezers.options import TweezersOptions
from supercoil.problems.tweezers.problem import clamped_problem, tweezers_records
from supercoil.problems.tweezers.result import TweezersResult

__all__ = ["TweezersOptions", "TweezersResult", "clamped_problem", "tweezers_branches",
           "tweezers_records"]
