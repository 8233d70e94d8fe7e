"""Figure of the twisted ring's energy and stability against the excess link.

Plotting never computes: every value drawn is passed in.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np


def plot_ring_stability(
    path: str | os.PathLike,
    *,
    excess_link: Sequence[float],
    energy: Sequence[float],
    unstable_count: Sequence[int],
    exact_excess_link: Sequence[float],
    exact_energy: Sequence[float],
    thresholds_exact: Mapping[int, float],
    thresholds_computed: Mapping[int, float],
    count_above: Mapping[int, int],
    twist_ratio: float,
    n_nodes: int,
) -> None:
    """Write a two-panel PNG to ``path``.

    Left: computed energies ``E L / A`` (markers) beside the exact curve of the
    twisted circle (line). Right: ``unstable_count`` at the sampled excess
    links (markers) and as a step plot whose jumps sit at the computed
    thresholds (the count is ``count_above[m]`` from ``thresholds_computed[m]``
    on), with the exact Michell thresholds (dashed) for each mode ``m``.
    """
    from matplotlib.figure import Figure

    excess_link = np.asarray(excess_link, dtype=float)
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax_energy, ax_count = fig.subplots(1, 2)

    ax_energy.plot(
        exact_excess_link,
        exact_energy,
        color="0.6",
        lw=2,
        label=r"exact circle $2\pi^2(1 + (C/A)\,\Delta Lk^2)$",
    )
    ax_energy.plot(excess_link, energy, "o", ms=4, color="C0", label=f"computed, N = {n_nodes}")
    ax_energy.set_xlabel(r"excess link $\Delta Lk$ (turns)")
    ax_energy.set_ylabel(r"energy $E\,L/A$")
    ax_energy.set_title("Energy of the twisted ring")
    ax_energy.legend(loc="upper left", fontsize="small")

    # The step joins the samples and the computed thresholds, where the count changes.
    steps = sorted(
        [*zip(excess_link, unstable_count, strict=True)]
        + [(thresholds_computed[m], count_above[m]) for m in thresholds_computed]
    )
    ax_count.step(
        [x for x, _ in steps],
        [c for _, c in steps],
        where="post",
        color="C0",
        label=f"unstable_count, N = {n_nodes}",
    )
    ax_count.plot(excess_link, unstable_count, "o", ms=4, color="C0")
    for index, (mode, value) in enumerate(sorted(thresholds_exact.items())):
        ax_count.axvline(
            value,
            color="C3",
            ls="--",
            lw=1,
            label="exact Michell $(A/C)\\sqrt{m^2-1}$" if index == 0 else None,
        )
        ax_count.annotate(
            f"m = {mode}",
            (value, 0.98),
            xycoords=("data", "axes fraction"),
            ha="right",
            va="top",
            rotation=90,
            fontsize="small",
            color="C3",
        )
    top = max([int(np.max(unstable_count, initial=0)), 2])
    ax_count.set_yticks(range(0, top + 1, 2))
    ax_count.set_ylim(-0.3, top + 0.8)
    ax_count.set_xlabel(r"excess link $\Delta Lk$ (turns)")
    ax_count.set_ylabel("unstable_count")
    ax_count.set_title("Stability of the circle (pair crossings)")
    ax_count.legend(loc="center left", fontsize="small")

    fig.suptitle(f"Twisted ring, C/A = {twist_ratio:.4g}, nondimensional (A = 1, L = 1)")
    fig.savefig(path, dpi=120)
