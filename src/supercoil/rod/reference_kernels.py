"""The JAX reference of the rod kernels: automatic differentiation of the formulas of
:mod:`supercoil.rod.stencil_loops` as first written, the oracle of the hand-derived kernels in
the tests (``tests/test_rod.py``) and ``benchmarks/bench_rod_kernels.py``. JAX is imported
only when a reference is asked for (it is a test dependency)."""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from supercoil.rod.kernels import CURVATURE_FORMS, FORM_CODE


@functools.cache
def reference_kernels(form: str) -> dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]:
    """JAX autodiff of the kernels' formulas as first written (``kb``, transported directors).

    Keys ``bending_value``, ``bending_gradient``, ``bending_hessian`` (arguments
    ``stencils, weights``) and ``twist_value``, ``twist_gradient``,
    ``twist_hessian`` (``stencils, frames``), shapes as :func:`bending_kernels`.
    Enables float64 in JAX. Compiles once per number of stencils.
    """
    if form not in FORM_CODE:
        raise ValueError(f"curvature form must be one of {CURVATURE_FORMS}, got {form!r}")
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    # Compiled kernels are cached on disk so that only the first run pays for XLA.
    cache = Path(os.environ.get("SUPERCOIL_CACHE_DIR", Path.home() / ".cache" / "supercoil"))
    try:
        (cache / "jax").mkdir(parents=True, exist_ok=True)
        jax.config.update("jax_compilation_cache_dir", str(cache / "jax"))
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    except OSError:  # read-only home: compile in memory only
        pass
    series_below = 1e-8  # tan^2(phi/2) below which phi^2 uses its Taylor series

    def curvature_squared(xm, x0, xp):
        e = x0 - xm
        f = xp - x0
        kb = 2.0 * jnp.cross(e, f) / (jnp.linalg.norm(e) * jnp.linalg.norm(f) + jnp.dot(e, f))
        tan2 = 0.25 * jnp.dot(kb, kb)  # tan^2(phi/2)
        if form == "tan":
            return 4.0 * tan2
        if form == "sin":
            return 4.0 * tan2 / (1.0 + tan2)  # 4 sin^2(phi/2)
        # phi^2 = 4 atan(t)^2 = 4 t^2 (atan(t)/t)^2 with t^2 = tan2; "double where"
        # keeps the derivatives of the unused branch finite.
        small = tan2 < series_below
        safe = jnp.where(small, 1.0, tan2)
        root = jnp.sqrt(safe)
        ratio2 = jnp.where(
            small, 1.0 - 2.0 * tan2 / 3.0 + 23.0 * tan2**2 / 45.0, (jnp.arctan(root) / root) ** 2
        )
        return 4.0 * tan2 * ratio2

    def transport(v, a, b):
        n = jnp.cross(a, b)
        c = jnp.dot(a, b)
        return c * v + jnp.cross(n, v) + n * jnp.dot(n, v) / (1.0 + c)

    def reference_twist(xm, x0, xp, frames):
        um_old, tm_old, u0_old, t0_old = frames[0], frames[1], frames[2], frames[3]
        tm = (x0 - xm) / jnp.linalg.norm(x0 - xm)
        t0 = (xp - x0) / jnp.linalg.norm(xp - x0)
        um = transport(um_old, tm_old, tm)
        u0 = transport(u0_old, t0_old, t0)
        carried = transport(um, tm, t0)
        return jnp.arctan2(jnp.dot(jnp.cross(carried, u0), t0), jnp.dot(carried, u0))

    def bending(v9, weight):
        return weight * curvature_squared(v9[0:3], v9[3:6], v9[6:9])

    def twist(v9, frames):
        return reference_twist(v9[0:3], v9[3:6], v9[6:9], frames)

    def batched(function):
        compiled = jax.jit(jax.vmap(function))
        return lambda stencils, data: np.asarray(compiled(np.asarray(stencils), np.asarray(data)))

    kernels = {}
    for name, function in (("bending", bending), ("twist", twist)):
        kernels[f"{name}_value"] = batched(function)
        kernels[f"{name}_gradient"] = batched(jax.grad(function))
        kernels[f"{name}_hessian"] = batched(jax.hessian(function))
    return kernels
