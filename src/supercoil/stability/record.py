"""The stability keys of a state's JSON record (docs/model.md, "Stability"), and with them
the solver's outcome (:func:`solved_state_record`), shared by the rod models' results."""

from __future__ import annotations

from collections.abc import Sequence


def stability_record(unstable_count: int, zero_modes: int, negative_count: int,
                     determinant_sign: int, lowest_eigenvalues: Sequence[float],
                     certified: bool) -> dict:
    """``unstable_count``, ``zero_modes``, ``negative_eigenvalue_count`` (the inertia),
    ``determinant_sign``, ``lowest_eigenvalues``, ``stable`` (no negative eigenvalue and
    no zero mode) and ``stability_certified``."""
    return {"unstable_count": unstable_count, "zero_modes": zero_modes,
            "negative_eigenvalue_count": negative_count, "determinant_sign": determinant_sign,
            "lowest_eigenvalues": [float(v) for v in lowest_eigenvalues],
            "stable": unstable_count == 0 and zero_modes == 0,
            "stability_certified": certified}


def solved_state_record(result) -> dict:
    """The keys that end a ring's summary in both rod models, in order: the stability
    keys (:func:`stability_record`) of ``result``, the solver's outcome (``converged``,
    ``status``, ``message``, ``residual``, ``newton_iterations``) and ``n_nodes``."""
    return {**stability_record(result.unstable_count, result.zero_modes,
                               result.negative_count, result.determinant_sign,
                               result.lowest_eigenvalues, result.stability_certified),
            "converged": result.converged,
            "status": result.status,
            "message": result.message,
            "residual": result.residual,
            "newton_iterations": result.iterations,
            "n_nodes": result.n_nodes}
