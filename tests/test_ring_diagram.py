"""The ring's bifurcation diagram with self-contact.

Oracles: Lk = Tw + Wr at every point (twist from the material frames, writhe
from the double sum); no penetration on contact branches (barrier); the alpha
branch's first special point is the geometric contact onset, where the
closest approach of non-neighbouring points is D; special points lie between
their neighbours and stored stability equals the recomputed inertia
(consistency_check); the JSON carries the keys of docs/model.md; the CLI refuses bad
input with exit status 2 and one line.
"""

import dataclasses
import json

import numpy as np
import pytest

from supercoil.cli.main import run
from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.continuation import consistency_check
from supercoil.io.store import load, save
from supercoil.problems.ring_branches import twisted_circle_problem
from supercoil.problems.ring_diagram import DiagramOptions, parse_modes, ring_diagram

POINT_KEYS = ("branch", "excess_link", "writhe", "twist", "energy", "unstable_count",
              "zero_modes", "contact_points", "contact_intervals", "n_contact_points",
              "n_contact_intervals", "min_gap_over_diameter")
OPTIONS = DiagramOptions(2 / 3, 40.0, n_nodes=48, modes=(2,), max_excess_link=2.0,
                         free_max_points=60, contact_max_points=40)


@pytest.fixture(scope="module")
def diagram():
    return ring_diagram(OPTIONS)


def test_branches_and_contact_onset(diagram):
    names = [b.name for b in diagram.branches]
    assert names == ["circle", "alpha", "alpha_contact"], diagram.notes
    alpha = diagram.branch("alpha")
    first = alpha.special_points[0]
    assert first.kind == "contact_onset"
    # at the located onset the closest approach is D, within the event tolerance
    probe = ContactProblem(_problem(), OPTIONS.contact_options(OPTIONS.diameter))
    gap = probe.min_distance(first.q) / OPTIONS.diameter
    slope = abs(alpha.records["min_gap_over_diameter"][first.index + 1]
                - alpha.records["min_gap_over_diameter"][first.index]) / (
        alpha.arclength[first.index + 1] - alpha.arclength[first.index])
    assert abs(gap - 1.0) <= 10 * slope * OPTIONS.event_tolerance + 1e-9
    # the contact-free run ended at the first point past its onset, which is kept
    assert first.index + 2 == len(alpha)
    assert alpha.message.endswith("the contact onset is located")
    # no strand passage on the way: Tw + Wr = dLk at every point (Wr from the double sum)
    np.testing.assert_allclose(alpha.records["twist"] + alpha.records["writhe"],
                               alpha.parameter_values, rtol=0, atol=1e-8)
    # the contact branch starts at the last contact-free point before the onset
    # that the barrier does not reach yet (closest approach above 1.01 D)
    contact = diagram.branch("alpha_contact")
    assert contact.parent == "alpha" and contact.origin.kind == "contact_onset"
    gaps = alpha.records["min_gap_over_diameter"][: first.index + 1]
    k = int(np.flatnonzero(gaps > 1.01)[-1])
    assert np.allclose(contact.states[0], alpha.states[k], atol=1e-6)


def _problem():
    problem, _ = twisted_circle_problem(OPTIONS.twist_ratio, 0.0, OPTIONS.n_nodes, "angle")
    return problem


def test_link_equals_twist_plus_writhe_everywhere(diagram):
    for b in diagram.branches:
        lk = b.records["twist"] + b.records["writhe"]
        assert np.allclose(lk, b.parameter_values, atol=1e-8), b.name


def test_contact_branch_never_penetrates_and_gains_a_contact(diagram):
    contact = diagram.branch("alpha_contact")
    assert len(contact) >= 10
    assert np.all(contact.records["min_gap_over_diameter"] >= 1.0 - 1e-9)
    assert np.max(contact.records["n_contact_points"]
                  + contact.records["n_contact_intervals"]) >= 1
    kinds = {p.kind for p in contact.special_points}
    assert "contact_onset" in kinds
    # with contact the subcritical alpha branch turns back up (a fold at the contact)
    assert contact.parameter_values.max() > contact.parameter_values[0]


