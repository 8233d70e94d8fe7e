"""How problems are solved: the verbs of the public API.

* :func:`equilibrium` of a :class:`~supercoil.api.model.Ring`;
* :func:`stability` of a computed state, with as many eigenpairs as asked;
* :func:`ring_diagram`: the circle, its Michell bifurcations and the branches off it,
  with self-contact (Coleman & Swigon 2000);
* :func:`tweezers`: the branches of a rod in magnetic tweezers as it is turned.

Each verb builds its own numerical problem from the immutable description it is
given, so a result never depends on earlier calls. Numerical failures are
returned as statuses; only invalid input raises
(:class:`~supercoil.errors.InputError`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from supercoil.api import cosserat
from supercoil.api.model import Barrier, Contact, CosseratRod, Ring, Rod, Tweezers
from supercoil.api.results import (
    Diagram,
    Equilibrium,
    EquilibriumStatus,
    RunStatus,
    Stability,
)
from supercoil.continuation.branch import Branch
from supercoil.errors import InputError

RING_TOLERANCE = 1e-10  # Newton's residual for a ring without contact
CONTACT_RING_TOLERANCE = 1e-9  # and with contact (the barrier's conditioning)


def _stability(report, n_nodes: int) -> Stability:
    modes = np.asarray(report.lowest_modes)[:, :3 * n_nodes]
    return Stability(unstable_count=int(report.unstable_count),
                     zero_modes=int(report.zero_modes),
                     negative_count=int(report.negative_count),
                     determinant_sign=int(report.determinant_sign),
                     eigenvalues=np.asarray(report.lowest_eigenvalues, float),
                     modes=modes.reshape(len(modes), n_nodes, 3),
                     zero_tolerance=float(report.zero_tolerance),
                     certified=bool(report.certified), message=report.message)


def equilibrium(problem: Ring, *, tolerance: float | None = None,
                max_iterations: int = 1000, n_modes: int = 6) -> Equilibrium:
    """An equilibrium of ``problem`` and its stability.

    Without contact: Newton from the twisted circle, which is an equilibrium at
    every excess link; above Michell's threshold ``(A/C) sqrt(m^2 - 1)`` it is
    returned with status ``UNSTABLE`` and its unstable count. With contact: the
    circle if it is stable, otherwise the circle pushed along its lowest unstable
    mode (or ``problem.initial``, or the curve of ``problem.knot``) relaxed by Newton minimisation under continuous
    collision detection to an equilibrium with self-contact. ``tolerance``: Newton's
    residual (default 1e-10 without contact, 1e-9 with); ``n_modes``: eigenpairs
    kept beyond the negative ones.
    """
    from supercoil.problems.ring import solve_ring
    from supercoil.problems.ring_contact import solve_supercoiled_ring

    if not isinstance(problem, Ring):
        raise InputError(f"equilibrium: expected a supercoil.Ring, got {type(problem).__name__}"
                         "; for a rod in tweezers use supercoil.tweezers (a branch in turns)")
    rod = problem.rod
    if isinstance(rod, CosseratRod):
        return cosserat.equilibrium(problem, tolerance, n_modes, max_iterations)
    if problem.contact is None:
        tolerance = RING_TOLERANCE if tolerance is None else tolerance
        result = solve_ring(rod.twist_ratio, problem.excess_link, n_nodes=rod.nodes,
                            curvature=rod.curvature, n_modes=n_modes, tolerance=tolerance)
    else:
        tolerance = CONTACT_RING_TOLERANCE if tolerance is None else tolerance
        initial = problem.initial
        if problem.knot is not None:
            from supercoil.problems.knot_ring import knot_start

            initial, _note = knot_start(problem.knot, rod.nodes,
                                        problem.contact.length_over_diameter, rod.twist_ratio)
        result = solve_supercoiled_ring(
            rod.twist_ratio, problem.excess_link, problem.contact.length_over_diameter,
            n_nodes=rod.nodes, treatment=problem.contact.treatment, curvature=rod.curvature,
            tolerance=tolerance, n_modes=n_modes, max_iterations=max_iterations,
            initial_points=initial)
    tolerances = {"newton_residual": tolerance, "zero_modes": result.zero_tolerance}
    if problem.contact is not None:
        from supercoil.contact.options import ContactOptions

        # the penetration the treatment accepts (its default, as the solve uses it)
        tolerances["penetration_over_diameter"] = ContactOptions(
            diameter=problem.contact.diameter, treatment=problem.contact.treatment).tolerance
    # the eigenvalues the solve computed; their modes on request (stability())
    stab = Stability(unstable_count=result.unstable_count, zero_modes=result.zero_modes,
                     negative_count=result.negative_count,
                     determinant_sign=result.determinant_sign,
                     eigenvalues=result.lowest_eigenvalues,
                     modes=np.zeros((0, rod.nodes, 3)), zero_tolerance=result.zero_tolerance,
                     certified=result.stability_certified)
    return Equilibrium(problem=problem, status=EquilibriumStatus.of(result.converged, stab),
                       message=result.message, points=result.points,
                       tensions=result.multipliers, energy=float(result.energy),
                       twist=float(result.twist), writhe=float(result.writhe),
                       link_error=float(result.link_error), residual=float(result.residual),
                       iterations=int(result.iterations), stability=stab,
                       contacts=result.contact, record=result.summary(),
                       tolerances=tolerances)


def _ring_energy(problem: Ring, points: np.ndarray):
    """The numerical problem of ``problem`` at the state ``points`` (its stability view)."""
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.rod.closed import ClosedRodEnergy
    from supercoil.rod.model import Rod as RodModel

    rod = problem.rod
    model = RodModel(n_nodes=rod.nodes, twist_stiffness=rod.twist_ratio, curvature=rod.curvature)
    base = ClosedRodEnergy(model, np.asarray(points, float), problem.excess_link)
    if problem.contact is None:
        return base
    options = ContactOptions(diameter=problem.contact.diameter,
                             treatment=problem.contact.treatment)
    return ContactProblem(base, options).stability_view()


def _report_of(problem: Ring, points, tensions, n_modes: int, zero_tolerance: float):
    from supercoil.stability.analysis import analyse

    energy = _ring_energy(problem, points)
    q = np.asarray(points, float).ravel()
    return analyse(energy, q, np.asarray(tensions, float), n_modes=n_modes,
                   zero_tolerance=zero_tolerance)


def stability(state: Equilibrium, *, n_modes: int = 6,
              zero_tolerance: float | None = None) -> Stability:
    """The stability of a computed ring state, recomputed from the state alone.

    ``n_modes``: eigenpairs wanted beyond the negative ones (their modes as node
    displacements, (k, N, 3)); ``zero_tolerance``: eigenvalues with ``|lambda|`` at
    most this are zero modes (default: the one the state was computed with).
    """
    if not isinstance(state, Equilibrium):
        raise InputError(f"stability: expected a supercoil.Equilibrium, got "
                         f"{type(state).__name__}")
    if int(n_modes) != n_modes or not 1 <= n_modes <= 100:
        raise InputError(f"n_modes: got {n_modes!r}; valid: an integer from 1 to 100")
    tol = state.stability.zero_tolerance if zero_tolerance is None else float(zero_tolerance)
    if isinstance(state.problem.rod, CosseratRod):
        return cosserat.stability(state, int(n_modes), tol)
    report = _report_of(state.problem, state.points, state.tensions, int(n_modes), tol)
    return _stability(report, len(state.points))


def _run_status(computed) -> tuple[RunStatus, str]:
    """The run's status from the problem's own verdict (``computed.ok``), and the reasons:
    each branch that did not end where it was asked to, and each failed step."""
    if computed.ok:
        return RunStatus.COMPLETE, "every branch ended where it was asked to"
    stopped = [f"{b.name}: {b.status.name} ({b.message})" for b in computed.branches
               if not computed.branch_ok(b)]
    notes = computed.notes
    failed = [n for n in notes if n.startswith(("failed:", "incomplete:"))]
    return RunStatus.INCOMPLETE, "; ".join(stopped + failed) or "a step failed"


def _settings(cls, fixed: dict, options: dict):
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(options) - (names - set(fixed)))
    if unknown:
        valid = ", ".join(sorted(names - set(fixed)))
        raise InputError(f"unknown option(s) {', '.join(unknown)}; valid: {valid}")
    try:
        return cls(**fixed, **options)
    except InputError:
        raise
    except (TypeError, ValueError) as exc:
        raise InputError(str(exc)) from None


def _tweezers_settings(problem: Tweezers, turns, options: dict):
    """The :class:`~supercoil.problems.tweezers.TweezersOptions` of ``problem`` over
    ``turns`` with the numerical ``options`` (a problem in DNA units: the DNA runs'
    defaults, :func:`~supercoil.units.tweezers.dna_numerics`, for those not given)."""
    from supercoil.problems.tweezers import TweezersOptions

    rod = problem.rod
    lod = None if problem.contact is None else problem.contact.length_over_diameter
    if problem.dna is not None:
        from supercoil.units.tweezers import dna_numerics

        options = dna_numerics(options)
    return _settings(TweezersOptions, {
        "twist_ratio": rod.twist_ratio, "length_over_diameter": lod, "n_nodes": rod.nodes,
        "tension": problem.tension, "end_distance": problem.end_distance}, {
        "turns": tuple(turns), **options})


def _computed(kind: str, settings, compute, progress, on_point, out, resume, overwrite,
              attributes: dict, provenance: dict,
              contact: Callable[[str], bool] = lambda name: name.endswith("_contact"),
              model: dict | None = None):
    """Run ``compute(settings, progress, on_point=, on_branch=, resume=)`` (a problem's
    driver) with the recording of ``out`` and the branches of ``resume``; returns
    ``(computed, writer, owned)``. ``contact(name)``: whether branch ``name`` has
    self-contact (as its points are stored). ``model``: a Cosserat rod's keys (stored
    with the settings, and a resumed result's must be the same), None for Kirchhoff."""
    from supercoil.api import recording
    from supercoil.io.store import ResultWriter

    if isinstance(resume, bool) or resume is None:
        again = bool(resume)
        source = None
    else:
        again, source = False, resume
    given = isinstance(out, ResultWriter)
    if again and out is None:
        raise InputError("resume=True continues the result in out; give out (its folder), or "
                         "give the stored result to continue as resume")
    if overwrite and (again or source is not None) and not given:
        raise InputError("resume and overwrite exclude each other: resume continues the "
                         "stored result, overwrite replaces it")
    stored = None
    if source is not None:
        stored = recording.stored_branches(source, kind, settings, model)
    elif again and not given:
        stored = recording.stored_branches(out, kind, settings, model)
    writer = out if given else None
    if out is not None and not given:
        writer = recording.open_folder(out, kind=kind, options=settings,
                                       attributes=attributes, provenance=provenance,
                                       overwrite=overwrite, resume=again, model=model)
    if again and given:
        recording.raise_limits(writer, recording.plain(dataclasses.asdict(settings)))
        stored = writer.stored_branches()
    say = progress or (lambda message: None)
    if stored is not None:
        recording.announce(stored, say)
    with recording.recording(writer, on_point, contact) as (
            point, final):
        computed = compute(settings, say, on_point=point, on_branch=final, resume=stored)
        if writer is not None:
            recording.store_branches(writer, computed.branches, computed.contact_branches)
    return computed, writer, writer is not None and not given


