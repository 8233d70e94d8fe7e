"""The supercoiled ring is the end of the quasi-static winding from the circle.

A ring wound past a contact onset under the barrier (C/A = 2, L/D = 60, N = 48, where a
contact forms between dLk 1.0 and 1.1): its answer at dLk = 2.5 is compared with an
explicit continuation in dLk from the circle written here with the library's parts,
a fixed step of 0.05 and nothing adaptive (no halving, no restarts, no re-picked pins):
each step minimised from the previous state under the barrier. Oracles: the same
state (energy and writhe), a stable one in contact, reached without a jump; its mirror image
at -dLk (same energy to 1e-9, opposite writhe and twist); Lk = Tw + Wr on both.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import solve_contact
from supercoil.problems.ring import michell_threshold, twisted_circle_problem
from supercoil.problems.ring_contact import (
    SNAP_OFFSET,
    circle_perturbation,
    solve_supercoiled_ring,
)
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import analyse
from supercoil.topology import writhe

TWIST_RATIO, EXCESS_LINK, LOD, NODES = 2.0, 2.5, 60.0, 48
STEP = 0.05


@pytest.fixture(scope="module")
def wound():
    return solve_supercoiled_ring(TWIST_RATIO, EXCESS_LINK, LOD, n_nodes=NODES)


def explicit_continuation(twist_ratio, excess_link, lod, nodes, step):
    """``(contact problem, solve result)`` at ``excess_link``: the circle pushed
    off along its critical mode just past Michell's threshold, then dLk raised in
    equal steps of at most ``step``, each minimised from the previous state."""
    threshold = michell_threshold(twist_ratio, nodes, rtol=1e-9)
    start = threshold * (1 + SNAP_OFFSET)
    base, q0 = twisted_circle_problem(twist_ratio, start, nodes)
    circle = newton(base, q0, NewtonOptions(tolerance=1e-9, mode="stationary"))
    report = analyse(base, circle.q, circle.multipliers, n_modes=2)
    assert report.unstable_count > 0  # past the threshold: the circle is a saddle
    problem = ContactProblem(base, ContactOptions(diameter=1.0 / lod, treatment="barrier"))
    options = NewtonOptions(tolerance=1e-9, mode="minimize", max_iterations=1000)
    q = circle.q + circle_perturbation(base, circle.q, report)
    levels = np.linspace(start, excess_link, int(np.ceil((excess_link - start) / step)) + 1)
    for level in levels:
        problem = problem.at(excess_link=float(level))
        problem.accept(q)
        res = solve_contact(problem, q, options)
        assert res.converged and res.admissible, (level, res.message)
        q = res.q
    return problem, res


def test_the_answer_is_the_end_of_the_winding(wound):
    assert wound.converged and wound.status == "converged", wound.message
    assert wound.unstable_count == 0
    path = wound.summary()["path"]
    assert path["branch"] == "contact" and path["excess_link"] == EXCESS_LINK
    assert path["jumps"] == [] and "one minimisation" not in wound.message
    problem, res = explicit_continuation(TWIST_RATIO, EXCESS_LINK, LOD, NODES, STEP)
    base = problem.base
    energy = base.elastic_energy(res.q)
    assert abs(wound.energy - energy) <= 1e-6 * energy
    x = res.q.reshape(-1, 3)
    assert wound.writhe == pytest.approx(writhe(x), abs=1e-6)
    assert problem.min_distance(res.q) < 1.01 * problem.diameter  # in contact (barrier)
    stability = analyse(problem.stability_view(), res.q, res.multipliers, n_modes=4)
    assert stability.unstable_count == 0
    assert wound.twist + wound.writhe == pytest.approx(EXCESS_LINK, abs=1e-9)


def test_minus_dlk_is_the_mirror_image_of_the_winding(wound):
    mirror = solve_supercoiled_ring(TWIST_RATIO, -EXCESS_LINK, LOD, n_nodes=NODES)
    assert mirror.converged and mirror.unstable_count == 0
    assert abs(mirror.energy - wound.energy) <= 1e-9 * abs(wound.energy)
    assert mirror.writhe == pytest.approx(-wound.writhe, abs=1e-12)
    assert mirror.twist == pytest.approx(-wound.twist, abs=1e-12)
    assert writhe(mirror.points) == pytest.approx(-wound.writhe, abs=1e-10)
    assert mirror.summary()["path"]["jumps"] == []
