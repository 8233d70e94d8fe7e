"""The DNA units preset: base pairs, nm, pN, kT, salt and superhelical density.

The model is nondimensional (docs/model.md, "Nondimensional units"): bending stiffness
A = 1 and contour length L = 1, so an energy is E·L/A, a force F·L²/A, a
torque M·L/A and a length a fraction of L. :class:`DNAPreset` maps a DNA
molecule onto those numbers and converts results back:

* contour length ``L = N_bp · 0.34 nm``;
* bending stiffness ``A = P_b · kT_ref`` with ``P_b = 50 nm``;
* twist stiffness ``C = P_t · kT_ref`` with ``P_t = 95 nm`` (an option), so
  ``C/A = P_t/P_b = 1.9``;
* relaxed link ``Lk0 = N_bp / 10.5`` and excess link ``ΔLk = σ · Lk0``
  (σ, the superhelical density);
* tube diameter D from the monovalent salt concentration (a table, see
  :data:`EFFECTIVE_DIAMETER_TABLE`) or given directly;
* ``kT(T) = kT_ref · T / T_ref`` with ``kT_ref = 4.11 pN·nm`` at
  ``T_ref = 298 K``.

Temperature convention: A and C are *stiffnesses* (pN·nm²) fixed by the
persistence lengths at the reference temperature, ``A = P_b · kT_ref``; a
temperature T changes only kT, hence only the values expressed in kT (the
persistence length at T would be ``A / kT(T)``, which this athermal model
never uses). The nondimensional problem (C/A, ΔLk, L/D) does not depend on T.

**The model is athermal** (zero temperature): it has no entropic elasticity,
so an open molecule keeps its full contour length L before it buckles, and
buckling torques come out above the measured ones; a ring's writhe and
energy are those of the elastic minimum, not thermal averages
(:data:`ATHERMAL_CAVEAT`, shown wherever DNA units are).

Every constant is documented below with its source; docs/units.md has the
same table.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from dataclasses import dataclass

from supercoil import checks

PRESET_NAME = "dna"

# --- constants and their sources -------------------------------------------------

KT_REFERENCE_PN_NM = 4.11
"""kT at the reference temperature, pN·nm. k_B = 1.380649e-23 J/K (SI, exact
since 2019) gives k_B · 298 K = 4.114 pN·nm; 4.11 is the value conventionally
used in single-molecule work and the one this package fixes (0.1 % below)."""

REFERENCE_TEMPERATURE_K = 298.0
"""The temperature at which kT = :data:`KT_REFERENCE_PN_NM` (25 °C)."""

RISE_NM_PER_BP = 0.34
"""Rise per base pair of B-DNA, nm (3.4 Å: Watson & Crick 1953 from Franklin's
and Wilkins' fibre diagrams; Coleman & Swigon 2002 use 3.4 Å; the extensible
worm-like-chain fit of PMC33432, Fig. 2, uses 0.34 nm/bp)."""

HELICAL_REPEAT_BP = 10.5
"""Base pairs per helical turn of relaxed B-DNA in solution (Wang 1979, PNAS
76:200, about 10.4-10.6 depending on conditions; 10.5 is the conventional
value). Lk0 = N_bp / 10.5."""

BENDING_PERSISTENCE_NM = 50.0
"""Bending persistence length P_b, nm (A = P_b · kT). About 50 nm in 0.1 M
monovalent salt: Hagerman 1988 (Annu. Rev. Biophys. Biophys. Chem. 17:265),
Bustamante et al. 1994 (Science 265:1599); PMC33432, Fig. 2, fits 50 nm at
100 mM Na+."""

TWIST_PERSISTENCE_NM = 95.0
"""Twist persistence length P_t, nm (C = P_t · kT); 95 nm by default, an
option of the preset. Published estimates range from about 75 to 120 nm, e.g. Bryant et al.
2003 (Nature 424:338, Fig. 3) measure C = 4.1e2 pN·nm² (linear fit; 4.4e2 from
twist fluctuations), i.e. P_t = 410 / 4.11 = 100 nm; Moroz & Nelson 1997
(PNAS 94:14418) fit 120 nm and Moroz & Nelson 1998 (Macromolecules 31:6333)
109 nm to Strick et al.'s extension data."""

STRETCH_MODULUS_PN = 1100.0
"""Stretch modulus S = EA of B-DNA, pN, the Cosserat rod's extension stiffness:
measured about 1000-1100 pN in 150 mM salt (Smith, Cui & Bustamante 1996, Science
271:795; Wang, Yin, Landick, Gelles & Block 1997, Biophys. J. 72:1335, about 1200)."""

