"""Continuation of your own energy: a pitchfork, located and switched.

The generic continuation under the rod problems takes any energy E(q; lambda)
given by its value, gradient and Hessian. Here E = x^4/4 - lambda x^2/2 + y^2/2:
the trivial state x = 0 loses stability at lambda = 0, where the branches
x = +-sqrt(lambda) bifurcate (a supercritical pitchfork). The bifurcation is found
as a change of the unstable count (the inertia of the Hessian) and followed off.

    python examples/04_own_energy.py
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

import supercoil as sc


def main() -> float:
    """Follow both branches; return the located bifurcation's lambda (exactly 0)."""
    energy = sc.Energy(
        energy=lambda q, lam: q[0] ** 4 / 4 - lam * q[0] ** 2 / 2 + q[1] ** 2 / 2,
        gradient=lambda q, lam: np.array([q[0] ** 3 - lam * q[0], q[1]]),
        hessian=lambda q, lam: sp.diags([3 * q[0] ** 2 - lam, 1.0]),
        n_dofs=2)
    options = sc.ContinuationOptions(max_step=0.1, event_tolerance=1e-10)
    trivial = sc.continuation(energy, [0.0, 0.0], start=-1.0, bounds=(-1.0, 1.0),
                              options=options, name="trivial")
    point = trivial.points_of_kind("bifurcation")[0]
    buckled = sc.switch_branch(energy, trivial, point, bounds=(-1.0, 1.0), options=options,
                               name="buckled")
    print(f"bifurcation at lambda = {point.parameter:.2e}, unstable count "
          f"{point.count_before} -> {point.count_after}")
    x, lam = buckled.states[:, 0], buckled.parameter_values
    print(f"buckled branch: {len(buckled)} points, max |x^2 - lambda| = "
          f"{np.max(np.abs(x**2 - lam)):.1e}, stable: {bool(np.all(buckled.stable[lam > 1e-3]))}")
    return float(point.parameter)


if __name__ == "__main__":
    main()
