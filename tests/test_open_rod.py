"""The clamped open rod: derivatives, exact twisted state, Greenhill buckling, Fuller closure."""

import numpy as np
import pytest

from supercoil.problems.ring import richardson
from supercoil.rod.model import Rod
from supercoil.rod.open import ClampedRodEnergy, straight_rod
from supercoil.solvers.newton import NewtonOptions, least_squares_multipliers, newton
from supercoil.solvers.problem import free_dofs
from supercoil.stability.analysis import negative_count
from supercoil.stability.bisection import locate_count_change
from supercoil.topology import writhe

# Greenhill: a rod clamped at both ends, free to slide axially (no tension),
# buckles under the axial moment M L / A = 2 x1 with tan(x1) = x1.
GREENHILL = 8.986818916


def bent_rod(n, amplitude, rng=None):
    """A rod with the clamps satisfied and an off-axis smooth bend in between."""
    pts = straight_rod(n)
    s = np.clip(pts[:, 2], 0, 1)
    bump = np.sin(np.pi * s) ** 3  # flat (C^2) at the clamped ends
    pts[:, 0] += amplitude * bump * np.cos(3 * s)
    pts[:, 1] += amplitude * bump * np.sin(2 * s)
    pts[[0, 1, -2, -1], :2] = 0.0
    return pts


def fourth_order_difference(f, q, d, eps=1e-5):
    """Directional derivative with an O(eps^4) central stencil (stiff rod terms)."""
    return (-f(q + 2 * eps * d) + 8 * f(q + eps * d) - 8 * f(q - eps * d)
            + f(q - 2 * eps * d)) / (12 * eps)


def make(n=30, turns=0.8, tension=5.0, pts=None, control=False):
    rod = Rod(n, twist_stiffness=0.7, closed=False)
    pts = straight_rod(n) if pts is None else pts
    return ClampedRodEnergy(rod, pts, turns, tension=tension, end_distance_control=control), pts


def test_gradient_and_hessian_match_finite_differences(rng):
    p, pts = make(pts=bent_rod(30, 0.05))
    q = pts.ravel() + 1e-4 * rng.standard_normal(90)
    H = p.hessian(q)
    g = p.gradient(q)
    for _ in range(3):
        d = rng.standard_normal(q.size)
        assert g @ d == pytest.approx(fourth_order_difference(p.energy, q, d), rel=1e-8)
        fdh = fourth_order_difference(p.gradient, q, d)
        assert np.max(np.abs(H.matvec(d) - fdh)) <= 1e-7 * np.max(np.abs(fdh))


def test_remembered_gradient_pieces_and_jacobian_equal_fresh_ones(rng):
    """The gradient keeps the pieces of the last state that the load does not change,
    and the Jacobian the last matrix (fast paths): against a fresh problem for each
    (turns, tension) and after the frames moved (accept), bit for bit."""
    pts = bent_rod(30, 0.05)
    p, _ = make(pts=pts)
    q = pts.ravel() + 1e-4 * rng.standard_normal(90)
    for turns, tension in ((0.8, 5.0), (1.7, 5.0), (1.7, -2.0), (0.8, 5.0)):
        p.turns, p.tension = turns, tension
        fresh, _ = make(turns=turns, tension=tension, pts=pts)
        assert np.array_equal(p.gradient(q), fresh.gradient(q))
        assert (p.constraint_jacobian(q) != fresh.constraint_jacobian(q)).nnz == 0
    q2 = q + 1e-4 * rng.standard_normal(90)
    p.accept(q2)  # new reference frames: the twist pieces must be recomputed
    fresh, _ = make(turns=0.8, tension=5.0, pts=pts)
    fresh.accept(q2)
    for state in (q2, q):
        assert np.array_equal(p.gradient(state), fresh.gradient(state))
    assert p.constraint_jacobian(q) is p.constraint_jacobian(q)
    p.set_constrained_edges(np.arange(2, 20))  # another constraint set: another Jacobian
    assert p.constraint_jacobian(q).shape == (18, 90)


