"""Secondary branches of the ring diagram (Coleman & Swigon 2002, Figures 2 and 3).

Oracles: the primary branch of mode 3 has D_3 symmetry (Coleman & Swigon 2002; Domokos
1995); the branches switched from its bifurcation points have C_2 symmetry, a single
two-fold axis (Coleman & Swigon 2002, caption of Figure 3: "those on the secondary
branches beta_I - beta_IV have C_2 symmetry"); every switched branch passes the consistency checker (stored stability equal
to the recomputed inertia, special points between their neighbours, Lk = Tw + Wr, no
penetration) and starts at its origin.
"""

import numpy as np
import pytest

from supercoil.contact.problem import ContactProblem
from supercoil.continuation import consistency_check
from supercoil.problems.ring_branches import twisted_circle_problem
from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
from supercoil.problems.ring_diagram.secondary import AMPLITUDES, roman, secondary_branches

# The integral contact on the B-spline: the pair sum's beta_contact leaves D_3 at N = 96,
# so its secondary branches depend on the mesh.
OPTIONS = DiagramOptions(2 / 3, 40.0, n_nodes=48, modes=(3,), max_excess_link=3.0,
                         free_max_points=60, contact_max_points=80, branch_depth=2,
                         secondary_max_points=20, contact_formulation="integral",
                         contact_curve="spline")


@pytest.fixture(scope="module")
def diagram():
    return ring_diagram(OPTIONS)


def _secondary(diagram):
    return [b for b in diagram.branches if diagram.generation(b) == 2]


def test_secondary_branches_start_at_a_bifurcation_point_of_beta(diagram):
    secondary = _secondary(diagram)
    assert secondary, diagram.notes
    for b in secondary:
        assert b.name.startswith("beta_I")
        assert b.parent in ("beta", "beta_contact")
        assert b.origin.kind == "bifurcation" and b.origin.branch == b.parent
        assert b.name in diagram.contact_branches
        # the first point lies on the hyperplane one switching amplitude (AMPLITUDES, in
        # units of D) from the origin along the critical mode: its distance in the
        # arclength metric is at least that amplitude and of its size
        base, _ = twisted_circle_problem(OPTIONS.twist_ratio, 0.0, OPTIONS.n_nodes, "angle")
        dq = b.states[0] - b.origin.q
        dlk = b.parameter_values[0] - b.origin.parameter
        distance = np.sqrt(np.sum(base.mass * dq**2) + (OPTIONS.diameter * dlk) ** 2)
        assert any(a * OPTIONS.diameter * (1 - 1e-6) <= distance <= 3 * a * OPTIONS.diameter
                   for a in AMPLITUDES), distance


def test_beta_bifurcates_at_its_three_point_contact_onset_and_is_stable_after_it(diagram):
    """Coleman & Swigon 2002, Figure 2: B_1, where beta's three points of contact appear,
    is a bifurcation point of beta, and beta is stable from B_1 on (the heavy interval
    from B_1 to P). In the barrier model the E mode of D_3 (a double eigenvalue) crosses
    zero just past the onset: one event, count 2 -> 0, two critical modes. The secondary
    branches that start there are unstable (Coleman & Swigon 2002: no configuration on
    them is)."""
    beta = diagram.branch("beta_contact")
    (onset,) = [p for p in beta.points_of_kind("contact_onset")]
    (b1,) = beta.points_of_kind("bifurcation")
    assert (b1.count_before, b1.count_after) == (2, 0)
    assert b1.critical_modes.shape[0] == 2
    values = np.sort(np.abs(b1.critical_eigenvalues))
    assert values[1] - values[0] <= 0.1 * values.mean()  # a (split) double eigenvalue
    assert abs(b1.parameter - onset.parameter) < 2e-3
    assert b1.label == "bifurcation at contact_onset (within the barrier's reach)"
    assert onset.label.endswith("points 0->3, intervals 0->0")
    after = beta.arclength > b1.arclength
    assert np.all(beta.unstable_count[after] == 0)
    assert beta.parameter_values[-1] == pytest.approx(OPTIONS.max_excess_link)
    secondary = _secondary(diagram)
    assert {b.origin.parameter for b in secondary} == {b1.parameter}
    for b in secondary:
        assert np.all(b.unstable_count >= 1), (b.name, b.unstable_count)


