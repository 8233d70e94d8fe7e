"""Human-readable tables of the ``supercoil`` command (rich)."""

from __future__ import annotations

from rich.table import Table


def _number(value: float, digits: int = 10) -> str:
    return f"{value:.{digits}g}"


def ring_table(summary: dict) -> Table:
    """A two-column table of a ring result (keys of ``RingResult.summary()``)."""
    table = Table(
        title=f"Twisted ring, C/A = {_number(summary['twist_ratio'], 6)}, "
        f"N = {summary['n_nodes']} (A = 1, L = 1)",
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
        ("determinant sign (seed 000)", f"{summary['determinant_sign']:+d}"),
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
    for name, value in rows:
        table.add_row(name, value)
    return table
