"""Symmetry group of a closed curve (Coleman & Swigon 2002: D_m on primary branches, C_2 on
secondary ones, none on the tertiary branch).

A rotation ``R`` about an axis through the centroid maps a closed curve onto
itself in one of two ways (Domokos 1995; Coleman & Swigon 2000):

* preserving the orientation along the curve: ``x(s + L/m) = R x(s)``, an
  ``m``-fold axis (``R`` a rotation by ``2 pi k / m``), the cyclic group ``C_m``;
* reversing it: ``x(c - s) = R x(s)`` for some ``c``, a two-fold axis through
  the two points ``s = c/2`` and ``s = c/2 + L/2`` of the curve.

An ``m``-fold axis with ``m`` reversing two-fold axes perpendicular to it is
the dihedral group ``D_m`` (order ``2m``); a single reversing two-fold axis is
``C_2`` (order 2); none at all is ``C_1``. The circle has every rotation:
``O(2)``.

The curve is sampled at ``n`` nodes equally spaced in arclength (a discrete
rod: inextensible, uniform edges). Shifts by fractions of a node spacing use
the curve's trigonometric (Fourier) interpolant, so that axes need not pass
through nodes: the symmetry of the sampled smooth curve is found, whatever the
mesh's phase. For each candidate map the best rotation is Kabsch's (the
proper orthogonal Procrustes fit, Kabsch 1976), and the map's *residual* is
the RMS distance ``sqrt(mean |x(s) - R^T y(s)|^2)`` of the fit, in the
curve's length units; a symmetry holds when its residual is below the
caller's ``tolerance``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_ORDER = 6
_GENERIC_SHIFT = 0.3819660112501051  # 1/phi^2 of the length: no rational order


def shifted(points: np.ndarray, shift: np.ndarray | float) -> np.ndarray:
    """``x(s + shift)`` of the closed curve sampled at ``s_i = i`` (node spacings).

    ``points`` ``(n, 3)``; ``shift`` a float or an array ``(k,)`` of shifts, giving
    ``(n, 3)`` or ``(k, n, 3)``: the trigonometric interpolant evaluated at the
    shifted nodes (the Nyquist term of an even ``n`` kept real).
    """
    x = np.asarray(points, dtype=float)
    n = x.shape[0]
    k = np.fft.fftfreq(n, 1.0 / n)
    spectrum = np.fft.fft(x, axis=0)
    sigma = np.atleast_1d(np.asarray(shift, dtype=float))
    phase = np.exp(2j * np.pi * np.outer(sigma, k) / n)
    if n % 2 == 0:
        phase[:, n // 2] = np.cos(np.pi * sigma)
    out = np.real(np.fft.ifft(phase[:, :, None] * spectrum[None], axis=1))
    return out[0] if np.ndim(shift) == 0 else out


def fit_residuals(x: np.ndarray, ys: np.ndarray, direct: bool = False) -> np.ndarray:
    """RMS residual of the best proper rotation taking each ``ys[c]`` onto ``x`` (both
    centred), ``(k,)``. By default from the singular values ``s`` of ``x^T y``:
    ``(|x|^2 + |y|^2 - 2 (s_1 + s_2 + d s_3)) / n`` with ``d`` the sign of its
    determinant, which cancels down to about ``sqrt(eps) |x|``; ``direct`` applies
    the rotation and measures the distances instead (exact to round-off)."""
    xc = x - x.mean(axis=0)
    yc = ys - ys.mean(axis=1, keepdims=True)
    cov = np.einsum("ia,cib->cab", xc, yc)
    if direct:
        u, _sv, vt = np.linalg.svd(cov)
        d = np.sign(np.linalg.det(u @ vt))
        d[d == 0] = 1.0
        u[:, :, 2] *= d[:, None]
        rotation = u @ vt  # x ~ y R^T per row: R = U diag(1, 1, d) V^T
        fitted = np.einsum("cib,cab->cia", yc, rotation)
        return np.sqrt(np.mean(np.sum((xc[None] - fitted) ** 2, axis=2), axis=1))
    return _procrustes_residuals(cov, np.sum(xc**2) + np.sum(yc**2, axis=(1, 2)), x.shape[0])


def _procrustes_residuals(cov: np.ndarray, squares: np.ndarray | float, n: int) -> np.ndarray:
    """RMS residuals of the best proper rotations from the covariances ``cov`` (k, 3, 3) of
    two centred ``n``-point sets and the sums ``squares`` of their squared norms (k,):
    ``sqrt((squares - 2 (s_1 + s_2 + d s_3)) / n)`` (:func:`fit_residuals`)."""
    sv = np.linalg.svd(cov, compute_uv=False)
    sign = np.sign(np.linalg.det(cov))
    sign[sign == 0] = 1.0
    trace = sv[:, 0] + sv[:, 1] + sign * sv[:, 2]
    return np.sqrt(np.maximum(squares - 2.0 * trace, 0.0) / n)


def integer_reversal_scan(x: np.ndarray) -> np.ndarray:
    """The residuals of ``x(c - s) = R x(s)`` at every integer ``c`` in ``[0, n)``, ``(n,)``,
    as :func:`reversal_residuals` (not ``direct``) gives them, in O(n log n): the
    covariance of the curve with its reversed copy shifted by ``c`` is a circular
    cross-correlation, ``sum_i xc_i (x) r_{i+c}`` with ``r_j = xc_{-j}``, computed for all
    ``c`` at once by FFT (a permutation keeps the centroid and the sum of squares)."""
    n = x.shape[0]
    xc = x - x.mean(axis=0)
    reversed_ = xc[(-np.arange(n)) % n]
    spectrum = np.conj(np.fft.rfft(xc, axis=0))[:, :, None] * \
        np.fft.rfft(reversed_, axis=0)[:, None, :]
    cov = np.fft.irfft(spectrum, n, axis=0)  # cov[c, a, b] = sum_i xc[i, a] r[i + c, b]
    return _procrustes_residuals(cov, 2.0 * np.sum(xc**2), n)


def cyclic_residual(points: np.ndarray, order: float) -> float:
    """Residual of ``x(s + L/order) = R x(s)`` (an ``order``-fold axis), in length units."""
    return float(cyclic_residuals(points, np.array([order]))[0])


def cyclic_residuals(points: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """:func:`cyclic_residual` for each of ``orders`` ``(k,)`` at once, ``(k,)``: one
    spectrum, one batched inverse transform and SVD (each value as computed alone, to
    round-off: bit for bit on the ring diagram's 169 states at N = 200)."""
    x = np.asarray(points, dtype=float)
    shifts = x.shape[0] / np.asarray(orders, dtype=float)
    return fit_residuals(x, shifted(x, shifts), direct=True)


def reversal_residuals(points: np.ndarray, c: np.ndarray, direct: bool = False) -> np.ndarray:
    """Residuals of ``x(c - s) = R x(s)`` (a reversing two-fold axis) for each ``c``
    (in node spacings), ``(k,)``; ``direct`` as in :func:`fit_residuals`."""
    x = np.asarray(points, dtype=float)
    reversed_ = x[(-np.arange(x.shape[0])) % x.shape[0]]  # x(-s)
    return fit_residuals(x, shifted(reversed_, np.asarray(c, dtype=float)), direct)


def reversal_axes(points: np.ndarray, tolerance: float, refine: bool = True
                  ) -> list[tuple[float, float]]:
    """The reversing two-fold axes: ``(c, residual)`` for each ``c`` in ``[0, n)`` (node
    spacings) where ``x(c - s) = R x(s)`` holds within ``tolerance``; each axis once.

    The residual is scanned at the integer ``c`` (the reversed curve's nodes
    permuted, no interpolation; :func:`integer_reversal_scan`), and refined by
    Brent's method within one node of each local minimum of that scan whose value
    allows an axis nearby: near an axis ``c*`` the residual is a V of slope at most
    the mean edge length ``h`` (shifting the curve by ``dc`` moves each node by about
    ``h dc``), so the nearest integer (within 1/2) has a residual below
    ``h / 2 + tolerance``; scan minima above ``h + tolerance`` are skipped. (The
    tests check it against a half-node trigonometric scan with every local minimum
    refined.)

    ``refine=False`` (enough to count the axes, as :func:`curve_symmetry` does): a
    scan minimum below half of both its neighbours (the V's bottom within a third of
    a node of it, so no neighbour is such a minimum too) whose own residual is
    within ``tolerance`` is taken as it is, ``c`` an integer; the others are refined.
    """
    x = np.asarray(points, dtype=float)
    values = integer_reversal_scan(x)
    left, right = np.roll(values, 1), np.roll(values, -1)
    h = float(np.mean(np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)))
    candidates = np.flatnonzero((values <= left) & (values <= right)
                                & (values <= h + tolerance))
    clear = None
    if not refine:
        clear = values[candidates] <= 0.5 * np.minimum(left, right)[candidates]
    return refined_axes(x, candidates.astype(float), 1.0, tolerance, clear)


