"""Stability of the twisted ring against Michell's exact thresholds, and Lk = Tw + Wr."""

import numpy as np
import pytest

from supercoil.problems.ring import (
    circle_energy,
    michell_excess_link,
    michell_threshold,
    richardson,
    solve_ring,
    twisted_circle_problem,
)
from supercoil.solvers.newton import least_squares_multipliers
from supercoil.solvers.problem import free_dofs
from supercoil.stability.analysis import analyse, eigen_system
from supercoil.stability.eigen import lowest_pairs


@pytest.mark.parametrize("twist_ratio,excess_link", [(2 / 3, 0.0), (2 / 3, 1.5), (1.0, 3.3),
                                                     (1.4, -2.0)])
def test_twisted_circle_energy_and_topology(twist_ratio, excess_link):
    r = solve_ring(twist_ratio, excess_link, n_nodes=80)
    assert r.converged
    # the "angle" curvature makes the regular polygon's bending energy exact
    assert r.energy == pytest.approx(circle_energy(twist_ratio, excess_link), rel=1e-12)
    assert abs(r.writhe) < 1e-12
    assert r.twist == pytest.approx(excess_link, abs=1e-12)
    assert r.link_error < 1e-9 and r.writhe_error < 1e-9


def test_unstable_count_rises_by_two_at_each_michell_threshold_and_determinant_misses_it():
    """Count 0 -> 2 -> 4 across (A/C)sqrt(3), (A/C)sqrt(8); det(Z^T H Z) keeps its sign."""
    ratio = 2 / 3
    rows = []
    for factor in (0.9, 1.1):
        for mode in (2, 3):
            dlk = factor * michell_excess_link(ratio, mode)
            rep = solve_ring(ratio, dlk, n_nodes=80)
            rows.append((mode, factor, rep.unstable_count, rep.determinant_sign))
    counts = {(m, f): c for m, f, c, _ in rows}
    assert counts[(2, 0.9)] == 0 and counts[(2, 1.1)] == 2
    assert counts[(3, 0.9)] == 2 and counts[(3, 1.1)] == 4
    assert {d for *_, d in rows} == {1}


def test_zero_modes_at_the_discrete_threshold():
    ratio, n = 1.0, 60
    crit = michell_threshold(ratio, n, mode=2, rtol=1e-12)
    rep = solve_ring(ratio, crit, n_nodes=n, zero_tolerance=1e-3)
    assert rep.zero_modes == 2
    assert rep.unstable_count == 0
    # and the pair is degenerate (the circle's rotational symmetry is removed, not broken)
    lo = np.sort(np.abs(rep.lowest_eigenvalues))[:2]
    assert np.all(lo < 1e-3)


def test_lanczos_eigenvalues_equal_dense_oracle():
    """Shift-invert Lanczos on the constrained pencil == dense null-space eigenproblem."""
    p, q = twisted_circle_problem(1.0, 1.5, 200)
    lam = least_squares_multipliers(p, q, free_dofs(p))
    dofs, H, J, mass, sym = eigen_system(p, q, lam)
    from supercoil.stability.eigen import dense_constrained_eigenpairs

    dense, _ = dense_constrained_eigenpairs(H, J, mass, sym)
    sparse_vals, _ = lowest_pairs(H, J, mass, n_wanted=8, n=dofs.size, m=J.shape[0],
                                  symmetry=sym, force_sparse=True)
    nearest = dense[np.argsort(np.abs(dense + 1e-3))[:8]]
    assert np.allclose(np.sort(sparse_vals), np.sort(nearest), rtol=1e-8, atol=1e-6)
    # below threshold all positive; mode-2 pair first and degenerate
    assert dense[0] > 0 and dense[1] == pytest.approx(dense[0], rel=1e-8)


