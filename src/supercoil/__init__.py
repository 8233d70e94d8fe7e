"""supercoil: equilibria, branches, bifurcations and stability of self-avoiding elastic rods.

Describe a problem, call a verb, read an immutable result::

    import supercoil as sc

    rod = sc.Rod(twist_ratio=2 / 3, nodes=132)
    ring = sc.Ring(rod, excess_link=2.5, contact=sc.Barrier(length_over_diameter=122))
    eq = sc.equilibrium(ring)        # eq.status, eq.writhe, eq.stability, eq.contacts

Units are nondimensional: bending stiffness A = 1 and rod length L = 1.
"""

from supercoil._version import __version__
from supercoil.api.energy import Energy, continuation, switch_branch
from supercoil.api.figures import plot
from supercoil.api.files import save
from supercoil.api.knot_diagram import knot_diagram
from supercoil.api.model import (
    AugmentedLagrangian,
    Barrier,
    Contact,
    CosseratRod,
    ExactContact,
    Penalty,
    Ring,
    Rod,
    Tweezers,
)
from supercoil.api.outputs import Exported, export, view
from supercoil.api.results import (
    Diagram,
    Equilibrium,
    EquilibriumStatus,
    RunStatus,
    Stability,
)
from supercoil.api.studies import run, sweep
from supercoil.api.verbs import equilibrium, ring_diagram, stability, tweezers, tweezers_path
from supercoil.continuation import (
    Branch,
    ContinuationOptions,
    ContinuationStatus,
    SpecialPoint,
    UserEvent,
)
from supercoil.errors import InputError
from supercoil.io.curves import read_curve
from supercoil.problems.knot_ring import tight_knot as tighten
from supercoil.topology import linking_number, writhe
from supercoil.topology import twist_from_frames as twist
from supercoil.topology.knots import KnotType, knot_curve, torus_knot
from supercoil.topology.knots import identify as knot_type
from supercoil.units.dna import DNAPreset

__all__ = [
    "AugmentedLagrangian",
    "Barrier",
    "Branch",
    "Contact",
    "ContinuationOptions",
    "ContinuationStatus",
    "CosseratRod",
    "DNAPreset",
    "Diagram",
    "Energy",
    "Equilibrium",
    "EquilibriumStatus",
    "ExactContact",
    "Exported",
    "InputError",
    "KnotType",
    "Penalty",
    "Ring",
    "Rod",
    "RunStatus",
    "SpecialPoint",
    "Stability",
    "Tweezers",
    "UserEvent",
    "__version__",
    "continuation",
    "equilibrium",
    "export",
    "knot_curve",
    "knot_diagram",
    "knot_type",
    "linking_number",
    "load",
    "plot",
    "read_curve",
    "ring_diagram",
    "run",
    "save",
    "stability",
    "sweep",
    "switch_branch",
    "tighten",
    "torus_knot",
    "tweezers",
    "tweezers_path",
    "twist",
    "view",
    "writhe",
]


def load(path):
    """Read a result -- ``result.h5``, or the output folder of any command that computes
    (``demo``, ``diagram ring``, ``tweezers``, ``run``, ``ring --out``), or its JSON
    summary (``diagram.json``, ``branch.json``, ``ring.json``: the result beside it) -- into a
    :class:`supercoil.io.store.Result`: ``.branches`` maps names to ``Branch`` objects,
    with the settings, status and summary (see ``docs/results.md``). A sweep's folder
    (``supercoil sweep``'s, holding ``sweep.nc``) or its ``sweep.nc`` is read as an
    ``xarray.Dataset`` with one dimension per swept key. A damaged or truncated file
    raises :class:`supercoil.errors.InputError`."""
    from pathlib import Path

    target = Path(path)
    if target.suffix == ".json" and target.is_file():
        target = target.parent  # a summary: the result file beside it
    if target.suffix == ".nc" or (target / "sweep.nc").is_file():
        from supercoil.sweeps import load_sweep

        return load_sweep(target)
    from supercoil.io.store import load as _load

    return _load(target)
