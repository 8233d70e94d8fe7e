"""Symmetry groups of closed curves (geometry.symmetry) against curves built with a known group.

Oracles: a circle is O(2); r(s) = 1 + a cos(m s) with z = b sin(m s) has D_m (an m-fold axis
along z, m reversing two-fold axes); perturbations that keep only a reversing axis (C_2), only
the m-fold axis (C_3) or nothing (C_1). Each curve is rotated at random and sampled from a
random starting point, so that no axis passes through a node.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from supercoil.geometry.symmetry import (
    curve_symmetry,
    cyclic_residual,
    cyclic_residuals,
    reversal_axes,
    shifted,
)

TOL = 1e-8


def sampled(radius, height, n=96, seed=0, phase=None):
    """The curve at ``n`` nodes from a random starting point (``phase``, in node spacings,
    if given: 0 puts the reversing axis of an even radius and odd height through node 0,
    1/2 through an edge midpoint), rotated and moved at random."""
    rng = np.random.default_rng(seed)
    start = rng.uniform() if phase is None else phase
    s = 2 * np.pi * (np.arange(n) + start) / n
    r = radius(s)
    x = np.stack([r * np.cos(s), r * np.sin(s), height(s)], axis=1)
    return Rotation.random(random_state=seed).apply(x) + rng.normal(size=3)


def test_shift_by_whole_nodes_is_a_roll_and_fractional_shifts_are_exact_for_trig_curves():
    x = sampled(lambda s: 1 + 0.2 * np.cos(3 * s), lambda s: 0.1 * np.sin(3 * s), n=48)
    np.testing.assert_allclose(shifted(x, 5.0), np.roll(x, -5, axis=0), atol=1e-12)
    s = 2 * np.pi * np.arange(48) / 48
    y = np.stack([np.cos(s), np.sin(2 * s), np.cos(3 * s)], axis=1)
    t = 2 * np.pi * 0.37 / 48
    exact = np.stack([np.cos(s + t), np.sin(2 * (s + t)), np.cos(3 * (s + t))], axis=1)
    np.testing.assert_allclose(shifted(y, 0.37), exact, atol=1e-12)


@pytest.mark.parametrize("radius, height, group, axes", [
    (lambda s: np.ones_like(s), lambda s: 0 * s, "O(2)", 0),
    (lambda s: 1 + 0.2 * np.cos(2 * s), lambda s: 0.15 * np.sin(2 * s), "D2", 2),
    (lambda s: 1 + 0.2 * np.cos(3 * s), lambda s: 0.15 * np.sin(3 * s), "D3", 3),
    (lambda s: 1 + 0.1 * np.cos(4 * s), lambda s: 0.1 * np.sin(4 * s), "D4", 4),
    # a cos 2s bump keeps the axis through s = 0 and breaks the three-fold one
    (lambda s: 1 + 0.2 * np.cos(3 * s) + 0.05 * np.cos(2 * s), lambda s: 0.15 * np.sin(3 * s),
     "C2", 1),
    # an even height breaks every reversing axis and keeps the three-fold one
    (lambda s: 1 + 0.2 * np.cos(3 * s), lambda s: 0.15 * np.sin(3 * s) + 0.05 * np.cos(3 * s),
     "C3", 0),
    (lambda s: 1 + 0.2 * np.cos(3 * s) + 0.05 * np.cos(2 * s) + 0.04 * np.sin(5 * s),
     lambda s: 0.15 * np.sin(3 * s) + 0.03 * np.cos(s), "C1", 0),
])
@pytest.mark.parametrize("seed", [0, 1])
def test_groups_of_curves_built_with_a_known_symmetry(radius, height, group, axes, seed):
    x = sampled(radius, height, seed=seed)
    result = curve_symmetry(x, TOL)
    assert result.group == group
    assert result.two_fold_axes == axes
    assert result.residual <= TOL


def test_reversal_axes_are_spaced_by_a_third_of_the_curve_for_d3():
    n = 90
    x = sampled(lambda s: 1 + 0.2 * np.cos(3 * s), lambda s: 0.15 * np.sin(3 * s), n=n, seed=3)
    cs = [c for c, _ in reversal_axes(x, TOL)]
    assert len(cs) == 3
    gaps = np.diff(sorted(cs + [min(cs) + n]))
    np.testing.assert_allclose(gaps, n / 3, atol=1e-4)


def test_a_broken_symmetry_has_a_residual_of_the_size_of_the_perturbation():
    for eps in (1e-2, 1e-3, 1e-4):
        x = sampled(lambda s, e=eps: 1 + 0.2 * np.cos(3 * s) + e * np.cos(2 * s),
                    lambda s: 0.15 * np.sin(3 * s))
        r = cyclic_residual(x, 3)
        assert 0.3 * eps < r < 3 * eps


def test_batched_cyclic_residuals_equal_the_single_ones():
    """curve_symmetry fits all orders at once: each value is the one computed alone (bit
    for bit here; round-off allowed, as batched kernels may take other SIMD paths)."""
    orders = np.array([1 / 0.3819660112501051, 6, 5, 4, 3, 2])
    for m, seed in ((2, 1), (3, 2), (5, 3)):
        x = sampled(lambda s, m=m: 1 + 0.2 * np.cos(m * s), lambda s, m=m: 0.1 * np.sin(m * s),
                    n=60, seed=seed)
        x = x + 1e-3 * np.random.default_rng(seed).normal(size=x.shape)  # and broken
        batched = cyclic_residuals(x, orders)
        np.testing.assert_allclose(batched, [cyclic_residual(x, k) for k in orders],
                                   rtol=1e-12, atol=1e-15)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="points"):
        curve_symmetry(np.zeros((3, 3)), 1e-6)
    with pytest.raises(ValueError, match="tolerance"):
        curve_symmetry(np.random.default_rng(0).normal(size=(10, 3)), 0.0)


def test_the_axis_invariant_combination_of_an_e_mode_keeps_that_axis():
    """A D_3 curve and the pair of radial modes cos 2s, sin 2s (an E representation of
    D_3): the combination axis_invariant_combination picks is mapped onto itself by the
    two-fold axis (exactly), while each mode alone is not; the other axes map it to
    different combinations (the three C_2 branches are images of each other)."""
    from supercoil.geometry.symmetry import (
        axis_invariant_combination,
        reversal_axes,
        reversal_image,
    )

    n = 48
    s = 2 * np.pi * np.arange(n) / n
    ripple = 1 + 0.1 * np.cos(3 * s)
    x = np.c_[np.cos(s) * ripple, np.sin(s) * ripple, 0.2 * np.sin(3 * s)]
    axes = reversal_axes(x, 1e-9)
    assert len(axes) == 3
    radial = np.c_[np.cos(s), np.sin(s), 0 * s]
    modes = np.stack([radial * np.cos(2 * s)[:, None], radial * np.sin(2 * s)[:, None]])
    for c, _ in axes:
        a = axis_invariant_combination(x, c, modes)
        v = np.tensordot(a, modes, 1)
        assert np.sum(v * v) == pytest.approx(1.0)
        np.testing.assert_allclose(reversal_image(x, c, v[None])[0], v, atol=1e-12)
    for mode in modes:
        image = reversal_image(x, axes[0][0], mode[None])[0]
        assert np.linalg.norm(image - mode) > 0.1 * np.linalg.norm(mode)
    a0 = axis_invariant_combination(x, axes[0][0], modes)
    a1 = axis_invariant_combination(x, axes[1][0], modes)
    assert abs(abs(a0 @ a1) / (np.linalg.norm(a0) * np.linalg.norm(a1)) - 1) > 0.1


@pytest.mark.parametrize("m, bump, height_bump", [
    (2, 0.0, 0.0), (3, 0.0, 0.0), (3, 0.05, 0.0), (4, 0.0, 0.0), (3, 0.05, 0.03)])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("n", [48, 97])
def test_reversal_axes_equal_the_half_node_scan_reference(m, bump, height_bump, seed, n):
    """reversal_axes (integer scan, pruned by the edge length, refined within a node)
    against reversal_axes_reference (half-node trigonometric scan, every local minimum
    refined): the same axes, to the refinement's tolerance, on curves with D_m, C_2 and
    no reversing axis, sampled from random phases (axes off the nodes) and with a loose
    tolerance as the ring diagram uses (0.05 D), so that near-misses are candidates too."""
    from symmetry_reference import reversal_axes_reference

    x = sampled(lambda s: 1 + 0.2 * np.cos(m * s) + bump * np.cos(2 * s),
                lambda s: 0.15 * np.sin(m * s) + height_bump * np.cos(s), n=n, seed=seed)
    for tolerance in (TOL, 1e-3):
        fast = reversal_axes(x, tolerance)
        reference = reversal_axes_reference(x, tolerance)
        assert len(fast) == len(reference), (fast, reference)
        for (c, r), (c_ref, r_ref) in zip(fast, reference):
            assert min(abs(c - c_ref), n - abs(c - c_ref)) < 1e-5
            assert abs(r - r_ref) < 1e-9


def test_the_integer_scan_by_fft_equals_the_permuted_copies():
    """integer_reversal_scan (covariances by FFT cross-correlation) against the residuals
    of the reversed curve's node permutations, each fitted by Kabsch (brute force)."""
    from supercoil.geometry.symmetry import fit_residuals, integer_reversal_scan

    for n, seed in ((48, 0), (97, 1), (200, 2)):
        x = sampled(lambda s: 1 + 0.2 * np.cos(3 * s) + 0.05 * np.cos(2 * s),
                    lambda s: 0.15 * np.sin(3 * s) + 0.03 * np.cos(s), n=n, seed=seed)
        index = (-(np.arange(n)[None, :] + np.arange(n)[:, None])) % n
        brute = fit_residuals(x, x[index])
        # both cancel sums of squares down to about sqrt(eps) of the curve's size
        np.testing.assert_allclose(integer_reversal_scan(x), brute, rtol=0, atol=1e-6)
        assert np.argmin(integer_reversal_scan(x)) == np.argmin(brute)


