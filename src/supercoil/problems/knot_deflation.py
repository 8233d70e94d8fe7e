"""Further equilibria of a knotted ring by deflation (Farrell, Birkisson & Funke 2015).

At a given ``dLk`` the known equilibria ``q_1 .. q_m`` are removed from the
equilibrium equations ``F(q) = grad E(q) = 0`` by the deflation operator

    G(q) = M(q) F(q),   M(q) = prod_i (1 / |q - q_i|^p + sigma)   (p = 2, sigma = 1),

whose roots are the roots of ``F`` other than the ``q_i`` (``M`` blows up at
them, so Newton's iterates are pushed away). Newton's step for ``G`` is the
step ``delta`` for ``F`` scaled (Sherman-Morrison, Farrell et al. 2015, eq. 3.4):
``delta / (1 - grad(log M) . delta)``.

Here ``F`` is the gradient of the ring's energy with the barrier contact on the
free DOFs (the six rigid pins fixed) and with the material sliding held by the
linear gauge of :meth:`~supercoil.contact.problem.ContactProblem.pin_sliding`
(a node's tangential position; without it the nearly null sliding mode makes
every known state a continuum). The known states are brought into the start's
frame first: each is aligned to the start by the rigid motion (Kabsch) and the
cyclic relabelling of its nodes that bring it closest, so that the pole sits on
the copy of it the iterates can reach (a copy slid by a fraction of an edge is
not deflated; :func:`distinct` then tells it by its energy). Every step is
limited by the collision bound (``ContactProblem.step_bound``) and vetted by
``ContactProblem.admissible`` (linking number and knot type), and
backtracked on ``|G|``.

Starts: each known state pushed by ``amplitude * D`` (node-wise, largest
displacement) along the two lowest eigenvectors of its Hessian, both signs:
the directions in which the energy landscape is softest, where neighbouring
equilibria lie (Farrell et al. start from the initial guess that found the
first solution; the known state is where the continuation stands).
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from supercoil.contact.problem import ContactProblem
from supercoil.problems.segments import set_pin
from supercoil.solvers.problem import free_dofs

log = logging.getLogger(__name__)
POWER, SHIFT = 2.0, 1.0  # p and sigma of the deflation operator
SAME_ENERGY = 1e-6  # two equilibria at one dLk whose energies agree to this (relative)
FREE_STEPS = 40  # Newton steps taken without asking |G| to fall (then backtracked on it)


@dataclasses.dataclass(frozen=True)
class Deflated:
    """A state found by deflation: ``q``, its ``dLk``, energy, Newton's iterations."""

    q: np.ndarray
    excess_link: float
    energy: float
    iterations: int


