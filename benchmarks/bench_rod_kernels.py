"""Benchmark: per-call cost of the discrete rod energy (energy, gradient, Hessian) against N.

Run from the repository root:

    python benchmarks/bench_rod_kernels.py
    python benchmarks/bench_rod_kernels.py --save before.npz     # keep the results
    python benchmarks/bench_rod_kernels.py --compare before.npz  # check them later

The problem is a closed rod (``ClosedRodEnergy``, C/A = 2/3, excess link 1.0,
exact turning-angle curvature) on the circle plus an out-of-plane bump
``1e-3 L (cos 2 phi + 0.5 sin 3 phi)``, with the reference directors carried
to that state by ``accept``. Every timed call is made at a *different* state
(the bumped circle plus a random displacement of size ``1e-4 h``, without
``accept``), so that no per-state cache can answer it; the twist terms are
generic because the frames are not adapted to the evaluated state.

Columns (wall time of one call, median of ``--repeat`` calls, warm: the JAX
kernels are compiled or loaded from the cache and every call is made once at
every N before timing):

* energy, gradient, hessian: one call each, at a fresh state;
* iteration: ``gradient``, ``hessian`` and ``energy`` at one fresh state, the
  calls of one Newton iteration with its line-search start.

``--save FILE`` stores energy, gradient and Hessian (sparse part, rank-one
vector and coefficient) at the first state of each N; ``--compare FILE``
prints the largest difference to stored results relative to the largest
stored entry, and exits with status 1 above ``--rtol`` (1e-12).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import jax
import numpy as np

from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy, Rod

SIZES = (200, 1000, 10000)
TWIST_RATIO, EXCESS_LINK = 2.0 / 3.0, 1.0
BUMP = 1e-3
JITTER = 1e-4  # random displacement of the timed states, in edge lengths


def bumped_ring(n_nodes: int) -> tuple[ClosedRodEnergy, np.ndarray]:
    """(problem, q) at the bumped twisted circle, frames adapted to it."""
    rod = Rod(n_nodes, twist_stiffness=TWIST_RATIO)
    phi = 2.0 * np.pi * np.arange(n_nodes) / n_nodes
    points = circle(n_nodes, rod.length)
    points[:, 2] += BUMP * rod.length * (np.cos(2.0 * phi) + 0.5 * np.sin(3.0 * phi))
    problem = ClosedRodEnergy(rod, points, EXCESS_LINK, reference_link=0)
    q = points.ravel()
    problem.accept(q)
    return problem, q


def states(problem: ClosedRodEnergy, q: np.ndarray, count: int, seed: int) -> list[np.ndarray]:
    """``count`` distinct states near ``q`` (random displacements of size ``JITTER h``)."""
    rng = np.random.default_rng(seed)
    h = problem.rod.edge_length
    return [q + JITTER * h * rng.standard_normal(q.size) for _ in range(count)]


def median_time(function, arguments: list[np.ndarray]) -> float:
    """Median wall time of ``function(x)`` over the states ``x`` in ``arguments``."""
    times = []
    for x in arguments:
        t0 = time.perf_counter()
        function(x)
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def iteration(problem: ClosedRodEnergy, q: np.ndarray) -> None:
    problem.gradient(q)
    problem.hessian(q)
    problem.energy(q)


def time_size(n_nodes: int, repeat: int) -> dict:
    problem, q = bumped_ring(n_nodes)
    pool = states(problem, q, 4 * repeat + 1, seed=n_nodes)
    iteration(problem, pool[-1])  # warm-up at this size
    columns = {
        "energy": problem.energy,
        "gradient": problem.gradient,
        "hessian": problem.hessian,
        "iteration": lambda x: iteration(problem, x),
    }
    return {
        name: median_time(function, pool[k * repeat : (k + 1) * repeat])
        for k, (name, function) in enumerate(columns.items())
    }


def results(n_nodes: int) -> dict[str, np.ndarray]:
    """Energy, gradient and Hessian parts at the first state of ``n_nodes`` (a fresh problem)."""
    problem, q = bumped_ring(n_nodes)
    x = states(problem, q, 1, seed=n_nodes)[0]
    parts = problem.hessian(x)
    sparse = parts.sparse.tocoo()
    return {
        f"{n_nodes}/energy": np.array([problem.energy(x)]),
        f"{n_nodes}/gradient": problem.gradient(x),
        f"{n_nodes}/hessian_indices": np.stack([sparse.row, sparse.col]).astype(float),
        f"{n_nodes}/hessian_values": sparse.data,
        f"{n_nodes}/rank_one_vector": parts.vectors[0],
        f"{n_nodes}/rank_one_coefficient": parts.coefficients,
    }


def compare(stored: dict[str, np.ndarray], current: dict[str, np.ndarray], n_nodes: int) -> float:
    """Largest difference relative to the largest stored entry, over the results of ``n_nodes``."""
    worst = 0.0
    for name in ("energy", "gradient", "rank_one_vector", "rank_one_coefficient"):
        a, b = current[f"{n_nodes}/{name}"], stored[f"{n_nodes}/{name}"]
        worst = max(worst, float(np.max(np.abs(a - b)) / np.max(np.abs(b))))
    # The Hessian's sparse part: compare as matrices (the stored pattern may differ).
    import scipy.sparse as sp

    def matrix(res):
        rows, cols = res[f"{n_nodes}/hessian_indices"].astype(np.int64)
        n = 3 * n_nodes
        return sp.csr_matrix((res[f"{n_nodes}/hessian_values"], (rows, cols)), shape=(n, n))

    a, b = matrix(current), matrix(stored)
    worst = max(worst, float(abs(a - b).max() / abs(b).max()))
    return worst


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=21, help="timed calls per column (median)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="node counts")
    parser.add_argument("--save", help="store the results (npz) for a later --compare")
    parser.add_argument("--compare", help="compare the results with a file from --save")
    parser.add_argument("--rtol", type=float, default=1e-12, help="--compare failure threshold")
    arguments = parser.parse_args()
    if arguments.repeat < 1:
        parser.error("--repeat must be >= 1")
    sizes = sorted(set(arguments.sizes))

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} CPUs; Python {platform.python_version()}, "
        f"numpy {np.__version__}, jax {jax.__version__}"
    )
    print(
        f"closed rod: C/A = {TWIST_RATIO:.4g}, excess link {EXCESS_LINK}, bump {BUMP} L; "
        f"median of {arguments.repeat} calls, each at a fresh state"
    )
    print()
    print("| N | energy (ms) | gradient (ms) | hessian (ms) | iteration (ms) |")
    print("|---:|---:|---:|---:|---:|")
    for n_nodes in sizes:
        row = time_size(n_nodes, arguments.repeat)
        print(
            f"| {n_nodes} | "
            + " | ".join(
                f"{1e3 * row[k]:.3f}" for k in ("energy", "gradient", "hessian", "iteration")
            )
            + " |",
            flush=True,
        )

    status = 0
    if arguments.save or arguments.compare:
        current = {}
        for n_nodes in sizes:
            current.update(results(n_nodes))
        if arguments.save:
            np.savez(arguments.save, **current)
            print(f"\nresults saved to {arguments.save}")
        if arguments.compare:
            stored = dict(np.load(arguments.compare))
            print()
            for n_nodes in sizes:
                worst = compare(stored, current, n_nodes)
                verdict = "ok" if worst <= arguments.rtol else "DIFFERS"
                print(f"N = {n_nodes}: largest relative difference {worst:.2e} ({verdict})")
                if worst > arguments.rtol:
                    status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