@pytest.mark.parametrize("m, bump, height_bump", [
    (2, 0.0, 0.0), (3, 0.0, 0.0), (3, 0.05, 0.0), (4, 0.0, 0.0), (3, 0.05, 0.03)])
@pytest.mark.parametrize("phase", [0.0, 0.5, None])
@pytest.mark.parametrize("n", [48, 97])
def test_axes_counted_without_refinement_are_the_refined_axes(m, bump, height_bump, phase, n):
    """reversal_axes(refine=False), which curve_symmetry uses, against the refined axes:
    as many, each within a third of a node of a refined one and within the tolerance;
    on curves whose axes pass through nodes (phase 0) or edge midpoints (1/2), the
    unrefined integer axes are taken (the fast path runs), off the mesh they are refined."""
    x = sampled(lambda s: 1 + 0.2 * np.cos(m * s) + bump * np.cos(2 * s),
                lambda s: 0.15 * np.sin(m * s) + height_bump * np.cos(s), n=n, seed=3,
                phase=phase)
    for tolerance in (TOL, 1e-3):
        refined = reversal_axes(x, tolerance)
        counted = reversal_axes(x, tolerance, refine=False)
        assert len(counted) == len(refined), (counted, refined)
        for c, r in counted:
            assert min(min(abs(c - a), n - abs(c - a)) for a, _ in refined) < 1 / 3
            assert r <= tolerance
        if phase is not None and counted:
            assert any(c == round(c) for c, _ in counted)
        if phase is None and tolerance == TOL:
            assert all(c != round(c) for c, _ in counted)
