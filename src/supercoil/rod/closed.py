"""Closed discrete Kirchhoff rod at fixed excess link (isotropic, inextensible).

Model (Bergou et al. 2008, 2010, with the twist reduced to one scalar):

* centreline: a closed polygon of ``n_nodes`` vertices, edges of fixed rest
  length ``h = L / n_nodes`` (inextensibility as equality constraints
  ``c_j = (|e_j|^2 - h^2) / (2h) = 0``; their multipliers are edge tensions);
* bending: ``sum_i A k_i^2 / (2h)`` (see :mod:`supercoil.rod.kernels`);
* twist: for an isotropic rod the excess twist density is uniform at
  equilibrium, so the material angles can be minimised out exactly and the
  twist energy is ``E_t = 2 pi^2 C Tw^2 / L`` with ``Tw = dLk - Wr``
  (Coleman & Swigon eq. 3-5). The writhe is never evaluated as a double sum
  here: ``Wr = Lk_u - Phi / 2pi`` where ``Phi`` is the total reference twist
  (holonomy of discrete parallel transport, a sum of local terms) and ``Lk_u``
  the integer linking number of the reference ribbon, fixed at set-up and kept
  by time-parallel transport of the reference directors. Hence the Hessian is
  banded plus one rank-one term ``k g g^T`` with ``g = grad(Phi) / 2pi``.

Minimising out the material angles is a Schur complement with a positive
definite block, so the number of negative eigenvalues (stability) is the same
as for the full model with material angles.
"""

from __future__ import annotations

import numpy as np

from supercoil.geometry.curves import edges, parallel_transport, perpendicular, signed_angle, unit
from supercoil.rod import kernels
from supercoil.rod.energy import RodEnergy
from supercoil.rod.model import Rod
from supercoil.topology.knots.passage import StrandPassageGuard


def initial_reference_frames(points: np.ndarray) -> np.ndarray:
    """Reference directors ``(n_edges, 3)`` of a closed polygon with equal reference twists.

    Space-parallel transport from edge 0 around the polygon, then each director
    is turned back by its share of the holonomy, so that every vertex carries
    the same reference twist (no single vertex holds the whole mismatch).
    """
    t = unit(edges(points, closed=True))
    n = len(t)
    u = np.empty_like(t)
    u[0] = perpendicular(t[:1])[0]
    for i in range(1, n):
        u[i] = parallel_transport(u[i - 1 : i], t[i - 1 : i], t[i : i + 1])[0]
    closing = parallel_transport(u[-1:], t[-1:], t[:1])[0]
    mismatch = float(signed_angle(closing[None], u[:1], t[:1])[0])  # total reference twist
    # Rotate u_i by -i * mismatch / n about t_i: each vertex then twists by mismatch / n.
    angle = -np.arange(n) * mismatch / n
    v = np.cross(t, u)
    return np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * v


