"""Benchmark: the stiff sliding's dense eigenproblem, the LU basis against the reference.

Along the tweezers' contact branch of a pinned long rod (default L/D = 200,
lambda = 150, C/A = 1.5, N = 202: the plectoneme grows across fold pairs and the
unstable count is 1 or 2 at most points), the count leaves the sliding's eigenvalue out
by finding the negative eigenpairs of the constrained Hessian without the sliding's row
(:mod:`supercoil.stability.sliding_count`). The script follows the branch for
``--points`` points and records every such eigenproblem (``H``, ``J``, ``M``, ``k``),
then solves each ``--repeat`` times with
:func:`~supercoil.stability.eigen.lowest_dense_pairs` (the basis of ``ker J`` from the
LU factors of ``J^T``, the ``k`` lowest pairs only) and with the reference
:func:`~supercoil.stability.eigen.dense_constrained_eigenpairs` (an SVD null space, every
pair), alternated, on one BLAS thread. It prints the median milliseconds a call of each,
their ratio, the largest difference of the eigenvalues (relative to each, and to the
largest of the ``k``: the Hessian's entries reach 1e11 there, so an eigenvalue of -25
is known to about 1e-2 by either method) and the smallest singular value of the overlap
of the two sets of eigenvectors (1: the same subspace).

Run: ``python benchmarks/bench_sliding_eigen.py [--ld 200] [--lam 150] [--nodes 202]
[--points 450] [--every 4] [--repeat 3]`` (about 3 minutes; most of it the branch).
"""

from __future__ import annotations

import argparse
import importlib
import time

import numpy as np

from supercoil.problems.greenhill import critical_turns
from supercoil.problems.tweezers import TweezersOptions, tweezers_branches
from supercoil.stability.eigen import dense_constrained_eigenpairs, lowest_dense_pairs

sliding_count = importlib.import_module("supercoil.stability.sliding_count")


def captured(ld: float, lam: float, nodes: int, twist_ratio: float, points: int,
             every: int) -> list[tuple]:
    """Every ``every``-th eigenproblem of the sliding count along the branch."""
    seen: list[tuple] = []
    calls = [0]

    def recording(H, J, mass, k):
        if calls[0] % every == 0:
            seen.append((H, J, mass, k))
        calls[0] += 1
        return lowest_dense_pairs(H, J, mass, k)

    tension = lam**2
    options = TweezersOptions(loop_sliding=True, twist_ratio=twist_ratio,
                              length_over_diameter=ld, tension=tension, n_nodes=nodes,
                              turns=(0.0, 1.5 * critical_turns(twist_ratio, tension)),
                              max_points=points)
    sliding_count.lowest_dense_pairs = recording
    try:
        result = tweezers_branches(options)
    finally:
        sliding_count.lowest_dense_pairs = lowest_dense_pairs
    last = result.branches[-1]
    print(f"{last.name}: {len(last)} points to {last.parameter_values[-1]:.4f} turns; "
          f"{calls[0]} eigenproblems, {len(seen)} kept")
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ld", type=float, default=200.0)
    parser.add_argument("--lam", type=float, default=150.0)
    parser.add_argument("--nodes", type=int, default=202)
    parser.add_argument("--twist-ratio", type=float, default=1.5)
    parser.add_argument("--points", type=int, default=450)
    parser.add_argument("--every", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    cases = captured(args.ld, args.lam, args.nodes, args.twist_ratio, args.points,
                     args.every)
    if not cases:
        raise SystemExit("no eigenproblem of the sliding count met: more --points?")
    fast, reference = [], []
    worst_value, worst_scaled, worst_overlap = 0.0, 0.0, 1.0
    for H, J, mass, k in cases:
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            values, vectors = lowest_dense_pairs(H, J, mass, k)
            t1 = time.perf_counter()
            ref_values, ref_vectors = dense_constrained_eigenpairs(H, J, mass)
            t2 = time.perf_counter()
            fast.append(t1 - t0)
            reference.append(t2 - t1)
        ref_values, ref_vectors = ref_values[:k], ref_vectors[:, :k]
        difference = np.abs(values - ref_values)
        worst_value = max(worst_value, float(np.max(difference / np.abs(ref_values))))
        worst_scaled = max(worst_scaled, float(difference.max() / np.abs(ref_values).max()))
        overlap = np.linalg.svd(vectors.T @ (mass[:, None] * ref_vectors), compute_uv=False)
        worst_overlap = min(worst_overlap, float(overlap.min()))
    n, m = cases[0][2].size, cases[0][1].shape[0]
    f, r = 1e3 * np.median(fast), 1e3 * np.median(reference)
    print(f"{len(cases)} eigenproblems (n = {n}, m = {m}, ker J of {n - m} dimensions), "
          f"{args.repeat} alternated calls each")
    print(f"lowest_dense_pairs: {f:.1f} ms a call (median); reference: {r:.1f} ms; "
          f"ratio {r / f:.2f}")
    print(f"largest difference of the eigenvalues: {worst_value:.1e} of the eigenvalue, "
          f"{worst_scaled:.1e} of the largest of the k; smallest singular value of the "
          f"eigenvectors' overlap {worst_overlap:.9f}")


if __name__ == "__main__":
    main()
