"""Topology of polygonal curves: writhe, linking number and twist (in turns).

- :func:`writhe`: exact Gauss integral of a polygon as signed solid angles
  (numba, parallel), with closures ``"closed"``, ``"chord"``, ``"none"`` and
  ``"axis"`` (straight tails along the pulling axis);
  :func:`writhe_reference` is the plain numpy oracle.
- :func:`linking_number`: Gauss linking number of two closed polygons.
- :func:`twist_from_frames`: total twist of a framed polygon by discrete
  parallel transport (Bergou et al. 2008); :func:`parallel_transport`.

For a closed framed polygon ``Lk = Tw + Wr`` (Călugăreanu, White), with the
three terms computed independently here.
"""

from supercoil.topology.linking import linking_number
from supercoil.topology.twist import parallel_transport, twist_from_frames
from supercoil.topology.writhe import writhe
from supercoil.topology.writhe_reference import writhe_reference

__all__ = [
    "linking_number",
    "parallel_transport",
    "twist_from_frames",
    "writhe",
    "writhe_reference",
]
