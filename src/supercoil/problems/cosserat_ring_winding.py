"""The Cosserat ring with self-contact at an excess link: the state reached by winding.

The same quasi-static path as the Kirchhoff ring's (:mod:`supercoil.problems.ring_contact`):

* while the twisted circle is stable at the requested ``dLk`` it is the answer
  (branch ``circle``);
* otherwise the circle is taken just beyond its discrete Michell threshold
  (:func:`supercoil.cosserat.ring.michell_threshold`), at ``dLk_c (1 + SNAP_OFFSET)``,
  pushed along its critical mode (the combination of the critical pair invariant
  under the two-fold axis through node 0, node 0 moving outward, its largest node
  displacement ``PERTURBATION_AMPLITUDE * L``) and relaxed by Newton minimisation
  with self-contact (:func:`supercoil.contact.solve.solve_contact`: barrier, penalty,
  augmented Lagrangian or exact contact, every step bounded by continuous collision
  detection on the centreline);
* ``dLk`` is then raised in steps of at most ``winding_step``, each relaxed from the
  last state; a step whose relaxation fails or changes the writhe by more than
  ``WRITHE_STEP`` is halved, down to ``winding_step / 2**MAX_HALVINGS`` (then taken as
  it comes: a jump, where the branch folded), and doubles again after a smooth one.

A refused step goes back to the last state by its positions and rotations
(:meth:`~supercoil.cosserat.problem.CosseratEnergy.state`): Newton re-bases the
rotations' chart at every iterate, so a state's ``q`` means that state only in the
chart it was accepted in. The contact acts on the centreline
(:mod:`supercoil.cosserat.centreline`); the link is kept by the frames and checked at
every accepted iterate (:class:`~supercoil.cosserat.closed.ClosedCosseratEnergy`). A
negative ``dLk`` winds the other way (the thresholds are ``-dLk_c``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import ContactSolveResult, solve_contact, solved_contact_report
from supercoil.cosserat.closed import LinkingError
from supercoil.cosserat.ring import (
    DEFAULT_STIFFNESS,
    CosseratRingResult,
    michell_threshold,
    ring_problem,
)
from supercoil.errors import InputError
from supercoil.geometry.symmetry import axis_invariant_combination
from supercoil.problems.cosserat_ring import relaxed_circle_state
from supercoil.solvers.newton import NewtonOptions
from supercoil.stability.analysis import DEFAULT_ZERO_TOLERANCE, analyse

PERTURBATION_AMPLITUDE = 1e-2  # of L, the push off the circle
SNAP_OFFSET = 1e-3  # the snap off the circle at dLk_c (1 + SNAP_OFFSET)
WINDING_STEP = 0.1  # largest step of dLk along the path
MAX_HALVINGS = 5
WRITHE_STEP = 0.15  # a step changing the writhe by more is halved
STEP_ITERATIONS = 300  # Newton iterations of a step (a step that needs more is halved)


def critical_push(problem, q: np.ndarray, report, amplitude: float) -> np.ndarray:
    """The increment of ``q`` along the circle's critical mode (module doc), in all the
    unknowns, scaled so that its largest centreline node displacement is ``amplitude``."""
    dofs = problem.centreline_dofs
    values = np.asarray(report.lowest_eigenvalues, float)
    modes = np.asarray(report.lowest_modes, float)
    x = problem.centreline(q).reshape(-1, 3)
    if len(values) >= 2 and abs(values[1] - values[0]) <= 1e-6 * max(abs(values[0]), 1e-300):
        fields = modes[:2][:, dofs].reshape(2, -1, 3)
        mass = np.asarray(problem.mass, float)[dofs].reshape(-1, 3)[:, 0]
        direction = axis_invariant_combination(x, 0.0, fields, mass) @ modes[:2]
    else:
        direction = modes[0]
    field = direction[dofs].reshape(-1, 3)
    if field[0] @ (x[0] - x.mean(axis=0)) < 0:  # node 0 outward
        direction = -direction
    return amplitude * direction / np.linalg.norm(field, axis=1).max()


class _Winding:
    """One solve of :func:`solve_cosserat_supercoiled_ring`."""

    def __init__(self, constants, excess_link, length_over_diameter, n_nodes, treatment,
                 tolerance, zero_tolerance, n_modes, max_iterations, winding_step):
        self.constants = constants  # (C/A, EA L^2/A, GA L^2/A)
        self.target = float(excess_link)
        self.sign = 1.0 if excess_link >= 0 else -1.0
        self.lod = float(length_over_diameter)
        self.n_nodes, self.treatment = n_nodes, treatment
        self.tolerance, self.zero_tolerance, self.n_modes = tolerance, zero_tolerance, n_modes
        self.step = winding_step
        self.newton = NewtonOptions(tolerance=tolerance, mode="minimize",
                                    max_iterations=max_iterations)
        self.iterations, self.steps = 0, 0
        self.jumps: list[float] = []
        self.notes: list[str] = []
        ratio, stretch, shear = constants
        ring = ring_problem(ratio, 0.0, n_nodes, stretch, shear,
                            link=int(np.rint(excess_link)))
        self.cp = ContactProblem(ring, ContactOptions(diameter=1.0 / self.lod,
                                                      treatment=treatment))

    @property
    def problem(self):
        """The ring under the contact problem, at its current parameter and chart."""
        return self.cp.base

    def solve(self) -> CosseratRingResult:
        self._rebase(self.target)
        problem, cp = self.problem, self.cp
        q = self.circle
        cp.keep_knot_type(problem.centreline(q).reshape(-1, 3))
        d0 = cp.min_distance(q)
        if not d0 > cp.diameter * (1 - cp.options.tolerance):
            raise InputError(f"length_over_diameter: the circle already penetrates itself "
                             f"(closest approach {d0 / cp.diameter:.4f} D); a thinner tube "
                             "(larger L/D) is valid", name="length_over_diameter")
        report = analyse(problem, q, np.zeros(0), n_modes=2)
        if report.unstable_count == 0:
            self.notes.append("circle stable: no perturbation")
            res = self._relax(q)
            return self._result(res, {"branch": "circle", "excess_link": self.target,
                                      "snap_at": None, "steps": 0, "jumps": []})
        return self._wind()

    def _rebase(self, excess_link: float):
        """The discrete twisted circle at ``excess_link``: the ring and its contact
        problem there, in the circle's chart, and the state; ``(ring, q)``."""
        ring, q = relaxed_circle_state(self.problem, excess_link, self.constants)
        self.cp = self.cp.at(excess_link=float(excess_link)).with_frames(ring.frames)
        self.circle = q
        return ring, q

    def _relax(self, start: np.ndarray, options: NewtonOptions | None = None
               ) -> ContactSolveResult:
        self.cp.accept(start)
        try:
            res = solve_contact(self.cp, start, options or self.newton)
        except LinkingError as exc:  # an iterate that lost the link: a failed relaxation
            return ContactSolveResult(start, np.zeros(self.cp.n_constraints), False, False,
                                      "link_lost", str(exc), 0, 0, float("inf"), 0.0)
        self.iterations += res.newton_iterations
        return res

    def _wind(self) -> CosseratRingResult:
        ratio, stretch, shear = self.constants
        threshold = michell_threshold(ratio, self.n_nodes, 2, stretch, shear, rtol=1e-9)
        snap = self.sign * min(abs(self.target), threshold * (1 + SNAP_OFFSET))
        problem, q = self._rebase(snap)
        report = analyse(problem, q, np.zeros(0), n_modes=2)
        if report.unstable_count == 0:  # the threshold's round-off: a little further
            snap = self.sign * min(abs(self.target), threshold * (1 + 10 * SNAP_OFFSET))
            problem, q = self._rebase(snap)
            report = analyse(problem, q, np.zeros(0), n_modes=2)
        cp = self.cp
        start = q + critical_push(problem, q, report, PERTURBATION_AMPLITUDE * problem.rod.length)
        self.notes.append(f"wound from the circle: it lost stability at dLk = "
                          f"{self.sign * threshold:.6g} and was pushed along its critical "
                          f"mode by {PERTURBATION_AMPLITUDE:g} L at dLk = {snap:.6g}")
        res = self._relax(start)
        level, size, jumped = snap, self.step, False
        smallest = self.step / 2**MAX_HALVINGS
        stepping = dataclasses.replace(self.newton, max_iterations=min(
            self.newton.max_iterations, STEP_ITERATIONS))
        while res.converged and abs(level) < abs(self.target):
            problem = cp.base
            saved = problem.configuration(res.q)
            writhe = problem.writhe(res.q)
            stop = self.sign * min(abs(self.target), abs(level) + size)
            cp = self.cp = cp.at(excess_link=stop)
            trial = self._relax(res.q, stepping)
            smooth = trial.converged and abs(problem.writhe(trial.q) - writhe) <= WRITHE_STEP
            if not smooth and abs(stop - level) > smallest:
                size = 0.5 * abs(stop - level)
                cp = self.cp = cp.at(excess_link=level)
                res = dataclasses.replace(res, q=cp.base.state(*saved))
                cp.accept(res.q)
                continue
            if not trial.converged:
                self.notes.append(f"the step from dLk = {level:.6g} to {stop:.6g} did not "
                                  f"converge")
                res = trial
                break
            if not smooth and not jumped:
                self.jumps.append(float(stop))  # one jump, however many steps it spans
            jumped = not smooth
            self.steps += 1
            res, level = trial, stop
            if smooth:
                size = min(self.step, 2.0 * size)
        if not res.converged:
            self.notes.append(f"the path stopped at dLk = {level:.6g}")
        return self._result(res, {"branch": "contact", "excess_link": level, "snap_at": snap,
                                  "steps": self.steps, "jumps": list(self.jumps)})

    def _result(self, res: ContactSolveResult, path: dict) -> CosseratRingResult:
        problem, cp = self.problem, self.cp
        q = res.q
        stab = analyse(cp.stability_view(), q, res.multipliers, n_modes=self.n_modes,
                       zero_tolerance=self.zero_tolerance)
        note = "; ".join(self.notes)
        if path["jumps"]:
            note += (f"; jumped at dLk = {', '.join(f'{j:.4g}' for j in path['jumps'])} "
                     f"(folds of the branch)")
        if res.converged and stab.unstable_count > 0:
            note += f"; the state is unstable ({stab.unstable_count} negative eigenvalue(s))"
        if problem.rod.edge_length > cp.diameter:
            note += (f"; warning: segments ({problem.rod.edge_length:.3g} L) are longer than "
                     f"the tube diameter ({cp.diameter:.3g} L): contact lines are "
                     f"under-resolved, use --nodes >= {math.ceil(1.0 / cp.diameter)}")
        contact, message, converged = solved_contact_report(cp, res, note)
        x, R = problem.configuration(q)
        twist, wr = problem.twist(q), problem.writhe(q)
        ratio, stretch, shear = self.constants
        dLk = problem.excess_link
        return CosseratRingResult(
            twist_ratio=ratio, excess_link=float(dLk), n_nodes=self.n_nodes,
            stretch_stiffness=stretch, shear_stiffness=shear, positions=x, rotations=R,
            energy=problem.rod.energy(x, R), twist=twist, writhe=wr,
            link_error=abs(twist + wr - dLk), link=problem.link,
            max_stretch_strain=problem.max_stretch_strain(q),
            max_shear_strain=problem.max_shear_strain(q),
            unstable_count=stab.unstable_count, zero_modes=stab.zero_modes,
            negative_count=stab.negative_count, determinant_sign=stab.determinant_sign,
            lowest_eigenvalues=stab.lowest_eigenvalues, stability_certified=stab.certified,
            converged=converged, status=res.status, message=message, residual=res.residual,
            iterations=self.iterations, length_over_diameter=self.lod,
            contact_treatment=self.treatment, contact=contact, path=path,
            multipliers=np.asarray(res.multipliers, float))


def solve_cosserat_supercoiled_ring(twist_ratio: float, excess_link: float,
                                    length_over_diameter: float, n_nodes: int = 100,
                                    stretch_stiffness: float = DEFAULT_STIFFNESS,
                                    shear_stiffness: float = DEFAULT_STIFFNESS,
                                    treatment: str = "barrier", tolerance: float = 1e-9,
                                    zero_tolerance: float = DEFAULT_ZERO_TOLERANCE,
                                    n_modes: int = 6, max_iterations: int = 1000,
                                    winding_step: float = WINDING_STEP) -> CosseratRingResult:
    """The Cosserat ring of tube ``D = L / length_over_diameter`` with self-contact at
    ``excess_link``, reached by winding from the circle (module doc); ``treatment``: the
    contact's (``barrier``, ``penalty``, ``augmented``, ``exact``)."""
    constants = (float(twist_ratio), float(stretch_stiffness), float(shear_stiffness))
    return _Winding(constants, excess_link, length_over_diameter, n_nodes, treatment,
                    tolerance, zero_tolerance, n_modes, max_iterations, winding_step).solve()
