"""Benchmark: the Cosserat ring's diagram against the Kirchhoff ring's, and one Newton step in N.

Run from the repository root:

    python benchmarks/bench_cosserat.py [--nodes 200] [--modes 2] [--stiffness 1e5]

Both diagrams are computed in one run, at C/A = 2/3 and L/D = 122 (Coleman &
Swigon 2000's DNA example): the circle and the primary branches of ``--modes``
without contact up to their first contact (for the Kirchhoff rod the contact
branches are cut to two points and not counted). It prints the processor time of
those branches for each model (a loaded host distorts it less than wall time) and
their ratio (target: the Cosserat diagram at N = 200 in at most three times the
Kirchhoff one's), after one warm-up run of each at N = 24 (numba caches). Then the
time of one Newton step of the Cosserat ring (gradient, the symmetrised Hessian, its
factorisation) at N, 2N and 4N: it should grow linearly.

BLAS threads count in the processor time; on a shared host run it with
``OPENBLAS_NUM_THREADS=1`` (measured: a (1200, 8) QR in the stability's symmetry
basis took 20 ms with OpenBLAS's threads on a loaded two-core host, 0.1 ms without).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


class Segments:
    """Processor seconds between the progress messages of a diagram: each message starts a
    segment, which counts when the message announces the circle or a branch without
    contact (the Kirchhoff diagram's contact branches are not compared)."""

    def __init__(self):
        self.marks: list[tuple[float, str]] = []

    def __call__(self, message: str) -> None:
        self.marks.append((time.process_time(), message))

    def contact_free(self, end: float) -> float:
        times = [t for t, _ in self.marks] + [end]
        return sum(times[i + 1] - times[i] for i, (_, message) in enumerate(self.marks)
                   if message.startswith("circle") or message.endswith("no contact"))


def diagrams(nodes: int, modes: tuple[int, ...], stiffness: float) -> dict[str, float]:
    """Processor seconds of the contact-free branches of each model's diagram."""
    from supercoil.problems.cosserat_ring_diagram import cosserat_ring_diagram
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram

    options = DiagramOptions(2 / 3, 122.0, nodes, modes, max_excess_link=6.0,
                             contact_max_points=2)
    names = ["circle", *("alpha" if m == 2 else "beta" if m == 3 else f"mode{m}"
                         for m in modes)]
    out = {}
    results = {}
    for label, compute in (("kirchhoff", lambda say: ring_diagram(options, say)),
                           ("cosserat", lambda say: cosserat_ring_diagram(
                               options, stiffness, stiffness, say))):
        segments = Segments()
        results[label] = compute(segments)
        out[label] = segments.contact_free(time.process_time())
    for label, diagram in results.items():
        for name in names:
            try:
                branch = diagram.branch(name)
            except KeyError:
                continue
            print(f"  {label:9s} {name:6s} {len(branch):4d} points, dLk "
                  f"{branch.parameter_values[0]:.4f} -> {branch.parameter_values[-1]:.4f}, "
                  f"{diagram.seconds.get(name, float('nan')):.2f} s (wall)")
    return out


def newton_step(nodes: int, repeat: int = 3) -> float:
    """Best of ``repeat`` times of gradient + Hessian + sparse LU of the Cosserat ring."""
    import scipy.sparse.linalg as spla

    from supercoil.cosserat.ring import ring_problem
    from supercoil.solvers.problem import free_dofs

    problem = ring_problem(2 / 3, 1.0, nodes, 1e5, 1e5)
    q = problem.initial_state()
    free = free_dofs(problem)
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        g = problem.gradient(q)[free]
        H = problem.hessian(q).sparse.tocsc()[free][:, free]
        spla.splu(H.tocsc()).solve(-g)
        best = min(best, time.perf_counter() - start)
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200)
    parser.add_argument("--modes", default="2")
    parser.add_argument("--stiffness", type=float, default=1e5,
                        help="EA L^2/A = GA L^2/A of the Cosserat rod")
    args = parser.parse_args(argv)
    modes = tuple(int(m) for m in args.modes.split(","))
    print("warm-up at N = 24")
    diagrams(24, modes, args.stiffness)
    print(f"N = {args.nodes}, modes {args.modes}, EA = GA = {args.stiffness:g} A/L^2")
    seconds = diagrams(args.nodes, modes, args.stiffness)
    ratio = seconds["cosserat"] / seconds["kirchhoff"]
    print(f"contact-free branches (CPU): Kirchhoff {seconds['kirchhoff']:.2f} s, Cosserat "
          f"{seconds['cosserat']:.2f} s, ratio {ratio:.2f} (target <= 3)")
    steps = {n: newton_step(n) for n in (args.nodes, 2 * args.nodes, 4 * args.nodes)}
    print("one Newton step of the Cosserat ring: " + ", ".join(
        f"N = {n}: {t * 1e3:.1f} ms" for n, t in steps.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
