"""Self-contact of the Cosserat rod: the contact terms in the Cosserat unknowns.

Oracles: the contact energy of a Cosserat state is that of its centreline (the same
numbers as the Kirchhoff rod's contact on the same polygon); its gradient and Hessian
in the Cosserat unknowns match central finite differences and vanish on the
rotation coordinates (the contact acts through the linear selection of the
positions); the collision bound of a step is that of its centreline's step.
"""

import numpy as np
import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.cosserat.centreline import centreline_dofs
from supercoil.cosserat.problem import CosseratEnergy
from supercoil.cosserat.rod import CosseratRod
from supercoil.cosserat.rotations import exp_so3
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod

N = 24
RADIUS = 0.05  # the stadium's half-width: its straight strands 2 RADIUS apart


def stadium(n: int = N) -> np.ndarray:
    """A closed stadium of length 1 (two half-circles of radius RADIUS joined by straight
    strands 2 RADIUS apart), slightly bent out of plane: nodes equally spaced in arc
    length."""
    ends = np.pi * RADIUS
    straight = (1.0 - 2 * ends) / 2
    s = np.arange(n) / n
    out = np.zeros((n, 3))
    for i, si in enumerate(s):
        if si < straight:
            out[i] = [si - straight / 2, -RADIUS, 0.0]
        elif si < straight + ends:
            a = (si - straight) / RADIUS - np.pi / 2
            out[i] = [straight / 2 + RADIUS * np.cos(a), RADIUS * np.sin(a), 0.0]
        elif si < 2 * straight + ends:
            out[i] = [straight / 2 - (si - straight - ends), RADIUS, 0.0]
        else:
            a = (si - 2 * straight - ends) / RADIUS + np.pi / 2
            out[i] = [-straight / 2 + RADIUS * np.cos(a), RADIUS * np.sin(a), 0.0]
    out[:, 2] = 0.01 * np.sin(2 * np.pi * 3 * s)
    return out


CASES = {
    "penalty pairs polygon": {"diameter": 0.104, "treatment": "penalty", "curve": "polygon",
                              "formulation": "pairs"},
    "penalty pairs spline": {"diameter": 0.104, "treatment": "penalty", "curve": "spline",
                             "formulation": "pairs"},
    "barrier pairs spline": {"diameter": 0.09, "treatment": "barrier", "curve": "spline",
                             "formulation": "pairs", "barrier_activation": 0.3},
    "barrier integral spline": {"diameter": 0.09, "treatment": "barrier", "curve": "spline",
                                "formulation": "integral", "barrier_activation": 0.3},
}


def cosserat_state(seed: int = 1):
    """A Cosserat ring on the stadium, random frames, its state perturbed (every DOF)."""
    rng = np.random.default_rng(seed)
    x = stadium()
    R = exp_so3(0.3 * rng.normal(size=(N, 3)))
    base = CosseratEnergy(CosseratRod(N, closed=True), x, R)
    q = base.initial_state() + 1e-4 * rng.normal(size=base.n_dofs)
    return base, q, rng


@pytest.mark.parametrize("name", sorted(CASES))
def test_contact_terms_in_cosserat_dofs_match_finite_differences(name):
    base, q, rng = cosserat_state()
    cp = ContactProblem(base, ContactOptions(**CASES[name]))
    assert cp.contact_energy(q) > 0  # the strands are within the contact's reach

    def contact_gradient(state):
        return cp.gradient(state) - base.gradient(state)

    g = contact_gradient(q)
    H = cp.contact_hessian(q).toarray()
    # the contact acts on the positions only
    rotations = np.setdiff1d(np.arange(base.n_dofs), centreline_dofs(N))
    assert np.all(g[rotations] == 0)
    assert np.all(H[rotations] == 0) and np.all(H[:, rotations] == 0)
    # the contact's third derivative is large (the barrier's, a pair's local minimum on
    # the spline): the central differences' O(eps^2) error fell from 2e-6 (eps = 1e-6)
    # to 3e-10 relative (eps = 1e-8), round-off staying below that
    eps = 1e-8
    for _ in range(3):
        v = rng.normal(size=base.n_dofs)
        fd = (cp.contact_energy(q + eps * v) - cp.contact_energy(q - eps * v)) / (2 * eps)
        assert fd == pytest.approx(g @ v, rel=1e-6, abs=1e-8 * np.abs(g).sum())
        fd_h = (contact_gradient(q + eps * v) - contact_gradient(q - eps * v)) / (2 * eps)
        scale = np.abs(H).max() * np.abs(v).max()
        assert np.max(np.abs(fd_h - H @ v)) <= 1e-5 * scale


@pytest.mark.parametrize("name", sorted(CASES))
def test_cosserat_contact_is_the_centreline_contact(name):
    """The same numbers as the Kirchhoff rod's contact on the same polygon (the fast path
    of the identity map against the selection)."""
    base, q, _ = cosserat_state()
    x = base.centreline(q)
    kirchhoff = ClosedRodEnergy(Rod(N, twist_stiffness=1.0), x.reshape(-1, 3), 0.0)
    options = ContactOptions(**CASES[name])
    cp, kp = ContactProblem(base, options), ContactProblem(kirchhoff, options)
    assert cp.contact_energy(q) == pytest.approx(kp.contact_energy(x), rel=1e-12)
    dofs = centreline_dofs(N)
    g_c = cp.gradient(q) - base.gradient(q)
    g_k = kp.gradient(x) - kirchhoff.gradient(x)
    np.testing.assert_allclose(g_c[dofs], g_k, rtol=1e-12, atol=1e-12 * np.abs(g_k).max())
    H_c = cp.contact_hessian(q).toarray()[np.ix_(dofs, dofs)]
    H_k = kp.contact_hessian(x).toarray()
    np.testing.assert_allclose(H_c, H_k, rtol=1e-12, atol=1e-12 * np.abs(H_k).max())
    # a step's collision bound is that of its centreline's step
    rng = np.random.default_rng(3)
    dq = 0.02 * rng.normal(size=base.n_dofs)
    assert cp.step_bound(q, dq) == kp.step_bound(x, dq[dofs])
    assert cp.min_distance(q) == kp.min_distance(x)
