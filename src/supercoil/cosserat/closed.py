"""A closed Cosserat ring at fixed excess link.

Nodes and rotations are periodic: ``n`` nodes, ``n`` elements, the last joining node
``n - 1`` back to node 0 (``CosseratRod(closed=True)``), every element's relative
rotation ``psi = log(R_a^T R_b)`` taken the short way (``|psi| < pi``).

How the link is kept. The material line ``d1``, projected normal to the centreline
(per element: the midpoint director ``R_m e_1`` projected normal to the chord), and the
centreline make a closed ribbon whose linking number ``Lk = Tw + Wr`` (Calugareanu
1959, White 1969; :func:`supercoil.topology.twist_from_frames` and
:func:`supercoil.topology.writhe`, each computed independently) is an integer,
invariant under every continuous deformation in which the centreline does not pass
through itself and no element's relative rotation passes through ``pi`` (the short
way would then jump to the other side and the interpolated frame by a half-turn).
So the unknowns never carry the link: it is set by the start (:func:`twisted_circle`,
``d1`` turned ``link`` times about the tangent) and kept by continuity.
:meth:`ClosedCosseratEnergy.admissible`, Newton's and the continuation's per-step
guard, refuses a state that breaks either condition (an element turning by
``pi / 2`` or more; a strand passed through another, which changes the link, or the
knot type of the start: :class:`~supercoil.topology.knots.StrandPassageGuard`), so
that the step is retried shorter; :meth:`ClosedCosseratEnergy.accept` checks both
conditions again at every accepted state (every ``|psi| < pi / 2`` and
``round(Tw + Wr) = link``) and raises :class:`LinkingError` for a state handed to it
that breaks them.

A continuous excess link. A closed ribbon has an integer link, while the excess link
``dLk`` of a rod (DNA's ``Lk - Lk_0``) is any number: it is the link less the turns of
the twist at rest, ``Lk_0 = tau0 L / 2 pi``. So the rod gets the intrinsic twist
``tau0 = 2 pi (link - dLk) / L``; for an isotropic section this shifts the twist at
rest and nothing else (the rod is straight at rest), and ``dLk`` is a parameter like
any other (:meth:`ClosedCosseratEnergy.parameter_derivative`). The reported
``twist`` is the excess twist ``Tw - Lk_0``, so that ``twist + writhe = dLk``.

Symmetries. The energy is invariant under the six rigid motions and under the
rotation of every section about its ``d3`` by one angle (isotropy): seven exact
symmetries, removed by fixing node 0 (position and rotation) and one coordinate of a
far node (:func:`ring_pins`). Sliding the material along the ring is a symmetry of the
continuous ring only (``near_symmetry_modes``); on the circle it is a rotation about
the axis combined with the isotropy, both exact.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from supercoil.cosserat.circle import circle_state
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import DOFS_PER_NODE, CosseratRod
from supercoil.cosserat.rotations import dexp, exp_so3
from supercoil.errors import InputError
from supercoil.topology import twist_from_frames, writhe
from supercoil.topology.knots.passage import StrandPassageGuard

# largest relative rotation of an element at an accepted state (the short way, with margin)
MAX_ELEMENT_ROTATION = np.pi / 2


class LinkingError(RuntimeError):
    """The ring's state no longer keeps its linking number (see :mod:`.closed`)."""


