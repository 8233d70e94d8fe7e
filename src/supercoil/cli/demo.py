"""``supercoil demo``: energy and stability of the twisted ring against the excess link.

Calls the ring API for a grid of excess links and the discrete Michell
thresholds, then hands the numbers to :mod:`supercoil.plotting` and
:mod:`supercoil.io`. No numerics here.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

from supercoil.cli._common import fail, warn, warning_in

TWIST_RATIO = 2.0 / 3.0  # C/A of DNA (seed 001)
N_NODES = 100
N_SAMPLES = 25
MODES = (2, 3)
SPAN = 1.2  # the grid runs to SPAN times the mode-3 threshold
NEWTON_TOLERANCE = 1e-10
DEFAULT_FOLDER = "supercoil-demo"
FILES = ("ring_stability.png", "ring_stability.json", "ring_stability.csv")
CSV_KEYS = (
    "excess_link",
    "twist",
    "writhe",
    "link_error",
    "energy",
    "energy_circle_exact",
    "unstable_count",
    "zero_modes",
    "negative_eigenvalue_count",
    "determinant_sign",
    "stable",
    "converged",
    "residual",
    "newton_iterations",
)


def prepare_folder(out: Path | None, force: bool) -> Path:
    """Create (or, with ``force``, reuse) the output folder; exit 2 if it is refused."""
    if out is None:
        for index in range(1, 10_000):
            candidate = Path(DEFAULT_FOLDER if index == 1 else f"{DEFAULT_FOLDER}-{index}")
            try:
                candidate.mkdir()
            except FileExistsError:
                continue
            except OSError as exc:
                fail(
                    f"cannot create the demo folder {candidate.resolve()} ({exc.strerror}); "
                    "run from a writable folder or give --out DIR"
                )
            return candidate
        fail(f"too many {DEFAULT_FOLDER}-* folders here; give --out DIR")
    if out.exists() and not out.is_dir():
        fail(f"--out {out}: is a file, not a folder; give a new folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        fail(
            f"--out {out}: folder exists and is not empty; give a new folder, or add --force "
            "to overwrite the demo's files in it"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(
            f"--out {out}: cannot create the folder ({exc.strerror}); give a folder in a "
            "writable location"
        )
    return out


def run_demo(folder: Path) -> bool:
    """Compute, write the three files into ``folder`` and say where; True if all converged."""
    import numpy as np
    from rich.console import Console
    from rich.progress import Progress

    from supercoil.io.results import envelope, write_json
    from supercoil.plotting.ring_stability import plot_ring_stability
    from supercoil.problems.ring import (
        circle_energy,
        michell_excess_link,
        michell_threshold,
        solve_ring,
    )

    exact = {m: float(michell_excess_link(TWIST_RATIO, m)) for m in MODES}
    excess_links = np.linspace(0.0, SPAN * exact[max(MODES)], N_SAMPLES)
    stderr = Console(stderr=True)
    rows = []
    with Progress(console=stderr, transient=True, disable=not stderr.is_terminal) as progress:
        task = progress.add_task("solving rings", total=N_SAMPLES + len(MODES))
        for value in excess_links:
            result = solve_ring(
                TWIST_RATIO, float(value), n_nodes=N_NODES, tolerance=NEWTON_TOLERANCE
            )
            rows.append(result.summary())
            zero_tolerance = result.zero_tolerance
            progress.advance(task)
        computed = {}
        for mode in MODES:
            computed[mode] = float(michell_threshold(TWIST_RATIO, N_NODES, mode=mode))
            progress.advance(task)

    thresholds = [
        {
            "mode": m,
            "excess_link_computed": computed[m],
            "excess_link_exact": exact[m],
            "relative_error": (computed[m] - exact[m]) / exact[m],
            "unstable_count_above": 2 * (m - 1),
        }
        for m in MODES
    ]
    png, json_file, csv_file = (folder / name for name in FILES)
    fine = np.linspace(0.0, excess_links[-1], 200)
    plot_ring_stability(
        png,
        excess_link=[row["excess_link"] for row in rows],
        energy=[row["energy"] for row in rows],
        unstable_count=[row["unstable_count"] for row in rows],
        exact_excess_link=fine,
        exact_energy=[circle_energy(TWIST_RATIO, x) for x in fine],
        thresholds_exact=exact,
        thresholds_computed=computed,
        count_above={t["mode"]: t["unstable_count_above"] for t in thresholds},
        twist_ratio=TWIST_RATIO,
        n_nodes=N_NODES,
    )
    payload = {
        "description": "twisted circular ring: energy and unstable count against excess link",
        "twist_ratio": TWIST_RATIO,
        "n_nodes": N_NODES,
        "points": rows,
        "thresholds": thresholds,
        "files": list(FILES),
    }
    tolerances = {
        "newton_residual": NEWTON_TOLERANCE,
        "zero_modes": zero_tolerance,
        "threshold_bisection_rtol": 1e-11,
    }
    write_json(envelope(payload, n_nodes=N_NODES, tolerances=tolerances), json_file)
    with open(csv_file, "w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(CSV_KEYS)
        for row in rows:
            writer.writerow([_csv_value(row[key]) for key in CSV_KEYS])

    where = folder.resolve()
    print(
        f"supercoil demo: twisted ring, C/A = 2/3, N = {N_NODES}, {N_SAMPLES} values of the "
        f"excess link from 0 to {excess_links[-1]:.4g} turns"
    )
    for m in MODES:
        print(
            f"  mode-{m} threshold: computed {computed[m]:.6f}, exact (A/C)sqrt({m * m - 1}) "
            f"= {exact[m]:.6f} (relative error {(computed[m] - exact[m]) / exact[m]:.1e})"
        )
    print(f"wrote {len(FILES)} files to {where}:")
    for name in FILES:
        print(f"  {where / name}")
    sys.stdout.flush()
    warnings = dict.fromkeys(filter(None, (warning_in(row.get("message")) for row in rows)))
    for line in warnings:
        warn(line)
    failures = [row["excess_link"] for row in rows if not row["converged"]]
    if failures:
        warn(
            f"not converged at excess link {', '.join(f'{x:.4g}' for x in failures)}; "
            f"see 'converged' and 'message' in {json_file.resolve()}"
        )
        return False
    return True


def _csv_value(value):
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, float):
        return repr(value)
    return value
