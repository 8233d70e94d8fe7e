"""Branches of the twisted ring without contact: the circle, its bifurcations, alpha and beta.

The circle is followed in the excess link ``dLk`` (branch ``circle``); its
unstable count rises by two at Michell's points ``dLk_m = (A/C) sqrt(m^2 - 1)``
(a pair of eigenvalues, the ``cos`` and ``sin`` of mode ``m``, crosses zero:
special points of kind ``bifurcation``, the determinant's sign unchanged).
The primary branches bifurcate there along the critical mode: ``alpha``
(m = 2) and ``beta`` (m = 3), configurations with D_m symmetry (Coleman &
Swigon 2000). Without contact they reach the rod itself eventually (the
alpha branch at C/A = 2/3 tends to the planar figure-eight, Wr -> 1,
dLk -> 1); a step through it is refused
(:meth:`~supercoil.rod.closed.ClosedRodEnergy.admissible`), so the branch stops
there with that status, and callers bound the branches (``excess_link_bounds``,
``max_points``); :mod:`supercoil.problems.ring_diagram` follows them on with
self-contact.

Per point, ``Branch.records`` hold ``excess_link``, ``writhe`` (the double
sum, :func:`supercoil.topology.writhe`), ``twist`` (the excess twist
measured from the material frames, independently of the writhe),
``energy`` (elastic, E L / A) and ``link_error`` = |Tw + Wr - dLk|;
``unstable_count``, ``zero_modes`` and ``determinant_sign`` are the branch's
own arrays (:mod:`supercoil.continuation.stability`: the rigid motions and the
material sliding off the circle removed: docs/model.md, "Stability").

Off the circle a homogeneous ring has the material sliding as an
approximate symmetry; continuation pins it by one phase row
(``ContinuationOptions.near_symmetry_gauge``, on by default) so that Newton,
the tangent and the unstable count stay well posed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    SpecialPoint,
    continuation,
    switch_branch,
)
from supercoil.problems.ring import michell_excess_link, twisted_circle_problem
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.topology import twist_from_frames, writhe

PRIMARY_NAMES = {2: "alpha", 3: "beta", 4: "gamma"}


def ring_records(ring: ClosedRodEnergy):
    """Per-point records of a ring branch (see module doc) for ``continuation(records=)``."""

    def records(q: np.ndarray, multipliers: np.ndarray, excess_link: float,
                problem=None) -> dict:
        # the ring at the point (the continuation's, with its frames), else this one there
        rod = (ring.at(excess_link=float(excess_link)) if problem is None
               else getattr(problem, "base", problem))
        points = q.reshape(-1, 3)
        wr = writhe(points, self_crossing="nan")  # a branch without contact may cross
        d1 = rod.material_directors(q)
        tw = twist_from_frames(points, d1, closed=True) - rod.reference_link + excess_link
        return {"excess_link": float(excess_link), "writhe": wr, "twist": tw,
                "energy": rod.elastic_energy(q), "link_error": abs(tw + wr - excess_link)}

    return records


@dataclass(frozen=True)
class RingBranches:
    """The circle, its bifurcation points and the primary branches followed from them."""

    twist_ratio: float
    n_nodes: int
    circle: Branch
    primary: dict[int, Branch] = field(default_factory=dict)  # mode m -> branch
    problem: ClosedRodEnergy | None = None  # the ring's problem (never changed)

    def bifurcation(self, mode: int) -> SpecialPoint:
        """The circle's bifurcation point of mode ``m`` (its count rises to 2 (m - 1))."""
        for point in self.circle.points_of_kind("bifurcation"):
            if point.count_before == 2 * (mode - 2) and point.count_after == 2 * (mode - 1):
                return point
        raise KeyError(f"the circle branch has no bifurcation point of mode {mode}")

    @property
    def branches(self) -> tuple[Branch, ...]:
        return (self.circle, *self.primary.values())


