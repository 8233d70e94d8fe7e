"""The closed ring (a DNA plasmid or any ring) at a given excess link.

The twisted circle is an equilibrium for every excess link ``dLk`` with energy
``E L / A = 2 pi^2 (1 + (C/A) dLk^2)``. It is stable below Michell's threshold
``dLk = (A/C) sqrt(3)`` and loses stability to mode ``m`` at
``dLk_m = (A/C) sqrt(m^2 - 1)`` (Michell 1889; Zajac 1962; Coleman & Swigon
2000): there a pair of eigenvalues (the ``cos`` and ``sin`` of mode
``m``) crosses zero, so the unstable count rises by two while the determinant
keeps its sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from supercoil import checks
from supercoil.errors import InputError
from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions, least_squares_multipliers, newton
from supercoil.solvers.problem import free_dofs
from supercoil.stability.analysis import (
    DEFAULT_ZERO_TOLERANCE,
    analyse,
    eigenvalue_nearest_zero,
    negative_count,
)
from supercoil.stability.bisection import locate_count_change
from supercoil.stability.record import solved_state_record
from supercoil.topology import twist_from_frames, writhe
from supercoil.topology.knots import identify


def circle_energy(twist_ratio: float, excess_link: float) -> float:
    """Exact energy ``E L / A`` of the twisted circle."""
    return 2 * np.pi**2 * (1 + twist_ratio * excess_link**2)


def michell_excess_link(twist_ratio: float, mode: int) -> float:
    """Exact excess link at which the circle loses stability to mode ``m >= 2``."""
    return np.sqrt(mode**2 - 1) / twist_ratio


@dataclass(frozen=True)
class RingResult:
    """A computed ring state, its topology and its stability (nondimensional)."""

    twist_ratio: float
    excess_link: float
    n_nodes: int
    points: np.ndarray  # (n_nodes, 3)
    multipliers: np.ndarray  # (n_nodes,) edge tensions
    energy: float
    twist: float
    writhe: float
    link_error: float
    writhe_error: float  # |Wr(local, used in the energy) - Wr(double sum)|
    unstable_count: int
    zero_modes: int
    negative_count: int
    determinant_sign: int
    lowest_eigenvalues: np.ndarray
    converged: bool
    # the solver's status, and for a converged state that is not stable what it is:
    # "converged; unstable equilibrium (2 unstable directions)", "...; marginal ..."
    status: str
    message: str
    residual: float
    iterations: int
    zero_tolerance: float
    curvature: str
    stability_certified: bool = True
    # self-contact (None for a ring computed without it)
    length_over_diameter: float | None = None
    contact_treatment: str | None = None
    contact: dict | None = None  # keys of supercoil.contact.report.contact_summary
    # with self-contact: the branch the state is on ("circle", "contact" or "given
    # curve") and the quasi-static path that reached it (problems.ring_contact)
    branch: str | None = None
    path: dict | None = None
    # the knot type of the state (supercoil.topology.knots.identify): the table's name
    # ("0_1", "3_1", ...; None if not found) and its chirality (+1, -1, 0)
    knot_type: str | None = None
    chirality: int = 0

    def summary(self) -> dict:
        """The JSON keys of ``supercoil ring`` (docs/model.md, "Nondimensional units")."""
        out = {
            "twist_ratio": self.twist_ratio,
            "excess_link": self.excess_link,
            "twist": self.twist,
            "writhe": self.writhe,
            "link_error": self.link_error,
            "writhe_error": self.writhe_error,
            "knot_type": self.knot_type,
            "chirality": self.chirality,
            "energy": self.energy,
            "energy_circle_exact": circle_energy(self.twist_ratio, self.excess_link),
            **solved_state_record(self),
            "michell_threshold_exact": michell_excess_link(self.twist_ratio, 2),
        }
        if self.contact_treatment is not None:
            out["length_over_diameter"] = self.length_over_diameter
            out["contact_treatment"] = self.contact_treatment
            out.update(self.contact or {})
            out["branch"] = self.branch
            out["path"] = self.path
        return out


def twisted_circle_problem(twist_ratio: float, excess_link: float, n_nodes: int,
                           curvature: str = "angle") -> tuple[ClosedRodEnergy, np.ndarray]:
    rod = Rod(n_nodes=n_nodes, twist_stiffness=twist_ratio, curvature=curvature)
    points = circle(n_nodes, rod.length)
    # A planar polygon has zero writhe and its parallel reference ribbon zero
    # twist, so Lk_u = 0 without the O(N^2) double sum at set-up (the reported
    # writhe is still the double sum, an independent check).
    problem = ClosedRodEnergy(rod, points, excess_link, reference_link=0)
    return problem, points.ravel()


def check_ring_inputs(twist_ratio: float, excess_link: float, n_nodes: int) -> None:
    """Raise InputError unless ``0 < C/A <= 1e6``, ``|dLk| <= 1e6`` and ``8 <= N <= 100000``."""
    checks.number("twist_ratio", twist_ratio, 0.0, checks.MAX_MAGNITUDE, low_open=True,
                  meaning="C/A")
    checks.number("excess_link", excess_link, -checks.MAX_MAGNITUDE, checks.MAX_MAGNITUDE,
                  meaning="dLk in turns")
    checks.integer("n_nodes", n_nodes, checks.MIN_NODES, checks.MAX_NODES,
                   meaning="nodes of the ring")


def solve_ring(twist_ratio: float, excess_link: float, n_nodes: int = 100,
               curvature: str = "angle", tolerance: float = 1e-10,
               zero_tolerance: float = DEFAULT_ZERO_TOLERANCE, n_modes: int = 6) -> RingResult:
    """Equilibrium of the twisted ring started from the circle, with its stability.

    Newton runs in ``stationary`` mode: above Michell's threshold the circle is
    an unstable equilibrium and is reported as such (leaving it needs
    self-contact).
    """
    check_ring_inputs(twist_ratio, excess_link, n_nodes)
    problem, q0 = twisted_circle_problem(twist_ratio, excess_link, n_nodes, curvature)
    result = newton(problem, q0, NewtonOptions(tolerance=tolerance, mode="stationary"))
    stab = analyse(problem, result.q, result.multipliers, n_modes=n_modes,
                   zero_tolerance=zero_tolerance)
    return ring_result(problem, result.q, result.multipliers, stab, converged=result.converged,
                       status=result.status.value, message=result.message,
                       residual=result.residual, iterations=result.iterations,
                       zero_tolerance=zero_tolerance)


def ring_result(problem, q: np.ndarray, multipliers: np.ndarray, stab, *, converged: bool,
                status: str, message: str, residual: float, iterations: int,
                zero_tolerance: float, known_knot=None, **extra) -> RingResult:
    """Assemble a :class:`RingResult`: topology from independent double sums and frames.

    ``problem`` is the :class:`ClosedRodEnergy` (of a contact problem, its ``base``).
    ``known_knot``: the knot type the computation guarded (a ``KnotType``); the state's
    type is named as it when their invariants agree (a view of the state may leave a
    second candidate of the same polynomials, 5_1 and 10_132).
    """
    rod = problem.rod
    twist_ratio, excess_link, n_nodes = rod.twist_ratio, problem.excess_link, rod.n_nodes
    points = q.reshape(-1, 3)
    if not stab.certified:
        message += "; warning: " + stab.message
    if converged and stab.unstable_count > 0:  # the status says what the state is
        status += (f"; unstable equilibrium ({stab.unstable_count} unstable "
                   f"direction{'s' if stab.unstable_count > 1 else ''})")
    elif converged and stab.zero_modes > 0:
        status += (f"; marginal equilibrium ({stab.zero_modes} zero "
                   f"mode{'s' if stab.zero_modes > 1 else ''})")
    # Modes m with (A/C) sqrt(m^2 - 1) < |dLk| have crossed; a mode needs about
    # eight nodes per wavelength to be resolved (measured error 1.8e-2 at N/m = 12.5).
    highest_mode = int(np.floor(np.sqrt((twist_ratio * excess_link) ** 2 + 1)))
    if highest_mode >= 2 and highest_mode > n_nodes / 8:
        message += (f"; warning: modes up to m = {highest_mode} have crossed but {n_nodes} nodes "
                    f"resolve only m <= {n_nodes // 8}: use --nodes >= {8 * highest_mode}")
    wr = writhe(points)
    knot = _knot_of(points)
    if knot is not None and known_knot is not None and knot.same_invariants(known_knot):
        knot = known_knot
    d1 = problem.material_directors(q)
    frame_twist = twist_from_frames(points, d1, closed=True)
    tw = frame_twist - problem.reference_link + excess_link
    return RingResult(
        twist_ratio=twist_ratio, excess_link=excess_link, n_nodes=n_nodes, points=points,
        multipliers=multipliers, energy=problem.elastic_energy(q), twist=tw, writhe=wr,
        link_error=abs(tw + wr - excess_link),
        writhe_error=abs(problem.writhe_local(q) - wr),
        unstable_count=stab.unstable_count, zero_modes=stab.zero_modes,
        negative_count=stab.negative_count, determinant_sign=stab.determinant_sign,
        lowest_eigenvalues=stab.lowest_eigenvalues, converged=converged,
        status=status, message=message, residual=residual,
        iterations=iterations, zero_tolerance=zero_tolerance, curvature=rod.curvature,
        stability_certified=stab.certified,
        knot_type=None if knot is None else knot.name,
        chirality=0 if knot is None else knot.chirality, **extra,
    )


def _knot_of(points: np.ndarray):
    """The :class:`~supercoil.topology.knots.KnotType` of a ring state, None if its
    strands meet."""
    try:
        return identify(points)
    except InputError:
        return None


class _CircleInertia:
    """Inertia of the twisted circle as a function of the excess link (one set-up per N).

    The regular polygon with uniform twist is an equilibrium of the discrete
    model by symmetry; its multipliers come from a least-squares solve.
    """

    def __init__(self, twist_ratio: float, n_nodes: int, curvature: str):
        self.problem, self.q = twisted_circle_problem(twist_ratio, 0.0, n_nodes, curvature)
        self.free = free_dofs(self.problem)

    def __call__(self, excess_link: float) -> int:
        problem = self.problem.at(excess_link=float(excess_link))
        lam = least_squares_multipliers(problem, self.q, self.free)
        return negative_count(problem, self.q, lam)

    def eigenvalue(self, excess_link: float) -> float:
        problem = self.problem.at(excess_link=float(excess_link))
        lam = least_squares_multipliers(problem, self.q, self.free)
        return eigenvalue_nearest_zero(problem, self.q, lam)


def circle_negative_count(twist_ratio: float, excess_link: float, n_nodes: int,
                          curvature: str = "angle") -> int:
    """Exact number of negative eigenvalues of the twisted circle (inertia only)."""
    return _CircleInertia(twist_ratio, n_nodes, curvature)(excess_link)


def michell_threshold(twist_ratio: float, n_nodes: int, mode: int = 2,
                      curvature: str = "angle", rtol: float = 1e-11) -> float:
    """Discrete excess link where the circle's unstable count rises to ``2 (m - 1)``.

    Bisection on the exact negative-eigenvalue count (Chamekh, Mani-Aouadi & Moakher
    2014 bisect on the sign of the determinant, which cannot see this pair crossing) down to a
    bracket of relative width 1e-3, then Brent's method on the crossing
    eigenvalue (the inertia cannot resolve eigenvalues below its round-off).
    """
    if mode < 2:
        raise ValueError(f"mode must be an integer >= 2, got {mode!r}")
    exact = michell_excess_link(twist_ratio, mode)
    below, above = 2 * (mode - 2), 2 * (mode - 1)
    count = _CircleInertia(twist_ratio, n_nodes, curvature)
    if count(0.9 * exact) != below:
        raise RuntimeError(f"unexpected unstable count below the mode-{mode} threshold "
                           f"at n_nodes={n_nodes}")
    return locate_count_change(count, 0.9 * exact, 1.1 * exact, above, rtol=rtol,
                               eigenvalue=count.eigenvalue)


def richardson(coarse: float, fine: float, order: float = 2.0, ratio: float = 2.0) -> float:
    """Richardson extrapolation of values at ``h`` and ``h / ratio`` with error ``O(h^order)``."""
    factor = ratio**order
    return (factor * fine - coarse) / (factor - 1)