HELIX_DIAMETER_NM = 2.0
"""Geometric diameter of the double helix, nm: the section whose slenderness L/D
sets the Cosserat rod's shear stiffness (a solid circular section, Cowper's shear
coefficient; the shear modulus of DNA is not measured directly)."""

DEFAULT_SALT_MM = 150.0
"""Monovalent salt concentration used when neither salt nor diameter is
given (about physiological ionic strength)."""

EFFECTIVE_DIAMETER_TABLE: tuple[tuple[float, float], ...] = (
    (10.0, 15.0),
    (20.0, 11.0),
    (50.0, 7.0),
    (100.0, 5.0),
    (200.0, 3.8),
)
"""Effective (electrostatic hard-core) diameter of DNA against NaCl
concentration: ``(c in mM, D in nm)``.

Intended source: Rybenkov, Cozzarelli & Vologodskii 1993 (PNAS 90:5307),
knotting probabilities of P22 DNA against NaCl, which agree with Stigter's
(1977) Poisson-Boltzmann effective diameters; Vologodskii & Cozzarelli's
simulations use the same values. **These numbers are approximate and were
not checked against the paper's table or figure**: no copy of it could be
found while this table was written (see docs/units.md). They have the right
size and trend (about 5 nm near physiological salt, growing roughly like the
Debye length at low salt) but may be off by 10-20 %; pass ``diameter_nm``
(``--diameter-nm``) to set D from a source you trust. Monovalent salt only.
"""

SALT_TABLE_NOTE = (
    "approximate values after Rybenkov, Cozzarelli & Vologodskii 1993 (PNAS 90:5307) and "
    "Stigter 1977, not verified against the published table; give diameter_nm "
    "(--diameter-nm) to set D from a trusted source"
)

ATHERMAL_CAVEAT = (
    "Athermal model (zero temperature): no entropic elasticity, so extension is the full "
    "contour length L before buckling, buckling torques exceed measured ones, and energies "
    "and writhes are those of the elastic minimum, not thermal averages."
)

SOURCES: dict[str, str] = {
    "kT_pN_nm": "4.11 pN nm at 298 K (k_B T with k_B = 1.380649e-23 J/K gives 4.114; 4.11 "
    "by convention); kT(T) = 4.11 * T / 298",
    "rise_nm_per_bp": "B-DNA rise 3.4 A (Watson & Crick 1953; Coleman & Swigon 2002)",
    "helical_repeat_bp": "relaxed B-DNA in solution, about 10.5 bp per turn (Wang 1979, PNAS "
    "76:200)",
    "bending_persistence_nm": "about 50 nm (Hagerman 1988; Bustamante et al. 1994, Science "
    "265:1599)",
    "twist_persistence_nm": "95 nm (the default); measured 100 nm (Bryant et al. 2003, Nature "
    "424:338: C = 410 pN nm^2), 109-120 nm (Moroz & Nelson 1997, 1998)",
    "effective_diameter": "monovalent salt table, " + SALT_TABLE_NOTE,
}

SALT_RANGE_MM = (EFFECTIVE_DIAMETER_TABLE[0][0], EFFECTIVE_DIAMETER_TABLE[-1][0])


def effective_diameter_nm(salt_mM: float) -> float:
    """Effective DNA diameter (nm) at a monovalent salt concentration ``salt_mM`` (mM).

    Linear in D against ``log(c)`` between the points of
    :data:`EFFECTIVE_DIAMETER_TABLE` (so the tabulated points are returned
    exactly and D decreases monotonically with c); a concentration outside the
    table is a ValueError (no extrapolation).
    """
    c = checks.number("salt_mM", salt_mM, meaning="salt concentration in mM")
    lo, hi = SALT_RANGE_MM
    if not lo <= c <= hi:
        raise checks.refuse(
            "salt_mM", f"{c:g} (salt concentration in mM) is outside the tabulated range {lo:g}-{hi:g} mM of "
            "monovalent salt (effective diameters are not extrapolated); give a concentration "
            f"from {lo:g} to {hi:g} mM, or the diameter itself in nm"
        )
    concentrations = [point[0] for point in EFFECTIVE_DIAMETER_TABLE]
    k = bisect_left(concentrations, c)
    c1, d1 = EFFECTIVE_DIAMETER_TABLE[k]
    if c == c1:
        return d1
    c0, d0 = EFFECTIVE_DIAMETER_TABLE[k - 1]
    t = math.log(c / c0) / math.log(c1 / c0)
    return d0 + t * (d1 - d0)


def _number(what: str, value: object) -> float:
    return checks.number(what, value)


