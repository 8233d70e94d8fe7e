"""PNG files of the tweezers' figures, encoded with numpy and zlib.

matplotlib saves a PNG through Pillow, whose encoder chooses a filter for every row
of the image by trying several of them (libpng's heuristic): on the tweezers' figures
that choice took most of the encoding (Pillow at zlib level 0, no deflating to speak
of, still took 15 of its 20 ms at level 1 on the hat curve). A figure's rows are
mostly equal to the row above (white background, grid, axes, lines), so
:func:`encode_png` filters every row with PNG's Up filter (its difference to the row
above, one numpy subtraction) and deflates the rows with zlib at level 1, as Pillow
did. On the four figures of issue 5's run: 19.9, 20.2, 20.1, 26.4 ms -> 6.6, 6.9,
6.6, 10.8 ms CPU (hat curve, torque, writhe, configurations; minima of 25 alternated
encodings of each, medians within 0.1 ms), files 1.6-4.4 % larger. The image decodes
to the same pixels (tests/test_plot.py), with the same chunks besides the pixels: the
dpi (``pHYs``) and the ``Software`` text matplotlib writes
(:func:`supercoil.plotting.tweezers.save_png`).
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"
ZLIB_LEVEL = 1  # as the tweezers' figures were saved by Pillow (tweezers.SAVE_OPTIONS)
UP = 2  # PNG's filter type Up: each byte minus the byte above it


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(data, zlib.crc32(kind))))


def encode_png(rgba: np.ndarray, *, dpi: float | None = None,
               text: Mapping[str, str] | None = None) -> bytes:
    """The PNG file of ``rgba`` (height, width, 4) ``uint8``, 8 bits a channel, colour type
    RGBA; ``dpi`` as its ``pHYs`` chunk (pixels per metre, rounded as Pillow rounds
    them) and ``text`` as ``tEXt`` chunks (Latin-1), before the pixels."""
    rgba = np.asarray(rgba)
    if rgba.dtype != np.uint8 or rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"an RGBA image of uint8 is needed, not {rgba.dtype} "
                         f"{rgba.shape}")
    height, width, _ = rgba.shape
    rows = rgba.reshape(height, width * 4)
    filtered = np.empty((height, width * 4 + 1), np.uint8)
    filtered[:, 0] = UP
    filtered[0, 1:] = rows[0]  # the row above the first is zero
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])  # modulo 256, as PNG's
    parts = [SIGNATURE, _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0,
                                                     0))]
    for key, value in (text or {}).items():
        parts.append(_chunk(b"tEXt", key.encode("latin-1") + b"\0"
                            + value.encode("latin-1")))
    if dpi is not None:
        per_metre = int(dpi / 0.0254 + 0.5)
        parts.append(_chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)))
    parts.append(_chunk(b"IDAT", zlib.compress(filtered, ZLIB_LEVEL)))
    parts.append(_chunk(b"IEND", b""))
    return b"".join(parts)