def test_branches_are_consistent(diagram):
    """Stored stability = recomputed inertia, special points between their neighbours.

    Contact branches: the KKT residual is left to the xfail test below, and a
    contact event next to the fold at the contact may lie a hair beyond the
    points' parameter range (it is located between its neighbours in arclength).
    """
    base = _problem()
    cp = ContactProblem(base, OPTIONS.contact_options(OPTIONS.diameter))
    for b in diagram.branches:
        contact = b.name in diagram.contact_branches
        report = consistency_check(b, cp if contact else base, residual_tolerance=1e-8,
                                   pin=lambda i, seg, b=b: diagram.pin_branch(b.name, i, seg, cp))
        problems = [p for p in report.problems if not contact or (
            "KKT residual" not in p and "outside the branch's parameter range" not in p)]
        assert not problems, (b.name, problems)


def test_sliding_residual_is_the_unpinned_kkt_residual(diagram):
    """The record is the residual without the gauge, recomputed by the extended system;
    before the first contact the pinned states are equilibria of the unpinned problem."""
    from supercoil.continuation.system import ExtendedSystem

    contact = diagram.branch("alpha_contact")
    cp = ContactProblem(_problem(), OPTIONS.contact_options(OPTIONS.diameter))
    for i in range(len(contact)):
        # the rigid pins point i was computed with (RingDiagram.pins)
        diagram.pin_branch("alpha_contact", i, False, cp)
        cp.accept(contact.states[i])
        system = ExtendedSystem(cp, "excess_link", contact.states[i])
        x = system.pack(contact.states[i], contact.multipliers[i], contact.parameter_values[i])
        residual = float(np.max(np.abs(system.residual(x))))
        assert contact.records["sliding_residual"][i] == pytest.approx(residual, rel=1e-6,
                                                                       abs=1e-12)
    free = (contact.records["n_contact_points"] + contact.records["n_contact_intervals"]) == 0
    assert free[0] and np.all(contact.records["sliding_residual"][free] < 1e-8)


def test_contact_branch_states_are_equilibria_without_the_gauge(diagram):
    """The primary branch is switched off the circle with a two-fold axis through node 0
    and followed with pins the half-turn about that axis maps onto themselves
    (rod.closed.rigid_pins), so every state keeps the axis exactly; the sliding mode
    is odd under it and the energy gradient even, so the discrete contact cannot push
    the material along the rod, and the states are equilibria without the gauge
    (before the axis was on the mesh, the sliding force was up to 5e-3 here).
    Oracles: the symmetry to round-off, and the KKT residual without the gauge."""
    from supercoil.geometry.symmetry import reversal_residuals

    contact = diagram.branch("alpha_contact")
    for q in contact.states:
        assert reversal_residuals(q.reshape(-1, 3), [0.0], direct=True)[0] < 1e-9
    base = _problem()
    cp = ContactProblem(base, OPTIONS.contact_options(OPTIONS.diameter))
    report = consistency_check(contact, cp, residual_tolerance=1e-6,
                               pin=lambda i, s: diagram.pin_branch("alpha_contact", i, s, cp))
    assert not [p for p in report.problems if "KKT residual" in p]


def test_stable_points_satisfy_condition_e(diagram):
    """Coleman & Swigon 2000 (condition E): a stable configuration of a family with
    dLk a function of Wr needs d(dLk)/d(Wr) >= 0 ("condition E"). Off the circle,
    every point with unstable_count 0 must have condition_e >= 0; and condition E
    must fail somewhere (the subcritical alpha branch has dLk falling as Wr grows)."""
    points = [p for p in diagram.payload()["points"] if p["branch"] != "circle"]
    assert all(p["condition_e"] >= 0 for p in points if p["unstable_count"] == 0)
    assert any(p["condition_e"] < 0 for p in points if p["branch"] == "alpha")


def test_payload_keys_and_branch_files(diagram, tmp_path):
    payload = diagram.payload()
    for point in payload["points"]:
        assert set(POINT_KEYS) <= set(point)
    for b in payload["branches"]:
        assert {"name", "parent", "origin"} <= set(b)
    for p in payload["special_points"]:
        assert {"kind", "branch", "excess_link", "writhe"} <= set(p)
    assert (payload["contact_formulation"], payload["contact_curve"], payload["sliding_gauge"],
            payload["contact_predictor"]) == ("integral", "spline", "integral", "quadratic")
    pins = payload["rigid_pins"]["alpha_contact"]
    assert pins[0]["from_point"] == 0 and len(pins[0]["dofs"]) == 6
    assert [tuple(p["dofs"]) for p in pins] == [d for _, d in diagram.pins["alpha_contact"]]
    json.dumps(payload["rigid_pins"])  # plain data
    contact = diagram.branch("alpha_contact")
    save(tmp_path / "c.h5", [contact])
    loaded = load(tmp_path / "c.h5").branch("alpha_contact")
    assert np.array_equal(loaded.states, contact.states)
    assert [p.kind for p in loaded.special_points] == [p.kind for p in contact.special_points]


