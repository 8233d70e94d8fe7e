"""The bifurcation diagram of a ring with self-contact (Coleman & Swigon 2002, Figures 1-4).

:func:`ring_diagram` computes, for a ring of twist ratio ``C/A`` and tube
diameter ``D = L / (L/D)`` (:class:`DiagramOptions`):

1. the circle in ``dLk`` (branch ``circle``) and its Michell bifurcation
   points (:mod:`supercoil.problems.ring_branches`);
2. for each requested mode ``m`` the primary branch switched from the
   circle's bifurcation of mode ``m`` (``alpha``, ``beta``, ...) and followed
   **without contact** up to its first contact, the special point
   ``contact_onset`` (:mod:`~supercoil.problems.ring_diagram.primary`);
3. from the last point before the onset the branch continued **with
   self-contact** (branch ``alpha_contact``, parent ``alpha``, origin the
   ``contact_onset`` point), its contact events located and classified
   (:mod:`supercoil.problems.contact_events`), the material sliding held by a
   gauge and the rigid pins re-picked where they lose their grip
   (:mod:`~supercoil.problems.ring_diagram.contact_branches`);
4. optionally the secondary and tertiary branches switched from the located
   bifurcation points (:mod:`~supercoil.problems.ring_diagram.secondary`).

The result, a :class:`RingDiagram`, holds the branches and gives one record
per point (:meth:`RingDiagram.points`) and the ``diagram.json`` payload
(:meth:`RingDiagram.payload`). The modules: ``options`` (the options),
``records`` (per-point records), ``primary``, ``contact_branches``,
``secondary`` (the branches of each kind), ``result`` (the diagram) and
``compute`` (the driver).
"""

from supercoil.problems.ring_diagram.compute import ring_diagram
from supercoil.problems.ring_diagram.options import (
    CONTINUATION_TREATMENTS,
    MAX_MODE,
    DiagramOptions,
    parse_modes,
)
from supercoil.problems.ring_diagram.result import RingDiagram, link_writhe_slope_sign

__all__ = ["CONTINUATION_TREATMENTS", "MAX_MODE", "DiagramOptions", "RingDiagram",
           "link_writhe_slope_sign", "parse_modes", "ring_diagram"]