def test_primary_is_d3_and_secondary_branches_are_c2(diagram):
    points = diagram.points()
    beta = [p["symmetry"] for p in points if p["branch"] == "beta"]
    assert beta[0] in ("O(2)", "D3") and set(beta[1:]) == {"D3"}
    for b in _secondary(diagram):
        groups = [p["symmetry"] for p in points if p["branch"] == b.name]
        # C2 once the branch has left its origin by more than the symmetry tolerance
        # (0.05 D); closer to it a point may still be labelled like its D3 parent
        first_c2 = groups.index("C2")
        assert set(groups[:first_c2]) <= {"D3"} and set(groups[first_c2:]) == {"C2"}, (
            b.name, groups)
        assert first_c2 <= len(groups) // 2, (b.name, groups)  # C2 on most of the branch


def test_secondary_branches_are_consistent(diagram):
    base, _ = twisted_circle_problem(OPTIONS.twist_ratio, 0.0, OPTIONS.n_nodes, "angle")
    cp = ContactProblem(base, OPTIONS.contact_options(OPTIONS.diameter))
    for b in _secondary(diagram):
        report = consistency_check(b, cp, residual_tolerance=1e-8,
                                   pin=lambda i, s, b=b: diagram.pin_branch(b.name, i, s, cp))
        # as for the contact branches (test_ring_diagram): the KKT residual holds the
        # sliding gauge's force, recorded per point as sliding_residual
        problems = [p for p in report.problems if "KKT residual" not in p]
        assert not problems, (b.name, problems)
        assert np.max(b.records["link_error"]) < 1e-9
        assert np.min(b.records["min_gap_over_diameter"]) > 1.0 - 1e-4


def test_payload_names_generations(diagram):
    payload = diagram.payload()
    generation = {b["name"]: b["generation"] for b in payload["branches"]}
    assert generation["circle"] == 0
    assert generation["beta"] == generation["beta_contact"] == 1
    assert all(generation[b.name] == 2 for b in _secondary(diagram))
    point = payload["points"][0]
    assert point["symmetry"] == "O(2)" and point["symmetry_residual_over_diameter"] < 0.05


def test_depth_one_adds_nothing_and_bad_depths_are_refused(diagram):
    primary_only = [b for b in diagram.branches if diagram.generation(b) < 2]
    assert len(primary_only) == 3
    assert secondary_branches(diagram, depth=1) is diagram
    with pytest.raises(ValueError, match="branch_depth"):
        DiagramOptions(2 / 3, 40.0, branch_depth=4)
    with pytest.raises(ValueError, match="depth"):
        secondary_branches(diagram, depth=0)
    assert [roman(k) for k in (1, 2, 3, 4, 9, 14)] == ["I", "II", "III", "IV", "IX", "XIV"]


def test_beta_keeps_d3_at_n40_with_either_gauge():
    """N = 40 is not a multiple of 3, so no node pin is symmetric; the beta branch
    stays D_3 all the same with the integral phase condition and with a pinned node,
    and its contact onset agrees with N = 48 (a multiple of 3).

    With the central difference of the residual in the excess link (before the
    analytic ``ClosedRodEnergy.parameter_derivative``) the node-pinned branch left
    D_3 (0.63 D) and reached contact at dLk 1.877 instead of 1.788: the difference's
    noise, not the pin's asymmetric reaction (measured 5e-6 D, as the integral
    gauge's), broke the symmetry.
    """
    from supercoil.geometry.symmetry import cyclic_residual

    def beta(n, gauge):
        opts = DiagramOptions(2 / 3, 40.0, n_nodes=n, modes=(3,), max_excess_link=3.0,
                              free_max_points=60, contact_max_points=2, gauge=gauge)
        return ring_diagram(opts).branch("beta")

    def worst_three_fold(branch):
        wr = branch.records["writhe"]
        return max(cyclic_residual(q.reshape(-1, 3), 3) for q, w in zip(branch.states, wr)
                   if w < 1.5) / OPTIONS.diameter

    onset = {}
    for n, gauge in ((48, "node"), (40, "integral"), (40, "node")):
        branch = beta(n, gauge)
        onset[n, gauge] = branch.points_of_kind("contact_onset")[0].parameter
        if n == 40:
            assert worst_three_fold(branch) < 0.05
    assert abs(onset[40, "integral"] - onset[48, "node"]) < 0.01
    assert abs(onset[40, "node"] - onset[48, "node"]) < 0.01


