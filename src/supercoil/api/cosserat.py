"""The verbs of :mod:`supercoil.api.verbs` for a :class:`~supercoil.api.model.CosseratRod`.

:func:`supercoil.equilibrium`, :func:`supercoil.stability`, :func:`supercoil.ring_diagram`
and :func:`supercoil.tweezers` hand a problem whose rod is a ``CosseratRod`` to the
functions here; they return the same result types. Self-contact acts on the rod's
centreline (:mod:`supercoil.cosserat.centreline`).
"""

from __future__ import annotations

import numpy as np

from supercoil.api.model import CosseratRod, Ring, Tweezers
from supercoil.api.results import Equilibrium, EquilibriumStatus, Stability
from supercoil.errors import InputError


def equilibrium(problem: Ring, tolerance: float | None, n_modes: int,
                max_iterations: int = 1000) -> Equilibrium:
    """Without contact, the relaxed twisted circle of a Cosserat ring (an equilibrium at
    every dLk; above the Michell threshold of the model it is returned ``UNSTABLE``);
    with contact, the state reached by winding from the circle
    (:mod:`supercoil.problems.cosserat_ring_winding`). ``tolerance``: Newton's residual
    (None: 1e-10 without contact, 1e-9 with)."""
    from supercoil.cosserat.ring import solve_cosserat_ring
    from supercoil.problems.cosserat_ring_winding import solve_cosserat_supercoiled_ring

    rod = problem.rod
    tolerances = {}
    if problem.initial is not None or problem.knot is not None:
        raise InputError("initial, knot: a starting curve is not available with the Cosserat "
                         "model (its sections' frames are unknowns too); the ring is wound "
                         "from the circle", name="initial" if problem.knot is None else "knot")
    if problem.contact is None:
        tolerance = 1e-10 if tolerance is None else tolerance
        result = solve_cosserat_ring(rod.twist_ratio, problem.excess_link, n_nodes=rod.nodes,
                                     stretch_stiffness=rod.stretch_stiffness,
                                     shear_stiffness=rod.shear_stiffness, tolerance=tolerance,
                                     n_modes=n_modes)
    else:
        from supercoil.contact.options import ContactOptions

        tolerance = 1e-9 if tolerance is None else tolerance
        contact = problem.contact
        result = solve_cosserat_supercoiled_ring(
            rod.twist_ratio, problem.excess_link, contact.length_over_diameter, rod.nodes,
            rod.stretch_stiffness, rod.shear_stiffness, contact.treatment, tolerance,
            n_modes=n_modes, max_iterations=max_iterations)
        # the penetration the treatment accepts (its default, as the solve uses it)
        tolerances["penetration_over_diameter"] = ContactOptions(
            diameter=contact.diameter, treatment=contact.treatment).tolerance
    zero_tolerance = _zero_tolerance()
    stab = Stability(unstable_count=result.unstable_count, zero_modes=result.zero_modes,
                     negative_count=result.negative_count,
                     determinant_sign=result.determinant_sign,
                     eigenvalues=result.lowest_eigenvalues,
                     modes=np.zeros((0, rod.nodes, 3)), zero_tolerance=zero_tolerance,
                     certified=result.stability_certified)
    record = {**result.summary(), "slenderness": rod.slenderness,
              "poisson_ratio": rod.poisson_ratio, "curvature_form": rod.curvature}
    return Equilibrium(problem=problem, status=EquilibriumStatus.of(result.converged, stab),
                       message=result.message, points=result.positions,
                       tensions=np.zeros(0), energy=float(result.energy),
                       twist=float(result.twist), writhe=float(result.writhe),
                       link_error=float(result.link_error), residual=float(result.residual),
                       iterations=int(result.iterations), stability=stab, record=record,
                       contacts=result.contact,
                       tolerances={"newton_residual": tolerance, "zero_modes": zero_tolerance,
                                   **tolerances},
                       frames=result.rotations)


def _zero_tolerance() -> float:
    from supercoil.stability.analysis import DEFAULT_ZERO_TOLERANCE

    return float(DEFAULT_ZERO_TOLERANCE)