def test_straight_twisted_rod_energy_is_exact():
    p, pts = make(n=40, turns=1.3, tension=0.0)
    assert p.energy(pts.ravel()) == pytest.approx(2 * np.pi**2 * 0.7 * 1.3**2, rel=1e-13)
    assert p.extension(pts.ravel()) == pytest.approx(1.0, abs=1e-14)


def test_tension_load_potential_and_equilibrium_of_the_straight_rod():
    p, pts = make(n=30, turns=0.5, tension=3.0)
    q = pts.ravel()
    assert p.load_potential(q) == pytest.approx(-3.0, rel=1e-13)
    res = newton(p, q, NewtonOptions(mode="stationary"))
    assert res.converged
    # the straight rod carries the tension: every constrained edge has multiplier +F
    # (grad c = +-t at its end nodes; at the pulled end -F t + lambda t = 0)
    assert np.allclose(res.multipliers, 3.0, rtol=1e-9)


def greenhill_turns(n):
    p, pts = make(n=n, turns=0.0, tension=0.0)
    p.rod = Rod(n, closed=False)  # C/A = 1 for the threshold in turns
    p._twist_coefficient = 4 * np.pi**2
    q = pts.ravel()
    free = free_dofs(p)

    def count(turns):
        p.turns = turns
        return negative_count(p, q, least_squares_multipliers(p, q, free))

    guess = GREENHILL / (2 * np.pi)
    return locate_count_change(count, 0.9 * guess, 1.1 * guess, 2, rtol=1e-11)


def test_greenhill_buckling_converges_with_second_order():
    exact = GREENHILL / (2 * np.pi)
    values = {n: greenhill_turns(n) for n in (50, 100, 200, 400)}
    errors = np.array([abs(values[n] - exact) / exact for n in (50, 100, 200, 400)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) < 0.2), (errors, orders)
    assert abs(richardson(values[200], values[400]) - exact) / exact < 1e-5


def test_fuller_closure_turns_equal_twist_plus_writhe():
    """turns = Tw + Wr with straight tails along the axis, Wr from the double sum."""
    p, _pts = make(n=60, pts=bent_rod(60, 0.02))
    for amp in np.linspace(0.02, 0.25, 12):
        q = bent_rod(60, amp).ravel()
        p.accept(q)
        tw = p.twist(q)
        wr = writhe(q.reshape(-1, 3), closure="axis")
        assert tw + wr == pytest.approx(p.turns, abs=1e-10)
        assert p.writhe_local(q) == pytest.approx(wr, abs=1e-10)


def test_rotation_about_the_axis_is_removed():
    p, pts = make(n=30, pts=bent_rod(30, 0.1))
    assert len(p.fixed) == 11  # 6 (clamp) + 4 (axis) + 1 (azimuth pin)
    assert p.symmetry_modes(pts.ravel()).shape == (1, 90)


def test_eigenmodes_keep_the_clamps_when_the_gauge_pin_is_released():
    """Off the axis the azimuth pin is released for the eigenvalues, the clamps are not."""
    from supercoil.stability.analysis import analyse

    pts = bent_rod(40, 0.08)
    p, _ = make(n=40, pts=pts)
    q = pts.ravel()
    rep = analyse(p, q, least_squares_multipliers(p, q, free_dofs(p)))
    clamped = np.setdiff1d(p.fixed, p.gauge_dofs)
    assert p.gauge_dofs.size == 1 and clamped.size == 10
    assert np.max(np.abs(rep.lowest_modes[:, clamped])) == 0.0
    assert np.max(np.abs(rep.lowest_modes[:, p.gauge_dofs])) > 0.0


@pytest.mark.parametrize("bad", ["closed", "offaxis", "turns"])
def test_bad_input(bad):
    rod = Rod(20, closed=(bad == "closed"))
    pts = straight_rod(20)
    if bad == "offaxis":
        pts[0, 0] = 0.1
    with pytest.raises(ValueError):
        ClampedRodEnergy(rod, pts, np.inf if bad == "turns" else 0.0)


