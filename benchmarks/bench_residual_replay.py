"""Benchmark: the contact branch's residuals and step bounds replayed from captured states.

Run from the repository root (``OPENBLAS_NUM_THREADS=1``):

    python benchmarks/bench_residual_replay.py capture FILE
    PYTHONPATH=OLD/src python benchmarks/bench_residual_replay.py replay FILE [--passes 4]
    PYTHONPATH=NEW/src python benchmarks/bench_residual_replay.py replay FILE [--passes 4]

``capture`` runs the tweezers branches (C/A = 4/3, L/D = 33, F L^2/A = 75,
0 -> 5 turns, N = 100) and records, from the first residual of the contact branch
on, every call of ``ExtendedSystem.residual`` (its ``x``), ``ContactProblem.step_bound``
(its ``q, dq``) and ``ContactProblem.accept`` with their results, and the extended
system (with its problem) as it was before the first of them, pickled. ``replay``
unpickles that system and makes the same calls in the same order (the remembered
states and neighbour lists evolve as on the branch; accept moves the frames), a
warm-up pass then ``--passes`` timed ones, each from a fresh copy; it prints one JSON
line: the seconds spent in the residuals and in the step bounds per pass, their
counts, a pure-Python probe per pass (the host's speed) and the number of results
that differ from the captured ones bit for bit. Alternate processes of the two trees
to compare them on a noisy host.
"""

from __future__ import annotations

import argparse
import io
import json
import pickle
import time
import types

import numpy as np


def _bending_kernel(form, name):
    from supercoil.rod import kernels

    value, gradient, hessian = kernels.bending_kernels(form)
    return {"value": value, "gradient": gradient, "hessian": hessian}[name]


class _Pickler(pickle.Pickler):
    """Pickles the rod's bending closures (``kernels.bending_kernels``) by their form."""

    def reducer_override(self, obj):
        if isinstance(obj, types.FunctionType) \
                and obj.__qualname__.startswith("bending_kernels.<locals>."):
            cells = dict(zip(obj.__code__.co_freevars,
                             (c.cell_contents for c in obj.__closure__), strict=True))
            return _bending_kernel, (cells["form"], obj.__name__)
        return NotImplemented


def capture(path: str) -> None:
    from supercoil.contact.problem import ContactProblem
    from supercoil.continuation.system import ExtendedSystem
    from supercoil.problems.tweezers import TweezersOptions, tweezers_branches

    events, start = [], {}
    residual, step_bound, accept = (ExtendedSystem.residual, ContactProblem.step_bound,
                                    ContactProblem.accept)

    def recorded_residual(self, x):
        if isinstance(self.problem, ContactProblem) and not start:
            buffer = io.BytesIO()
            _Pickler(buffer, protocol=5).dump(self)
            start.update(system=buffer.getvalue(), id=id(self))
        out = residual(self, x)
        if start and id(self) == start["id"]:
            events.append(("residual", np.array(x), out.copy()))
        return out

    def recorded_step_bound(self, q, dq):
        out = step_bound(self, q, dq)
        if start:
            events.append(("step_bound", (np.array(q), np.array(dq)), out))
        return out

    def recorded_accept(self, q):
        if start:
            events.append(("accept", np.array(q), None))
        return accept(self, q)

    ExtendedSystem.residual = recorded_residual
    ContactProblem.step_bound = recorded_step_bound
    ContactProblem.accept = recorded_accept
    tweezers_branches(TweezersOptions(twist_ratio=4 / 3, length_over_diameter=33, tension=75,
                                      turns=(0, 5), n_nodes=100))
    with open(path, "wb") as f:
        pickle.dump({"system": start["system"], "events": events}, f)
    print(f"{len(events)} calls captured to {path}")


def _probe() -> float:
    start = time.perf_counter()
    total = 0
    for i in range(200_000):
        total += i * i
    return time.perf_counter() - start


def replay(path: str, passes: int) -> None:
    with open(path, "rb") as f:
        data = pickle.load(f)
    events = data["events"]
    out = {"residual_s": [], "step_bound_s": [], "probe_s": [], "mismatches": 0,
           "residuals": sum(e[0] == "residual" for e in events),
           "step_bounds": sum(e[0] == "step_bound" for e in events)}
    for k in range(passes + 1):
        system = pickle.loads(data["system"])
        problem = system.problem
        # memos whose layout a tree may have changed: recomputed at their first use
        problem.curve._sample_memo = None
        problem.base.__dict__.pop("_jacobian_layout", None)
        spent = {"residual": 0.0, "step_bound": 0.0}
        mismatches = 0
        for kind, arg, expected in events:
            if kind == "accept":
                problem.accept(arg)
                continue
            start = time.perf_counter()
            found = system.residual(arg) if kind == "residual" else problem.step_bound(*arg)
            spent[kind] += time.perf_counter() - start
            same = (np.array_equal(found, expected) and found.shape == expected.shape
                    if kind == "residual" else found == expected)
            mismatches += not same
        if k == 0:
            continue  # warm-up: numba's first use
        out["residual_s"].append(spent["residual"])
        out["step_bound_s"].append(spent["step_bound"])
        out["probe_s"].append(_probe())
        out["mismatches"] += mismatches
    print(json.dumps(out))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("capture", "replay"))
    parser.add_argument("file")
    parser.add_argument("--passes", type=int, default=4)
    args = parser.parse_args(argv)
    if args.command == "capture":
        capture(args.file)
    else:
        replay(args.file, args.passes)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
