"""The closed Cosserat ring at a given excess link: equilibrium, topology, stability.

:func:`solve_cosserat_ring` relaxes the twisted circle (:func:`.closed.twisted_circle`)
by Newton on the manifold and reports its energy, twist, writhe and stability.
Nondimensional as the Kirchhoff ring: ``A = L = 1``, ``twist_ratio = C / A``,
``stretch_stiffness = EA L^2 / A``, ``shear_stiffness = GA L^2 / A``.

The twisted circle is an equilibrium for every excess link; with shear and extension
its directors tilt out of the tangent and it stretches (:mod:`.circle`), its energy
tending to ``2 pi^2 (A + C dLk^2) / L`` as GA and EA grow. It loses stability to mode
``m`` where a pair of eigenvalues crosses zero (the unstable count rises by two, the
determinant keeps its sign): :func:`michell_threshold` finds it by bisection on the
count, which converges at second order in the element size to the continuous
Cosserat circle's threshold (:func:`.circle.michell_threshold`), itself Michell's
``(A / C) sqrt(m^2 - 1)`` shifted by ``(C - 3 A / 2) kappa^2 / GA - A kappa^2 / (2 EA)``
(relative, ``kappa = 2 pi / L``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil.cosserat.circle import circle_state
from supercoil.cosserat.closed import ClosedCosseratEnergy, twisted_circle
from supercoil.cosserat.newton import ManifoldNewtonOptions, solve_equilibrium
from supercoil.cosserat.rod import CosseratRod
from supercoil.errors import InputError
from supercoil.stability.analysis import (
    DEFAULT_ZERO_TOLERANCE,
    analyse,
    eigenvalue_nearest_zero,
    negative_count,
)
from supercoil.stability.bisection import locate_count_change
from supercoil.stability.record import solved_state_record

DEFAULT_STIFFNESS = 1e4  # EA L^2 / A and GA L^2 / A when not given


def kirchhoff_circle_energy(twist_ratio: float, excess_link: float) -> float:
    """``E L / A = 2 pi^2 (1 + (C / A) dLk^2)``: the inextensible, unshearable circle."""
    return float(2 * np.pi**2 * (1 + twist_ratio * excess_link**2))


def michell_excess_link(twist_ratio: float, mode: int) -> float:
    """Michell's threshold of mode ``m`` in the Kirchhoff limit, ``sqrt(m^2 - 1) A / C``."""
    return float(np.sqrt(mode**2 - 1) / twist_ratio)


@dataclass(frozen=True)
class CosseratRingResult:
    """A computed Cosserat ring, its topology and stability (nondimensional)."""

    twist_ratio: float
    excess_link: float
    n_nodes: int
    stretch_stiffness: float
    shear_stiffness: float
    positions: np.ndarray  # (n_nodes, 3)
    rotations: np.ndarray  # (n_nodes, 3, 3)
    energy: float
    twist: float  # excess twist Tw - Lk_0, from the frames
    writhe: float  # double sum
    link_error: float  # |twist + writhe - excess_link|
    link: int  # the ribbon's integer linking number
    max_stretch_strain: float
    max_shear_strain: float
    unstable_count: int
    zero_modes: int
    negative_count: int
    determinant_sign: int
    lowest_eigenvalues: np.ndarray
    stability_certified: bool
    converged: bool
    status: str
    message: str
    residual: float
    iterations: int
    # with self-contact (supercoil.problems.cosserat_ring_winding): the tube, the
    # treatment, the contact summary, the winding path and the contact multipliers
    length_over_diameter: float | None = None
    contact_treatment: str | None = None
    contact: dict | None = None
    path: dict | None = None
    multipliers: np.ndarray | None = None

    def summary(self) -> dict:
        """JSON-ready keys, those of the Kirchhoff ring plus the model's."""
        out = {
            "model": "cosserat",
            "twist_ratio": self.twist_ratio,
            "excess_link": self.excess_link,
            "stretch_stiffness": self.stretch_stiffness,
            "shear_stiffness": self.shear_stiffness,
            "twist": self.twist,
            "writhe": self.writhe,
            "link_error": self.link_error,
            "energy": self.energy,
            "energy_circle_exact": kirchhoff_circle_energy(self.twist_ratio, self.excess_link),
            "max_stretch_strain": self.max_stretch_strain,
            "max_shear_strain": self.max_shear_strain,
            **solved_state_record(self),
            "michell_threshold_exact": michell_excess_link(self.twist_ratio, 2),
        }
        if self.contact_treatment is not None:
            out.update(length_over_diameter=self.length_over_diameter,
                       contact_treatment=self.contact_treatment, **(self.contact or {}),
                       branch=(self.path or {}).get("branch"), path=self.path)
        return out