def refined_axes(x: np.ndarray, centres: np.ndarray, reach: float, tolerance: float,
                 as_they_are: np.ndarray | None = None) -> list[tuple[float, float]]:
    """The axes found by Brent's method within ``reach`` of each of ``centres``: those
    whose residual is within ``tolerance``, each once (sorted by ``c``).
    ``as_they_are`` (bool per centre): a centre whose own residual is within
    ``tolerance`` is taken without refinement."""
    from scipy.optimize import minimize_scalar  # here: scipy.optimize takes ~0.1 s to import

    n = x.shape[0]
    axes: list[tuple[float, float]] = []
    for i, c0 in enumerate(centres):
        c, value = float(c0) % n, np.inf
        if as_they_are is not None and as_they_are[i]:
            value = float(reversal_residuals(x, [c0], True)[0])
        if value > tolerance:
            # The mean square is smooth (quadratic) at its minimum, the RMS a V; the
            # offset from c0 is the variable, as Brent's tolerance is relative to it.
            result = minimize_scalar(
                lambda dc, c0=float(c0): float(reversal_residuals(x, [c0 + dc], True)[0]) ** 2,
                bounds=(-reach, reach), method="bounded", options={"xatol": 1e-10})
            c, value = float(c0 + result.x) % n, float(np.sqrt(result.fun))
        if value > tolerance:
            continue
        if any(min(abs(c - a), n - abs(c - a)) < 0.25 for a, _ in axes):
            continue
        axes.append((c, value))
    return sorted(axes)