def stability(state: Equilibrium, n_modes: int, zero_tolerance: float) -> Stability:
    """The stability of a Cosserat ring's state, from its centreline and frames; the
    modes are the node displacements (k, N, 3) of the eigenvectors."""
    from supercoil.cosserat.closed import ClosedCosseratEnergy
    from supercoil.cosserat.rod import CosseratRod as Discrete
    from supercoil.stability.analysis import analyse

    rod = state.problem.rod
    if state.frames is None:
        raise InputError("state: a Cosserat ring's state needs its frames (state.frames)",
                         name="state")
    discrete = Discrete(rod.nodes, twist_stiffness=rod.twist_ratio,
                        shear_stiffness=rod.shear_stiffness,
                        stretch_stiffness=rod.stretch_stiffness, closed=True)
    problem = ClosedCosseratEnergy(discrete, state.problem.excess_link,
                                   np.asarray(state.points, float),
                                   np.asarray(state.frames, float))
    q = problem.initial_state()
    contact = state.problem.contact
    if contact is not None:
        from supercoil.contact.options import ContactOptions
        from supercoil.contact.problem import ContactProblem

        if contact.treatment == "exact":
            raise InputError("state: the stability of a state with exact contact needs its "
                             "active constraints; it is reported by equilibrium()",
                             name="state")
        problem = ContactProblem(problem, ContactOptions(
            diameter=contact.diameter, treatment=contact.treatment)).stability_view()
    report = analyse(problem, q, np.zeros(0), n_modes=n_modes, zero_tolerance=zero_tolerance)
    modes = np.asarray(report.lowest_modes).reshape(-1, rod.nodes, 6)[:, :, :3]
    return Stability(unstable_count=int(report.unstable_count),
                     zero_modes=int(report.zero_modes),
                     negative_count=int(report.negative_count),
                     determinant_sign=int(report.determinant_sign),
                     eigenvalues=np.asarray(report.lowest_eigenvalues, float), modes=modes,
                     zero_tolerance=float(report.zero_tolerance),
                     certified=bool(report.certified), message=report.message)


def ring_diagram_driver(rod: CosseratRod, contact, settings, resume):
    """The driver of the Cosserat ring's diagram
    (:mod:`supercoil.problems.cosserat_ring_diagram`) for :func:`supercoil.ring_diagram`:
    the circle, its bifurcations and the primary branches up to their first
    self-contact, then with ``contact`` (the tube of ``settings``) on with self-contact
    and the branches switched at their bifurcation points (``branch_depth``); without
    it the diagram ends at the first contacts of the rod's own section (diameter
    L / ``rod.slenderness``). Every point is stored as it comes (centrelines with the
    sections' frames), and a stored run is continued (``resume``)."""
    from supercoil.problems.cosserat_ring_diagram import cosserat_ring_diagram

    if settings.branch_depth != 1 and contact is None:
        raise InputError("branch_depth: the Cosserat ring's secondary branches are followed "
                         "with self-contact; give a contact, or branch_depth 1",
                         name="branch_depth")

    def compute(settings, progress, *, on_point=None, on_branch=None, resume=None):
        return cosserat_ring_diagram(settings, rod.stretch_stiffness, rod.shear_stiffness,
                                     progress, contact=contact is not None,
                                     on_point=on_point, on_branch=on_branch, resume=resume)

    return compute


def tweezers_driver(problem: Tweezers):
    """The driver of the Cosserat rod in tweezers
    (:mod:`supercoil.problems.cosserat_tweezers`, under load or displacement control,
    with the problem's self-contact) for :func:`supercoil.tweezers`. Every point is
    stored as it comes (centrelines with the sections' frames), and a stored run is
    continued (``resume``)."""
    from supercoil.problems.cosserat_tweezers import cosserat_tweezers

    rod = problem.rod

    def compute(settings, progress, *, on_point=None, on_branch=None, resume=None):
        return cosserat_tweezers(settings, rod.stretch_stiffness, rod.shear_stiffness,
                                 progress, on_point=on_point, on_branch=on_branch,
                                 resume=resume)

    return compute