def _finished(diagram: Diagram, writer, owned: bool, json_name: str) -> Diagram:
    """Close an owned result with the diagram's summary and write its JSON beside it."""
    if owned:
        from supercoil.api.recording import finish
        from supercoil.io.results import write_json

        finish(writer, diagram)
        write_json(diagram.summary, writer.path.parent / json_name)
    return diagram


def ring_diagram(rod: Rod, contact: Contact | None = None, *, max_excess_link: float = 6.0,
                 modes: tuple[int, ...] = (2, 3), progress: Callable[[str], None] | None = None,
                 on_point: Callable[[Branch], None] | None = None, out=None,
                 resume=None, overwrite: bool = False, **options) -> Diagram:
    """The bifurcation diagram of a ring in its excess link, with self-contact.

    The circle is followed in ``dLk`` through Michell's bifurcations; the primary
    branches of ``modes`` are switched off it and followed without contact to their
    first contact, then with ``contact`` (a :class:`~supercoil.api.model.Barrier` or
    :class:`~supercoil.api.model.Penalty`; default ``Barrier(100)``) up to
    ``max_excess_link`` (Coleman & Swigon 2000, Figures 1-4). Further ``options``
    are those of :class:`supercoil.problems.ring_diagram.DiagramOptions`
    (``branch_depth``, ``contact_max_points``, ``contact_max_step``, ...).

    ``on_point(branch)`` is called after every accepted point with the branch so
    far (its last point the new one), ``progress(message)`` as branches start.
    ``out``: an output folder (created if missing): every accepted point is
    appended to ``out/result.h5`` before ``on_point`` sees it, so a run stopped
    by Ctrl-C, a signal or a crash keeps every point reported; at the end the
    file gets the final branches, the summary and the status, and ``diagram.json``
    (the summary, :attr:`Diagram.summary`) is written beside it. An existing
    ``result.h5`` is refused unless ``overwrite``. ``out`` may also be an open
    :class:`supercoil.io.store.ResultWriter`: the points and final branches are
    stored in it, and the caller adds the summary and status and closes it. On
    Ctrl-C the result is closed with status ``interrupted`` (``failed`` on an
    error) and the exception raised again. ``resume``: ``True`` continues the
    result in ``out``; a result (:func:`supercoil.load`'s, or its file or
    folder) is continued from: its finished branches are kept, the others
    continued from their last point. The stored options must be these, but for a
    point limit, which may be raised (``docs/results.md``, ``--resume``).
    """
    from supercoil.api.files import options_attributes
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    compute = ring_diagram
    model = None
    if isinstance(rod, CosseratRod):
        model = _model_keys(rod)
        _check_contact(contact)
        tube = {} if contact is None else {
            "length_over_diameter": contact.length_over_diameter, "contact": contact.treatment}
        settings = _settings(DiagramOptions, {
            "twist_ratio": rod.twist_ratio, "length_over_diameter": rod.slenderness,
            "n_nodes": rod.nodes, **tube}, {
            "max_excess_link": max_excess_link, "modes": tuple(modes), **options})
        compute = cosserat.ring_diagram_driver(rod, contact, settings, resume)
        problem = Ring(rod, 0.0, contact)
    else:
        if not isinstance(rod, Rod):
            raise InputError(f"rod: expected a supercoil.Rod or supercoil.CosseratRod, got "
                             f"{rod!r}")
        contact = Barrier(100.0) if contact is None else contact
        _check_contact(contact)
        settings = _settings(DiagramOptions, {
            "twist_ratio": rod.twist_ratio,
            "length_over_diameter": contact.length_over_diameter,
            "n_nodes": rod.nodes, "contact": contact.treatment}, {
            "max_excess_link": max_excess_link, "modes": tuple(modes), **options})
        problem = Ring(rod, 0.0, contact)
    computed, writer, owned = _computed(
        "ring_diagram", settings, compute, progress, on_point, out, resume, overwrite,
        options_attributes(settings, closed=True),
        {"contact_treatment": settings.contact, "n_nodes": settings.n_nodes}, model=model)
    status, message = _run_status(computed)
    diagram = Diagram(kind="ring_diagram", problem=problem, settings=settings,
                      branches={b.name: b for b in computed.branches}, status=status,
                      message=message, notes=tuple(computed.notes), computed=computed)
    return _finished(diagram, writer, owned, "diagram.json")