def test_secondary_branches_are_dashed_in_the_diagram_and_in_supercoil_plot(diagram, tmp_path,
                                                                           capsys):
    """diagram.json keeps each branch's generation; the figures draw generation 2 dashed
    (Coleman & Swigon 2002, Figure 2) both when written and when redrawn from the file."""
    from supercoil.cli.diagram_output import write_diagram
    from supercoil.cli.saving import open_writer
    from supercoil.plotting.figures import branch_rows
    from supercoil.plotting.result_data import load_result
    from supercoil.plotting.style import GENERATION_STYLES

    writer = open_writer(tmp_path, resume=False, problem="ring_diagram", settings={})
    write_diagram(diagram, tmp_path, OPTIONS.contact, writer)
    rows = {r["name"]: r for r in branch_rows(load_result(tmp_path / "diagram.json"),
                                                ("writhe", "excess_link"))}
    assert rows["beta"]["linestyle"] == "-" and rows["circle"]["linestyle"] == "-"
    for b in _secondary(diagram):
        assert rows[b.name]["linestyle"] == GENERATION_STYLES[2] != "-"


DNA_OPTIONS = DiagramOptions(2 / 3, 122.0, n_nodes=132, modes=(3,), max_excess_link=6.0,
                              contact_max_points=150)


@pytest.fixture(scope="module")
def dna_diagram():
    """Coleman & Swigon's DNA example (C/A = 2/3, L/D = 122), beta only, N = 132 (a
    multiple of 6: D_3's axes through nodes)."""
    return ring_diagram(DNA_OPTIONS)


def test_beta_at_the_dna_parameters_is_stable_from_b1_to_p(dna_diagram):
    """Coleman & Swigon 2002, Figure 2 (C/A = 2/3, L/D = 122): "condition theta holds
    only for the configurations in the heavily drawn interval of branch beta that runs from the
    bifurcation point B_1 to the bifurcation point P". Oracle: on beta_contact (N = 132,
    a multiple of 3) the unstable count is 0 exactly between two located bifurcation
    points, B_1 at the three-point contact onset (count 2 -> 0) and P (0 -> 2), both
    through a double eigenvalue (an E mode of D_3), and beta keeps D_3 throughout (the
    integral phase condition's reaction has no net torque: sliding_phase_modes)."""
    diagram = dna_diagram
    beta = diagram.branch("beta_contact")
    # measured with these options: the fold at the contact (count 3 -> 2) and B_1 lie in
    # one segment; the fold's own count change is not reported as a bifurcation
    b1, p = beta.points_of_kind("bifurcation")
    assert (b1.count_before, b1.count_after, p.count_before, p.count_after) == (2, 0, 0, 2)
    for point in (b1, p):
        # a double eigenvalue: the two agree to 1e-3 of how far the nearest eigenvalue
        # moves across the located segment (at a point located close to the crossing both
        # are near zero, and their relative difference means nothing)
        values = point.critical_eigenvalues
        i = point.index
        scale = max(abs(beta.nearest_eigenvalue[i]), abs(beta.nearest_eigenvalue[i + 1]))
        assert values.size == 2 and abs(values[1] - values[0]) <= 1e-3 * scale
    (onset,) = beta.points_of_kind("contact_onset")
    assert abs(b1.parameter - onset.parameter) < 1e-3 and 5.0 < p.parameter < 5.2
    between = (beta.arclength > b1.arclength) & (beta.arclength < p.arclength)
    assert between.sum() > 10 and np.all(beta.unstable_count[between] == 0)
    assert np.all(beta.unstable_count[beta.arclength > p.arclength] >= 2)
    points = [q for q in diagram.points() if q["branch"] == "beta_contact"]
    assert {q["symmetry"] for q in points} == {"D3"}


def test_a_switch_that_keeps_the_parents_symmetry_fell_back():
    """secondary.fell_back: after a switch at a double eigenvalue (two critical modes)
    a branch whose every point keeps the D_3 of the bifurcation point (or has the circle's
    O(2)) is the parent's family; one C_2 point makes it new; a simple eigenvalue is never
    judged (its branch may keep the symmetry)."""
    from types import SimpleNamespace

    from supercoil.problems.ring_diagram.secondary import fell_back

    n = 48
    s = 2 * np.pi * np.arange(n) / n

    def curve(three, two):
        r = 1 + three * np.cos(3 * s) + two * np.cos(2 * s)
        return np.c_[np.cos(s) * r, np.sin(s) * r, three * 2 * np.sin(3 * s)].ravel() / (2 * np.pi)

    point = SimpleNamespace(q=curve(0.1, 0.0), critical_modes=np.zeros((2, 3 * n)))
    d3 = [curve(0.1 + 0.01 * k, 0.0) for k in range(4)]
    diameter = 0.02
    assert fell_back(SimpleNamespace(states=np.array(d3 + [curve(0.0, 0.0)])), point, diameter)
    assert not fell_back(SimpleNamespace(states=np.array(d3 + [curve(0.1, 0.05)])), point,
                         diameter)
    simple = SimpleNamespace(q=point.q, critical_modes=np.zeros((1, 3 * n)))
    assert not fell_back(SimpleNamespace(states=np.array(d3)), simple, diameter)


