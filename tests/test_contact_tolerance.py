"""Contact treatments to a stated penetration tolerance.

The penalty is raised, and the augmented Lagrangian's multipliers updated, until
the penetration is within the tolerance (Chamekh, Mani-Aouadi & Moakher 2009);
the output reports the penetration reached. Oracles: the penetration of each
returned state (recomputed from its segments) against its tolerance, and the
four treatments' agreement on one supercoiled ring: to first order two
treatments' energies differ by at most the work of the contact forces over the
difference of their gaps, ``sum(f) * (tol_1 + tol_2) * D``.
"""

from __future__ import annotations

import pytest

from supercoil.contact.options import ContactOptions
from supercoil.contact.problem import ContactProblem
from supercoil.contact.solve import max_penetration, solve_contact
from supercoil.problems.ring_contact import solve_supercoiled_ring, validate_diameter
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.solvers.newton import NewtonOptions

TWIST_RATIO, EXCESS_LINK, LOD, NODES = 1.0, 2.0, 60.0, 60
# the gap each treatment may leave, over D: the barrier acts below 1e-2 D of gap
GAP = {"exact": 1e-4, "augmented": 1e-4, "penalty": 1e-3, "barrier": 1e-2}


@pytest.fixture(scope="module")
def treated():
    ring = solve_supercoiled_ring(TWIST_RATIO, EXCESS_LINK, LOD, n_nodes=NODES)
    assert ring.converged, ring.message
    assert ring.summary()["contacts"], "the test ring must have contact"
    q0 = ring.points.ravel()
    out = {}
    for treatment in ("exact", "augmented", "penalty", "barrier"):
        rod = Rod(n_nodes=NODES, twist_stiffness=TWIST_RATIO)
        base = ClosedRodEnergy(rod, ring.points, EXCESS_LINK)
        problem = ContactProblem(base, ContactOptions(diameter=validate_diameter(LOD),
                                                      treatment=treatment))
        q = q0 * (1.0 + 2e-3) if treatment == "barrier" else q0  # the barrier needs a gap
        res = solve_contact(problem, q, NewtonOptions(tolerance=1e-9, max_iterations=300))
        out[treatment] = (problem, res)
    return ring, out


def test_penalty_default_tolerance_is_1e_3():
    assert ContactOptions(diameter=0.01, treatment="penalty").tolerance == 1e-3


@pytest.mark.parametrize("treatment", ["exact", "augmented", "penalty", "barrier"])
def test_penetration_within_the_tolerance(treated, treatment):
    _ring, out = treated
    problem, res = out[treatment]
    assert res.converged and res.admissible, res.message
    reached = max_penetration(problem, res.q)
    assert res.max_penetration_over_diameter == reached
    assert reached <= problem.options.tolerance
    if treatment == "penalty":
        # the penalty was raised to get there, and says so
        assert problem.stiffness > problem.default_stiffness
        assert "penetration" in res.message and "x the default" in res.message


def test_the_four_treatments_agree(treated):
    ring, out = treated
    exact_problem, exact = out["exact"]
    e_exact = exact_problem.base.elastic_energy(exact.q)
    wr_exact = exact_problem.base.writhe_local(exact.q)
    force = sum(c["force"] for c in ring.summary()["contacts"])
    D = validate_diameter(LOD)
    for treatment, (problem, res) in out.items():
        energy = problem.base.elastic_energy(res.q)
        work = force * (GAP[treatment] + GAP["exact"]) * D
        assert abs(energy - e_exact) <= 3 * work + 1e-9 * abs(e_exact), (treatment, energy)
        # the writhe moves with the gap: a fraction of D over the length of the contact
        assert abs(problem.base.writhe_local(res.q) - wr_exact) <= 2 * GAP[treatment] + 1e-8, \
            treatment


def test_the_ring_reports_its_penetration():
    ring = solve_supercoiled_ring(TWIST_RATIO, EXCESS_LINK, LOD, n_nodes=NODES,
                                  treatment="penalty")
    s = ring.summary()
    assert ring.converged, ring.message
    assert s["penetration_tolerance"] == 1e-3
    assert 0.0 <= s["max_penetration_over_diameter"] <= 1e-3
    assert s["min_gap_over_diameter"] >= 1.0 - 1e-3