def _model_keys(rod: CosseratRod) -> dict:
    """A Cosserat rod's keys, which a result records and a resumed run must share."""
    return {"model": "cosserat", "stretch_stiffness": rod.stretch_stiffness,
            "shear_stiffness": rod.shear_stiffness, "slenderness": rod.slenderness,
            "poisson_ratio": rod.poisson_ratio}


def _check_contact(contact) -> None:
    if contact is not None and not isinstance(contact, Contact):
        raise InputError(f"contact: expected a Barrier or Penalty, got {contact!r}")


def tweezers(problem: Tweezers, turns: tuple[float, float] | None = None, *,
             superhelical_density: tuple[float, float] | None = None,
             progress: Callable[[str], None] | None = None,
             on_point: Callable[[Branch], None] | None = None, out=None, resume=None,
             overwrite: bool = False, **options) -> Diagram:
    """The branches of a rod in magnetic tweezers turned through ``turns = (start, stop)``
    (default (0, 5)).

    The straight rod is followed from ``start`` turns to its buckling (Greenhill's
    condition for a clamped rod), the buckled branch off it, and with contact the
    plectoneme's branch (its hat curve: extension against turns); under displacement
    control (``end_distance``) the branch ``clamped`` from the planar clamped buckle,
    with ``tension`` the end's reaction. A problem in DNA
    units (:meth:`~supercoil.api.model.Tweezers.from_dna`) may be turned through
    ``superhelical_density = (start, stop)`` instead (σ = turns · 10.5 / N_bp; not
    both). Further ``options`` are those of
    :class:`supercoil.problems.tweezers.TweezersOptions` (``max_points``,
    ``contact_max_step``, ...).

    ``on_point``, ``progress``, ``out``, ``resume`` and ``overwrite`` act as for
    :func:`ring_diagram`, with ``branch.json`` in place of ``diagram.json``.
    """
    from supercoil.api.files import options_attributes
    from supercoil.problems.tweezers import tweezers_branches

    if not isinstance(problem, Tweezers):
        raise InputError(f"tweezers: expected a supercoil.Tweezers, got "
                         f"{type(problem).__name__}")
    if problem.dna is not None:
        from supercoil.units.tweezers import span_in_turns

        turns = span_in_turns(problem.dna, turns, superhelical_density, (0.0, 5.0))
    elif superhelical_density is not None:
        raise InputError("superhelical_density needs a problem in DNA units "
                         "(Tweezers.from_dna); give turns", name="superhelical_density")
    turns = (0.0, 5.0) if turns is None else turns
    settings = _tweezers_settings(problem, turns, options)
    attributes = options_attributes(settings, closed=False)
    if problem.dna is not None:
        from supercoil.units.tweezers import dna_attributes

        attributes.update(dna_attributes(problem.dna, problem.force_pN))
    compute, model = tweezers_branches, None
    if isinstance(problem.rod, CosseratRod):
        compute, model = cosserat.tweezers_driver(problem), _model_keys(problem.rod)
    computed, writer, owned = _computed(
        "tweezers", settings, compute, progress, on_point, out, resume, overwrite,
        attributes,
        {"contact_treatment": "barrier" if settings.length_over_diameter else "none",
         "n_nodes": settings.n_nodes}, model=model)
    status, message = _run_status(computed)
    diagram = Diagram(kind="tweezers", problem=problem, settings=settings,
                      branches={b.name: b for b in computed.branches}, status=status,
                      message=message, notes=tuple(computed.notes), computed=computed)
    return _finished(diagram, writer, owned, "branch.json")