def test_repin_follows_the_shape_and_leaves_straight_rods_unpinned():
    """The pin is the larger azimuthal coordinate of the node farthest from the axis:
    its quality (rotation on the pin over the largest nodal rotation) is >= 1/sqrt(2)."""
    p, pts = make(n=30, pts=bent_rod(30, 0.1))
    q = pts.ravel()
    p.repin(q)
    assert p.gauge_dofs.size == 1 and p.pin_quality(q) >= 1 / np.sqrt(2) - 1e-12
    clamps = np.setdiff1d(p.fixed, p.gauge_dofs)
    assert clamps.size == 10
    node, coordinate = divmod(int(p.gauge_dofs[0]), 3)
    # the same shape turned by 90 degrees about the axis: same node, other coordinate
    x = pts.copy()
    x[:, 0], x[:, 1] = -pts[:, 1], pts[:, 0].copy()
    p.repin(x.ravel())
    assert divmod(int(p.gauge_dofs[0]), 3) == (node, 1 - coordinate)
    assert p.pin_quality(x.ravel()) >= 1 / np.sqrt(2) - 1e-12
    assert np.array_equal(np.setdiff1d(p.fixed, p.gauge_dofs), clamps)
    p.repin(straight_rod(30).ravel())
    assert p.gauge_dofs.size == 0 and p.pin_quality(straight_rod(30).ravel()) == 1.0
    assert np.array_equal(p.fixed, clamps)


def test_accept_after_a_jump_restores_twist_from_the_writhe():
    """Jumping straight to a far state rebuilds the frames: Tw = turns - Wr (double sum)."""
    p, _pts = make(n=60, pts=bent_rod(60, 0.02))
    for amp in (0.4, 0.05, 0.3):  # far apart: edges turn by more than 45 degrees
        q = bent_rod(60, amp).ravel()
        p.accept(q)
        wr = writhe(q.reshape(-1, 3), closure="axis")
        assert p.twist(q) + wr == pytest.approx(p.turns, abs=1e-10)


def looped_rod(n, gap):
    """A clamped rod with a planar loop in the x-z plane whose strands cross, over each
    other at ``gap > 0`` (along y) and under at ``gap < 0``."""
    pts = straight_rod(n)
    z = pts[:, 2]
    inside = (z > 0.3) & (z < 0.7)
    v = (z[inside] - 0.3) / 0.4
    pts[inside, 2] = 0.3 + 0.4 * (v + np.sin(2 * np.pi * v) / np.pi)  # backwards for a while
    pts[inside, 0] = 0.05 * (1 - np.cos(2 * np.pi * v))
    pts[inside, 1] = gap * np.sin(2 * np.pi * v) * np.sin(np.pi * v) ** 2
    return pts


def test_a_rod_with_self_contact_does_not_pass_through_itself():
    """Oracle: Fuller's closure turns = Tw + Wr. Moving one strand of a loop through the
    other changes the double-sum writhe by 2 while the twist carried by the frames moves
    continuously: the crossed state is refused, the phantom rod admits it."""
    p, _pts = make(n=200)
    over, under = (looped_rod(200, g).ravel() for g in (0.01, -0.01))
    # 2 from the crossing, less the continuous change of the strands' 0.02 L move
    assert abs(writhe(over.reshape(-1, 3), closure="axis") - writhe(
        under.reshape(-1, 3), closure="axis")) == pytest.approx(2.0, abs=0.1)
    p.accept(over)  # a jump from the straight rod: Tw = turns - Wr
    assert p.admissible(over) and p.admissible(under)  # a phantom rod by default
    p.impenetrable = True
    assert p.admissible(over)
    assert p.twist(over) + writhe(over.reshape(-1, 3), closure="axis") == pytest.approx(
        p.turns, abs=1e-10)
    assert not p.admissible(under)
    assert "passed through itself" in p.refusal
    # past a tail (a node beyond an end's plane) the closure cannot tell: admitted
    beyond = under.reshape(-1, 3).copy()
    beyond[100, 2] = -0.1
    assert p.admissible(beyond.ravel())
    # from a state whose closure is off by 2 (as after a pass through a tail), the
    # same closure is admitted and the crossing back refused
    p.accept(under)
    assert p.admissible(under) and not p.admissible(over)
