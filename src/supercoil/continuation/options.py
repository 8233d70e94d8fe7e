"""Options and status of a continuation run (immutable, validated on construction)."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from supercoil.errors import InputError


class ContinuationStatus(enum.Enum):
    """How a continuation run ended; :attr:`ok` runs ended where they were asked to."""

    PARAMETER_BOUND = "reached a bound of the parameter (the last point lies on it)"
    MAX_POINTS = "maximum number of points reached"
    MAX_ARCLENGTH = "maximum arclength reached"
    STEP_TOO_SMALL = "the corrector failed at the minimum step"
    START_FAILED = "the starting point did not converge"
    CLOSED_LOOP = "the branch closed on itself (it came back to one of its points)"
    STOPPED = "stopped by the caller's condition before a point it refused"

    @property
    def ok(self) -> bool:
        return self in (ContinuationStatus.PARAMETER_BOUND, ContinuationStatus.MAX_POINTS,
                        ContinuationStatus.MAX_ARCLENGTH, ContinuationStatus.CLOSED_LOOP,
                        ContinuationStatus.STOPPED)

    @property
    def complete(self) -> bool:
        """The run reached what it was asked to reach: a bound of the parameter or of the
        arclength, a closed loop, or the caller's stop (a hand-over designed by the
        caller). A run stopped by its point limit is :attr:`ok` but not complete."""
        return self.ok and self is not ContinuationStatus.MAX_POINTS


@dataclass(frozen=True)
class ContinuationOptions:
    """Options of :func:`supercoil.continuation.continuation`.

    Arclength is measured in the metric ``ds^2 = sum_i M_i dq_i^2 +
    parameter_weight^2 dlambda^2`` (``M`` the problem's lumped ``mass``, so that
    steps mean the same under mesh refinement; multipliers carry no weight).

    * ``initial_step``, ``min_step``, ``max_step``: arclength steps. After a
      corrector that converged in at most ``fast_iterations`` iterations the
      step grows by ``growth``; after a failure (no convergence in
      ``max_corrector_iterations``, divergence, a singular bordered matrix, a
      tangent turned by more than ``max_turn_degrees``) it is multiplied by
      ``shrink`` and the step is retried from the last accepted point.
    * ``parameter_bounds``: ``(low, high)``; the run stops on the bound, the last
      point corrected at exactly that parameter value.
    * ``max_points`` (the starting point included), ``max_arclength``.
    * ``tolerance``: corrector tolerance on ``max |F|``, F the KKT residual;
      a residual below the round-off floor ``eps ||H|| ||q||`` is accepted too.
    * ``direction``: +1 starts towards increasing parameter, -1 decreasing.
    * ``predictor``: ``"tangent"`` (Euler), ``"secant"`` (after two points) or
      ``"quadratic"``: the tangent predictor plus ``ds^2/2`` times the curvature
      estimated from the last two tangents (``(t_k - t_{k-1}) / (s_k - s_{k-1})``;
      :func:`~supercoil.continuation.step.quadratic_term`). The
      predictor's error falls from ``O(ds^2)`` to ``O(ds^3)`` where the branch is
      smooth: measured on the tweezers' contact branch, whose stiff barrier
      makes the corrector's iterations grow fast with the predictor's error,
      93 points instead of 289 (the same events).
    * ``factor_refinement``: bordered solves by iterative refinement with the
      corrector's last bordered factor (the same border row, at an iterate
      nearby) instead of a new factorisation, to the accuracy of a new factor's
      own solve, a new one where refinement does not converge
      (:meth:`~supercoil.continuation.bordered.BorderedFactor.refined_solve`):
      the tangent at each corrected point, and the Newton steps whose residual
      is below ``REFINE_BELOW`` of the one where the factor was made. The
      iterates and tangents are the same to round-off, with fewer
      factorisations.
    * ``chord_steps``: where the residual fell below ``CHORD_BELOW`` (1e-2) of
      the one where the last bordered factor was made and within 1e3
      tolerances, the next step is first tried with that factor (no Hessian, no
      factorisation) and kept only when it lands within ``tolerance``
      (:func:`~supercoil.continuation.corrector.correct`'s ``chord_below``): the
      same iteration counts, the points the same below the tolerance. Measured
      on the tweezers' contact branch (N = 100): 60 of 67 tried landed, 633
      factorisations instead of 693 (``python benchmarks/bench_tweezers_steps.py
      --problems 75,33 --against '{"chord_steps": false}'``).
    * ``zero_tolerance``: eigenvalues (of ``H v = mu M v`` on the constraint
      tangent space) with ``|mu|`` below it are ``zero_modes``, never signed.
    * ``n_modes``: eigenvalues computed at each point beyond the unstable ones.
    * ``detect_folds``, ``detect_bifurcations``: event detection switches.
    * ``event_tolerance``: arclength accuracy of located special points (folds,
      bifurcations, user events). At a fold the parameter value is then exact
      to about ``curvature * event_tolerance^2``.
    * ``switch_below``: bisection on the unstable count stops at this fraction
      of a step; the signed eigenvalue nearest zero is then solved for by
      Brent's method (Chamekh, Mani-Aouadi & Moakher 2014 bisect only).
    * ``phase_conditions``: add ``<M s_k, q - q_start> = 0`` for each symmetry
      mode ``s_k`` of ``problem.symmetry_modes(q_start)`` (with a Lagrange
      unknown each), to follow branches whose continuous symmetry is not pinned
      by the problem (e.g. an O(2) orbit after branch switching). Dense rows,
      taken as extra borders like the integral gauge's (``gauge`` below).
    * ``near_symmetry_gauge``: pin one DOF (as a phase row ``q_i = q_i(start)``)
      against each approximate symmetry of the problem that is not a
      combination of its exact ones at the start (``near_symmetry_modes``: a
      closed rod's material sliding off the circle, nearly null and otherwise
      unremoved, which makes Newton, the tangent and the count ill-posed).
      Sparse; nothing changes for problems without near-symmetries.
    * ``gauge``: how ``near_symmetry_gauge`` pins each approximate symmetry.
      ``"node"``: one DOF, the row ``q_i = q_i(start)`` (sparse; its reaction is a
      force on one node, which breaks the state's symmetries: measured on the
      ring's beta branch at N = 128, the D_3 configurations lost their symmetry
      without contact). ``"integral"``: the phase condition
      ``<M g, q - q_start> = 0`` with ``g`` the unit mode at the start (Doedel's
      integral phase condition; one dense row, which the linear algebra pins to
      one DOF and carries as extra borders, so it keeps the band LU and the
      banded inertia: :func:`~supercoil.solvers.pinned_rows.dense_rows`): its reaction
      is spread along the mode, so a state invariant under a symmetry of the
      rod stays invariant.
    * ``regauge``: with ``near_symmetry_gauge``, when a step fails, pick the
      pinned DOF afresh at the last point (the row becomes ``q_i = q_i(last
      point)`` on the DOF where the sliding moves most there, or the integral
      condition re-anchored there), correct the last point in the new gauge at
      its parameter value (added as a point when it moved) and retry the step
      once, instead of keeping the start's DOF
      for the whole branch. Measured on the ring's contact branch: with the
      start's pin the steps fell to zero at dLk 2.37 (N = 200); restarted there
      with a fresh pin, the branch went on. (Re-picking at every point made
      the tangent turn between gauges and stopped the branch earlier.)
    * ``rephase``: with ``gauge="integral"``, re-anchor the phase condition at
      every accepted point: the next step solves ``<M g_k, q - q_k> = 0`` with
      ``g_k`` the mode at the last point ``q_k`` (AUTO's convention: Doedel's
      integral phase condition relative to the previous solution), and the
      last point's tangent is recomputed in that gauge. A condition anchored at
      the branch start degrades as the state and its sliding mode move away
      from it, and can turn the branch back on itself (on the ring's α contact
      branch, before the sequence of contacts of Coleman & Swigon 2002).
    * ``midpoint_phase``: with ``rephase``, each step's phase rows are the modes
      at the step's predicted midpoint ``x_k + ds/2 d`` (still anchored at the
      last point): ``<M g(q_mid), q - q_k> = 0`` is the midpoint rule for the
      condition ``<M g, dq/ds> = 0`` along the branch, its error ``O(ds^3)`` per
      step where the modes at the last point leave ``O(ds^2)``. A branch that
      moves along the near symmetry only at second order then does not drift
      along it step by step: measured on the tweezers' localised loop (L/D =
      100, F L^2/A = 1600, N = 102, the loop centred by symmetry), over 54 steps
      to its contact the loop's radii lost their mirror symmetry by 3.2e-3 of the
      largest with the modes at the last point (the force the row held growing to
      1.1e-6, above the tolerance of the contact branch started there), by 1.8e-5
      with the midpoint modes (force 6e-9).
    * ``detect_closed_loops``: stop with ``CLOSED_LOOP`` when the branch comes
      back to one of its own points: the last step's chord passes within
      ``closed_loop_tolerance`` times its length of an earlier point (at least
      three points back), the tangents there agree within 15 degrees and the
      unstable counts are equal. A solution curve through a regular point is
      unique, so the branch would only retrace itself (isolas, loops left
      over by the discretisation); without the check the run circles until
      ``max_points``. With it, a corrected point that lies on the branch's own
      earlier path (within ``closed_loop_tolerance`` times the step), its
      tangent the other way, is refused and the step shortened: a jump back
      across the sheets of a fold (:func:`~supercoil.continuation.closure.retraced`).
      And a corrected point whose raw unstable count differs from the step start's
      with no fold between them (a bifurcation crossed, or a step over a fold onto
      the sheet beyond it) is taken again at half the step; the half step is kept
      when it does not change the count, and where it fails the step is refused and
      taken again shorter (and taken after all where every shorter one fails;
      docs/continuation.md, "Steps across a fold onto another sheet").
    * ``max_corrector_distance``: the corrector's trust region, in units of the
      step: a correction whose iterate lies farther than
      ``max_corrector_distance * ds`` from the predicted point (before a
      ``step_bound`` shortened it), plus the norm of the start point's own
      Newton correction (:func:`~supercoil.continuation.corrector.own_correction`),
      is stopped there and counted as a failure (the step shrinks). A point at distance ``ds`` from the predictor makes a
      chord at 45 degrees to the tangent; a step along an arc that turns by
      ``max_turn_degrees`` (its chord by half that) lands about
      ``ds tan(max_turn_degrees / 2)`` from it (0.27 ds at 30 degrees; accepted
      corrections measured up to 0.53 ds on the tweezers' contact branches). With
      ``1.0``, the corrections it stopped there were jumps across the contact
      onset's corner that the turn test refused after 5-9 Newton iterations, or
      that did not converge; stopped after 1-3 (Allgower & Georg 1990, sec. 6.1:
      the corrector's distance as a step-control criterion). Measured on the
      tweezers' contact branch (N = 100, L/D = 33, F L^2/A = 75, 0 to 5 turns):
      the same points bit for bit, 461 corrector iterations against 501
      (``python benchmarks/bench_tweezers_steps.py --problems 75,33 --against
      '{"max_corrector_distance": null}'``). None: no limit.
    * ``finite_difference_step``: relative step of the central difference of
      the residual in the parameter when the problem has no
      ``parameter_derivative`` (error ``O(step^2)`` relative).
    """

    initial_step: float = 0.05
    min_step: float = 1e-6
    max_step: float = 0.5
    growth: float = 1.5
    shrink: float = 0.5
    fast_iterations: int = 3
    max_corrector_iterations: int = 10
    max_turn_degrees: float = 30.0
    parameter_bounds: tuple[float, float] = (-math.inf, math.inf)
    max_points: int = 200
    max_arclength: float = math.inf
    tolerance: float = 1e-10
    direction: int = 1
    predictor: str = "tangent"
    factor_refinement: bool = False
    chord_steps: bool = False
    parameter_weight: float = 1.0
    zero_tolerance: float = 1e-6
    n_modes: int = 2
    detect_folds: bool = True
    detect_bifurcations: bool = True
    event_tolerance: float = 1e-10
    switch_below: float = 1e-3
    phase_conditions: bool = False
    near_symmetry_gauge: bool = True
    gauge: str = "node"
    regauge: bool = False
    rephase: bool = False
    midpoint_phase: bool = False
    detect_closed_loops: bool = True
    closed_loop_tolerance: float = 0.1
    finite_difference_step: float = 6e-6
    max_corrector_distance: float | None = None

    def __post_init__(self) -> None:
        def positive(name):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0):
                raise InputError(f"{name} must be positive, got {value!r}")

        for name in ("initial_step", "min_step", "max_step", "tolerance", "parameter_weight",
                     "zero_tolerance", "event_tolerance", "switch_below", "max_arclength",
                     "finite_difference_step", "max_turn_degrees", "closed_loop_tolerance"):
            positive(name)
        if not self.min_step <= self.initial_step <= self.max_step:
            raise InputError(f"need min_step <= initial_step <= max_step, got {self.min_step}, "
                             f"{self.initial_step}, {self.max_step}")
        if not self.growth >= 1.0:
            raise InputError(f"growth must be >= 1, got {self.growth!r}")
        if not 0.0 < self.shrink < 1.0:
            raise InputError(f"shrink must be in (0, 1), got {self.shrink!r}")
        low, high = self.parameter_bounds
        if not low < high:
            raise InputError(f"parameter_bounds must be (low, high) with low < high, got "
                             f"{self.parameter_bounds!r}")
        if self.max_points < 2:
            raise InputError(f"max_points must be >= 2, got {self.max_points!r}")
        if self.fast_iterations < 0 or self.max_corrector_iterations < 1:
            raise InputError("fast_iterations must be >= 0 and max_corrector_iterations >= 1")
        if self.direction not in (1, -1):
            raise InputError(f"direction must be +1 or -1, got {self.direction!r}")
        if self.gauge not in ("node", "integral"):
            raise InputError(f"gauge must be 'node' or 'integral', got {self.gauge!r}")
        if self.rephase and self.gauge != "integral":
            raise InputError("rephase re-anchors the integral phase condition: it needs "
                             f"gauge='integral', got gauge={self.gauge!r}")
        if self.midpoint_phase and not self.rephase:
            raise InputError("midpoint_phase moves the rephased phase condition's modes to the "
                             "step's midpoint: it needs rephase=True")
        if self.predictor not in ("tangent", "secant", "quadratic"):
            raise InputError(f"predictor must be 'tangent', 'secant' or 'quadratic', "
                             f"got {self.predictor!r}")
        if self.n_modes < 1:
            raise InputError(f"n_modes must be >= 1, got {self.n_modes!r}")
        if self.max_corrector_distance is not None and not (
                isinstance(self.max_corrector_distance, (int, float))
                and math.isfinite(self.max_corrector_distance)
                and self.max_corrector_distance > 0):
            raise InputError(f"max_corrector_distance must be None or a positive finite number, "
                             f"got {self.max_corrector_distance!r}")
        if self.max_turn_degrees >= 180.0:
            raise InputError(f"max_turn_degrees must be below 180, got {self.max_turn_degrees!r}")