def ring_problem(twist_ratio: float, excess_link: float, n_nodes: int,
                 stretch_stiffness: float = DEFAULT_STIFFNESS,
                 shear_stiffness: float = DEFAULT_STIFFNESS,
                 link: int | None = None) -> ClosedCosseratEnergy:
    """The closed ring started from the twisted circle, ``d1`` turned ``link`` times
    (default ``round(dLk)``)."""
    if not (np.isfinite(twist_ratio) and twist_ratio > 0):
        raise InputError(f"twist_ratio (C/A) must be a positive finite number, got "
                         f"{twist_ratio!r}")
    if not np.isfinite(excess_link):
        raise InputError(f"excess_link must be a finite number, got {excess_link!r}")
    if not (isinstance(n_nodes, (int, np.integer)) and n_nodes >= 8):
        raise InputError(f"n_nodes must be an integer >= 8, got {n_nodes!r}")
    rod = CosseratRod(int(n_nodes), twist_stiffness=float(twist_ratio),
                      shear_stiffness=shear_stiffness, stretch_stiffness=stretch_stiffness,
                      closed=True)
    return ClosedCosseratEnergy(rod, excess_link, link=link)


def relax(problem: ClosedCosseratEnergy, q: np.ndarray,
          options: ManifoldNewtonOptions | None = None):
    """Newton on the manifold from ``q`` at the problem's excess link; returns the
    result and the equilibrium's ``q`` (the chart re-based there, the link checked)."""
    x, R = problem.configuration(q)
    result = solve_equilibrium(problem.rod, x, R, problem.fixed, options=options)
    q = problem.state(result.positions, result.rotations)
    problem.accept(q)
    return result, q


def solve_cosserat_ring(twist_ratio: float, excess_link: float, n_nodes: int = 100,
                        stretch_stiffness: float = DEFAULT_STIFFNESS,
                        shear_stiffness: float = DEFAULT_STIFFNESS, tolerance: float = 1e-10,
                        zero_tolerance: float = DEFAULT_ZERO_TOLERANCE,
                        n_modes: int = 6) -> CosseratRingResult:
    """Equilibrium of the twisted Cosserat ring started from the circle, with its stability.

    The circle is relaxed in its symmetric family (:func:`relax_circle`), then by Newton on
    the manifold (symmetrised tangent) in all the DOFs, which make the gradient vanish
    whatever the stability: above Michell's threshold the circle is reported as an
    unstable equilibrium. The unstable count is the inertia of the symmetrised Hessian with the
    seven exact symmetries pinned (rigid motions and the sections' rotation about
    ``d3``) and the material sliding removed.
    """
    problem = ring_problem(twist_ratio, excess_link, n_nodes, stretch_stiffness,
                           shear_stiffness)
    exact = circle_state(twist_ratio, excess_link, stretch_stiffness, shear_stiffness)
    x, R, _ = relax_circle(problem.rod, problem.link, exact.tilt, exact.stretch, tolerance)
    result, q = relax(problem, problem.state(x, R), ManifoldNewtonOptions(tolerance=tolerance))
    stab = analyse(problem, q, np.zeros(0), n_modes=n_modes, zero_tolerance=zero_tolerance)
    message = result.message
    if not stab.certified:
        message += "; warning: " + stab.message
    twist, wr = problem.twist(q), problem.writhe(q)
    free = np.setdiff1d(np.arange(problem.n_dofs), problem.fixed)
    x, R = problem.configuration(q)
    return CosseratRingResult(
        twist_ratio=float(twist_ratio), excess_link=float(excess_link), n_nodes=int(n_nodes),
        stretch_stiffness=float(stretch_stiffness), shear_stiffness=float(shear_stiffness),
        positions=x, rotations=R, energy=problem.rod.energy(x, R), twist=twist, writhe=wr,
        link_error=abs(twist + wr - excess_link), link=problem.link,
        max_stretch_strain=problem.max_stretch_strain(q),
        max_shear_strain=problem.max_shear_strain(q),
        unstable_count=stab.unstable_count, zero_modes=stab.zero_modes,
        negative_count=stab.negative_count, determinant_sign=stab.determinant_sign,
        lowest_eigenvalues=stab.lowest_eigenvalues, stability_certified=stab.certified,
        converged=result.converged, status=result.status.value, message=message,
        residual=float(np.max(np.abs(problem.gradient(q)[free]))),
        iterations=result.iterations)