def tweezers_path(problem: Tweezers, turns: tuple[float, float] = (0.0, 5.0), *,
                  protocol: str = "up-down", step: float = 0.02,
                  force_range: tuple[float, float] | None = None,
                  force_step: float | None = None, **options):
    """The quasi-static path of a tweezers experiment (load control): the state an
    experiment follows as the end is turned slowly, with the jumps at folds.

    ``protocol``: ``"up"`` (from ``turns[0]`` to ``turns[1]``), ``"up-down"`` (and
    back) or ``"force-ramp"`` (up to ``turns[1]``, then the tension ramped down to
    ``force_range[0]``, up to ``force_range[1]`` and back, in steps of ``force_step``;
    default 1/50 of the range); ``step``: turns per step. Further ``options`` as for
    :func:`tweezers`. Returns a
    :class:`~supercoil.problems.tweezers_protocol.PathResult`: per-step records
    (``points``), ``states``, ``jumps``, ``ok`` and ``message``.
    """
    from supercoil.problems.tweezers_protocol import check_path, quasistatic_path

    if not isinstance(problem, Tweezers):
        raise InputError(f"tweezers_path: expected a supercoil.Tweezers, got "
                         f"{type(problem).__name__}")
    settings = _tweezers_settings(problem, turns, options)
    ramp = None if force_range is None else tuple(force_range)
    check_path(settings, protocol, step, force_range=ramp, force_step=force_step)
    rod = problem.rod
    return quasistatic_path(settings, protocol, step=step, force_range=ramp,
                            force_step=force_step,
                            cosserat=((rod.stretch_stiffness, rod.shear_stiffness)
                                      if isinstance(rod, CosseratRod) else None))