class ClosedRodEnergy(RodEnergy):
    """The constrained energy problem of a closed rod at excess link ``excess_link``.

    Implements :class:`supercoil.solvers.problem.ConstrainedEnergy`. Holds the
    reference directors as mutable state, carried along by :meth:`accept`.
    ``reference_link`` is ``Lk_u``; pass it to continue from a saved state.
    Rigid motions are removed by fixing six DOFs (:func:`rigid_pins`).
    """

    def __init__(self, rod: Rod, points: np.ndarray, excess_link: float,
                 reference_directors: np.ndarray | None = None,
                 reference_link: int | None = None):
        points = np.asarray(points, dtype=float)
        if points.shape != (rod.n_nodes, 3):
            raise ValueError(f"points must have shape ({rod.n_nodes}, 3), got {points.shape}")
        if not np.isfinite(points).all():
            raise ValueError("points contain non-finite coordinates")
        if not rod.closed:
            raise ValueError("ClosedRodEnergy needs a closed Rod (closed=True)")
        if not np.isfinite(excess_link):
            raise ValueError(f"excess_link must be finite, got {excess_link!r}")
        self.excess_link = float(excess_link)
        n = rod.n_nodes
        idx = np.arange(n)
        if reference_directors is None:
            reference_directors = initial_reference_frames(points)
        self._setup(rod, points, np.stack([(idx - 1) % n, idx, (idx + 1) % n], 1),
                    np.stack([idx, (idx + 1) % n], 1), (idx - 1) % n, idx, reference_directors)
        if reference_link is None:
            from supercoil.topology import writhe  # set-up only, never inside Newton

            frame_twist = self.reference_twist_total(points.ravel()) / (2 * np.pi)
            reference_link = int(np.rint(frame_twist + writhe(points)))
        self.reference_link = int(reference_link)
        self.fixed = rigid_pins(points)
        self.gauge_dofs = self.fixed  # all six pins only remove rigid motions
        # every state keeps the link and the knot type of ``points`` (admissible)
        self.passage_guard = StrandPassageGuard(points)
        self.refusal: str | None = None

    twist_parameter = "excess_link"
    parameters = ("excess_link",)
    frame_attributes = RodEnergy.frame_attributes + (("reference_link", "reference_link"),)

    def twist_offset(self) -> float:
        return self.excess_link - self.reference_link

    def repin(self, q: np.ndarray) -> None:
        """Re-pick the six rigid-motion pins (:func:`rigid_pins`) for the state ``q``.

        The pins chosen on the circle remove rotations less and less well as
        the ring folds into a plectoneme (:meth:`pin_quality` fell to 0.1 on
        the alpha branch at L/D = 122): the pinned Hessian then keeps a nearly
        null rotation, whose eigenvalue the gauge's small force can push
        through zero, and a continuation folds back and forth there (measured:
        the branch snaked from dLk 3.40, N = 200). Call this between
        continuation runs: the pinned coordinates keep their values at ``q``.
        """
        self.fixed = rigid_pins(np.asarray(q, dtype=float).reshape(-1, 3))
        self.gauge_dofs = self.fixed

    def pin_grip(self, q: np.ndarray) -> float:
        """:func:`rotation_pin_determinant` of the current pins at ``q``: zero where they do
        not remove some rigid motion (cheap: one 6 x 6 determinant)."""
        return rotation_pin_determinant(np.asarray(q, dtype=float).reshape(-1, 3), self.fixed)

    def pin_quality(self, q: np.ndarray) -> float:
        """:func:`rotation_pin_determinant` of the current pins at ``q`` over that of the
        pins :func:`rigid_pins` would choose there, in ``[0, 1]`` (1 right after
        :meth:`repin`)."""
        x = np.asarray(q, dtype=float).reshape(-1, 3)
        best = rotation_pin_determinant(x, rigid_pins(x))
        return min(1.0, rotation_pin_determinant(x, self.fixed) / best) if best > 0 else 0.0

    # An accepted state whose edges turned by more than this (degrees) from the
    # last one is a jump (a stored state), not a step: see accept.
    jump_turn_degrees = 45.0

    def accept(self, q: np.ndarray) -> None:
        """Carry the reference directors to ``q``; keep the reference twist well spread.

        ``Phi`` is the sum of per-vertex signed angles in ``(-pi, pi]``: a
        vertex whose reference twist reaches ``pi`` slips ``Phi`` by ``2 pi``
        and the tracked writhe by one. Along a branch the tangents turn by a
        few degrees per accepted point (at most 11 degrees measured on the
        ring's alpha branch at N = 40) and time-parallel transport keeps the
        per-vertex twists small. Going back to a stored state (branch
        switching, a consistency check) transports the frames in one jump:
        measured, from near the figure-eight back to the circle, the twists
        piled up so that a later small step slipped the writhe by one. So:

        * after a jump (some edge turned by more than :attr:`jump_turn_degrees`)
          the directors are rebuilt as at set-up (equal reference twists) and
          ``Lk_u`` is recomputed from the double-sum writhe (O(N^2), about
          20 ms at N = 1000): the tracked writhe is then the true one;
        * after a step, if some vertex carries more than ``pi / 2`` of reference
          twist, the directors are rebuilt the same way and ``Lk_u`` shifted by
          the whole turns this changes ``Phi`` by, so that the tracked writhe
          (continuous along the branch) is unchanged.
        """
        q = np.asarray(q, dtype=float)
        t_new = unit(self._edge_vectors(q))
        jump = bool(np.min(np.sum(t_new * self._tangents, axis=1))
                    < np.cos(np.radians(self.jump_turn_degrees)))
        super().accept(q)
        if not jump and np.max(np.abs(kernels.twist_value(self._stencils(q),
                                                           self._frames()))) <= np.pi / 2:
            return
        phi_old = self.reference_twist_total(q)
        points = q.reshape(-1, 3)
        self._set_frames(t_new, initial_reference_frames(points))
        phi_new = self.reference_twist_total(q)
        if jump:
            from supercoil.topology import writhe  # jumps only, never inside Newton

            self.reference_link = int(np.rint(phi_new / (2 * np.pi) + writhe(points)))
        else:
            self.reference_link += int(np.rint((phi_new - phi_old) / (2 * np.pi)))

    def admissible(self, q: np.ndarray) -> bool:
        """Whether ``q`` kept the linking number and the knot type of the curve the problem
        was set up with (Newton's and the continuation's per-step guard: a refused state's
        step is retried shorter; :class:`~supercoil.topology.knots.StrandPassageGuard`).
        ``refusal`` says why the last refused state was refused. With self-contact
        :meth:`supercoil.contact.problem.ContactProblem.admissible` is the guard."""
        if self.passage_guard.admissible(q, self.writhe_local):
            return True
        self.refusal = self.passage_guard.refusal
        return False

    def writhe_local(self, q: np.ndarray) -> float:
        """Writhe from the reference twist: ``Lk_u - Phi / 2pi`` (no double sum)."""
        return self.reference_link - self.reference_twist_total(q) / (2 * np.pi)

    def symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """The six rigid motions at ``q`` (shape ``(6, n_dofs)``): translations, rotations.

        (Off the circle a homogeneous ring has a seventh, approximate symmetry,
        sliding the material along itself; the circle's sliding is a rotation.)
        """
        x = q.reshape(-1, 3)
        r = x - x.mean(axis=0)
        modes = []
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            modes.append(np.tile(e, len(x)))
            modes.append(np.cross(e, r).ravel())
        return np.array(modes)

    def near_symmetry_modes(self, q: np.ndarray) -> np.ndarray:
        """Sliding the material along the centreline, ``(x_{i+1} - x_{i-1}) / 2`` (shape
        ``(1, n_dofs)``): an exact symmetry of the continuous homogeneous ring,
        broken only by the discretisation. It is removed from the unstable count
        (docs/model.md, "Stability"); on the circle it is a rigid rotation.
        """
        x = q.reshape(-1, 3)
        return (0.5 * (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0))).ravel()[None, :]

    def material_directors(self, q: np.ndarray) -> np.ndarray:
        """Material directors ``d1`` (shape ``(n, 3)``) with uniform excess twist.

        The material angle ``theta_i`` of edge ``i`` is chosen so that each
        vertex carries the same total twist ``Phi / n``; ``theta`` is single
        valued around the ring, so the material ribbon has linking number
        ``Lk_u`` and its twist, measured from these directors by
        :func:`supercoil.topology.twist_from_frames`, is an independent check
        of Lk = Tw + Wr.
        """
        carried = self.carried_to(q)  # directors adapted to the current tangents
        ref = kernels.twist_value(carried._stencils(q), carried._frames())
        mean = ref.mean()
        theta = np.zeros(len(ref))
        theta[1:] = np.cumsum(mean - ref[1:])
        t = carried._tangents
        u = carried._directors
        v = np.cross(t, u)
        return np.cos(theta)[:, None] * u + np.sin(theta)[:, None] * v


