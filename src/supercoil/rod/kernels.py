"""Local stencil kernels of the discrete Kirchhoff rod, differentiated with JAX.

Each kernel is a scalar function of the three vertices ``x_{i-1}, x_i, x_{i+1}``
around one interior vertex (a flat vector of 9 numbers) plus per-vertex data.
``jax.grad`` / ``jax.hessian`` give exact local gradients ``(9,)`` and Hessians
``(9, 9)``, which :mod:`supercoil.rod.assembly` scatters into the global sparse
pattern, so every formula exists once.

Curvature. With ``e = x_i - x_{i-1}``, ``f = x_{i+1} - x_i`` and turning angle
``phi``, the curvature binormal of Bergou et al. (2008, eq. 1) is
``kb = 2 e x f / (|e||f| + e.f)`` with ``|kb| = 2 tan(phi/2)``. The bending
energy of vertex ``i`` is ``A * k^2 / (l_{i-1} + l_i)`` (rest lengths), i.e.
``int A/2 kappa^2 ds`` with ``kappa = k / lbar``, where ``k`` is one of

* ``"angle"``: ``k = phi`` (the exact turning angle; a regular polygon then has
  exactly the bending energy of its circle),
* ``"tan"``:   ``k = 2 tan(phi/2)`` (Bergou et al. 2008),
* ``"sin"``:   ``k = 2 sin(phi/2)``.

All three converge as O(h^2); their error constants differ (see
``tests/test_ring.py`` and docs/model.md).

Twist. ``reference_twist`` is the signed angle at vertex ``i`` between the
reference director of edge ``i-1`` parallel-transported onto edge ``i`` and the
reference director of edge ``i`` (Bergou et al. 2010, sec. 6). The reference
directors are carried along by *time-parallel transport* from the previous
state (``u_old``, ``t_old``), so the kernel is a smooth function of the
vertices. Summed around a closed rod it is the holonomy of discrete parallel
transport, which does not depend on the reference directors (mod 2 pi) and
whose variation is minus 2 pi times the variation of the writhe
(Călugăreanu–White–Fuller). Its Hessian is therefore the banded Hessian of the
writhe, obtained from a local expression, never from the double sum.
"""

from __future__ import annotations

import os
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
# Compiled kernels are cached on disk so that only the first run pays for XLA.
_CACHE = Path(os.environ.get("SUPERCOIL_CACHE_DIR", Path.home() / ".cache" / "supercoil")) / "jax"
try:
    _CACHE.mkdir(parents=True, exist_ok=True)
    jax.config.update("jax_compilation_cache_dir", str(_CACHE))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
except OSError:  # read-only home: compile in memory only
    pass

import jax.numpy as jnp

# Kernels run on fixed-size chunks of stencils so that XLA compiles each kernel
# once, whatever the number of nodes (JAX recompiles on every new shape).
CHUNK = 512

CURVATURE_FORMS = ("angle", "tan", "sin")

# Below this value of tan^2(phi/2) the angle form uses its Taylor series, so that
# derivatives stay finite at the straight configuration (phi = 0).
_SERIES_BELOW = 1e-8


def _kb(xm, x0, xp):
    e = x0 - xm
    f = xp - x0
    return 2.0 * jnp.cross(e, f) / (jnp.linalg.norm(e) * jnp.linalg.norm(f) + jnp.dot(e, f))


def curvature_squared(xm, x0, xp, form: str):
    """Squared discrete curvature measure ``k^2`` at a vertex (see module docstring)."""
    kb = _kb(xm, x0, xp)
    tan2 = 0.25 * jnp.dot(kb, kb)  # tan^2(phi/2)
    if form == "tan":
        return 4.0 * tan2
    if form == "sin":
        return 4.0 * tan2 / (1.0 + tan2)  # 4 sin^2(phi/2)
    if form == "angle":
        # phi^2 = 4 atan(t)^2 = 4 t^2 (atan(t)/t)^2 with t^2 = tan2; "double where"
        # keeps the derivatives of the unused branch finite.
        small = tan2 < _SERIES_BELOW
        safe = jnp.where(small, 1.0, tan2)
        root = jnp.sqrt(safe)
        ratio2 = jnp.where(small, 1.0 - 2.0 * tan2 / 3.0 + 23.0 * tan2**2 / 45.0,
                           (jnp.arctan(root) / root) ** 2)
        return 4.0 * tan2 * ratio2
    raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")


def _transport(v, a, b):
    n = jnp.cross(a, b)
    c = jnp.dot(a, b)
    return c * v + jnp.cross(n, v) + n * jnp.dot(n, v) / (1.0 + c)


def reference_twist(xm, x0, xp, um_old, tm_old, u0_old, t0_old):
    """Reference twist at a vertex (radians) with time-parallel transported directors."""
    tm = (x0 - xm) / jnp.linalg.norm(x0 - xm)
    t0 = (xp - x0) / jnp.linalg.norm(xp - x0)
    um = _transport(um_old, tm_old, tm)
    u0 = _transport(u0_old, t0_old, t0)
    carried = _transport(um, tm, t0)
    return jnp.arctan2(jnp.dot(jnp.cross(carried, u0), t0), jnp.dot(carried, u0))


def _split(v9):
    return v9[0:3], v9[3:6], v9[6:9]


def _bend_flat(v9, weight, form):
    xm, x0, xp = _split(v9)
    return weight * curvature_squared(xm, x0, xp, form)


def _twist_flat(v9, frames):
    xm, x0, xp = _split(v9)
    return reference_twist(xm, x0, xp, frames[0], frames[1], frames[2], frames[3])


def _chunked(fn):
    """Apply a vmapped, jitted kernel on chunks of ``CHUNK`` stencils (padded)."""
    compiled = jax.jit(jax.vmap(fn))

    def run(stencils, data):
        stencils = np.asarray(stencils)
        data = np.asarray(data)
        n = stencils.shape[0]
        pad = (-n) % CHUNK
        if pad:  # pad with copies of the first stencil: always a valid input
            stencils = np.concatenate([stencils, np.repeat(stencils[:1], pad, axis=0)])
            data = np.concatenate([data, np.repeat(data[:1], pad, axis=0)])
        out = [np.asarray(compiled(stencils[i:i + CHUNK], data[i:i + CHUNK]))
               for i in range(0, n + pad, CHUNK)]
        return np.concatenate(out)[:n]

    return run


def _make_bending(form: str):
    def value(v9, weight):
        return _bend_flat(v9, weight, form)

    return _chunked(value), _chunked(jax.grad(value)), _chunked(jax.hessian(value))


_BENDING = {form: _make_bending(form) for form in CURVATURE_FORMS}

twist_value = _chunked(_twist_flat)
twist_gradient = _chunked(jax.grad(_twist_flat))
twist_hessian = _chunked(jax.hessian(_twist_flat))


def bending_kernels(form: str):
    """``(value, gradient, hessian)`` of the per-vertex bending energy.

    Each takes ``stencils`` of shape ``(n_vertices, 9)`` and ``weights`` of shape
    ``(n_vertices,)`` (``A / (l_{i-1} + l_i)``) and returns shapes
    ``(n_vertices,)``, ``(n_vertices, 9)``, ``(n_vertices, 9, 9)``.
    """
    if form not in _BENDING:
        raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")
    return _BENDING[form]