def diagram_of(options, rod=None, **kwargs) -> Diagram:
    """:func:`ring_diagram` or :func:`tweezers` of options already made: a
    :class:`~supercoil.problems.ring_diagram.DiagramOptions` or a
    :class:`~supercoil.problems.tweezers.TweezersOptions` (as the command line and the
    study files make them); ``kwargs``: the verb's ``progress``, ``on_point``, ``out``,
    ``resume``, ``overwrite``. ``rod``: a :class:`~supercoil.api.model.CosseratRod` to
    compute with instead of the Kirchhoff rod the options describe."""
    from supercoil.api.model import contact_from_name
    from supercoil.problems.ring_diagram import DiagramOptions
    from supercoil.problems.tweezers import TweezersOptions

    if isinstance(options, DiagramOptions):
        rest = {k: v for k, v in dataclasses.asdict(options).items()
                if k not in ("twist_ratio", "length_over_diameter", "n_nodes", "contact")}
        return ring_diagram(Rod(options.twist_ratio, options.n_nodes) if rod is None else rod,
                            contact_from_name(options.contact, options.length_over_diameter),
                            **rest, **kwargs)
    if isinstance(options, TweezersOptions):
        problem, rest = tweezers_arguments(options, rod)
        return tweezers(problem, **rest, **kwargs)
    raise InputError(f"options: expected DiagramOptions or TweezersOptions, got "
                     f"{type(options).__name__}")


def tweezers_arguments(options, rod=None) -> tuple[Tweezers, dict]:
    """``(problem, options)`` of :func:`tweezers` and :func:`tweezers_path` for a
    :class:`~supercoil.problems.tweezers.TweezersOptions` (``turns`` among the options);
    ``rod``: the problem's rod (default: the Kirchhoff rod the options describe)."""
    lod = options.length_over_diameter
    rod = Rod(options.twist_ratio, options.n_nodes) if rod is None else rod
    problem = Tweezers(rod, tension=options.tension,
                       end_distance=options.end_distance,
                       contact=None if lod is None else Barrier(lod))
    rest = {k: v for k, v in dataclasses.asdict(options).items()
            if k not in ("twist_ratio", "length_over_diameter", "n_nodes", "tension",
                         "end_distance")}
    return problem, rest
