"""A clamped Cosserat rod twisted at one end until it buckles and forms a loop.

The rod is clamped at both ends on the axis z, pulled by a small force and turned at
one end (the tweezers problem of supercoil.tweezers, here with the Cosserat model:
shear and extension). The straight rod, twisted uniformly and stretched by F L / EA,
buckles at Greenhill's condition (in the Kirchhoff limit); the buckled branch off
it gives up turns as its writhe grows, the rod coiling into a loop (the
problem of Chamekh, Mani-Aouadi & Moakher 2009). Without self-contact the loop may
pass through itself further on.

    python examples/06_cosserat_twisted_rod.py
"""

from __future__ import annotations

import numpy as np

import supercoil as sc


def main(nodes: int = 40, tension: float = 5.0, stiffness: float = 1e4,
         max_points: int = 80) -> float:
    """Twist the rod; return the turns at which the straight rod buckles."""
    rod = sc.CosseratRod(twist_ratio=0.8, stretch_stiffness=stiffness,
                         shear_stiffness=stiffness, nodes=nodes)
    run = sc.tweezers(sc.Tweezers(rod, tension=tension), (0.0, 3.0), max_points=max_points)
    straight, buckled = run.branches["straight"], run.branches["buckled"]
    onset = next(p for p in straight.points_of_kind("bifurcation") if p.count_before == 0)
    print(f"straight rod: extension {straight.records['extension'][0]:.6f} L "
          f"(1 + F/EA = {1 + tension / stiffness:.6f}); buckles at {onset.parameter:.4f} "
          f"turns")
    writhe = np.abs(buckled.records["writhe"])
    print(f"buckled branch: {len(buckled)} points, writhe up to {writhe.max():.3f} at "
          f"{buckled.parameter_values[np.argmax(writhe)]:.4f} turns")
    return float(onset.parameter)


if __name__ == "__main__":
    main()