def test_cli_writes_the_diagram(tmp_path, capsys):
    out = tmp_path / "d"
    status = run(["diagram", "ring", "--twist-ratio", str(2 / 3), "--length-over-diameter",
                  "40", "--nodes", "40", "--modes", "2", "--max-excess-link", "1.5",
                  "--out", str(out)])
    data = json.loads((out / "diagram.json").read_text())
    assert status == (0 if data["ok"] else 1)
    for key in ("schema_version", "units", "conventions", "provenance", "points",
                "branches", "special_points"):
        assert key in data
    for name in ("link_writhe.png", "contact_map.png", "configurations.png"):
        assert (out / name).stat().st_size > 1000
    stored = load(out)
    for b in data["branches"]:
        assert b["file"] == "result.h5" and len(stored.branch(b["name"])) == b["n_points"]
    assert stored.summary == data and stored.status == ("complete" if data["ok"]
                                                          else "incomplete")
    assert sorted(p.name for p in out.iterdir()) == [
        "configurations.png", "contact_map.png", "diagram.json", "link_writhe.png",
        "result.h5"]  # no journal or temporary file left


def test_cli_interrupt_keeps_every_point_computed(tmp_path, capsys, monkeypatch):
    """Ctrl-C during alpha: the circle (final) and alpha up to its last computed point
    (the one the interrupt came at) are kept in result.h5; exit 1, one line naming
    them and how to continue; no diagram.json."""
    import supercoil
    from supercoil.problems import ring_diagram as rd

    original = rd.ring_diagram
    last = {}

    def interrupted(options, progress=None, *, on_point=None, on_branch=None, resume=None):
        count = [0]

        def point(branch):
            on_point(branch)
            last[branch.name] = branch
            count[0] += 1
            if count[0] == 15:
                raise KeyboardInterrupt

        return original(options, progress, on_point=point, on_branch=on_branch)

    monkeypatch.setattr(rd, "ring_diagram", interrupted)
    out = tmp_path / "d"
    status = run(["diagram", "ring", "--twist-ratio", str(2 / 3), "--length-over-diameter",
                  "40", "--nodes", "40", "--modes", "2", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1 and err[-1].startswith("interrupted: kept circle (") and \
        "--resume" in err[-1]
    result = supercoil.load(out)
    assert result.status == "interrupted" and result.complete_branches == {"circle"}
    alpha = result.branch("alpha")
    assert len(alpha) == len(last["alpha"])
    assert np.array_equal(alpha.parameter_values, last["alpha"].parameter_values)
    assert np.allclose(alpha.records["twist"] + alpha.records["writhe"],
                       alpha.parameter_values, atol=1e-8)
    assert len(result.branch("circle")) > 2
    assert not (out / "diagram.json").exists()


@pytest.mark.parametrize("args, words", [
    (["--length-over-diameter", "3"], "above pi"),
    (["--modes", "1"], "--modes"),
    (["--modes", "alpha"], "--modes"),
    (["--contact-max-points", "1"], "--contact-max-points"),
    (["--branch-depth", "4"], "--branch-depth"),
    (["--secondary-max-points", "1"], "--secondary-max-points"),
    (["--secondary-max-branches", "-1"], "--secondary-max-branches"),
])
def test_cli_refuses_bad_input(tmp_path, capsys, args, words):
    base = {"--twist-ratio": "1", "--length-over-diameter": "100", "--modes": "2",
            "--out": str(tmp_path / "x")}
    for flag, value in zip(args[::2], args[1::2]):
        base[flag] = value
    argv = ["diagram", "ring"] + [w for kv in base.items() for w in kv]
    assert run(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and words in err and "\n" not in err


def test_cli_refuses_existing_folder(tmp_path, capsys):
    (tmp_path / "keep.txt").write_text("x")
    argv = ["diagram", "ring", "--twist-ratio", "1", "--length-over-diameter", "100",
            "--out", str(tmp_path)]
    assert run(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "--overwrite" in err and "\n" not in err


def test_options_validate():
    with pytest.raises(ValueError):
        DiagramOptions(2 / 3, 3.0)
    with pytest.raises(ValueError):
        DiagramOptions(2 / 3, 100.0, contact="exact")
    assert parse_modes("3,2") == (2, 3)
    with pytest.raises(ValueError):
        parse_modes("1")


def test_link_writhe_lines_are_stable_up_to_the_located_bifurcation(diagram):
    """The figure's circle is heavy up to Michell's point (located), not to the last
    stable sample before it: the special point enters the polyline twice."""
    from supercoil.plotting.figures import through_special_points

    payload = diagram.payload()
    rows = [p for p in payload["points"] if p["branch"] == "circle"]
    line = {"name": "circle", "writhe": [r["writhe"] for r in rows],
            "excess_link": [r["excess_link"] for r in rows],
            "stable": [r["stable"] for r in rows]}
    specials = [p for p in payload["special_points"] if p["branch"] == "circle"]
    out = through_special_points(line, specials, ("writhe", "excess_link"))
    dlk, stable = np.array(out["excess_link"]), np.array(out["stable"])
    michell = 1.5 * np.sqrt(3)
    last_stable = dlk[stable].max()
    assert last_stable == pytest.approx(michell, rel=2e-2)
    assert last_stable > max(r["excess_link"] for r in rows if r["stable"])
    assert np.all(np.diff(dlk) >= 0) and len(dlk) == len(rows) + 2 * len(specials)


def test_sparse_constrained_eigenvalues_equal_the_dense_oracle_with_contact(diagram):
    """On a contact state the material sliding is not an eigenvector, so removing it
    must be a constraint (as in the dense null-space oracle), not a projection."""
    from supercoil.stability.analysis import eigen_system
    from supercoil.stability.eigen import dense_constrained_eigenpairs, lowest_pairs

    contact = diagram.branch("alpha_contact")
    i = len(contact) - 1
    cp = ContactProblem(_problem(), OPTIONS.contact_options(OPTIONS.diameter))
    cp.accept(contact.states[i])
    dofs, H, J, mass, sym = eigen_system(cp.at(excess_link=float(contact.parameter_values[i])),
                                         contact.states[i], contact.multipliers[i])
    assert sym.shape[1] == 7  # six rigid motions and the material sliding
    dense, _ = dense_constrained_eigenpairs(H, J, mass, sym)
    sparse, vectors = lowest_pairs(H, J, mass, n_wanted=5, n=dofs.size, m=J.shape[0],
                                   symmetry=sym, force_sparse=True)
    nearest = dense[np.argsort(np.abs(dense + 1e-3))[:5]]
    # the barrier's stiffness leaves both at about 1e-7 relative (measured); the
    # projection this replaced was 7e-3 off
    assert np.allclose(np.sort(sparse), np.sort(nearest), rtol=1e-6, atol=1e-6)
    # the modes satisfy the constraints and are M-orthogonal to the symmetries, to
    # the accuracy of the stiff KKT solves (measured 7e-6 with the barrier engaged)
    assert np.max(np.abs(J @ vectors)) < 1e-4 * np.max(np.abs(vectors))
    assert np.max(np.abs(sym.T @ (mass[:, None] * vectors))) < 1e-4


def test_contact_events_are_classified_from_the_counts_on_either_side(diagram, monkeypatch):
    """Hand-made transitions between neighbouring points -> the kinds of docs/model.md.

    Counts (points, intervals) at six points: (1, 0) -> (2, 0) split (the new
    contacts lie next to the old one), -> (2, 1) interval onset, -> (1, 1) release,
    -> (2, 1) onset (a contact far from the others), -> (0, 0) release. Both
    indicators of one transition located at the same place merge into one point.
    """
    import dataclasses

    from supercoil.continuation import SpecialPoint
    from supercoil.problems import contact_events

    base = diagram.branch("alpha_contact")
    k = 6
    arrays = {name: getattr(base, name)[:k] for name in (
        "parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
        "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")}
    points = np.array([1, 2, 2, 1, 2, 0])
    intervals = np.array([0, 0, 1, 1, 1, 0])
    positions = [[(0.2, 0.6)], [(0.19, 0.6), (0.21, 0.61)], [(0.2, 0.6)] * 3,
                 [(0.2, 0.6)] * 2, [(0.2, 0.6), (0.2, 0.6), (0.45, 0.9)], []]
    monkeypatch.setattr(contact_events, "_positions", lambda problem, q, mu: np.array(
        positions[int(np.flatnonzero(np.all(base.states[:k] == q, axis=1))[0])],
        dtype=float).reshape(-1, 2))

    def change(i, label, s):
        return SpecialPoint(kind="contact_change", label=label, branch=base.name, index=i,
                            parameter=float(base.parameter_values[i]), arclength=s,
                            q=base.states[i], multipliers=base.multipliers[i],
                            tangent=base.tangents[i], tolerance=1e-6)

    s = arrays["arclength"]
    specials = (change(0, "points>=2", s[0] + 1e-3), change(1, "intervals>=1", s[1] + 1e-3),
                change(1, "points>=3", s[1] + 1e-3),  # same transition, merged
                change(2, "points>=2", s[2] + 1e-3), change(3, "points>=2", s[3] + 1e-3),
                change(4, "points>=1", s[4] + 1e-3))
    branch = dataclasses.replace(base, special_points=specials,
                                 records={"n_contact_points": points,
                                          "n_contact_intervals": intervals}, **arrays)
    classified = contact_events.classify_contact_events(branch, problem=None)
    kinds = [p.kind for p in classified.special_points]
    assert kinds == ["contact_split", "contact_interval_onset", "contact_release",
                     "contact_onset", "contact_release"]


def test_integral_contact_on_the_spline_gives_a_consistent_branch():
    """The double-integral contact (ContactOptions.formulation) through the whole diagram:
    the same checks as the pair sum's branch (stored stability = inertia, Lk = Tw + Wr,
    no penetration), and the branch reaches the asked excess link."""
    options = dataclasses.replace(OPTIONS, contact_formulation="integral", contact_curve="spline")
    diagram = ring_diagram(options)
    contact = diagram.branch("alpha_contact")
    assert contact.parameter_values.max() == pytest.approx(options.max_excess_link)
    assert np.all(contact.records["min_gap_over_diameter"] >= 1.0 - 1e-9)
    lk = contact.records["twist"] + contact.records["writhe"]
    assert np.allclose(lk, contact.parameter_values, atol=1e-8)
    cp = ContactProblem(_problem(), ContactOptions(diameter=options.diameter,
                                                   formulation="integral", curve="spline"))
    report = consistency_check(contact, cp, residual_tolerance=1e-8,
                               pin=lambda i, s: diagram.pin_branch("alpha_contact", i, s, cp))
    problems = [p for p in report.problems if "KKT residual" not in p
                and "outside the branch's parameter range" not in p]
    assert not problems, problems


def test_contact_branch_counts_do_not_depend_on_the_rigid_pins(diagram):
    """The rigid pins are picked at the start of a contact branch and re-picked between
    its runs where they lose their grip (RingDiagram.pins).
    Oracle: the unstable count stored at every point equals the count of negative
    eigenvalues of the constrained Hessian with the rigid motions and the sliding
    projected out instead of pinned (stability.analysis: no pins at all). (At L/D = 122,
    N = 200 the construction pins gave a spurious count and fold pairs from dLk 3.40:
    benchmarks/bench_ring_diagram.py.)"""
    from supercoil.rod.closed import rigid_pins
    from supercoil.stability.analysis import eigen_system
    from supercoil.stability.eigen import dense_constrained_eigenpairs

    contact = diagram.branch("alpha_contact")
    cp = ContactProblem(_problem(), OPTIONS.contact_options(OPTIONS.diameter))
    construction = cp.base.fixed.copy()
    first = diagram.pins["alpha_contact"][0]
    assert first == (0, tuple(int(d) for d in rigid_pins(contact.states[0].reshape(-1, 3))))
    for i, q in enumerate(contact.states):
        cp.accept(q)
        at = cp.at(excess_link=float(contact.parameter_values[i]))
        _dofs, H, J, mass, sym = eigen_system(at, q, contact.multipliers[i])
        values, _ = dense_constrained_eigenpairs(H, J, mass, sym)
        assert int(np.sum(values < -1e-6)) == contact.unstable_count[i], i
    np.testing.assert_array_equal(cp.base.fixed, construction)


def test_repin_picks_the_best_rigid_pins_and_keeps_the_state():
    from supercoil.rod.closed import rigid_pins, rotation_pin_determinant

    rod, q = twisted_circle_problem(OPTIONS.twist_ratio, 0.0, OPTIONS.n_nodes, "angle")
    rng = np.random.default_rng(3)
    q = q + 2.0 * rng.standard_normal(q.size) * OPTIONS.diameter
    assert rod.pin_quality(q) < 1.0  # the circle's pins on a perturbed state
    rod.repin(q)
    assert rod.pin_quality(q) == 1.0
    assert np.array_equal(rod.fixed, rigid_pins(q.reshape(-1, 3)))
    assert np.array_equal(rod.gauge_dofs, rod.fixed) and list(rod.fixed[:3]) == [0, 1, 2]
    # the determinant: zero when a pinned coordinate does not see the rotations
    points = q.reshape(-1, 3)
    assert rotation_pin_determinant(points, rod.fixed) > 0
    assert rotation_pin_determinant(points, np.array([0, 1, 2, 3, 4])) == 0.0
    assert rotation_pin_determinant(points, np.array([0, 1, 2, 3, 4, 5])) < 1e-15


def test_rigid_pins_of_a_state_with_an_axis_through_node_0_are_equivariant():
    """rod.closed.rigid_pins: on a state with a two-fold axis along x through node 0
    (x_i = R x_{-i}, R the half-turn), the pinned DOFs are mapped onto themselves by
    that map (nodes 0 and n/2 onto themselves, k onto n - k, the same coordinate), and
    they remove every rigid motion (the 6 x 6 determinant, brute force over the six
    rigid motions, against rotation_pin_determinant); a perturbed state without the
    axis keeps node 0 fully pinned."""
    from supercoil.rod.closed import rigid_pins, rotation_pin_determinant

    n = 60
    s = 2 * np.pi * np.arange(n) / n
    # a symmetric figure-eight-like curve: x even, y and z odd in s about node 0
    points = np.c_[np.cos(s) + 0.3 * np.cos(2 * s), np.sin(s), 0.4 * np.sin(2 * s)]
    flip = np.array([1.0, -1.0, -1.0])
    points = 0.5 * (points + points[(-np.arange(n)) % n] * flip)  # exactly symmetric
    assert np.array_equal(points[(-np.arange(n)) % n] * flip, points)
    pins = rigid_pins(points)
    mapped = {3 * ((-(d // 3)) % n) + d % 3 for d in pins}
    assert mapped == {int(d) for d in pins}
    rows = []
    for d in pins:
        node, k = divmod(int(d), 3)
        e = np.eye(3)[k]
        motions = [np.eye(3)[t] @ e for t in range(3)]  # translations
        motions += [np.cross(np.eye(3)[a], points[node] - points[0]) @ e for a in range(3)]
        rows.append(motions)
    det = abs(np.linalg.det(np.array(rows)))
    assert det > 0 and det == pytest.approx(rotation_pin_determinant(points, pins), rel=1e-12)
    rng = np.random.default_rng(0)
    assert list(rigid_pins(points + 1e-3 * rng.standard_normal(points.shape))[:3]) == [0, 1, 2]


def test_contact_runs_keep_the_grip_of_their_pins(diagram):
    """segments.follow(grip=...): within each run of a contact branch the six rigid pins
    keep at least a quarter of the grip (rotation_pin_determinant) they had at the run's
    start, a point where they would not is refused and the pins re-picked there (a
    fixed pin set can pass through a configuration where it removes no rotation: the
    count flickered there, measured on alpha at N = 200). Oracle: the determinant
    recomputed at every stored point with the pins it was computed with."""
    from supercoil.rod.closed import rotation_pin_determinant

    contact = diagram.branch("alpha_contact")
    starts = [i for i, _ in diagram.pins["alpha_contact"]]
    for (start, dofs), end in zip(diagram.pins["alpha_contact"], starts[1:] + [len(contact)]):
        held = rotation_pin_determinant(contact.states[start].reshape(-1, 3), np.array(dofs))
        for i in range(start, end):
            grip = rotation_pin_determinant(contact.states[i].reshape(-1, 3), np.array(dofs))
            assert grip >= 0.25 * held * (1 - 1e-12), (i, grip / held)


def test_a_mesh_without_a_modes_symmetry_is_noted():
    """N = 50 is not a multiple of 3: beta's D_3 is not a symmetry of the mesh, and the
    diagram says so (with the multiple to use); N = 48 is, and says nothing."""
    def notes(n):
        options = DiagramOptions(2 / 3, 40.0, n_nodes=n, modes=(2, 3), max_excess_link=1.0,
                                 free_max_points=3, contact_max_points=2)
        return [note for note in ring_diagram(options).notes if "not a multiple" in note]

    (note,) = notes(50)
    assert note.startswith("N = 50 is not a multiple of 3:") and note.endswith("of 6")
    assert notes(48) == []
