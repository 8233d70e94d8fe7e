"""Scalar contact potentials of the gap ``g = d - D`` between two segments.

Each treatment turns the condition ``g >= 0`` into an energy ``psi(g)`` per
segment pair, summed over the pairs; ``psi``, ``psi'`` and ``psi''`` are
returned together so that the equilibrium and its stability (the Hessian)
come from one function. The normal contact force of a pair is ``-psi'(g)``
(F·L²/A when A = L = 1), never negative.

* penalty (Chamekh, Mani-Aouadi & Moakher 2014, sec. 3): ``psi = k/2 min(g, 0)^2``;
  C¹, the force ``k max(-g, 0)`` needs a penetration to exist.
* augmented Lagrangian (Chamekh, Mani-Aouadi & Moakher 2014; Nocedal & Wright
  2006, eq. 17.65 for inequalities): ``psi = -lam g + k/2 g^2`` where
  ``lam - k g > 0``, else
  ``-lam^2 / (2k)``; with the multiplier update ``lam <- max(lam - k g, 0)``
  the penetration tends to zero at finite ``k``. We return it shifted by the
  constant ``lam^2 / (2k)``, i.e. ``k/2 min(g - lam/k, 0)^2``, which vanishes
  for separated pairs, so that summing over the pairs within reach gives a
  continuous energy whatever the reach.
* barrier (Li et al. 2020, "Incremental Potential Contact", eq. 6):
  ``psi = -kappa (g - g_hat)^2 log(g / g_hat)`` for ``0 < g < g_hat``, 0 above;
  C² at ``g_hat`` and infinite at ``g = 0``, so a state that minimises it
  with step-wise collision detection never touches (gap > 0).
"""

from __future__ import annotations

import numpy as np


def penalty(gap: np.ndarray, stiffness: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k/2 min(g,0)^2`` and its first two derivatives in ``g``."""
    g = np.asarray(gap, dtype=float)
    inside = g < 0
    value = np.where(inside, 0.5 * stiffness * g * g, 0.0)
    first = np.where(inside, stiffness * g, 0.0)
    second = np.where(inside, stiffness, 0.0)
    return value, first, second


def augmented(gap: np.ndarray, multiplier: np.ndarray, stiffness: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Augmented-Lagrangian term of ``g >= 0`` (multiplier ``lam >= 0``), shifted by ``lam^2/2k``."""
    g = np.asarray(gap, dtype=float)
    lam = np.asarray(multiplier, dtype=float)
    active = lam - stiffness * g > 0
    shifted = g - lam / stiffness
    value = np.where(active, 0.5 * stiffness * shifted * shifted, 0.0)
    first = np.where(active, -lam + stiffness * g, 0.0)
    second = np.where(active, stiffness, 0.0)
    return value, first, second


def augmented_update(gap: np.ndarray, multiplier: np.ndarray, stiffness: float) -> np.ndarray:
    """First-order multiplier update ``lam <- max(lam - k g, 0)`` (the pair's contact force)."""
    return np.maximum(np.asarray(multiplier, dtype=float) - stiffness * np.asarray(gap), 0.0)


def barrier(gap: np.ndarray, stiffness: float, activation: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IPC log barrier ``-kappa (g - g_hat)^2 log(g / g_hat)`` on ``0 < g < g_hat``.

    Returns ``inf`` (value) for ``g <= 0``: such a state is inadmissible.
    """
    g = np.asarray(gap, dtype=float)
    gh = activation
    inside = (g > 0) & (g < gh)
    gs = np.where(inside, g, gh)  # safe argument outside the support
    log = np.log(gs / gh)
    diff = gs - gh
    value = np.where(inside, -stiffness * diff * diff * log, 0.0)
    first = np.where(inside, -stiffness * (2 * diff * log + diff * diff / gs), 0.0)
    second = np.where(inside, -stiffness * (2 * log + 4 * diff / gs - diff * diff / (gs * gs)),
                      0.0)
    value = np.where(g <= 0, np.inf, value)
    return value, first, second
