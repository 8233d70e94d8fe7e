"""One question, one answer: the supercoiled ring does not depend on the thread counts.

Oracles: the same state, bit for bit, from processes with one and with two BLAS
and numba threads; and the push off the circle does not depend on which basis
of its double critical eigenvalue an eigensolver returned (any rotation of the
pair gives the same perturbation).
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest

from supercoil.problems.ring import twisted_circle_problem
from supercoil.problems.ring_contact import circle_perturbation
from supercoil.solvers.newton import NewtonOptions, newton
from supercoil.stability.analysis import analyse

PROGRAM = """
import hashlib, sys
from supercoil.problems.ring_contact import solve_supercoiled_ring
r = solve_supercoiled_ring(1.0, 2.0, 60.0, n_nodes=60)
print(r.energy.hex(), r.writhe.hex(), r.unstable_count, r.status,
      hashlib.sha256(r.points.tobytes()).hexdigest())
"""


def _run(threads: int) -> str:
    env = dict(os.environ, OPENBLAS_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads),
               MKL_NUM_THREADS=str(threads), NUMBA_NUM_THREADS=str(threads))
    out = subprocess.run([sys.executable, "-c", PROGRAM], env=env, capture_output=True,
                         text=True, timeout=900, check=True)
    return out.stdout.strip()


def test_one_and_two_threads_give_the_same_state():
    one, two = _run(1), _run(2)
    assert one == two
    assert one.split()[3] == "converged"


@pytest.mark.parametrize("angle", [0.3, 1.1, 2.5])
def test_the_push_off_the_circle_does_not_depend_on_the_eigenbasis(angle):
    problem, q0 = twisted_circle_problem(1.0, 2.0, 40)
    circle = newton(problem, q0, NewtonOptions(tolerance=1e-10, mode="stationary"))
    report = analyse(problem, circle.q, circle.multipliers, n_modes=2)
    assert report.lowest_eigenvalues[0] < 0  # above Michell's threshold: a double pair
    modes = report.lowest_modes.copy()
    c, s = np.cos(angle), np.sin(angle)
    rotated = modes.copy()
    rotated[0], rotated[1] = c * modes[0] + s * modes[1], -s * modes[0] + c * modes[1]
    other = dataclasses.replace(report, lowest_modes=rotated)
    flipped = dataclasses.replace(report, lowest_modes=-modes)
    reference = circle_perturbation(problem, circle.q, report)
    scale = np.max(np.abs(reference))
    np.testing.assert_allclose(circle_perturbation(problem, circle.q, other), reference,
                               atol=1e-9 * scale)
    np.testing.assert_allclose(circle_perturbation(problem, circle.q, flipped), reference,
                               atol=1e-12 * scale)
