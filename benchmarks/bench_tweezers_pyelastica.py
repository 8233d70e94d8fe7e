"""The tweezers benchmark problem in PyElastica (the peer), for bench_tweezers.py.

Run with an interpreter that has PyElastica (``pip install pyelastica`` or
``pip install -e ".[pyelastica]"``)::

    python benchmarks/bench_tweezers_pyelastica.py [--steps K] [--elements N]

A Cosserat rod of length L = 1 and diameter D = L/33 (C/A = 4/3 through
G = E/1.5 and a circular section), clamped at its start, its end held on the
axis (free to slide along it) under the dead load F L^2/A = 75 and turned
5 times about the axis during the first half of the simulated time, then held
while the damping brings it to rest; self-contact is PyElastica's damped
penalty (``RodSelfContact``). Explicit position-Verlet time steps of
``0.0025 L / N`` (PyElastica's plectoneme example); ``--steps`` runs only
that many steps and reports the rate (to extrapolate the full run's wall
time). Prints one JSON line: wall time, steps, extension, writhe (tails of
10 L along the end tangents), the largest overlap of non-neighbouring
elements over D, and the end's largest speed (how static the state is).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def main() -> None:
    import elastica as ea
    from scipy.spatial.transform import Rotation

    parser = argparse.ArgumentParser()
    parser.add_argument("--elements", type=int, default=100)
    parser.add_argument("--steps", type=int, default=0, help="0: the whole run")
    parser.add_argument("--turns", type=float, default=5.0)
    parser.add_argument("--final-time", type=float, default=27.5)
    args = parser.parse_args()

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Contact, ea.Forcing,
                    ea.Damping):
        pass

    n = args.elements
    length, radius = 1.0, 0.5 / 33.0
    area = np.pi * radius**2
    density = 1.0 / (area * length)  # unit mass
    youngs = 1e6
    shear = youngs / 1.5  # C/A = G J / (E I) = 2 G / E = 4/3
    bending = youngs * np.pi * radius**4 / 4.0
    force = 75.0 * bending / length**2
    axis = np.array([0.0, 1.0, 0.0])
    sim = Simulator()
    rod = ea.CosseratRod.straight_rod(n, np.zeros(3), axis, np.array([0.0, 0.0, 1.0]),
                                      length, radius, density, youngs_modulus=youngs,
                                      shear_modulus=shear)
    rod.velocity_collection[2, n // 2] -= 1e-4  # break the symmetry
    sim.append(rod)
    dt = 0.0025 * length / n
    total_steps = round(args.final_time / dt)
    twist_time = 0.5 * args.final_time
    sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=2.0 / density
                          / area, time_step=dt)

    class TurnedClamp(ea.ConstraintBase):
        """Start clamped; end on the axis, free along it, turned at a constant rate."""

        def __init__(self, position_start, position_end, director_start, director_end,
                     turns, duration, **kwargs):
            super().__init__(**kwargs)
            angle = 2 * np.pi * turns
            self.duration = duration
            self.start_position = np.array(position_start, dtype=float)
            self.start_director = np.array(director_start, dtype=float)
            end = np.array(director_end, dtype=float)
            local_axis = end @ -axis  # the axis in the end's material frame
            local_axis /= np.linalg.norm(local_axis)
            # PyElastica's directors are rows: turning the frame by the angle about
            # local_axis multiplies them on the left by the rotation of that vector
            self.final_director = Rotation.from_rotvec(angle * local_axis).as_matrix() @ end
            self.omega = angle / duration * local_axis

        def constrain_values(self, system, time):
            system.position_collection[..., 0] = self.start_position
            system.director_collection[..., 0] = self.start_director
            system.position_collection[0, -1] = 0.0
            system.position_collection[2, -1] = 0.0
            if time >= self.duration:
                system.director_collection[..., -1] = self.final_director

        def constrain_rates(self, system, time):
            system.velocity_collection[..., 0] = 0.0
            system.omega_collection[..., 0] = 0.0
            system.velocity_collection[0, -1] = 0.0
            system.velocity_collection[2, -1] = 0.0
            system.omega_collection[..., -1] = -self.omega if time < self.duration else 0.0

    sim.constrain(rod).using(TurnedClamp, constrained_position_idx=(0, -1),
                             constrained_director_idx=(0, -1), turns=args.turns,
                             duration=twist_time)
    sim.add_forcing_to(rod).using(ea.EndpointForces, np.zeros(3), force * axis,
                                  ramp_up_time=1.0)
    sim.detect_contact_between(rod, rod).using(ea.RodSelfContact, k=1e4, nu=10)
    sim.finalize()
    stepper = ea.PositionVerlet()
    steps = total_steps if args.steps <= 0 else min(args.steps, total_steps)
    t, start = 0.0, time.perf_counter()
    for _ in range(steps):
        t = stepper.step(sim, t, dt)
    wall = time.perf_counter() - start
    x = rod.position_collection.T.copy()
    writhe = float(ea.compute_writhe(x.T[None], np.float64(10 * length), "next_tangent")[0])
    mids = 0.5 * (x[1:] + x[:-1])
    dist = np.linalg.norm(mids[:, None] - mids[None], axis=2)
    s = np.arange(len(mids)) * length / n
    far = np.abs(s[:, None] - s[None]) > np.pi * radius  # pi D / 2 neighbour exclusion
    overlap = float(max(0.0, 1.0 - dist[far].min() / (2 * radius))) if far.any() else 0.0
    print(json.dumps({"elements": n, "steps": steps, "total_steps": total_steps,
                      "simulated_time": t, "wall_time_s": wall,
                      "seconds_per_step": wall / max(steps, 1),
                      "extension": float(x[-1, 1] - x[0, 1]) / length, "writhe": writhe,
                      "overlap_over_diameter": overlap,
                      "largest_speed": float(np.abs(rod.velocity_collection).max())}))


if __name__ == "__main__":
    main()
