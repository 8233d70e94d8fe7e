"""Benchmark: per-call cost of the discrete rod energy (energy, gradient, Hessian) against N.

Run from the repository root:

    python benchmarks/bench_rod_kernels.py
    python benchmarks/bench_rod_kernels.py --save before.npz     # keep the results
    python benchmarks/bench_rod_kernels.py --compare before.npz  # check them later
    python benchmarks/bench_rod_kernels.py --check-kernels       # against JAX autodiff

The problem is a closed rod (``ClosedRodEnergy``, C/A = 2/3, excess link 1.0,
exact turning-angle curvature) on the circle plus an out-of-plane bump
``1e-3 L (cos 2 phi + 0.5 sin 3 phi)``, with the reference directors carried
to that state by ``accept``. Every timed call is made at a *different* state
(the bumped circle plus a random displacement of size ``1e-4 h``, without
``accept``), so that no per-state cache can answer it; the twist terms are
generic because the frames are not adapted to the evaluated state.

Columns (wall time of one call, median of ``--repeat`` calls, warm: every call
is made once at every N before timing, so compiled kernels are loaded):

* energy, gradient, hessian: one call each, at a fresh state;
* iteration: ``gradient``, ``hessian`` and ``energy`` at one fresh state, the
  calls of one Newton iteration with its line-search start.

``--save FILE`` stores energy, gradient and Hessian (sparse part, rank-one
vector and coefficient) at the first state of each N; ``--compare FILE``
prints, per quantity, the largest difference to the stored results over the
largest stored entry. ``--check-kernels`` compares the local kernels
(bending in the three curvature forms, reference twist; value, gradient,
Hessian) with ``supercoil.rod.reference_kernels.reference_kernels`` (JAX autodiff) at
the same states. Exit status 1 if a difference exceeds ``--rtol`` (2e-12).
The script runs on any version of the package with the same public API
(``--check-kernels`` needs ``reference_kernels``), so "before" figures can be
taken from an older checkout: ``PYTHONPATH=old/src python benchmarks/...``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numba
import numpy as np
import scipy
import scipy.sparse as sp

from supercoil.geometry.curves import circle
from supercoil.rod.closed import ClosedRodEnergy
from supercoil.rod.model import Rod

SIZES = (200, 1000, 10000)
TWIST_RATIO, EXCESS_LINK = 2.0 / 3.0, 1.0
BUMP = 1e-3
JITTER = 1e-4  # random displacement of the timed states, in edge lengths
# --compare / --check-kernels threshold. The writhe gradient (the rank-one
# vector) is a sum of local terms that cancel near a planar ring: the former
# JAX path carried ~1e-12 of round-off there (against extended precision).
RTOL = 2e-12


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


def differences(stored: dict, current: dict, n_nodes: int) -> dict[str, float]:
    """Per quantity: largest difference over the largest stored entry."""
    out = {}
    for name in ("energy", "gradient", "rank_one_vector", "rank_one_coefficient"):
        a, b = current[f"{n_nodes}/{name}"], stored[f"{n_nodes}/{name}"]
        out[name] = float(np.max(np.abs(a - b)) / np.max(np.abs(b)))

    def matrix(res):  # compared as matrices: the stored pattern may differ
        rows, cols = res[f"{n_nodes}/hessian_indices"].astype(np.int64)
        n = 3 * n_nodes
        return sp.csr_matrix((res[f"{n_nodes}/hessian_values"], (rows, cols)), shape=(n, n))

    a, b = matrix(current), matrix(stored)
    out["hessian_sparse"] = float(abs(a - b).max() / abs(b).max())
    return out


def kernel_differences(n_nodes: int, stencil_count: int = 1000) -> dict[str, float]:
    """Numba kernels against their JAX reference at the first state of ``n_nodes``.

    Largest difference over the largest reference entry, per kernel, except
    for the reference twists (in radians). At most ``stencil_count`` stencils
    (the reference compiles once per count).
    """
    from supercoil.rod import kernels
    from supercoil.rod.reference_kernels import reference_kernels

    problem, q = bumped_ring(n_nodes)
    x = states(problem, q, 1, seed=n_nodes)[0]
    count = min(stencil_count, n_nodes)
    stencils = problem._pattern.gather(x)[:count]
    weights = problem._bend_weight[:count]
    frames = problem._frames()[:count]
    out = {}
    for form in kernels.CURVATURE_FORMS:
        reference = reference_kernels(form)
        for part, kernel in zip(("value", "gradient", "hessian"), kernels.bending_kernels(form)):
            a, b = kernel(stencils, weights), reference[f"bending_{part}"](stencils, weights)
            out[f"bending {form} {part}"] = float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
    twist = (kernels.twist_value, kernels.twist_gradient, kernels.twist_hessian)
    for part, kernel in zip(("value", "gradient", "hessian"), twist):
        a, b = kernel(stencils, frames), reference[f"twist_{part}"](stencils, frames)
        # Reference twists are angles, here all tiny (~1e-6): compared in radians.
        scale = 1.0 if part == "value" else np.max(np.abs(b))
        out[f"twist {part}"] = float(np.max(np.abs(a - b)) / scale)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=21, help="timed calls per column (median)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="node counts")
    parser.add_argument("--save", help="store the results (npz) for a later --compare")
    parser.add_argument("--compare", help="compare the results with a file from --save")
    parser.add_argument("--rtol", type=float, default=RTOL, help="--compare failure threshold")
    parser.add_argument(
        "--check-kernels", action="store_true", help="compare the kernels with the JAX reference"
    )
    arguments = parser.parse_args()
    if arguments.repeat < 1:
        parser.error("--repeat must be >= 1")
    sizes = sorted(set(arguments.sizes))

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} CPUs; Python {platform.python_version()}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}, numba {numba.__version__}"
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
        cells = " | ".join(
            f"{1e3 * row[k]:.3f}" for k in ("energy", "gradient", "hessian", "iteration")
        )
        print(f"| {n_nodes} | {cells} |", flush=True)

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
            print(f"\ndifferences to {arguments.compare} (over the largest stored entry):")
            for n_nodes in sizes:
                found = differences(stored, current, n_nodes)
                worst = max(found.values())
                verdict = "ok" if worst <= arguments.rtol else "DIFFERS"
                details = ", ".join(f"{k} {v:.1e}" for k, v in found.items())
                print(f"N = {n_nodes}: {details} ({verdict})")
                status = max(status, int(worst > arguments.rtol))
    if arguments.check_kernels:
        print(
            "\nkernels against the JAX reference (over the largest reference entry; twist value in rad):"
        )
        for n_nodes in sizes:
            found = kernel_differences(n_nodes)
            worst = max(found.values())
            verdict = "ok" if worst <= arguments.rtol else "DIFFERS"
            print(f"N = {n_nodes}: largest {worst:.1e} ({verdict})")
            for name, value in found.items():
                print(f"    {name}: {value:.1e}")
            status = max(status, int(worst > arguments.rtol))
    return status


if __name__ == "__main__":
    sys.exit(main())