def _positive(what: str, value: object) -> float:
    return checks.number(what, value, 0.0, low_open=True)


@dataclass(frozen=True)
class DNAPreset:
    """A DNA molecule in physical units and its nondimensional model (A = 1, L = 1).

    ``base_pairs``: number of base pairs N_bp (a whole number from 12 to 1e7).
    ``superhelical_density``: σ = ΔLk / Lk0 (finite; 0 = relaxed).
    ``salt_mM``: monovalent salt (mM) giving the tube diameter through
    :func:`effective_diameter_nm`; ``diameter_nm``: the diameter itself. At
    most one of the two; with neither, the salt is :data:`DEFAULT_SALT_MM`.
    ``temperature_K``: temperature of the kT unit (> 0).
    The remaining fields are the constants of the module, overridable.

    Immutable and validated on construction: an :class:`~supercoil.errors.InputError`
    naming the field, what is wrong and what is valid (``base_pairs`` from 12 to
    1e7, ``superhelical_density`` from -1 to 1, a ring longer than pi diameters).
    """

    base_pairs: int
    superhelical_density: float = 0.0
    salt_mM: float | None = None
    diameter_nm: float | None = None
    temperature_K: float = REFERENCE_TEMPERATURE_K
    bending_persistence_nm: float = BENDING_PERSISTENCE_NM
    twist_persistence_nm: float = TWIST_PERSISTENCE_NM
    rise_nm_per_bp: float = RISE_NM_PER_BP
    helical_repeat_bp: float = HELICAL_REPEAT_BP
    stretch_modulus_pN: float = STRETCH_MODULUS_PN

    name = PRESET_NAME

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "base_pairs", checks.integer("base_pairs", self.base_pairs,
                                                checks.MIN_BASE_PAIRS, checks.MAX_BASE_PAIRS))
        checks.number("superhelical_density", self.superhelical_density, -1.0, 1.0,
                      meaning="sigma = dLk / Lk0; -1 unwinds the double helix completely")
        _positive("temperature_K", self.temperature_K)
        for field in ("bending_persistence_nm", "twist_persistence_nm", "rise_nm_per_bp",
                      "helical_repeat_bp", "stretch_modulus_pN"):
            _positive(field, getattr(self, field))
        if self.salt_mM is not None and self.diameter_nm is not None:
            raise checks.refuse("salt_mM", "and diameter_nm both set the tube diameter: give "
                                "one of them (the diameter comes from the salt unless given)")
        if self.diameter_nm is not None:
            _positive("diameter_nm", self.diameter_nm)
        else:
            if self.salt_mM is None:
                set_(self, "salt_mM", DEFAULT_SALT_MM)
            effective_diameter_nm(self.salt_mM)  # range check
        lod, bp = self.length_over_diameter, self.base_pairs
        if lod <= math.pi:
            fewest = math.floor(math.pi * self.effective_diameter_nm / self.rise_nm_per_bp) + 1
            raise checks.refuse("base_pairs", f"= {bp} gives a molecule {self.length_nm:g} nm "
                                f"long, L/D = {lod:.3g} with a tube of diameter "
                                f"{self.effective_diameter_nm:.3g} nm, but a ring needs L/D > "
                                f"pi: give base_pairs >= {fewest}")
        if lod > checks.MAX_MAGNITUDE:
            raise checks.refuse("base_pairs", f"= {bp} gives L/D = {lod:.3g} with a tube of "
                                f"diameter {self.effective_diameter_nm:.3g} nm; L/D must be "
                                f"at most {checks.MAX_MAGNITUDE:g}: give fewer base pairs or a "
                                "larger diameter")
        if self.twist_ratio > checks.MAX_MAGNITUDE:
            raise checks.refuse("twist_persistence_nm", f"gives C/A = {self.twist_ratio:.3g}; "
                                f"C/A must be at most {checks.MAX_MAGNITUDE:g}")

    # --- physical quantities ---------------------------------------------------

    @property
    def length_nm(self) -> float:
        """Contour length L = N_bp · rise (nm)."""
        return self.base_pairs * self.rise_nm_per_bp

    @property
    def kT_pN_nm(self) -> float:
        """kT at ``temperature_K``: kT_ref · T / T_ref (pN·nm)."""
        return KT_REFERENCE_PN_NM * self.temperature_K / REFERENCE_TEMPERATURE_K

    @property
    def bending_stiffness_pN_nm2(self) -> float:
        """A = P_b · kT_ref (pN·nm²), fixed at the reference temperature."""
        return self.bending_persistence_nm * KT_REFERENCE_PN_NM

    @property
    def twist_stiffness_pN_nm2(self) -> float:
        """C = P_t · kT_ref (pN·nm²), fixed at the reference temperature."""
        return self.twist_persistence_nm * KT_REFERENCE_PN_NM

    @property
    def stretch_stiffness(self) -> float:
        """The Cosserat rod's ``EA L^2 / A`` from the stretch modulus (nondimensional)."""
        return self.stretch_modulus_pN * self.length_nm**2 / self.bending_stiffness_pN_nm2

    @property
    def section_slenderness(self) -> float:
        """``L / d`` with ``d`` the double helix's diameter (:data:`HELIX_DIAMETER_NM`):
        the Cosserat rod's section, which sets its shear stiffness."""
        return self.length_nm / HELIX_DIAMETER_NM

    @property
    def effective_diameter_nm(self) -> float:
        """Tube diameter D (nm): ``diameter_nm`` if given, else from the salt table."""
        if self.diameter_nm is not None:
            return float(self.diameter_nm)
        return effective_diameter_nm(self.salt_mM)

    @property
    def relaxed_link(self) -> float:
        """Lk0 = N_bp / helical repeat (turns)."""
        return self.base_pairs / self.helical_repeat_bp

    # --- the nondimensional model ----------------------------------------------

    @property
    def twist_ratio(self) -> float:
        """C/A = P_t / P_b."""
        return self.twist_persistence_nm / self.bending_persistence_nm

    @property
    def excess_link(self) -> float:
        """ΔLk = σ · Lk0 (turns)."""
        return self.superhelical_density * self.relaxed_link

    @property
    def length_over_diameter(self) -> float:
        """L / D."""
        return self.length_nm / self.effective_diameter_nm

    @property
    def length_over_persistence(self) -> float:
        """L / P_b (contour length in bending persistence lengths)."""
        return self.length_nm / self.bending_persistence_nm

    def ring_parameters(self) -> dict[str, float]:
        """Keyword arguments of ``solve_supercoiled_ring``: C/A, ΔLk (turns) and L/D."""
        return {"twist_ratio": self.twist_ratio, "excess_link": self.excess_link,
                "length_over_diameter": self.length_over_diameter}

    # --- scales: one nondimensional unit in physical units ---------------------

    @property
    def energy_scale_kT(self) -> float:
        """A / L in kT at ``temperature_K`` (= P_b / L at the reference temperature)."""
        return self.bending_stiffness_pN_nm2 / self.length_nm / self.kT_pN_nm

    @property
    def force_scale_pN(self) -> float:
        """A / L² in pN (the force of F·L²/A = 1)."""
        return self.bending_stiffness_pN_nm2 / self.length_nm**2

    @property
    def torque_scale_pN_nm(self) -> float:
        """A / L in pN·nm (the torque of M·L/A = 1)."""
        return self.bending_stiffness_pN_nm2 / self.length_nm

    # --- converters ---------------------------------------------------------------

    def length_to_nm(self, length: float) -> float:
        """A length in units of L (a fraction of L) to nm."""
        return length * self.length_nm

    def length_from_nm(self, length_nm: float) -> float:
        """A length in nm to units of L."""
        return length_nm / self.length_nm

    def energy_to_kT(self, energy: float) -> float:
        """E·L/A to kT at ``temperature_K``."""
        return energy * self.energy_scale_kT

    def energy_from_kT(self, energy_kT: float) -> float:
        """kT at ``temperature_K`` to E·L/A."""
        return energy_kT / self.energy_scale_kT

    def force_to_pN(self, force: float) -> float:
        """F·L²/A to pN."""
        return force * self.force_scale_pN

    def force_from_pN(self, force_pN: float) -> float:
        """pN to F·L²/A."""
        return force_pN / self.force_scale_pN

    def force_per_length_to_pN_per_nm(self, force_per_length: float) -> float:
        """A line force (F·L²/A per unit of L, i.e. f·L³/A) to pN/nm."""
        return force_per_length * self.force_scale_pN / self.length_nm

    def torque_to_pN_nm(self, torque: float) -> float:
        """M·L/A to pN·nm."""
        return torque * self.torque_scale_pN_nm

    def torque_from_pN_nm(self, torque_pN_nm: float) -> float:
        """pN·nm to M·L/A."""
        return torque_pN_nm / self.torque_scale_pN_nm

    def superhelical_density_of(self, excess_link: float) -> float:
        """σ = ΔLk / Lk0 of an excess link in turns."""
        return excess_link / self.relaxed_link

    # --- records -----------------------------------------------------------------

    def record(self) -> dict:
        """The constants and inputs used, with their sources (for JSON provenance)."""
        return {
            "name": self.name,
            "base_pairs": self.base_pairs,
            "superhelical_density": float(self.superhelical_density),
            "salt_mM": None if self.salt_mM is None else float(self.salt_mM),
            "diameter_nm_given": None if self.diameter_nm is None else float(self.diameter_nm),
            "temperature_K": float(self.temperature_K),
            "kT_pN_nm": self.kT_pN_nm,
            "kT_reference_pN_nm": KT_REFERENCE_PN_NM,
            "reference_temperature_K": REFERENCE_TEMPERATURE_K,
            "bending_persistence_nm": float(self.bending_persistence_nm),
            "twist_persistence_nm": float(self.twist_persistence_nm),
            "rise_nm_per_bp": float(self.rise_nm_per_bp),
            "helical_repeat_bp": float(self.helical_repeat_bp),
            "bending_stiffness_pN_nm2": self.bending_stiffness_pN_nm2,
            "stretch_modulus_pN": float(self.stretch_modulus_pN),
            "twist_stiffness_pN_nm2": self.twist_stiffness_pN_nm2,
            "length_nm": self.length_nm,
            "diameter_nm": self.effective_diameter_nm,
            "relaxed_link": self.relaxed_link,
            "energy_scale_kT": self.energy_scale_kT,
            "force_scale_pN": self.force_scale_pN,
            "torque_scale_pN_nm": self.torque_scale_pN_nm,
            "salt_table_mM_nm": [list(point) for point in EFFECTIVE_DIAMETER_TABLE],
            "salt_table_note": SALT_TABLE_NOTE,
            "sources": dict(SOURCES),
            "athermal": ATHERMAL_CAVEAT,
        }

    def conventions(self) -> dict[str, str]:
        """Conventions added to a JSON file written in this preset's units."""
        return {
            "units_preset": (
                "dna: the unsuffixed keys keep their nondimensional meaning (A = 1, L = 1); "
                "keys ending in _nm, _kT, _pN, _pN_nm, _pN_per_nm are the same quantities in "
                "physical units, from the constants in provenance.units_preset "
                "(A = P_b kT_ref, C = P_t kT_ref at the reference temperature; energies in kT "
                "at temperature_K)"
            ),
            "superhelical_density": "sigma = excess_link / relaxed_link, relaxed_link = "
            "base_pairs / helical repeat (turns)",
            "athermal": ATHERMAL_CAVEAT,
        }


