"""The rod model's keys of a study file (``[rod] model``, ``stretch_stiffness``,
``shear_stiffness``): their cross-checks against the problem (:mod:`supercoil.io.study`)."""

from __future__ import annotations

from collections.abc import Mapping

MODELS = ("kirchhoff", "cosserat")


def model_problem(s: Mapping, kind: str) -> str | None:
    """What is wrong with the study's model keys (the message after the file's name), or
    None: stiffnesses only with the Cosserat model; an end distance z/L >= 1 only with
    it (the Kirchhoff rod is inextensible)."""
    rod = s["rod"]
    cosserat = rod.get("model") == "cosserat"
    for key in ("stretch_stiffness", "shear_stiffness"):
        if key in rod and not cosserat:
            return (f'[rod] {key} needs model = "cosserat" (the Kirchhoff rod is '
                    "inextensible and unshearable)")
    if not cosserat:
        end_distance = s.get("problem", {}).get("end_distance")
        if kind == "tweezers" and isinstance(end_distance, (int, float)) \
                and not end_distance < 1.0:
            return ("[problem] end_distance: z/L must lie in (0, 1) for the inextensible "
                    'Kirchhoff rod; a stretched rod needs model = "cosserat"')
        return None
    return None
