"""A hat curve of a magnetic tweezers experiment, in pN and nm.

A 600 bp DNA molecule pulled with 0.5 pN in 150 mM salt and turned: it stays
straight and twists until it buckles (Greenhill's condition for a clamped rod),
then forms a plectoneme whose extension falls linearly with the turns. Prints
extension (nm) and torque (pN nm) against turns and sigma. The model is
athermal: the extension before buckling is the full contour length.

    python examples/03_tweezers_hat_curve.py
"""

from __future__ import annotations

import supercoil as sc
from supercoil.units.tweezers import tweezers_parameters


def main(base_pairs: int = 600, force_pN: float = 0.5, nodes: int = 80,
         turns: float = 4.0) -> float:
    """Compute the branches; return the buckling turns of the straight molecule."""
    dna = sc.DNAPreset(base_pairs=base_pairs, salt_mM=150)
    numbers = tweezers_parameters(dna, force_pN)
    rod = sc.Rod(twist_ratio=numbers["twist_ratio"], nodes=nodes)
    problem = sc.Tweezers(rod, tension=numbers["tension"],
                          contact=sc.Barrier(numbers["length_over_diameter"]))
    result = sc.tweezers(problem, turns=(0.0, turns))
    print(result)
    lk0 = dna.relaxed_link
    for name, branch in result.branches.items():
        for i in range(0, len(branch), max(1, len(branch) // 6)):
            t = branch.parameter_values[i]
            print(f"{name:>16} turns {t:6.3f} (sigma {t / lk0:+.4f}): extension "
                  f"{dna.length_to_nm(branch.records['extension'][i]):7.1f} nm, torque "
                  f"{dna.torque_to_pN_nm(branch.records['torque'][i]):6.2f} pN nm")
    buckling = result.branches["straight"].points_of_kind("bifurcation")[0]
    return float(buckling.parameter)


if __name__ == "__main__":
    main()