def ring_summary_in_dna_units(summary: dict, preset: DNAPreset) -> dict:
    """A ring summary (``RingResult.summary()`` keys) with DNA-unit keys added.

    Adds ``base_pairs``, ``superhelical_density``, ``relaxed_link``, ``length_nm``,
    ``diameter_nm``, ``salt_mM``, ``temperature_K``, ``kT_pN_nm``, ``energy_kT``,
    ``energy_circle_exact_kT``, ``michell_threshold_superhelical_density``,
    ``min_gap_nm`` (the closest centre-line approach, min_gap_over_diameter · D)
    and, inside contact entries, ``force_pN`` and ``force_per_length_pN_per_nm``.
    Returns a new dict; the nondimensional keys and their values are unchanged.
    """
    out = dict(summary)
    out.update({
        "base_pairs": preset.base_pairs,
        "superhelical_density": float(preset.superhelical_density),
        "relaxed_link": preset.relaxed_link,
        "length_nm": preset.length_nm,
        "diameter_nm": preset.effective_diameter_nm,
        "salt_mM": None if preset.salt_mM is None else float(preset.salt_mM),
        "temperature_K": float(preset.temperature_K),
        "kT_pN_nm": preset.kT_pN_nm,
        "energy_kT": preset.energy_to_kT(summary["energy"]),
    })
    if "energy_circle_exact" in summary:
        out["energy_circle_exact_kT"] = preset.energy_to_kT(summary["energy_circle_exact"])
    if "michell_threshold_exact" in summary:
        out["michell_threshold_superhelical_density"] = preset.superhelical_density_of(
            summary["michell_threshold_exact"])
    if "min_gap_over_diameter" in summary:
        gap = summary["min_gap_over_diameter"]
        out["min_gap_nm"] = None if gap is None else gap * preset.effective_diameter_nm
    for key in ("contacts", "contact_points"):
        if key in summary:
            out[key] = [{**c, "force_pN": preset.force_to_pN(c["force"])} for c in summary[key]]
    if "contact_intervals" in summary:
        out["contact_intervals"] = [
            {**c, "force_per_length_pN_per_nm":
             preset.force_per_length_to_pN_per_nm(c["force_per_length"])}
            for c in summary["contact_intervals"]
        ]
    return out
