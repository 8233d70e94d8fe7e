"""The rod model's options of ``ring``, ``diagram ring`` and ``tweezers``: ``--model``,
``--stretch-stiffness`` and ``--shear-stiffness``, their checks and the rod they make."""

from __future__ import annotations

from typing import Annotated

import typer

from supercoil.api.model import DEFAULT_POISSON_RATIO, DEFAULT_SLENDERNESS, make_rod  # noqa: F401
from supercoil.cli._common import fail

MODELS = ("kirchhoff", "cosserat")

ModelOption = Annotated[str, typer.Option(
    "--model", metavar="MODEL",
    help="The rod model: kirchhoff (inextensible and unshearable, the default) or cosserat "
    "(the special Cosserat rod of Simo and Reissner: shear and extension too; "
    "docs/cosserat.md).")]
StretchOption = Annotated[float | None, typer.Option(
    "--stretch-stiffness", metavar="EA*L^2/A",
    help="With --model cosserat: the extension stiffness EA*L^2/A (> 0). Default: a solid "
    f"circular section of the rod's L/D (--length-over-diameter, else {DEFAULT_SLENDERNESS:g}), "
    "16 (L/D)^2.", show_default=False)]
ShearOption = Annotated[float | None, typer.Option(
    "--shear-stiffness", metavar="GA*L^2/A",
    help="With --model cosserat: the shear stiffness GA*L^2/A (> 0). Default: a solid "
    f"circular section of the rod's L/D (as --stretch-stiffness) and Poisson ratio "
    f"{DEFAULT_POISSON_RATIO:g}, 48 (L/D)^2 / (7 + 6 nu) (Cowper's shear coefficient).",
    show_default=False)]


def check_model(model: str, stretch_stiffness: float | None,
                shear_stiffness: float | None) -> None:
    """Exit 2 on an unknown model, or on stiffnesses given to the Kirchhoff model."""
    if model not in MODELS:
        fail(f"--model {model!r}: valid models are {', '.join(MODELS)}")
    given = [name for name, value in (("--stretch-stiffness", stretch_stiffness),
                                      ("--shear-stiffness", shear_stiffness))
             if value is not None]
    if given and model != "cosserat":
        verb = "needs" if len(given) == 1 else "need"
        fail(f"{' and '.join(given)} {verb} --model cosserat (the Kirchhoff rod is "
             "inextensible and unshearable)")


def model_record(rod) -> dict:
    """The JSON keys of the rod's model: ``model`` and, for a Cosserat rod, its
    stiffnesses."""
    if getattr(rod, "model", "kirchhoff") != "cosserat":
        return {"model": "kirchhoff"}
    return {"model": "cosserat", "stretch_stiffness": rod.stretch_stiffness,
            "shear_stiffness": rod.shear_stiffness, "slenderness": rod.slenderness,
            "poisson_ratio": rod.poisson_ratio}
