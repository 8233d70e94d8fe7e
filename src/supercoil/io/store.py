"""Result files: one self-describing HDF5 file per computation (``docs/results.md``).

The pieces: :mod:`supercoil.io.store_write` (:class:`ResultWriter`, whole-file
snapshots), :mod:`supercoil.io.journal` (the append-only journal of the
changes between two snapshots), :mod:`supercoil.io.store_read` (:func:`load`,
:class:`Result`, checksum verification), :mod:`supercoil.io.contents` (what a
file holds), :mod:`supercoil.io.branch_codec` (a branch as named arrays) and
:mod:`supercoil.io.checksums`. This module gathers their public names.
"""

from __future__ import annotations

from supercoil.io.contents import FORMAT, READABLE_VERSIONS, RUN_STATUSES, SCHEMA_VERSION
from supercoil.io.store_read import RESULT_NAME, Result, ResultFileError, load, resolve
from supercoil.io.store_write import ResultWriter, write_snapshot

__all__ = ["FORMAT", "READABLE_VERSIONS", "RESULT_NAME", "RUN_STATUSES", "SCHEMA_VERSION",
           "Result", "ResultFileError", "ResultWriter", "load", "resolve", "save",
           "write_snapshot"]


def save(path, branches, *, problem: str = "branches", settings: dict | None = None,
         attributes: dict | None = None, summary: dict | None = None,
         status: str = "complete", overwrite: bool = False) -> None:
    """Write ``branches`` (:class:`~supercoil.continuation.Branch` objects) as one result
    file at ``path``, readable with :func:`load`."""
    with ResultWriter.create(path, problem=problem, settings=settings or {},
                             attributes=attributes, overwrite=overwrite) as writer:
        for branch in branches:
            writer.write_branch(branch, complete=True)
        if summary is not None:
            writer.set_summary(summary)
        writer.set_status(status)
