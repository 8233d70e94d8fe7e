"""The append-only journal beside a result file (``result.h5.journal``).

While a run writes its result, every change (a branch's new points, a branch
made final, the summary, the status) is one record appended to the journal
with one ``write`` to the operating system: a point is in the journal as soon
as it is accepted, and a killed process (SIGKILL included) loses nothing that
was written. The HDF5 file itself is only ever replaced whole (written to a
temporary file, then renamed), so it always opens; it names the journal
generation it continues, and :func:`read_journal` returns the records of that
generation for the reader to replay.

A record::

    magic  b"SCJRNL01"                 8 bytes
    length of the payload              8 bytes, little-endian
    SHA-256 of the payload             32 bytes
    SHA-256 of the 48 bytes above      its first 8 bytes
    payload: header length (4 bytes, little-endian), the header (JSON: op, args,
             arrays = [[name, dtype, shape, offset, nbytes], ...]), the arrays' bytes

The first record (op ``journal``) holds the generation. A record cut short at
the end of the file (its header whole and right, its payload short) is a
write the process did not finish (it was killed): it is ignored. Any other
mismatch (a header or a payload whose hash does not match) is damage.
"""

from __future__ import annotations

import json
import os
import struct
from pathlib import Path

import numpy as np

MAGIC = b"SCJRNL01"
_HEAD = struct.Struct("<8sQ32s8s")
_DTYPES = ("<f8", "<i8", "|b1")
SUFFIX = ".journal"


class JournalError(ValueError):
    """A damaged journal; the message says where."""


class JournalLocked(OSError):
    """Another process holds the journal's lock (it is writing the result)."""


def journal_path(result: Path) -> Path:
    return result.with_name(result.name + SUFFIX)


def encode(op: str, args: dict, arrays: dict | None = None) -> bytes:
    """One record (see the module docstring)."""
    import hashlib

    table, blobs, offset = [], [], 0
    for name, a in (arrays or {}).items():
        a = np.asarray(a, order="C")
        if a.dtype.kind == "b":
            a = a.astype(np.bool_)
        elif a.dtype.kind in "iu":
            a = a.astype("<i8")
        else:
            a = a.astype("<f8")
        data = a.tobytes()
        table.append([name, a.dtype.str, list(a.shape), offset, len(data)])
        blobs.append(data)
        offset += len(data)
    header = json.dumps({"op": op, "args": args, "arrays": table},
                        separators=(",", ":")).encode("utf-8")
    payload = struct.pack("<I", len(header)) + header + b"".join(blobs)
    digest = hashlib.sha256(payload).digest()
    return _HEAD.pack(MAGIC, len(payload), digest, _check(len(payload), digest)) + payload


def _check(length: int, digest: bytes) -> bytes:
    import hashlib

    return hashlib.sha256(MAGIC + struct.pack("<Q", length) + digest).digest()[:8]


def _decode(payload: bytes, where: str) -> tuple[str, dict, dict]:
    (n,) = struct.unpack_from("<I", payload)
    header = json.loads(payload[4:4 + n].decode("utf-8"))
    body = memoryview(payload)[4 + n:]
    arrays = {}
    for name, dtype, shape, offset, nbytes in header["arrays"]:
        if dtype not in _DTYPES:
            raise JournalError(f"{where}: array {name!r} of dtype {dtype!r}")
        shape = tuple(int(s) for s in shape)
        if int(np.prod(shape, dtype=np.int64)) * np.dtype(dtype).itemsize != nbytes \
                or offset + nbytes > len(body):
            raise JournalError(f"{where}: array {name!r} does not fit its record")
        arrays[name] = np.frombuffer(body[offset:offset + nbytes], dtype=dtype).reshape(shape)
    return str(header["op"]), dict(header["args"]), arrays


def read_journal(path: Path) -> tuple[str | None, list[tuple[str, dict, dict]]]:
    """``(generation, records)`` of the journal at ``path`` (``(None, [])`` if there is
    none); raises :class:`JournalError` naming the record that is damaged."""
    import hashlib

    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None, []
    records, at = [], 0
    while len(data) - at >= _HEAD.size:
        magic, length, digest, check = _HEAD.unpack_from(data, at)
        where = f"{path}: damaged journal: record {len(records)} (byte {at})"
        if magic != MAGIC or check != _check(length, digest):
            raise JournalError(f"{where}: not a journal record, or its header was altered")
        if len(data) - at - _HEAD.size < length:
            break  # the last write was cut short by the end of the process
        payload = data[at + _HEAD.size:at + _HEAD.size + length]
        if hashlib.sha256(payload).digest() != digest:
            raise JournalError(f"{where}: checksum mismatch (the record was altered)")
        try:
            records.append(_decode(payload, where))
        except (ValueError, KeyError, TypeError, struct.error) as exc:
            raise JournalError(f"{where}: unreadable ({exc})") from None
        at += _HEAD.size + length
    if not records:
        return None, []
    op, args, _ = records[0]
    if op != "journal":
        raise JournalError(f"{path}: damaged journal: it does not start with its generation "
                           "record")
    return str(args["generation"]), records[1:]


class Journal:
    """The writer's end: an exclusive lock on the journal file and its appends."""

    def __init__(self, path: Path):
        self.path = path
        self._fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            _lock(self._fd)
        except BaseException:
            os.close(self._fd)
            raise
        self._size = 0
        self._torn = False

    def start(self, generation: str) -> None:
        """Empty the journal and begin ``generation``."""
        os.ftruncate(self._fd, 0)
        self._size = 0
        self._torn = False
        self.append("journal", {"generation": generation})

    def append(self, op: str, args: dict, arrays: dict | None = None) -> None:
        """Append one record with one write; a record left half-written (an exception
        in the middle) is cut off before the next one."""
        record = encode(op, args, arrays)
        if self._torn:
            os.ftruncate(self._fd, self._size)
        self._torn = True
        view = memoryview(record)
        while view:
            view = view[os.write(self._fd, view):]
        self._torn = False
        self._size += len(record)

    def close(self, remove: bool = False) -> None:
        if self._fd is None:
            return
        if remove:
            self.path.unlink(missing_ok=True)
        os.close(self._fd)  # releases the lock
        self._fd = None


def _lock(fd: int) -> None:
    try:
        import fcntl
    except ImportError:  # no advisory locks on this platform
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise JournalLocked("locked") from None
