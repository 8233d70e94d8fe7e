"""Generic continuation: branches of equilibria, their stability and special points.

Knows nothing of rods: it follows any
:class:`~supercoil.solvers.problem.ConstrainedEnergy` whose energy depends on
a scalar attribute named by the caller (``excess_link``, ``turns``,
``tension``, ...).

* Pseudo-arclength predictor–corrector (Keller 1977; Allgower & Georg 1990),
  the bordered Jacobian factorised as one sparse matrix so that folds are
  regular points (Govaerts 2000, ch. 3), adaptive steps, both directions,
  landing exactly on parameter bounds.
* Stability at every point: the exact unstable count from the KKT inertia,
  zero modes, and the determinant sign of Chamekh, Mani-Aouadi & Moakher 2014 beside it.
* Events located along the branch: folds (sign of ``dlambda/ds``),
  bifurcations (a change of the unstable count that is not a fold, pairs of
  eigenvalues included), user events (sign changes of named scalars).
* Branch switching along the critical mode (Seydel 2010).
* :class:`Branch` results with save / load and a :func:`consistency_check`.
"""

from supercoil.continuation.branch import SCHEMA_VERSION, Branch, SpecialPoint
from supercoil.continuation.consistency import ConsistencyReport, consistency_check
from supercoil.continuation.events import UserEvent
from supercoil.continuation.options import ContinuationOptions, ContinuationStatus
from supercoil.continuation.pseudo_arclength import continuation
from supercoil.continuation.switching import switch_branch

__all__ = [
    "SCHEMA_VERSION",
    "Branch",
    "ConsistencyReport",
    "ContinuationOptions",
    "ContinuationStatus",
    "SpecialPoint",
    "UserEvent",
    "consistency_check",
    "continuation",
    "switch_branch",
]