def twisted_circle(rod: CosseratRod, link: int, tilt: float = 0.0, stretch: float = 0.0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The regular polygon of chords ``(1 + stretch) h`` in the ``xy`` plane
    (counter-clockwise about ``+z``, node 0 on ``+x``), ``d3`` along the circle's tangent
    tilted by ``tilt`` toward ``+z``, ``d1`` (the inward normal at node 0) turned ``link``
    times uniformly about ``d3``: ``R_i = Rz(2 pi i / n) R_0 exp(2 pi link i / n e_3)``.
    :func:`supercoil.cosserat.circle.circle_state` gives the tilt and stretch of the
    continuous rod's equilibrium."""
    n = rod.n_nodes
    angles = 2 * np.pi * np.arange(n) / n
    radius = (1 + stretch) * rod.element_length / (2 * np.sin(np.pi / n))
    positions = radius * np.stack([np.cos(angles), np.sin(angles), np.zeros(n)], axis=1)
    c, s = np.cos(tilt), np.sin(tilt)
    R0 = np.array([[-1.0, 0.0, 0.0], [0.0, -s, c], [0.0, c, s]])  # columns d1, d2, d3
    spin = exp_so3(angles[:, None] * np.array([0.0, 0.0, 1.0]))
    twist = exp_so3(link * angles[:, None] * np.array([0.0, 0.0, 1.0]))
    return positions, spin @ R0 @ twist


def symmetry_generators(positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """``(7, n, 6)`` nodal displacements and spatial spins of the exact symmetries:
    translations, rotations about the centroid, rotation of the sections about ``d3``."""
    x = np.asarray(positions, dtype=float)
    r = x - x.mean(axis=0)
    out = np.zeros((7, len(x), 6))
    for k in range(3):
        e = np.eye(3)[k]
        out[k, :, :3] = e
        out[3 + k, :, :3] = np.cross(e, r)
        out[3 + k, :, 3:] = e
    out[6, :, 3:] = rotations[:, :, 2]
    return out


def ring_pins(positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Seven DOFs whose fixing removes the exact symmetries: node 0 (position and
    rotation) and the coordinate of node ``n/4``, ``n/2`` or ``3n/4`` that the remaining
    symmetry (a rigid turn about ``d3`` of node 0, less the isotropy) moves most, i.e.
    that maximises the ``|det|`` of the symmetries' response on the pins."""
    x = np.asarray(positions, dtype=float)
    n = len(x)
    modes = symmetry_generators(x, rotations).reshape(7, -1)
    best, best_det = None, -1.0
    for node in sorted({n // 4, n // 2, (3 * n) // 4} - {0}):
        for c in range(3):
            pins = list(range(6)) + [DOFS_PER_NODE * node + c]
            det = abs(np.linalg.det(modes[:, pins]))
            if det > best_det:
                best, best_det = pins, det
    return np.array(best, dtype=np.int64)


def _nondimensional(rod: CosseratRod, stiffness: float) -> float:
    return stiffness * rod.length**2 / rod.bending_stiffness


class ClosedCosseratEnergy(CosseratEnergy):
    """A closed Cosserat ring at excess link ``excess_link`` (module doc).

    ``rod``: a closed :class:`CosseratRod`; its intrinsic twist is set from
    ``excess_link`` and the link. ``positions``, ``rotations``: the start (default:
    :func:`twisted_circle` with ``link = round(excess_link)`` turns and the tilt and
    stretch of the continuous rod's circle, :func:`.circle.circle_state`); ``link``, the
    integer linking number of the start's ribbon, is measured from it when not given.
    """

    twist_parameter = "excess_link"
    parameters = ("excess_link",)

    def __init__(self, rod: CosseratRod, excess_link: float, positions: np.ndarray | None = None,
                 rotations: np.ndarray | None = None, link: int | None = None):
        if not rod.closed:
            raise InputError("the rod of a ring must be closed (CosseratRod(closed=True))")
        if not np.isfinite(excess_link):
            raise InputError(f"excess_link must be a finite number, got {excess_link!r}")
        if positions is None and rotations is None:
            link = int(np.rint(excess_link)) if link is None else link
            try:
                exact = circle_state(rod.twist_stiffness / rod.bending_stiffness,
                                     excess_link, _nondimensional(rod, rod.stretch_stiffness),
                                     _nondimensional(rod, rod.shear_stiffness))
                tilt, stretch = exact.tilt, exact.stretch
            except InputError:  # a shear stiffness too small for a slightly tilted circle
                tilt, stretch = 0.0, 0.0
            positions, rotations = twisted_circle(rod, link, tilt, stretch)
        elif positions is None or rotations is None:
            raise InputError("give both positions and rotations, or neither")
        super().__init__(rod, positions, rotations)
        # a link measured to round-off: Tw + Wr of a closed ribbon is an integer
        measured = self._linking_number(*self.configuration(self.initial_state()))
        if link is None:
            link = int(np.rint(measured))
        if not isinstance(link, (int, np.integer)) or abs(measured - link) > 1e-6:
            raise InputError(f"link must be the integer linking number of the start's ribbon, "
                             f"{measured:.6g}; got {link!r}")
        self.link = int(link)
        self.excess_link = float(excess_link)
        x, R = self.configuration(self.initial_state())
        self._check_rotations(x, R, "the start")
        self.fixed = ring_pins(x, R)
        self.gauge_dofs = self.fixed
        # every state keeps the link and the knot type of the start (admissible)
        self.passage_guard = StrandPassageGuard(x)
        self.refusal: str | None = None

    # -- the parameter ------------------------------------------------------------------
    @property
    def excess_link(self) -> float:
        return self._excess_link

    @excess_link.setter
    def excess_link(self, value: float) -> None:
        self._excess_link = float(value)
        tau0 = 2 * np.pi * (self.link - self._excess_link) / self.rod.length
        self.rod = dataclasses.replace(self.rod, intrinsic_twist=tau0)

    def parameter_derivative(self, q: np.ndarray, multipliers: np.ndarray,
                             parameter: str) -> np.ndarray | None:
        """``d gradient / d excess_link`` (exact: the gradient is affine in the intrinsic
        twist, ``d tau0 / d dLk = -2 pi / L``); None for another parameter."""
        if parameter != "excess_link":
            return None
        local = self.elements_at(q)[2].intrinsic_twist_derivative() * (-2 * np.pi
                                                                         / self.rod.length)
        g = self._nodal(local)
        g[:, 3:] = np.einsum("nji,nj->ni", dexp(self._chart(q)), g[:, 3:])
        return g.ravel()

    # -- the link -----------------------------------------------------------------------
    def ribbon(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(points (n, 3), d1 (n, 3))``: the centreline and, per element, the midpoint
        director ``d1`` projected normal to the chord and normalised."""
        return self._ribbon(*self.configuration(q))

    def _ribbon(self, x, R):
        state = self.rod.elements(x, R)
        t = state.chord / np.linalg.norm(state.chord, axis=1, keepdims=True)
        d1 = state.Rm[:, :, 0]
        d1 = d1 - np.sum(d1 * t, axis=1, keepdims=True) * t
        return x, d1 / np.linalg.norm(d1, axis=1, keepdims=True)

    def _linking_number(self, x, R) -> float:
        points, d1 = self._ribbon(x, R)
        return twist_from_frames(points, d1, closed=True) + writhe(points)

    def frame_twist(self, q: np.ndarray) -> float:
        """Twist ``Tw`` of the ribbon (:meth:`ribbon`) in turns, from the frames alone."""
        return twist_from_frames(*self.ribbon(q), closed=True)

    def writhe(self, q: np.ndarray) -> float:
        """Writhe of the centreline polygon (exact double sum)."""
        return writhe(self.configuration(q)[0])

    def writhe_local(self, q: np.ndarray) -> float:
        """The writhe the ring's link carries at ``q``: ``link - Tw`` (frames only, no double
        sum); it equals :meth:`writhe` while the link is kept."""
        return self.link - self.frame_twist(q)

    def twist(self, q: np.ndarray) -> float:
        """Excess twist ``Tw - Lk_0 = Tw - link + dLk``: ``twist + writhe = dLk``."""
        return self.frame_twist(q) - self.link + self.excess_link

    def _check_rotations(self, x, R, where: str) -> None:
        largest = float(np.max(self.rod.elements(x, R).theta))
        if largest >= MAX_ELEMENT_ROTATION:
            raise LinkingError(f"{where}: an element turns by {np.degrees(largest):.1f} "
                               f"degrees (at most {np.degrees(MAX_ELEMENT_ROTATION):.0f}, so "
                               f"that its relative rotation stays the short way); use more "
                               f"nodes")

    def admissible(self, q: np.ndarray) -> bool:
        """Whether ``q`` kept the ring's link and the knot type of its start (module doc):
        no strand passed through another (``round(Tw + Wr)`` the ring's ``link``, and the
        knot type, :class:`~supercoil.topology.knots.StrandPassageGuard`, the writhe
        carried by the link being ``link - Tw``) and every element's rotation below
        :data:`MAX_ELEMENT_ROTATION`. Newton's and the continuation's per-step guard: a
        refused state's step is retried shorter. ``refusal`` says why the last refused
        state was refused."""
        x, R = self.configuration(q)
        # the link in full (the frames' twist and the double-sum writhe) at every state:
        # the sections can slip a turn of twist with the centreline held, which the guard's
        # shortcut (a centreline too close to the last verified one to have passed a
        # strand) cannot see
        lk = self._linking_number(x, R)
        if abs(lk - self.link) > 0.5:
            self.refusal = (f"the linking number would change from {self.link} to "
                            f"{int(np.rint(lk))} (a strand through another, or the sections "
                            "turned by whole turns)")
            return False
        if not self.passage_guard.admissible(x, lambda _x: self.link - twist_from_frames(
                *self._ribbon(x, R), closed=True)):
            self.refusal = self.passage_guard.refusal
            return False
        return self.rotations_admissible(q)

    def rotations_admissible(self, q: np.ndarray) -> bool:
        """Whether every element's relative rotation at ``q`` is below
        :data:`MAX_ELEMENT_ROTATION` (the part of :meth:`admissible` that the
        centreline cannot show: with self-contact the contact problem guards the link
        and the knot type on the centreline, and asks this of its rod,
        :class:`~supercoil.contact.step_guards.StepGuards`). ``refusal`` says why."""
        x, R = self.configuration(q)
        largest = float(np.max(self.rod.elements(x, R).theta))
        if largest >= MAX_ELEMENT_ROTATION:
            self.refusal = (f"an element would turn by {np.degrees(largest):.1f} degrees (at "
                            f"most {np.degrees(MAX_ELEMENT_ROTATION):.0f}, so that its "
                            "relative rotation stays the short way)")
            return False
        return True

    def accept(self, q: np.ndarray) -> None:
        """Re-base the chart, then check that the link is kept (module doc): every
        element's rotation below :data:`MAX_ELEMENT_ROTATION` and ``round(Tw + Wr)`` the
        ring's ``link``; :class:`LinkingError` otherwise."""
        super().accept(q)
        x, R = self.configuration(q)
        self._check_rotations(x, R, "accepted state")
        lk = self._linking_number(x, R)
        if abs(lk - self.link) > 0.5:
            raise LinkingError(f"the ribbon's linking number changed from {self.link} to "
                               f"{int(np.rint(lk))} (the centreline passed through itself, or "
                               f"the sections turned by whole turns between accepted states)")

    # -- symmetries ---------------------------------------------------------------------
    def _to_chart(self, q: np.ndarray, spatial: np.ndarray) -> np.ndarray:
        """Tangent vectors ``(..., n, 6)`` of displacements and spatial spins as ``q``
        increments ``(..., n_dofs)``: ``d theta = T(phi)^-1 w``."""
        T = dexp(self._chart(q))
        out = np.array(spatial, dtype=float)
        out[..., 3:] = np.linalg.solve(T, out[..., 3:, None])[..., 0]
        return out.reshape(out.shape[:-2] + (-1,))

    def symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """``(7, n_dofs)``: translations, rotations, the sections' rotation about ``d3``."""
        return self._to_chart(q, symmetry_generators(*self.configuration(q)))

    def near_symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """``(1, n_dofs)``: sliding the material along the ring by half an element each way,
        ``dx_i = (x_{i+1} - x_{i-1}) / 2``, spin ``d3_i x (d3_{i+1} - d3_{i-1}) / 2``
        plus the mean twist of the two elements about ``d3_i``. On a uniformly twisted
        circle it is exactly a rotation about the axis plus the isotropy (both move
        ``x`` and ``d3`` as one rigid rotation), so it adds nothing there."""
        x, R = self.configuration(q)
        d3 = R[:, :, 2]
        twist = self.rod.elements(x, R).psi[:, 2]
        out = np.zeros((len(x), 6))
        out[:, :3] = 0.5 * (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0))
        out[:, 3:] = np.cross(d3, 0.5 * (np.roll(d3, -1, axis=0) - np.roll(d3, 1, axis=0))) \
            + 0.5 * (twist + np.roll(twist, 1))[:, None] * d3
        return self._to_chart(q, out[None])