def circle_branch(twist_ratio: float, n_nodes: int, max_excess_link: float,
                  options: ContinuationOptions | None = None, curvature: str = "angle"
                  ) -> tuple[Branch, ClosedRodEnergy]:
    """The circle followed from ``dLk = 0`` to ``max_excess_link`` (name ``circle``).

    Returns the branch and the problem (unchanged by the continuation; the branch keeps
    the frames of its points).
    """
    problem, q = twisted_circle_problem(twist_ratio, 0.0, n_nodes, curvature)
    step = 0.1 * max_excess_link
    opts = options or ContinuationOptions(initial_step=step, max_step=2 * step,
                                          parameter_bounds=(0.0, max_excess_link))
    branch = continuation(problem, q, parameter="excess_link", options=opts, name="circle",
                          records=ring_records(problem))
    return branch, problem


def primary_branch(problem: ClosedRodEnergy, circle: Branch, point: SpecialPoint, name: str,
                   options: ContinuationOptions | None = None, amplitude: float = 2e-3
                   ) -> Branch:
    """The branch switched from the circle's bifurcation ``point`` (along its critical mode).

    ``amplitude`` is the distance of the first point from the bifurcation in
    the arclength metric (the mass-weighted displacement, about the RMS
    displacement of a node for L = 1).
    """
    opts = options or ContinuationOptions(initial_step=amplitude, max_step=0.1, max_points=60)
    return switch_branch(problem, circle, point, opts, name=name, amplitude=amplitude,
                         records=ring_records(problem))


def ring_branches(twist_ratio: float, n_nodes: int = 40, modes: Sequence[int] = (2, 3),
                  excess_link_bounds: dict[int, tuple[float, float]] | None = None,
                  max_points: int = 60, max_step: float = 0.1,
                  amplitude: float = 2e-3) -> RingBranches:
    """The circle, its bifurcations of ``modes`` and their primary branches (no contact).

    ``excess_link_bounds[m]`` bounds the primary branch of mode ``m`` (default:
    ``dLk`` within a factor 3 of its bifurcation point either way); the branch
    also stops after ``max_points`` points.
    """
    modes = tuple(sorted(int(m) for m in modes))
    if not modes or modes[0] < 2:
        raise ValueError(f"modes must be integers >= 2, got {modes!r}")
    top = michell_excess_link(twist_ratio, modes[-1])
    circle, problem = circle_branch(twist_ratio, n_nodes, 1.1 * top)
    result = RingBranches(twist_ratio, n_nodes, circle, {}, problem)
    for mode in modes:
        point = result.bifurcation(mode)
        exact = michell_excess_link(twist_ratio, mode)
        bounds = (excess_link_bounds or {}).get(mode, (exact / 3, 3 * exact))
        opts = ContinuationOptions(initial_step=amplitude, max_step=max_step,
                                   max_points=max_points, parameter_bounds=bounds)
        name = PRIMARY_NAMES.get(mode, f"mode{mode}")
        result.primary[mode] = primary_branch(problem, circle, point, name, opts, amplitude)
    return result


def radial_harmonics(points: np.ndarray, n_harmonics: int = 12) -> np.ndarray:
    """Fourier amplitudes ``|c_k|``, k = 0 .. n_harmonics, of the distance to the centroid.

    Along the arclength (vertex index): a configuration with D_m symmetry has
    only multiples of ``m``.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    distance = np.linalg.norm(points - points.mean(axis=0), axis=1)
    return np.abs(np.fft.rfft(distance))[: n_harmonics + 1] / len(distance)


def mode_bifurcation(circle, mode: int, notes: list[str]):
    """``(name, point)`` of the primary branch of ``mode`` off the ``circle`` branch: its
    bifurcation point, where the unstable count goes from ``2 (mode - 2)`` to
    ``2 (mode - 1)`` (Michell's m-th threshold), or None with a note when the circle
    has none."""
    name = PRIMARY_NAMES.get(mode, f"mode{mode}")
    bifurcations = {p.count_after: p for p in circle.points_of_kind("bifurcation")}
    point = bifurcations.get(2 * (mode - 1))
    if point is None or point.count_before != 2 * (mode - 2):
        notes.append(f"the circle branch has no bifurcation point of mode {mode}: "
                     f"{name} not computed")
        return name, None
    return name, point
