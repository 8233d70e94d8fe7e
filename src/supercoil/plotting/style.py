"""One style for every figure and the viewer: colours, markers, axis labels with units.

The figures (:mod:`supercoil.plotting.figures`, :mod:`supercoil.plotting.ring_diagram`)
draw inside :func:`styled` and save through :func:`save`; the HTML viewer takes
the same colours and markers from :func:`viewer_style`, so a branch or a
special point looks the same in a PNG, an SVG and the browser.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Sequence
from pathlib import Path

# Okabe & Ito's colour-blind-safe palette (Nature Methods 8, 441, 2011), black last
BRANCH_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9",
                 "#F0E442", "#000000")

# special point kind -> (matplotlib marker, colour); the kinds of docs/model.md,
# "Special points and branches"
SPECIAL_MARKERS = {
    "bifurcation": ("o", "#C0392B"),
    "fold": ("s", "#1E8449"),
    "contact_onset": ("v", "#E67E22"),
    "contact_release": ("^", "#8E44AD"),
    "contact_split": ("D", "#2C3E50"),
    "contact_interval_onset": ("P", "#B7950B"),
    "jump": ("X", "#7F8C8D"),
    "endpoint": ("x", "#000000"),
    "count_change": ("o", "#AAB7B8"),
}
OTHER_MARKER = ("*", "#000000")

CONTACT_COLOR = "#E31A1C"  # contacts on tubes and in the contact map
TUBE_COLOR = "#4A7FC1"

STABLE_WIDTH = 3.0  # line width (pt) of stable stretches
UNSTABLE_WIDTH = 0.9

# Axis labels with units (nondimensional: A = 1, L = 1; topology in turns)
LABELS = {
    "excess_link": r"excess link $\Delta Lk$ (turns)",
    "writhe": r"writhe $Wr$ (turns)",
    "twist": r"excess twist $Tw$ (turns)",
    "energy": r"energy $E\,L/A$",
    "turns": r"end rotation $n$ (turns)",
    "extension": r"extension $z/L$",
    "torque": r"torque $M\,L/A$",
    "arclength": r"arc length $s/L$",
    "force": r"force $F\,L^2/A$",
    # DNA units (supercoil.plotting.dna)
    "superhelical_density": r"superhelical density $\sigma$",
    "extension_nm": r"extension $z$ (nm)",
    "torque_pN_nm": r"torque $M$ (pN nm)",
    "force_pN": r"force $F$ (pN)",
}

RC = {
    "font.size": 9.0,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9.5,
    "legend.fontsize": 8.0,
    "legend.frameon": False,
    "xtick.labelsize": 8.5,
    "ytick.labelsize": 8.5,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "axes.linewidth": 0.8,
    "axes.grid": True,
    "grid.alpha": 0.25,
    "grid.linewidth": 0.6,
    "lines.solid_capstyle": "round",
    "savefig.dpi": 200,
    "svg.fonttype": "path",  # the SVG looks the same without our fonts
    "svg.hashsalt": "supercoil",  # reproducible SVG ids
    "mathtext.fontset": "dejavusans",
}

FORMATS = ("png", "svg")
SINGLE = (4.8, 3.6)  # inches: one-column figure


@contextlib.contextmanager
def styled() -> Iterator[None]:
    """Draw and save inside this context to get the house style."""
    import matplotlib

    with matplotlib.rc_context(RC):
        yield


def branch_color(index: int) -> str:
    return BRANCH_COLORS[index % len(BRANCH_COLORS)]


def special_marker(kind: str) -> tuple[str, str]:
    return SPECIAL_MARKERS.get(kind, OTHER_MARKER)


def save(fig, path: str | os.PathLike, formats: Sequence[str] | None = None) -> list[Path]:
    """Save ``fig`` to ``path`` (with its suffix), or to ``path.<fmt>`` for each of
    ``formats``. Metadata carry no date, so the same data give the same files. PNGs
    are deflated at zlib level 1 (as the tweezers' figures): the same pixels, files
    about a sixth larger, encoded several times faster."""
    path = Path(path)
    targets = [path] if formats is None else [path.with_suffix("." + f) for f in formats]
    with styled():
        for target in targets:
            fmt = target.suffix.lstrip(".").lower()
            metadata = {"Date": None} if fmt == "svg" else {}
            extra = {"pil_kwargs": {"compress_level": 1}} if fmt == "png" else {}
            fig.savefig(target, format=fmt, metadata=metadata, **extra)
    return targets


def viewer_style() -> dict:
    """The colours and marker shapes for the HTML viewer (JSON-serialisable)."""
    shapes = {"o": "circle", "s": "square", "v": "triangle-down", "^": "triangle-up",
              "D": "diamond", "P": "plus", "X": "cross", "x": "cross", "*": "star"}
    return {"branch_colors": list(BRANCH_COLORS),
            "special": {k: {"shape": shapes[m], "color": c}
                        for k, (m, c) in SPECIAL_MARKERS.items()},
            "other": {"shape": "star", "color": OTHER_MARKER[1]},
            "contact_color": CONTACT_COLOR, "tube_color": TUBE_COLOR,
            "stable_width": STABLE_WIDTH, "unstable_width": UNSTABLE_WIDTH}


# Coleman & Swigon 2002, Figure 2: primary branches solid, secondary long dashes, tertiary short
# dashes (the ring diagram's ``generation``: 0 circle, 1 primary, 2, 3)
GENERATION_STYLES = {0: "-", 1: "-", 2: (0, (6, 3)), 3: (0, (2, 2))}


def generation_style(generation: int):
    """The matplotlib line style of a branch of ``generation``."""
    return GENERATION_STYLES.get(int(generation), "-")