def rotation_pin_determinant(points: np.ndarray, pins: np.ndarray) -> float:
    """``|det|`` of the response of the six pinned coordinates to the rigid motions:
    row ``(e_k, r_i x e_k)`` for each pinned DOF ``3 i + k`` (translations, then
    rotations about node 0; ``r_i = x_i - x_0``).

    Zero when the pins do not remove some rigid motion (or are not six); it scales as
    ``|r|^3``. With node 0 fully pinned it is the ``|det|`` of the three other rows'
    rotation parts.
    """
    x = np.asarray(points, dtype=float).reshape(-1, 3)
    pins = np.asarray(pins, dtype=np.int64)
    if pins.size != 6:
        return 0.0
    return float(abs(np.linalg.det(_rigid_rows(x, pins))))


def _rigid_rows(points: np.ndarray, dofs) -> np.ndarray:
    """Rows ``(e_k, (x_i - x_0) x e_k)`` of the DOFs ``3 i + k``, ``(len(dofs), 6)``."""
    dofs = np.asarray(dofs, dtype=np.int64)
    node, k = np.divmod(dofs, 3)
    unit = np.eye(3)[k]
    return np.hstack([unit, np.cross(points[node] - points[0], unit)])


# the equivariant pins (rigid_pins) are taken when they remove rotations at least this
# well relative to the best of all candidate sets
EQUIVARIANT_PIN_QUALITY = 0.25


