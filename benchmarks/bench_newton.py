"""Benchmark: cost of one Newton step of the closed-rod equilibrium solver against N.

Run from the repository root:

    python benchmarks/bench_newton.py

The problem is the twisted ring (``twisted_circle_problem``, C/A = 2/3, excess
link 1.0) at a slightly perturbed, non-planar state: the circle plus
``1e-3 L (cos 2 phi + 0.5 sin 3 phi)`` out of its plane, so that the twist
(writhe) terms of the gradient and Hessian are generic. Multipliers are the
least-squares ones at that state, as at the start of ``newton``.

One Newton step, as in the loop of :func:`supercoil.solvers.newton.newton`:

* assemble: gradient, constraints, constraint Jacobian (free DOFs) and the
  Hessian of the Lagrangian (``_hessian``: sparse part + rank-one twist term);
* factor+solve: ``KKTFactor(H, J)`` (SuperLU on the banded ordering, Woodbury
  for the rank-one term) and one ``factor.solve(rhs)``;
* inertia (separate column, not part of the step): the exact count
  ``factor.reduced_negative_count`` (block elimination, Haynsworth), which
  stability analysis and ``mode="minimize"`` Newton use.

Two more columns describe the computed step, not its cost: "neg. count" is
the reduced negative count returned by the timed inertia call, "backward
error" is the normwise backward error of the KKT solve.

Everything is warmed up first (JAX kernels compiled or loaded from the cache;
one untimed step at every N). Each column is the best of ``--repeat`` runs;
"step" is the best of the per-run sums assemble + factor+solve. The exponent
``p`` in ``time ~ N^p`` is fitted by least squares of log(time) against log(N)
over N = 1000 ... 10000 and over all N. The script exits with status 1 if the
step exponent over N = 1000 ... 10000 exceeds ``--max-exponent`` (1.15).

``--profile`` runs one step and one inertia count under cProfile at every N
and prints the functions with the largest own time.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import platform
import pstats
import sys
import time

import numpy as np
import scipy

from supercoil.problems.ring import twisted_circle_problem
from supercoil.solvers.kkt import KKTFactor
from supercoil.solvers.newton import _hessian, least_squares_multipliers
from supercoil.solvers.problem import free_dofs

SIZES = (100, 300, 1000, 3000, 10000)
FIT_FROM = 1000
TWIST_RATIO, EXCESS_LINK = 2.0 / 3.0, 1.0
BUMP = 1e-3
MAX_EXPONENT = 1.15


def perturbed_ring(n_nodes: int):
    """(problem, q, free, multipliers) at the perturbed, non-planar twisted ring."""
    problem, q = twisted_circle_problem(TWIST_RATIO, EXCESS_LINK, n_nodes)
    phi = 2.0 * np.pi * np.arange(n_nodes) / n_nodes
    points = q.reshape(-1, 3).copy()
    points[:, 2] += BUMP * problem.rod.length * (np.cos(2.0 * phi) + 0.5 * np.sin(3.0 * phi))
    q = points.ravel()
    problem.accept(q)  # reference directors carried to the perturbed tangents
    free = free_dofs(problem)
    return problem, q, free, least_squares_multipliers(problem, q, free)


def assemble(problem, q, free, lam):
    """Right-hand side, Hessian parts and Jacobian of one Newton-KKT step."""
    rhs = -np.concatenate([problem.gradient(q)[free], problem.constraints(q)])
    jacobian = problem.constraint_jacobian(q)[:, free]
    hessian = _hessian(problem, q, lam, free)
    return rhs, hessian, jacobian


def factor_solve(hessian, jacobian, rhs):
    factor = KKTFactor(hessian, jacobian)
    return factor, factor.solve(rhs)


def time_size(n_nodes: int, repeat: int) -> dict:
    """Best wall times (s) of the step's parts at ``n_nodes``, with sanity data."""
    problem, q, free, lam = perturbed_ring(n_nodes)
    rhs, hessian, jacobian = assemble(problem, q, free, lam)  # warm-up at this size
    factor, _ = factor_solve(hessian, jacobian, rhs)
    _ = factor.reduced_negative_count
    best = {"assemble": np.inf, "factor_solve": np.inf, "step": np.inf, "inertia": np.inf}
    for _ in range(repeat):
        t0 = time.perf_counter()
        rhs, hessian, jacobian = assemble(problem, q, free, lam)
        t1 = time.perf_counter()
        factor, sol = factor_solve(hessian, jacobian, rhs)
        t2 = time.perf_counter()
        negative = factor.reduced_negative_count  # computed on first use: a fresh count
        t3 = time.perf_counter()
        best["assemble"] = min(best["assemble"], t1 - t0)
        best["factor_solve"] = min(best["factor_solve"], t2 - t1)
        best["step"] = min(best["step"], t2 - t0)
        best["inertia"] = min(best["inertia"], t3 - t2)
    best["backward_error"] = backward_error(hessian, jacobian, sol, rhs)
    best["negative_count"] = negative
    return best


