"""The bifurcation diagram of a DNA-like ring with self-contact (Coleman & Swigon 2000).

C/A = 2/3 and L/D = 122, as in their Figures 1-4: the twisted circle loses
stability at Michell's excess link (A/C) sqrt(3) = 2.598, where the alpha branch
(mode 2) bifurcates; alpha writhes until it touches itself, then continues with
self-contact. Prints the special points and draws excess link against writhe.

    python examples/01_ring_diagram.py
"""

from __future__ import annotations

import numpy as np

import supercoil as sc


def main(nodes: int = 132, max_excess_link: float = 3.0, contact_max_points: int = 300,
         figure: str | None = "ring_diagram.png") -> float:
    """Compute the diagram; return the excess link of the circle's first bifurcation."""
    rod = sc.Rod(twist_ratio=2 / 3, nodes=nodes)
    diagram = sc.ring_diagram(rod, sc.Barrier(length_over_diameter=122), modes=(2,),
                              max_excess_link=max_excess_link,
                              contact_max_points=contact_max_points)
    print(diagram)
    for p in diagram.special_points:
        print(f"{p.branch:>14} {p.kind:<24} dLk = {p.parameter:.5f}")
    if figure is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 4))
        for name, branch in diagram.branches.items():
            wr, dlk = branch.records["writhe"], branch.parameter_values
            ax.plot(wr, np.where(branch.stable, dlk, np.nan), "-", lw=2, label=name)
            ax.plot(wr, dlk, ":", lw=1, color=ax.lines[-1].get_color())
        ax.set_xlabel("writhe Wr (turns)")
        ax.set_ylabel("excess link ΔLk (turns)")
        ax.legend(frameon=False)
        fig.savefig(figure, dpi=150, bbox_inches="tight")
        print(f"wrote {figure}")
    circle = diagram.branches["circle"]
    return float(circle.points_of_kind("bifurcation")[0].parameter)


if __name__ == "__main__":
    main()