def _half_turn_image(points: np.ndarray, axis_node_0: np.ndarray) -> np.ndarray:
    """``x_i -> R x_{-i}``, ``R`` the half-turn about the line along x through the point
    ``axis_node_0`` (node 0 of a state symmetric about that line), ``(n, 3)``."""
    n = points.shape[0]
    image = points[(-np.arange(n)) % n].copy()
    image[:, 1:] = 2 * axis_node_0[1:] - image[:, 1:]
    return image


def test_a_tertiary_branch_breaks_the_two_fold_axis_of_beta_ii(dna_diagram):
    """Coleman & Swigon 2002, Figures 2 and 3: beta_II, the secondary branch from P, has
    C_2 symmetry and a bifurcation point S from which the tertiary branch beta*_II issues with no
    symmetry left. Oracles: the secondary states keep the axis through node 0 to
    round-off (the discrete problem is equivariant: on_mesh_direction, rigid_pins);
    S is a located change of the count by one whose single critical mode is odd under
    that axis (a pitchfork: secondary.mirror_axis); the tertiary half-branches
    on the two sides of S leave the symmetry (C_1 beyond the symmetry tolerance) and
    are each other's images under the axis, point by point (which is why
    secondary_branches computes one of them)."""
    from supercoil.geometry.symmetry import reversal_residuals
    from supercoil.problems.ring_diagram.secondary import follow_bifurcating_branch, mirror_axis

    beta = dna_diagram.branch("beta_contact")
    p = beta.points_of_kind("bifurcation")[-1]
    assert 5.0 < p.parameter < 5.3 and p.critical_modes.shape[0] == 2
    found = []
    # S lies between points 33 and 34 of the side +1 half-branch (the points beyond it,
    # up to a second such bifurcation at point 46, are the costliest to compute)
    for side, points in ((1, 36), (-1, 48)):
        half = follow_bifurcating_branch(dna_diagram, beta, p, side, max_points=points)
        assert half is not None and len(half) >= 2
        for q in half.states:
            assert reversal_residuals(q.reshape(-1, 3), [0.0], direct=True)[0] < 1e-9
        found += [(half, point) for point in half.points_of_kind("bifurcation")
                  if mirror_axis(point) == 0]
    assert found, "no symmetry-breaking bifurcation on beta_II"
    secondary, s = found[0]
    assert abs(s.count_after - s.count_before) == 1 and s.critical_modes.shape[0] == 1
    assert s.located and p.parameter < s.parameter < 6.0
    axis = np.asarray(s.q).reshape(-1, 3)[0]
    plus = follow_bifurcating_branch(dna_diagram, secondary, s, 1, max_points=12)
    minus = follow_bifurcating_branch(dna_diagram, secondary, s, -1, max_points=12)
    assert len(plus) == len(minus) == 12
    # to the located S's own asymmetry (its image misfits by about 2e-7; measured: the
    # halves agree to 4e-7 in dLk and 1e-6 of the size in the states)
    np.testing.assert_allclose(minus.parameter_values, plus.parameter_values, rtol=0,
                               atol=1e-5)
    size = np.ptp(plus.states[0].reshape(-1, 3), axis=0).max()
    for a, b in zip(plus.states, minus.states):
        image = _half_turn_image(a.reshape(-1, 3), axis)
        assert np.max(np.abs(image - b.reshape(-1, 3))) < 1e-5 * size
    tolerance = 0.05 * DNA_OPTIONS.diameter
    from supercoil.geometry.symmetry import curve_symmetry

    groups = [curve_symmetry(q.reshape(-1, 3), tolerance).group for q in plus.states]
    assert groups[-1] == "C1", groups
    assert reversal_residuals(plus.states[-1].reshape(-1, 3), [0.0], direct=True)[0] > tolerance
    # the consistency checker on the tertiary half-branch (the KKT residual holds the
    # sliding gauge's force: without an axis on the mesh the contact pushes the material)
    report = consistency_check(plus, dna_diagram.contact_problem, residual_tolerance=1e-8)
    assert not [q for q in report.problems if "KKT residual" not in q], report.problems
    assert np.max(plus.records["link_error"]) < 1e-9
    assert np.min(plus.records["min_gap_over_diameter"]) > 1.0 - 1e-4
