"""Human-readable tables of the ``supercoil`` command (rich)."""

from __future__ import annotations

from rich.table import Table


def _number(value: float, digits: int = 10) -> str:
    return f"{value:.{digits}g}"


def ring_table(summary: dict, initial: str | None = None) -> Table:
    """A two-column table of a ring result (keys of ``RingResult.summary()``);
    ``initial``: the file of the starting curve, if not the circle. A summary
    in DNA units (``supercoil.units.dna.ring_summary_in_dna_units``) adds rows in
    bp, nm, kT and pN and the athermal caveat as the caption."""
    kind = "Twisted ring" if summary.get("contact_treatment") is None else "Supercoiled ring"
    dna = "base_pairs" in summary
    caption = None
    if dna:
        from supercoil.units.dna import ATHERMAL_CAVEAT

        kind = f"DNA {kind[0].lower()}{kind[1:]}, {summary['base_pairs']} bp"
        caption = ATHERMAL_CAVEAT
    table = Table(
        title=f"{kind}, C/A = {_number(summary['twist_ratio'], 6)}, "
        f"N = {summary['n_nodes']} (A = 1, L = 1)",
        caption=caption,
        show_header=False,
    )
    table.add_column("quantity", style="bold")
    table.add_column("value")
    stability = (
        "stable"
        if summary["stable"]
        else ("unstable" if summary["unstable_count"] else "marginal (zero modes)")
    )
    eigenvalues = ", ".join(f"{v:.4g}" for v in summary["lowest_eigenvalues"][:4])
    rows = [
        ("excess link (turns)", _number(summary["excess_link"])),
        ("twist (turns)", _number(summary["twist"])),
        ("writhe (turns)", _number(summary["writhe"])),
        ("|Tw + Wr - dLk|", f"{summary['link_error']:.2e}"),
        ("energy E*L/A", _number(summary["energy"])),
        ("exact circle energy", _number(summary["energy_circle_exact"])),
        (
            "stability",
            (
                f"{stability}: unstable_count {summary['unstable_count']}, "
                f"zero_modes {summary['zero_modes']}"
            ),
        ),
        ("determinant sign (Chamekh et al. 2014)", f"{summary['determinant_sign']:+d}"),
        ("lowest eigenvalues", eigenvalues),
        ("Michell threshold (A/C)sqrt(3)", _number(summary["michell_threshold_exact"])),
        (
            "Newton",
            (
                f"{summary['status']}, {summary['newton_iterations']} iterations, "
                f"residual {summary['residual']:.2e}"
            ),
        ),
    ]
    if summary.get("contact_treatment") is not None:
        gap = summary["min_gap_over_diameter"]
        rows += [
            ("started from", "the circle" if initial is None else initial),
            ("branch (quasi-static path)", _path_text(summary.get("path"))),
            ("L/D, contact treatment",
             f"{_number(summary['length_over_diameter'], 6)}, {summary['contact_treatment']}"),
            ("closest approach / D", "none within reach" if gap is None else _number(gap, 8)),
            ("contacts",
             (f"{summary['n_contact_points']} point(s), "
              f"{summary['n_contact_intervals']} interval(s)")),
            ("contact points (s1, s2, force)",
             "; ".join(f"({c['s1']:.4f}, {c['s2']:.4f}, {c['force']:.4g})"
                       for c in summary["contact_points"]) or "none"),
            ("contact intervals",
             "; ".join(f"[{c['s1_start']:.4f}, {c['s1_end']:.4f}] x "
                       f"[{c['s2_start']:.4f}, {c['s2_end']:.4f}], "
                       f"{c['force_per_length']:.4g} per length"
                       for c in summary["contact_intervals"]) or "none"),
        ]
    if dna:
        rows += _dna_rows(summary)
    if initial is not None:  # references that belong to the circle
        circle_rows = ("exact circle energy", "Michell threshold (A/C)sqrt(3)",
                       "circle buckles at sigma (Michell)")
        rows = [row for row in rows if row[0] not in circle_rows]
    for name, value in rows:
        table.add_row(name, value)
    return table


def _path_text(path: dict | None) -> str:
    """The branch a ring's answer is on and how the winding from dLk = 0 reached it."""
    if not path:
        return "not recorded"
    text = str(path.get("branch"))
    if path.get("snap_at") is not None:
        text += f", left the circle at dLk {path['snap_at']:.6g}"
    jumps = path.get("jumps") or []
    text += (f", jumped at dLk {', '.join(f'{j:.6g}' for j in jumps)}" if jumps
             else ", no jump")
    if path.get("restarts"):
        text += f", {path['restarts']} saddle(s) left along the unstable mode"
    return text


def _dna_rows(summary: dict) -> list[tuple[str, str]]:
    """Rows in DNA units (keys added by ``ring_summary_in_dna_units``)."""
    salt = summary["salt_mM"]
    diameter = f"D = {_number(summary['diameter_nm'], 4)} nm" + (
        f" ({_number(salt, 4)} mM salt)" if salt is not None else " (given)")
    rows = [
        ("DNA (preset dna)",
         (f"{summary['base_pairs']} bp, L = {_number(summary['length_nm'], 6)} nm, {diameter}, "
         f"T = {_number(summary['temperature_K'], 5)} K")),
        ("superhelical density sigma",
         (f"{_number(summary['superhelical_density'], 6)} "
         f"(Lk0 = {_number(summary['relaxed_link'], 6)} turns)")),
        ("energy (kT)", _number(summary["energy_kT"], 6)),
        ("circle buckles at sigma (Michell)",
         f"+/-{_number(summary['michell_threshold_superhelical_density'], 4)}"),
    ]
    if summary.get("contact_treatment") is not None:
        gap = summary.get("min_gap_nm")
        rows += [
            ("closest approach (nm)", "none within reach" if gap is None else _number(gap, 6)),
            ("contact forces (pN)",
             ", ".join(f"{c['force_pN']:.4g}" for c in summary["contact_points"]) or "none"),
        ]
    return rows