def aligned(q: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``q`` (a ring) moved rigidly and relabelled cyclically (both directions kept) to
    lie closest to ``reference`` (same number of nodes)."""
    x, y = q.reshape(-1, 3), reference.reshape(-1, 3)
    yc = y - y.mean(axis=0)
    best, best_d = x, np.inf
    for shift in range(len(x)):
        xs = np.roll(x, shift, axis=0)
        xc = xs - xs.mean(axis=0)
        u, _s, vt = np.linalg.svd(xc.T @ yc)
        d = np.sign(np.linalg.det(u @ vt))
        rotation = u @ np.diag([1.0, 1.0, d]) @ vt
        moved = xc @ rotation + y.mean(axis=0)
        dist = float(np.sum((moved - y) ** 2))
        if dist < best_d:
            best, best_d = moved, dist
    return best.ravel()


def deflation_factor(q: np.ndarray, known: list[np.ndarray]) -> tuple[float, np.ndarray]:
    """``M(q)`` and ``grad log M(q)`` (module doc)."""
    m, g = 1.0, np.zeros_like(q)
    for k in known:
        r = q - k
        n2 = max(float(r @ r), 1e-300)
        factor = n2 ** (-POWER / 2) + SHIFT
        m *= factor
        g += (-POWER * n2 ** (-POWER / 2 - 1) * r) / factor
    return m, g


def _gauge(cp: ContactProblem, q: np.ndarray, free: np.ndarray):
    """The sliding gauge's row on the free DOFs and its target (module doc)."""
    x = q.reshape(-1, 3)
    n = len(x)
    fixed_nodes = set((np.asarray(cp.fixed) // 3).tolist())
    k = next(i for i in range(n // 4, n // 4 + n) if i % n not in fixed_nodes) % n
    t = x[(k + 1) % n] - x[(k - 1) % n]
    row = np.zeros(q.size)
    row[3 * k:3 * k + 3] = t / np.linalg.norm(t)
    return row[free], float(row @ q)


def deflated_newton(cp: ContactProblem, start: np.ndarray, known: list[np.ndarray],
                    tolerance: float = 1e-8, max_iterations: int = 150) -> Deflated | None:
    """Newton on the deflated equations from ``start`` at ``cp.excess_link``; None when it
    does not converge. ``known``: states already in ``start``'s frame (:func:`aligned`).

    The equations are the ring's with its constraints (the edge lengths): ``grad E +
    J^T lam + mu a = 0``, ``c(q) = 0`` and the sliding gauge ``a . q = a . q_start``,
    on the free DOFs; ``M`` depends on ``q`` alone."""
    q = np.array(start, dtype=float)
    set_pin(cp, cp.base, q)
    free = free_dofs(cp)
    a, target = _gauge(cp, q, free)
    known_free = [k[free] for k in known]
    nf = free.size

    def jacobian(state):
        return cp.constraint_jacobian(state).toarray()[:, free]

    def residual(state, lam):
        f = cp.gradient(state)[free]
        c = cp.constraints(state)
        return np.concatenate([f + jacobian(state).T @ lam[:-1] + lam[-1] * a, c,
                               [a @ state[free] - target]])

    jac = jacobian(q)
    basis = np.vstack([jac, a]).T
    lam = -np.linalg.lstsq(basis, cp.gradient(q)[free], rcond=None)[0]
    m_c = jac.shape[0]
    r = residual(q, lam)
    for iteration in range(max_iterations):
        if np.max(np.abs(r)) < tolerance:
            cp.accept(q)
            return Deflated(q, float(cp.excess_link), float(cp.energy(q)), iteration)
        jac = jacobian(q)
        h = cp.lagrangian_hessian(q, lam[:-1]).dense()[np.ix_(free, free)]
        rows = np.vstack([jac, a])
        kkt = np.zeros((nf + m_c + 1, nf + m_c + 1))
        kkt[:nf, :nf], kkt[:nf, nf:], kkt[nf:, :nf] = h, rows.T, rows
        try:
            delta = np.linalg.solve(kkt, -r)
        except np.linalg.LinAlgError:
            return None
        m, grad_log_m = deflation_factor(q[free], known_free)
        denominator = 1.0 - grad_log_m @ delta[:nf]
        step = delta / denominator if abs(denominator) > 1e-12 else delta
        dq = np.zeros_like(q)
        dq[free] = step[:nf]
        fraction = min(1.0, 0.9 * cp.step_bound(q, dq))
        merit = m * np.linalg.norm(r)
        for _ in range(12):
            trial, lam_t = q + fraction * dq, lam + fraction * step[nf:]
            if cp.admissible(trial):
                r_t = residual(trial, lam_t)
                m_t, _ = deflation_factor(trial[free], known_free)
                if np.all(np.isfinite(r_t)) and (m_t * np.linalg.norm(r_t) < merit
                                                 or iteration < FREE_STEPS):
                    break
            fraction *= 0.5
        else:
            log.debug("deflated Newton: no step reduces |G| at iteration %d (|r| = %.3g)",
                      iteration, np.max(np.abs(r)))
            return None
        log.debug("deflated Newton %d: |r| %.3g -> %.3g, step fraction %.3g, M %.3g",
                  iteration, np.max(np.abs(r)), np.max(np.abs(r_t)), fraction, m_t)
        q, lam, r = trial, lam_t, r_t
        cp.accept(q)
    return None


def soft_directions(cp: ContactProblem, q: np.ndarray, count: int = 2) -> list[np.ndarray]:
    """The ``count`` lowest eigenvectors of the Hessian at ``q`` on the free DOFs (full
    length, zero on the pins), each scaled to a largest node displacement of 1."""
    set_pin(cp, cp.base, q)
    free = free_dofs(cp)
    h = cp.hessian(q).dense()[np.ix_(free, free)]
    _values, vectors = np.linalg.eigh(0.5 * (h + h.T))
    out = []
    for j in range(min(count, vectors.shape[1])):
        v = np.zeros(q.size)
        v[free] = vectors[:, j]
        out.append(v / np.max(np.linalg.norm(v.reshape(-1, 3), axis=1)))
    return out


def deflate_at(cp: ContactProblem, excess_link: float, states: list[np.ndarray],
               amplitude: float = 0.5, directions: int = 2,
               tolerance: float = 1e-8) -> list[Deflated]:
    """New equilibria at ``excess_link`` by deflation of ``states`` (module doc), each
    found one deflated in turn for the following starts. ``cp`` is unchanged (its
    problem at ``excess_link`` carries the frames from state to state)."""
    cp = cp.at(excess_link=float(excess_link))
    found: list[Deflated] = []
    D = cp.diameter
    for base_state in states:
        cp.accept(base_state)
        for v in soft_directions(cp, base_state, directions):
            for sign in (1.0, -1.0):
                start = base_state + sign * amplitude * D * v
                if not cp.admissible(start):
                    continue
                known = [aligned(s, start) for s in states] + [
                    aligned(d.q, start) for d in found]
                # the state the start came from is deflated in its own frame
                known.append(np.array(base_state, dtype=float))
                result = deflated_newton(cp, start, known, tolerance)
                if result is not None and distinct(result.energy, [
                        float(cp.energy(s)) for s in states] + [d.energy for d in found]):
                    found.append(result)
                cp.accept(base_state)
    return found


def distinct(energy: float, energies: list[float]) -> bool:
    """Whether an equilibrium of ``energy`` differs from those of ``energies`` (one dLk):
    energy is invariant under the rigid motions and the sliding that relate copies."""
    return all(abs(energy - e) > SAME_ENERGY * max(1.0, abs(e)) for e in energies)