@dataclass(frozen=True)
class CurveSymmetry:
    """The symmetry group of a closed curve (module docstring).

    ``group``: ``"O(2)"``, ``"D<m>"``, ``"C<m>"`` or ``"C1"``; ``order`` the
    largest ``m`` of an orientation-preserving ``m``-fold axis (1 if none;
    ``0`` for the circle's continuum); ``two_fold_axes`` the number of
    reversing two-fold axes; ``residual`` the largest residual among the maps
    that make up the group (0 for ``C1``).
    """

    group: str
    order: int
    two_fold_axes: int
    residual: float


def curve_symmetry(points: np.ndarray, tolerance: float,
                   max_order: int = MAX_ORDER) -> CurveSymmetry:
    """The symmetry group of the closed curve ``points`` ``(n, 3)`` (module docstring).

    ``tolerance``: largest residual (length units) of a map counted as a symmetry;
    orders ``2 .. max_order`` are tried for orientation-preserving axes.
    """
    x = np.asarray(points, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 4:
        raise ValueError(f"points must be (n >= 4, 3), got shape {x.shape}")
    if not tolerance > 0:
        raise ValueError(f"tolerance must be positive, got {tolerance!r}")
    # the generic shift and every order at once, in one batched fit (the same values;
    # curve_symmetry at N = 200: 1.6-1.9 ms -> 1.3-1.4 ms a state)
    orders = [m for m in range(max_order, 1, -1) if x.shape[0] >= 2 * m]
    residuals = cyclic_residuals(x, np.array([1.0 / _GENERIC_SHIFT, *orders]))
    if residuals[0] <= tolerance:
        return CurveSymmetry("O(2)", 0, 0, float(residuals[0]))
    order, worst = 1, 0.0
    for m, value in zip(orders, residuals[1:], strict=True):
        if value <= tolerance:  # the highest order that holds
            order, worst = m, float(value)
            break
    axes = reversal_axes(x, tolerance, refine=False)
    if axes:
        worst = max(worst, max(r for _, r in axes))
    if order >= 2:
        return CurveSymmetry(f"D{order}" if axes else f"C{order}", order, len(axes), worst)
    if axes:
        return CurveSymmetry("C2", 1, len(axes), worst)
    return CurveSymmetry("C1", 1, 0, 0.0)


def reversal_rotation(points: np.ndarray, c: float) -> np.ndarray:
    """The proper rotation ``R`` (3, 3) of the reversing two-fold axis ``c`` (node
    spacings): ``x(s) - xbar = R (x(c - s) - xbar)`` in the least-squares sense (Kabsch)."""
    x = np.asarray(points, dtype=float)
    y = shifted(x[(-np.arange(x.shape[0])) % x.shape[0]], float(c))  # x(c - s)
    xc, yc = x - x.mean(axis=0), y - y.mean(axis=0)
    u, _sv, vt = np.linalg.svd(xc.T @ yc)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag([1.0, 1.0, d]) @ vt


def reversal_image(points: np.ndarray, c: float, modes: np.ndarray) -> np.ndarray:
    """Displacement fields ``modes`` (k, n, 3) mapped by the two-fold axis ``c`` of the curve
    ``points``: ``(g v)(s) = R v(c - s)`` (:func:`reversal_rotation`), ``(k, n, 3)``. A mode
    with ``g v = v`` keeps that axis (the curve moved along it stays symmetric about it)."""
    x = np.asarray(points, dtype=float)
    v = np.asarray(modes, dtype=float)
    rotation = reversal_rotation(x, c)
    n = x.shape[0]
    out = np.empty_like(v)
    for k in range(v.shape[0]):
        out[k] = shifted(v[k][(-np.arange(n)) % n], float(c)) @ rotation.T
    return out


def axis_invariant_combination(points: np.ndarray, c: float, modes: np.ndarray,
                               mass: np.ndarray | None = None) -> np.ndarray:
    """The unit combination ``sum_i a_i v_i`` of ``modes`` (k, n, 3) nearest to invariant
    under the two-fold axis ``c`` (:func:`reversal_image`): the eigenvector of the
    symmetrised matrix ``<v_i, g v_j>`` (weights ``mass`` per node) with the eigenvalue
    nearest +1. Returns ``a`` (k,). At a bifurcation of a D_m state through a double
    eigenvalue (an E mode), the direction that keeps one of its two-fold axes is the one
    along which the C_2 branch starts (the secondary branches of Coleman & Swigon 2002)."""
    v = np.asarray(modes, dtype=float)
    w = np.ones(v.shape[1]) if mass is None else np.asarray(mass, dtype=float)
    image = reversal_image(points, c, v)
    gram = np.einsum("ina,n,jna->ij", v, w, v)
    action = np.einsum("ina,n,jna->ij", v, w, image)
    # the generalised problem action a = mu gram a, symmetrised (g is an isometry)
    values, vectors = np.linalg.eig(np.linalg.solve(gram, 0.5 * (action + action.T)))
    a = np.real(vectors[:, int(np.argmin(np.abs(np.real(values) - 1.0)))])
    return a / np.sqrt(a @ gram @ a)