def rigid_pins(points: np.ndarray) -> np.ndarray:
    """Six DOF indices whose fixing removes the rigid motions of a free body.

    By default node 0 is fixed (translations) and three coordinates of far nodes
    are chosen to maximise ``|det|`` of their response to infinitesimal rotations
    about node 0 (:func:`rotation_pin_determinant`; so rotations are removed
    as well as the geometry allows).
    At an equilibrium the rigid motions are null vectors of the Hessian, so
    fixing these DOFs restricts the Hessian to a complement of the rigid modes
    and leaves its inertia unchanged.

    Equivariant pins. For an even number of nodes and a state that the two-fold map
    ``x_i -> R x_{-i}`` (``R`` the half-turn about the line through node 0 along
    ``x``) leaves unchanged (:func:`_axis_through_node_0`), the six are taken, when
    they reach ``EQUIVARIANT_PIN_QUALITY`` of the best determinant, among sets
    that this map maps onto themselves (:func:`_equivariant_sets`). On the
    circle (node 0 on the ``x`` axis, :func:`~supercoil.geometry.curves.circle`)
    that line is the two-fold axis through nodes 0 and ``n/2``
    (:func:`~supercoil.problems.ring_diagram.primary.on_mesh_direction` switches the
    primary branches along it). With such pins the pinned equations are
    equivariant, so a state symmetric about that axis stays exactly so along a
    branch; with others the pins turn the axis a little at each step, the
    integral phase condition (invariant to rotations only to first order) then
    slides the material, and the symmetry is lost by ``O(step^2)`` per step
    (measured: alpha, N = 200, the axis 0.01 node spacings off the mesh by
    dLk 6), which unfolds the symmetry-breaking bifurcations of secondary
    branches.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(points)
    candidates = [3 * node + k for node in (n // 3, (2 * n) // 3, n // 2, n // 6)
                  for k in range(3)]
    best, best_det = None, -1.0
    for a in range(len(candidates)):
        for b in range(a + 1, len(candidates)):
            for c in range(b + 1, len(candidates)):
                dofs = [candidates[a], candidates[b], candidates[c]]
                if len(set(dofs)) < 3:
                    continue
                det = abs(np.linalg.det(_rigid_rows(points, [0, 1, 2] + dofs)))
                if det > best_det:
                    best, best_det = dofs, det
    if best is None or best_det <= 1e-12 * np.ptp(points) ** 3:
        raise ValueError("cannot remove rigid rotations: the curve is (nearly) a straight line")
    best = [0, 1, 2] + best
    if n % 2 == 0 and n >= 8 and _axis_through_node_0(points):
        sets = _equivariant_sets(n)
        rows = _rigid_rows(points, np.arange(3 * n))
        dets = np.abs(np.linalg.det(rows[sets]))
        k = int(np.argmax(dets))
        if dets[k] >= EQUIVARIANT_PIN_QUALITY * best_det:
            best = [int(d) for d in sets[k]]
    return np.array(sorted(best), dtype=np.int64)


def _equivariant_sets(n: int) -> np.ndarray:
    """Six-DOF pin sets (even ``n``) that ``x_i -> R x_{-i}`` maps onto themselves, ``R``
    the half-turn about the line through node 0 along ``x`` (coordinates map to
    coordinates), ``(k, 6)``. Nodes 0 and ``n/2`` are their own images, node ``k`` and
    ``n - k`` each other's: node 0 (all three) with one coordinate of node ``n/2`` and
    one coordinate of a pair ``k``, ``n - k``; or two coordinates of node 0 with two
    pairs (when nodes 0 and ``n/2`` come close, as at alpha's crossing, the first kind
    loses its grip on rotations)."""
    half = n // 2
    nodes = sorted({(j * n) // 24 for j in range(1, 12)} - {0, half})
    pairs = [(k, c) for k in nodes for c in range(3)]
    sets = []
    for k, c in pairs:
        for a in range(3):
            sets.append([0, 1, 2, 3 * half + a, 3 * k + c, 3 * (n - k) + c])
    for i in range(len(pairs)):
        for j in range(i + 1, len(pairs)):
            (k, c), (m, d) = pairs[i], pairs[j]
            for skipped in range(3):
                origin = [a for a in range(3) if a != skipped]
                sets.append(origin + [3 * k + c, 3 * (n - k) + c, 3 * m + d, 3 * (n - m) + d])
    return np.array(sets, dtype=np.int64)


def _axis_through_node_0(points: np.ndarray, tolerance: float = 1e-8) -> bool:
    """True when ``x_i = R x_{-i}`` for every node within ``tolerance`` times the curve's
    size, ``R`` the half-turn about the line through node 0 along ``x``: the curve has a
    two-fold axis on that line, through node 0 (and node ``n/2`` for even ``n``)."""
    x = np.asarray(points, dtype=float)
    n = x.shape[0]
    image = x[(-np.arange(n)) % n] - x[0]
    image[:, 1:] *= -1.0
    image += x[0]
    size = float(np.ptp(x, axis=0).max())
    return bool(np.max(np.abs(image - x)) <= tolerance * max(size, 1e-300))