def relax_circle(rod: CosseratRod, link: int, tilt: float = 0.0, stretch: float = 0.0,
                 tolerance: float = 1e-10, max_iterations: int = 30
                 ) -> tuple[np.ndarray, np.ndarray, int]:
    """The discrete twisted circle's equilibrium: ``(positions, rotations, iterations)``.

    The circle of :func:`.closed.twisted_circle` is invariant under the screw symmetry
    (turn by ``2 pi / n`` about the axis, shift the nodes by one, turn the sections by
    ``2 pi link / n`` about ``d3``), so a critical point of the energy restricted to the
    circles of every ``(stretch, tilt)`` is a critical point of the full energy
    (symmetric criticality, Palais 1979). Newton in these two parameters, with the
    symmetrised tangent projected on them, finds it whatever the stability of the
    circle, where Newton in all the DOFs, with the pins' reactions breaking the
    symmetry, wanders near a threshold (the crossing pair is nearly null).
    """
    p = np.array([stretch, tilt], dtype=float)
    for it in range(max_iterations + 1):
        x, R = twisted_circle(rod, link, p[1], p[0])
        g = rod.gradient(x, R)
        K = rod.symmetric_tangent(x, R)
        # forces of stiffness ||K|| are known to eps ||K|| |x| at best
        floor = 10 * np.finfo(float).eps * float(abs(K).sum(axis=1).max()) * rod.length
        if np.max(np.abs(g)) <= max(tolerance, floor):
            return x, R, it
        radial = x / np.linalg.norm(x, axis=1, keepdims=True)
        T = np.zeros((2, rod.n_nodes, 6))
        T[0, :, :3] = radial * np.linalg.norm(x[0]) / (1 + p[0])  # d x / d stretch
        T[1, :, 3:] = radial  # spin of the tilt: about the outward normal
        T = T.reshape(2, -1)
        p -= np.linalg.solve(T @ (K @ T.T), T @ g)
    raise RuntimeError(f"the twisted circle did not relax in {max_iterations} iterations "
                       f"(largest force or moment {np.max(np.abs(g)):.2e})")


class CircleInertia:
    """The relaxed twisted circle's unstable count and crossing eigenvalue as functions
    of the excess link (one problem per ``n_nodes``, each call relaxed from the circle)."""

    def __init__(self, twist_ratio: float, n_nodes: int,
                 stretch_stiffness: float = DEFAULT_STIFFNESS,
                 shear_stiffness: float = DEFAULT_STIFFNESS, link: int = 0):
        self.problem = ring_problem(twist_ratio, float(link), n_nodes, stretch_stiffness,
                                    shear_stiffness, link)
        self.constants = (float(twist_ratio), float(stretch_stiffness), float(shear_stiffness))

    def equilibrium(self, excess_link: float) -> np.ndarray:
        """The relaxed circle, from the continuous rod's (tilted, stretched) circle."""
        return self.relaxed(excess_link)[1]

    def relaxed(self, excess_link: float) -> tuple[ClosedCosseratEnergy, np.ndarray]:
        """``(problem at excess_link, the relaxed circle's q)`` (:meth:`equilibrium`)."""
        problem = self.problem.at(excess_link=float(excess_link))
        ratio, stretch, shear = self.constants
        exact = circle_state(ratio, excess_link, stretch, shear)
        x, R, _ = relax_circle(problem.rod, problem.link, exact.tilt, exact.stretch)
        q = problem.state(x, R)
        problem.accept(q)
        return problem, q

    def __call__(self, excess_link: float) -> int:
        return negative_count(*self.relaxed(excess_link), np.zeros(0))

    def eigenvalue(self, excess_link: float) -> float:
        return eigenvalue_nearest_zero(*self.relaxed(excess_link), np.zeros(0))


def michell_threshold(twist_ratio: float, n_nodes: int, mode: int = 2,
                      stretch_stiffness: float = DEFAULT_STIFFNESS,
                      shear_stiffness: float = DEFAULT_STIFFNESS, rtol: float = 1e-10) -> float:
    """Discrete excess link where the Cosserat circle's unstable count rises to
    ``2 (m - 1)``: bisection on the exact count (Chamekh, Mani-Aouadi & Moakher 2009
    bisect on the determinant's sign, which cannot see this pair crossing) to a bracket
    of relative width 1e-3, then Brent's method on the crossing eigenvalue. The start
    is the circle with ``d1`` turned ``round(dLk_m)`` times (Michell's ``dLk_m``)."""
    if not (isinstance(mode, (int, np.integer)) and mode >= 2):
        raise InputError(f"mode must be an integer >= 2, got {mode!r}")
    michell = michell_excess_link(twist_ratio, mode)
    below, above = 2 * (mode - 2), 2 * (mode - 1)
    count = CircleInertia(twist_ratio, n_nodes, stretch_stiffness, shear_stiffness,
                          int(np.rint(michell)))
    lo, hi = 0.85 * michell, 1.15 * michell
    if count(lo) != below:
        raise RuntimeError(f"unexpected unstable count below the mode-{mode} threshold at "
                           f"n_nodes={n_nodes}")
    return locate_count_change(count, lo, hi, above, rtol=rtol, eigenvalue=count.eigenvalue)
