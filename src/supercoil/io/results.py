"""The JSON result envelope shared by every command and file (docs/model.md, "Files and
exit statuses").

Every JSON file written by supercoil carries, beside the payload of its
command, four common keys:

* ``schema_version``: the version of this layout (``"1.0"``);
* ``units``: ``"nondimensional"`` (A = 1, L = 1) or the name of a units preset;
* ``conventions``: short statements of what the keys mean (units, signs,
  topology, stability), so that a file can be read without the docs;
* ``provenance``: supercoil, Python and numpy versions, number of nodes,
  contact treatment, tolerances and a UTC timestamp.

:func:`write_json` writes such a dict to a path (``"-"`` is standard output),
converting numpy scalars and arrays, atomically (temporary file + rename), so
that an interrupted run never leaves a truncated file behind.
"""

from __future__ import annotations

import json
import math
import os
import platform
import sys
import tempfile
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

SCHEMA_VERSION = "1.0"

ENVELOPE_KEYS = ("schema_version", "units", "conventions", "provenance")

CONVENTIONS: dict[str, str] = {
    "units": "nondimensional: bending stiffness A = 1, rod length L = 1; "
    "lengths and arc lengths are fractions of L",
    "twist_ratio": "C/A, twist stiffness over bending stiffness",
    "energy": "E*L/A, elastic energy only (bending + twist); forces F*L^2/A, torques M*L/A",
    "excess_link": "excess linking number dLk = Lk - Lk0 in turns; "
    "positive = right-handed (overwinding for DNA)",
    "twist": "excess twist in turns, from the material frames",
    "writhe": "Gauss double-sum writhe of the centreline; a right-handed helix has positive writhe",
    "link_identity": "closed rods: excess_link = twist + writhe; link_error = "
    "|twist + writhe - excess_link| with twist and writhe computed independently",
    "closure": "writhe of an open curve is taken after closing it: none = the open polygon "
    "alone, chord = straight chord from the last vertex to the first, axis = straight "
    "semi-infinite tails along the axis from both ends",
    "unstable_count": "number of negative eigenvalues of the constrained Hessian after "
    "removing rigid motions and continuous symmetries (0 = stable)",
    "zero_modes": "eigenvalues with |mu| <= provenance.tolerances.zero_modes (mass-weighted, "
    "H v = mu M v), counted apart and never given a sign",
    "determinant_sign": "sign of det of the reduced stiffness (the test of Chamekh, "
    "Mani-Aouadi & Moakher 2014); it sees only the parity of the count, so pair crossings at "
    "symmetric bifurcations keep it",
}


def envelope(
    payload: dict,
    *,
    n_nodes: int,
    units: str = "nondimensional",
    tolerances: dict,
    contact_treatment: str = "none",
) -> dict:
    """Return ``payload`` with the common keys ``schema_version``, ``units``,
    ``conventions`` and ``provenance`` added (a new dict; ``payload`` is untouched).

    Raises ``ValueError`` if the payload already uses one of those keys.
    """
    clash = [key for key in ENVELOPE_KEYS if key in payload]
    if clash:
        raise ValueError(f"payload keys {clash} are reserved for the JSON envelope")
    import numpy as np

    provenance = {
        "supercoil_version": _version(),
        "n_nodes": int(n_nodes),
        "contact_treatment": contact_treatment,
        "tolerances": dict(tolerances),
        "python_version": platform.python_version(),
        "numpy_version": np.__version__,
        "platform": platform.platform(),
        "timestamp": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    return {
        "schema_version": SCHEMA_VERSION,
        "units": units,
        **payload,
        "conventions": dict(CONVENTIONS),
        "provenance": provenance,
    }


def _version() -> str:
    from supercoil import __version__

    return __version__


def to_jsonable(value: Any) -> Any:
    """Plain Python data for ``json``: numpy scalars and arrays converted, tuples as
    lists, paths as strings, non-finite floats as ``None`` (strict JSON has no NaN)."""
    import numpy as np

    if isinstance(value, dict):
        return {str(key): to_jsonable(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(item) for item in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


def dumps(data: dict) -> str:
    """The JSON text of ``data`` (indented, strict JSON, trailing newline)."""
    return json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n"


def write_json(data: dict, path: str | os.PathLike) -> None:
    """Write ``data`` as JSON to ``path``; ``"-"`` writes to standard output.

    The file is written to a temporary file in the same folder and renamed
    over ``path``, so readers never see a partial file. Raises ``OSError`` if
    the folder does not exist or is not writable.
    """
    text = dumps(data)
    if str(path) == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
        return
    target = Path(path)
    folder = target.parent
    handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, 0o644 & ~_umask())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
