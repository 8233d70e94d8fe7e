"""A DNA plasmid in base pairs and superhelical density: its supercoiled equilibrium.

A 700 bp plasmid at sigma = -0.06 in 150 mM monovalent salt (the DNA preset:
bending persistence 50 nm, twist persistence 95 nm, 0.34 nm and 1/10.5 turn per
bp, the effective diameter from the salt). The circle is unstable at this
excess link, so the ring writhes until it touches itself. The model is athermal:
the state is the elastic minimum, not a thermal average.

    python examples/02_dna_plasmid.py
"""

from __future__ import annotations

import supercoil as sc


def main(base_pairs: int = 700, sigma: float = -0.06, nodes: int = 120) -> float:
    """Compute the plasmid; return |Tw + Wr - dLk|, zero up to round-off."""
    dna = sc.DNAPreset(base_pairs=base_pairs, superhelical_density=sigma, salt_mM=150)
    rod = sc.Rod(twist_ratio=dna.twist_ratio, nodes=nodes)
    ring = sc.Ring(rod, excess_link=dna.excess_link,
                   contact=sc.Barrier(length_over_diameter=dna.length_over_diameter))
    eq = sc.equilibrium(ring)
    print(eq)
    print(f"{base_pairs} bp, sigma = {sigma:+.3f}: dLk = {dna.excess_link:.3f} turns, "
          f"L = {dna.length_nm:.0f} nm, D = {dna.effective_diameter_nm:.2f} nm")
    print(f"writhe {eq.writhe:+.3f}, twist {eq.twist:+.3f} turns; elastic energy "
          f"{dna.energy_to_kT(eq.energy):.1f} kT; closest approach "
          f"{eq.contacts['min_gap_over_diameter']:.3f} D")
    return abs(eq.twist + eq.writhe - dna.excess_link)


if __name__ == "__main__":
    main()
