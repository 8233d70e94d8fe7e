"""Two speed-ups of the continuation measured alone on the tweezers' problem (N = 100, L/D = 33,
C/A = 4/3, F L^2/A = 75, 0 -> 5 turns), each against its absence, alternated in one process.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_tweezers_switches.py [--repeat K]
[--only chord|derivative]``. Prints the smallest and the median process CPU time of
:func:`~supercoil.problems.tweezers.tweezers_branches` with and without

* ``chord``: the corrector's chord steps (``step.CHORD_BELOW`` set to 0
  turns them off: no iterate is then below the threshold);
* ``derivative``: the clamped rod's exact ``parameter_derivative`` (without it the
  continuation takes its central difference of two residuals).

One warm-up run first; then ``K`` rounds (default 6), each running both settings.
"""

from __future__ import annotations

import argparse
import time

from supercoil.continuation import step
from supercoil.problems import tweezers
from supercoil.rod.open import ClampedRodEnergy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=6)
    parser.add_argument("--only", choices=("chord", "derivative"))
    args = parser.parse_args()
    options = tweezers.TweezersOptions(twist_ratio=4 / 3, length_over_diameter=33,
                                       tension=75, turns=(0, 5), n_nodes=100)
    exact = ClampedRodEnergy.parameter_derivative
    chord_below = step.CHORD_BELOW

    def setting(chord: bool, derivative: bool) -> None:
        step.CHORD_BELOW = chord_below if chord else 0.0
        ClampedRodEnergy.parameter_derivative = exact if derivative else (
            lambda self, q, multipliers, parameter: None)

    switches = [args.only] if args.only else ["chord", "derivative"]
    tweezers.tweezers_branches(options)  # warm-up: numba's kernels, memoised layouts
    for switch in switches:
        times: dict[bool, list[float]] = {True: [], False: []}
        for _ in range(args.repeat):
            for on in (True, False):
                setting(chord=on if switch == "chord" else True,
                        derivative=on if switch == "derivative" else True)
                start = time.process_time()
                tweezers.tweezers_branches(options)
                times[on].append(time.process_time() - start)
        setting(True, True)
        for on in (True, False):
            values = sorted(times[on])
            print(f"{switch} {'on ' if on else 'off'}: CPU min {values[0]:.3f} median "
                  f"{values[len(values) // 2]:.3f} s ({', '.join(f'{v:.2f}' for v in times[on])})",
                  flush=True)


if __name__ == "__main__":
    main()
