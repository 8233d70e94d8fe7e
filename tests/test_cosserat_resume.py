"""The Cosserat ring diagram stored point by point and continued.

Oracles: a branch stored as centrelines with each point's frames (the sections'
rotation matrices and rotation coordinates) is rebuilt in the rod's unknowns bit for
bit, and the stored rotations are rotations (R R^T = I) that give the stored link
(Lk = Tw + Wr at the recorded excess link); a run interrupted inside its contact branch
and resumed from its file ends where the uninterrupted run ends (measured: 1.6e-10 in
the states and dLk, the corrector's own level, the last stored point corrected again);
a result of one rod model is not resumed with another.
"""

from collections import defaultdict

import numpy as np
import pytest

import supercoil as sc
from supercoil.cosserat.ring import michell_excess_link, ring_problem
from supercoil.problems.cosserat_stored import cosserat_branch

ROD = sc.CosseratRod(2 / 3, 1e5, 1e5, nodes=24)
LOD = 20.0
OPTIONS = {"modes": (2,), "max_excess_link": 4.0, "contact_max_points": 30}


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    out = tmp_path_factory.mktemp("cosserat") / "full"
    diagram = sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, **OPTIONS)
    return diagram, sc.load(out)


def test_stored_branches_rebuild_the_computed_states_bit_for_bit(full):
    diagram, stored = full
    for name, branch in diagram.branches.items():
        read = stored.branches[name]
        assert read.states.shape[1] == 3 * ROD.nodes  # the centrelines, for every reader
        a, b = cosserat_branch(branch), cosserat_branch(read)
        np.testing.assert_array_equal(a.states, b.states)
        np.testing.assert_array_equal(a.tangents, b.tangents)
        for f, g in zip(a.frames, b.frames):
            assert f.equals(g) and g.stored
    contact = stored.branches["alpha_contact"]
    rotations = np.asarray([f.values["reference_rotations"] for f in contact.frames])
    assert rotations.shape == (len(contact), ROD.nodes, 3, 3)
    assert np.max(np.abs(rotations @ np.swapaxes(rotations, -1, -2) - np.eye(3))) < 1e-13
    # the chart-free state (positions, rotations) of a point has the ring's link
    i = len(contact) - 1
    dlk = float(contact.parameter_values[i])
    # the diagram turns d1 by the whole turns nearest alpha's Michell threshold
    link = int(np.rint(michell_excess_link(ROD.twist_ratio, 2)))
    ring = ring_problem(ROD.twist_ratio, dlk, ROD.nodes, ROD.stretch_stiffness,
                        ROD.shear_stiffness, link=link)
    q = ring.state(contact.states[i].reshape(-1, 3), rotations[i])
    assert ring.twist(q) + ring.writhe(q) == pytest.approx(dlk, abs=1e-9)


def interrupt_at(name: str, count: int):
    """An ``on_point`` that raises KeyboardInterrupt at the ``count``-th point of branch
    ``name``."""
    seen = defaultdict(int)

    def on_point(branch):
        seen[branch.name] += 1
        if seen[name] == count:
            raise KeyboardInterrupt
    return on_point


def assert_same_branches(resumed, whole, atol: float = 1e-8):
    """The resumed result's branches are the uninterrupted run's, point for point."""
    assert list(resumed.branches) == list(whole.branches)
    for name, b in whole.branches.items():
        r = resumed.branches[name]
        assert len(r) == len(b), name
        np.testing.assert_allclose(r.states, b.states, atol=atol, rtol=0, err_msg=name)
        np.testing.assert_allclose(r.parameter_values, b.parameter_values, atol=atol, rtol=0)


def test_a_run_interrupted_in_its_contact_branch_resumes_to_the_same_end(tmp_path, full):
    _, whole = full
    out = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):
        sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, on_point=interrupt_at("alpha_contact", 12),
                        **OPTIONS)
    cut = sc.load(out)
    assert cut.status == "interrupted" and len(cut.branches["alpha_contact"]) == 12
    with pytest.raises(sc.InputError, match="another rod"):
        sc.ring_diagram(sc.Rod(2 / 3, nodes=24), sc.Barrier(LOD), out=out, resume=True,
                        **OPTIONS)
    with pytest.raises(sc.InputError, match="another rod"):
        sc.ring_diagram(sc.CosseratRod(2 / 3, 1e4, 1e5, nodes=24), sc.Barrier(LOD), out=out,
                        resume=True, **OPTIONS)
    sc.ring_diagram(ROD, sc.Barrier(LOD), out=out, resume=True, **OPTIONS)
    resumed = sc.load(out)
    assert_same_branches(resumed, whole)
    for name, b in whole.branches.items():
        assert [(p.kind, p.index) for p in resumed.branches[name].special_points] == \
            [(p.kind, p.index) for p in b.special_points], name


def test_tweezers_interrupted_in_their_contact_branch_resume_to_the_same_end(tmp_path):
    problem = sc.Tweezers(sc.CosseratRod(0.8, 1e4, 1e4, nodes=16), tension=5.0,
                          contact=sc.Barrier(14.0))
    whole = sc.tweezers(problem, (0.0, 2.2), out=tmp_path / "full")
    assert "buckled_contact" in whole.branches, whole.notes
    out = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):
        sc.tweezers(problem, (0.0, 2.2), out=out, on_point=interrupt_at("buckled_contact", 5))
    assert len(sc.load(out).branches["buckled_contact"]) == 5
    resumed = sc.tweezers(problem, (0.0, 2.2), out=out, resume=True)
    assert resumed.status == whole.status
    assert_same_branches(sc.load(out), sc.load(tmp_path / "full"))
