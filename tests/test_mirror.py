"""Mirror symmetry of the supercoiled ring: -dLk gives the mirror image of +dLk.

Oracle: the reflection ``z -> -z`` maps an isotropic rod's state at ``dLk`` to a
state at ``-dLk`` with the same energy and the opposite twist and writhe. The
returned state at ``-dLk`` is checked independently: its writhe is the double sum
of its own points, its energy that of a rod set up afresh at ``-dLk`` on them.
"""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.problems.ring_contact import solve_supercoiled_ring
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod
from supercoil.topology import writhe

# C/A, |dLk|, L/D, N: below Michell's threshold (the circle) and two supercoiled
# states with contact above it (one reached through a jump)
GRID = [(2.0, 0.5, 60.0, 40), (1.0, 2.0, 60.0, 60), (1 / 1.4, 2.6, 60.0, 60)]


@pytest.mark.parametrize("twist_ratio, excess_link, lod, nodes", GRID)
def test_minus_dlk_is_the_mirror_image(twist_ratio, excess_link, lod, nodes):
    plus = solve_supercoiled_ring(twist_ratio, excess_link, lod, n_nodes=nodes)
    minus = solve_supercoiled_ring(twist_ratio, -excess_link, lod, n_nodes=nodes)
    assert plus.converged, plus.message
    assert minus.converged, minus.message
    assert minus.excess_link == -excess_link
    assert abs(minus.energy - plus.energy) <= 1e-9 * abs(plus.energy)
    assert minus.writhe == pytest.approx(-plus.writhe, abs=1e-12)
    assert minus.twist == pytest.approx(-plus.twist, abs=1e-12)
    assert minus.unstable_count == plus.unstable_count
    assert minus.summary()["branch"] == plus.summary()["branch"]
    # the returned state, checked on its own: its double-sum writhe and its energy at -dLk
    assert writhe(minus.points) == pytest.approx(-plus.writhe, abs=1e-10)
    rod = Rod(n_nodes=nodes, twist_stiffness=twist_ratio)
    fresh = ClosedRodEnergy(rod, minus.points, -excess_link)
    energy = fresh.elastic_energy(minus.points.ravel())
    assert abs(energy - plus.energy) <= 1e-9 * abs(plus.energy)
    mirror = minus.points * np.array([1.0, 1.0, -1.0])
    np.testing.assert_array_equal(mirror, plus.points)