def test_lanczos_that_does_not_converge_falls_back_on_the_dense_pairs(monkeypatch):
    """Where ARPACK gives up (``ArpackNoConvergence``), the pairs nearest the shift come
    from the dense reference: the same values as the converged Lanczos run gives (oracle),
    ascending, M-orthonormal vectors."""
    import scipy.sparse.linalg as spla

    p, q = twisted_circle_problem(1.0, 3.2, 200)  # past sqrt(8): four negative
    lam = least_squares_multipliers(p, q, free_dofs(p))
    dofs, H, J, mass, sym = eigen_system(p, q, lam)
    args = {"n_wanted": 6, "n": dofs.size, "m": J.shape[0], "symmetry": sym,
            "force_sparse": True, "sigma": -50.0}
    converged, _ = lowest_pairs(H, J, mass, **args)

    calls = []

    def gives_up(*_args, **_kwargs):
        calls.append(1)
        raise spla.ArpackNoConvergence("no convergence", np.zeros(0), np.zeros((0, 0)))

    monkeypatch.setattr(spla, "eigsh", gives_up)
    values, vectors = lowest_pairs(H, J, mass, **args)
    assert calls == [1]
    assert np.all(np.diff(values) >= 0)
    assert np.allclose(values, converged, rtol=1e-8, atol=1e-6)
    gram = vectors.T @ (mass[:, None] * vectors)
    assert np.allclose(gram, np.eye(values.size), atol=1e-8)


def test_analyse_matches_dense_count():
    p, q = twisted_circle_problem(1.0, 3.2, 40)
    lam = least_squares_multipliers(p, q, free_dofs(p))
    rep = analyse(p, q, lam)
    assert rep.unstable_count == 4  # past sqrt(8): modes 2 and 3 (pairs)
    assert np.sum(rep.lowest_eigenvalues < 0) == 4


@pytest.mark.parametrize("mode", [2, 3])
def test_michell_threshold_converges_with_order_two_and_richardson(mode):
    ratio = 1.0
    exact = michell_excess_link(ratio, mode)
    values = {n: michell_threshold(ratio, n, mode=mode, rtol=1e-11) for n in (50, 100, 200, 400)}
    errors = np.array([abs(values[n] - exact) / exact for n in (50, 100, 200, 400)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2.0) <= 0.2), (errors, orders)
    assert errors[1] <= 1e-2  # N = 100
    extrapolated = richardson(values[200], values[400])
    assert abs(extrapolated - exact) / exact <= 1e-4


def test_thresholds_scale_with_the_twist_ratio():
    """dLk_m = (A/C) sqrt(m^2 - 1): at C/A = 2/3 the mode-2 point is 1.5 sqrt(3)."""
    crit = michell_threshold(2 / 3, 100, mode=2)
    assert crit == pytest.approx(1.5 * np.sqrt(3), rel=1e-3)


def test_angle_curvature_beats_tangent_form_at_michell():
    """Why "angle" is the default: smaller error constant than Bergou's 2 tan(phi/2)."""
    exact = michell_excess_link(1.0, 2)
    err = {form: abs(michell_threshold(1.0, 100, mode=2, curvature=form) - exact) / exact
           for form in ("angle", "tan")}
    assert err["angle"] < 1e-3 < err["tan"]


@pytest.mark.parametrize("bad", [{"twist_ratio": 0.0, "excess_link": 1.0},
                                 {"twist_ratio": 1.0, "excess_link": np.nan},
                                 {"twist_ratio": -1.0, "excess_link": 1.0}])
def test_bad_ring_input_raises(bad):
    with pytest.raises(ValueError):
        solve_ring(**bad)


@pytest.mark.parametrize("n_nodes", [3000, 10000])
def test_inertia_stays_exact_on_fine_meshes(n_nodes):
    """Counts 0, 2, 4 on both sides of sqrt(3), sqrt(8) at N = 3000 and 10000.

    (A bounded look-ahead that finally divided by near-null pivots reported the
    stable circle as unstable from N ~ 2000 on.)
    """
    from supercoil.problems.ring import circle_negative_count

    for excess_link, expected in ((1.0, 0), (2.0, 2), (3.0, 4)):
        assert circle_negative_count(1.0, excess_link, n_nodes) == expected


def test_fine_mesh_ring_reports_round_off_limited_convergence_honestly():
    r = solve_ring(1.0, 1.0, n_nodes=3000)
    assert r.converged and r.unstable_count == 0 and r.stability_certified
    if r.residual > 1e-10:
        assert r.status.startswith("converged to the round-off floor")
        assert "round-off floor" in r.message


def test_under_resolved_twist_is_flagged():
    r = solve_ring(1.0, 30.0, n_nodes=50)
    assert "warning: modes up to m = 30" in r.message
    assert "warning" not in solve_ring(1.0, 3.0, n_nodes=50).message
