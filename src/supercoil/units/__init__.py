"""Units presets: physical input mapped onto the nondimensional model (A = 1, L = 1).

Only the DNA preset exists (:mod:`supercoil.units.dna`, docs/units.md). The
model is athermal: see :data:`supercoil.units.dna.ATHERMAL_CAVEAT`.
"""

from supercoil.units.dna import (
    ATHERMAL_CAVEAT,
    BENDING_PERSISTENCE_NM,
    DEFAULT_SALT_MM,
    EFFECTIVE_DIAMETER_TABLE,
    HELICAL_REPEAT_BP,
    KT_REFERENCE_PN_NM,
    REFERENCE_TEMPERATURE_K,
    RISE_NM_PER_BP,
    SALT_RANGE_MM,
    TWIST_PERSISTENCE_NM,
    DNAPreset,
    effective_diameter_nm,
    ring_summary_in_dna_units,
)

__all__ = [
    "ATHERMAL_CAVEAT",
    "BENDING_PERSISTENCE_NM",
    "DEFAULT_SALT_MM",
    "EFFECTIVE_DIAMETER_TABLE",
    "HELICAL_REPEAT_BP",
    "KT_REFERENCE_PN_NM",
    "REFERENCE_TEMPERATURE_K",
    "RISE_NM_PER_BP",
    "SALT_RANGE_MM",
    "TWIST_PERSISTENCE_NM",
    "DNAPreset",
    "effective_diameter_nm",
    "ring_summary_in_dna_units",
]