def backward_error(hessian, jacobian, sol: np.ndarray, rhs: np.ndarray) -> float:
    """Normwise backward error ``|K z - b| / (|K| |z| + |b|)`` (infinity norms) of a KKT solve.

    ``K = [[H, J^T], [J, 0]]`` with the rank-one terms of ``H`` included. The
    relative residual ``|K z - b| / |b|`` is not used: ``|K|`` grows like
    ``N^3`` (bending stiffness ``A / h^3``), so it measures conditioning, not
    the solver.
    """
    n = jacobian.shape[1]
    residual = (
        np.concatenate([hessian.matvec(sol[:n]) + jacobian.T @ sol[n:], jacobian @ sol[:n]]) - rhs
    )
    row_sums = np.asarray(abs(hessian.sparse).sum(axis=1)).ravel()
    for coefficient, vector in zip(hessian.coefficients, hessian.vectors):
        row_sums = row_sums + abs(coefficient) * np.abs(vector) * np.abs(vector).sum()
    row_sums = row_sums + np.asarray(abs(jacobian).sum(axis=0)).ravel()
    norm_k = max(float(row_sums.max()), float(abs(jacobian).sum(axis=1).max()))
    scale = norm_k * float(np.abs(sol).max()) + float(np.abs(rhs).max())
    return float(np.abs(residual).max() / scale)


def fit_exponent(sizes, times) -> float:
    """Least-squares slope of log(time) against log(N)."""
    return float(np.polyfit(np.log(sizes), np.log(times), 1)[0])


def _profile(function, top: int) -> str:
    profiler = cProfile.Profile()
    profiler.enable()
    function()
    profiler.disable()
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(top)
    return out.getvalue()


def profile_size(n_nodes: int, top: int) -> str:
    """cProfile of one step, then of one inertia count: functions with the most own time."""
    problem, q, free, lam = perturbed_ring(n_nodes)
    rhs, hessian, jacobian = assemble(problem, q, free, lam)
    factor_solve(hessian, jacobian, rhs)
    factors = []

    def step():
        step_rhs, step_hessian, step_jacobian = assemble(problem, q, free, lam)
        factors.append(factor_solve(step_hessian, step_jacobian, step_rhs)[0])

    report = f"--- cProfile, one Newton step, N = {n_nodes} ---\n" + _profile(step, top)
    report += f"--- cProfile, inertia count, N = {n_nodes} ---\n"
    return report + _profile(lambda: factors[0].reduced_negative_count, top)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="timed runs per N (best is kept)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="node counts")
    parser.add_argument(
        "--max-exponent",
        type=float,
        default=MAX_EXPONENT,
        help="fail if the step exponent over N >= 1000 exceeds this",
    )
    parser.add_argument("--profile", action="store_true", help="print a cProfile per N")
    parser.add_argument("--top", type=int, default=12, help="rows per profile")
    arguments = parser.parse_args()
    if arguments.repeat < 1:
        parser.error("--repeat must be >= 1")
    sizes = sorted(set(arguments.sizes))

    problem, q, free, lam = perturbed_ring(100)  # compile / load the JAX kernels
    rhs, hessian, jacobian = assemble(problem, q, free, lam)
    _ = factor_solve(hessian, jacobian, rhs)[0].reduced_negative_count

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} CPUs; Python {platform.python_version()}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}"
    )
    print(
        f"ring: C/A = {TWIST_RATIO:.4g}, excess link {EXCESS_LINK}, out-of-plane bump {BUMP} L; "
        f"best of {arguments.repeat} runs"
    )
    print()
    print(
        "| N | assemble (s) | factor+solve (s) | step total (s) | inertia (s) "
        "| neg. count | backward error |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|")
    rows = []
    for n_nodes in sizes:
        row = time_size(n_nodes, arguments.repeat)
        rows.append(row)
        print(
            f"| {n_nodes} | {row['assemble']:.4f} | {row['factor_solve']:.4f} | "
            f"{row['step']:.4f} | {row['inertia']:.4f} | {row['negative_count']} | "
            f"{row['backward_error']:.1e} |",
            flush=True,
        )
    print()

    columns = ("assemble", "factor_solve", "step", "inertia")
    large = [i for i, n in enumerate(sizes) if n >= FIT_FROM]
    step_exponent = float("nan")
    print("| fit of time ~ N^p | " + " | ".join(columns) + " |")
    print("|---|" + "---:|" * len(columns))
    ranges = [(f"N = {sizes[0]} … {sizes[-1]}", list(range(len(sizes))))]
    if len(large) >= 2 and len(large) < len(sizes):
        ranges.insert(0, (f"N = {sizes[large[0]]} … {sizes[large[-1]]}", large))
    for label, index in ranges:
        exponents = {
            c: fit_exponent([sizes[i] for i in index], [rows[i][c] for i in index]) for c in columns
        }
        if index == large:
            step_exponent = exponents["step"]
        print(f"| {label} | " + " | ".join(f"{exponents[c]:.3f}" for c in columns) + " |")
    print()

    if arguments.profile:
        for n_nodes in sizes:
            print(profile_size(n_nodes, arguments.top))

    if not np.isfinite(step_exponent):
        print(f"no fit over N >= {FIT_FROM}: give at least two such sizes")
        return 0
    if step_exponent > arguments.max_exponent:
        print(
            f"FAIL: step exponent {step_exponent:.3f} over N >= {FIT_FROM} exceeds "
            f"{arguments.max_exponent}"
        )
        return 1
    print(
        f"OK: step exponent {step_exponent:.3f} over N >= {FIT_FROM} is within "
        f"{arguments.max_exponent}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
