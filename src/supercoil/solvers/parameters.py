"""Functional update of a problem's parameters: ``problem.at(name=value)``.

A problem's load parameters (a ring's ``excess_link``, a clamped rod's ``turns``
and ``tension``) are never set on the problem a caller holds: ``at`` returns a
new problem of the same class at the new values, sharing everything that does
not depend on them (the rod, the stencil patterns, the compiled layouts), and
leaves the original unchanged. Continuation evaluates its residual at
``problem.at(**{parameter: lambda})``.

:class:`Parametrised` implements ``at`` once, as a shallow copy whose parameters
are set on the copy only; a class lists its parameters in ``parameters`` and, if
setting one must rebind more than the attribute (a rotation that an end clamp
imposes, a rod with another intrinsic twist), does so in ``_set_parameter``
without writing into arrays the copy shares with the original.
:func:`problem_at` gives any protocol object the same update (``at`` if it has
one, else a shallow copy with the attribute set on the copy).
"""

from __future__ import annotations

import copy

from supercoil.errors import InputError


class Parametrised:
    """Mixin: ``at(**values)``, a copy of the problem at other parameter values."""

    # the names ``at`` accepts
    parameters: tuple[str, ...] = ()

    def at(self, **values: float):
        """A new problem of this class at ``values`` (``name=value`` for some of
        :attr:`parameters`), sharing all else with this one, which is unchanged."""
        unknown = sorted(set(values) - set(self.parameters))
        if unknown:
            raise InputError(f"{type(self).__name__}.at: unknown parameter(s) "
                             f"{', '.join(map(repr, unknown))}; valid: "
                             f"{', '.join(map(repr, self.parameters)) or 'none'}")
        new = copy.copy(self)
        for name, value in values.items():
            new._set_parameter(name, float(value))
        return new

    def _set_parameter(self, name: str, value: float) -> None:
        """Set ``name`` on this (new) problem; rebinds, never writes into shared arrays."""
        setattr(self, name, value)


def problem_at(problem, **values: float):
    """``problem.at(**values)`` if the problem has ``at``; otherwise a shallow copy
    with each ``name`` set on the copy (a caller's own protocol object, whose
    parameter is a plain attribute), the original unchanged."""
    at = getattr(problem, "at", None)
    if at is not None:
        return at(**values)
    missing = sorted(name for name in values if not hasattr(problem, name))
    if missing:
        raise InputError(f"the problem has no parameter attribute(s) "
                         f"{', '.join(map(repr, missing))}")
    new = copy.copy(problem)
    for name, value in values.items():
        setattr(new, name, float(value))
    return new
