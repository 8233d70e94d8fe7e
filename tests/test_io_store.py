"""Result files (supercoil.io.store): round trips, partial branches, interrupted writers,
damaged files (random byte flips and truncations with fixed seeds)."""

from __future__ import annotations

import dataclasses
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import interruptible
import numpy as np
import pytest

import supercoil
from supercoil.continuation import Branch, ContinuationStatus, SpecialPoint
from supercoil.errors import InputError
from supercoil.io.store import ResultFileError, ResultWriter, load, save

POINT_ARRAYS = ("parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")


def special(rng, name, index, n_dofs, m, kind="bifurcation", records=True):
    return SpecialPoint(
        kind=kind, label=f"{kind}-label", branch=name, index=index,
        parameter=float(rng.normal()), arclength=float(rng.random()),
        q=rng.normal(size=n_dofs), multipliers=rng.normal(size=m),
        tangent=rng.normal(size=n_dofs + m + 1), unstable_count=2, count_before=0,
        count_after=2, critical_eigenvalues=rng.normal(size=2),
        critical_modes=rng.normal(size=(2, n_dofs)), located=bool(index % 2),
        tolerance=1e-8, records={"writhe": np.float64(rng.normal()),
                                 "vector": rng.normal(size=3)} if records else {})


def make_branch(k=7, n_dofs=12, m=4, name="alpha", seed=0, origin=True) -> Branch:
    rng = np.random.default_rng(seed)
    return Branch(
        name=name, parent="circle" if origin else None,
        origin=special(rng, "circle", 3, n_dofs, m) if origin else None,
        parameter="excess_link", parameter_values=rng.normal(size=k),
        states=rng.normal(size=(k, n_dofs)), multipliers=rng.normal(size=(k, m)),
        unstable_count=rng.integers(0, 4, size=k), zero_modes=rng.integers(0, 2, size=k),
        determinant_sign=rng.choice([-1, 1], size=k), nearest_eigenvalue=rng.normal(size=k),
        tangents=rng.normal(size=(k, n_dofs + m + 1)), arclength=np.cumsum(rng.random(k)),
        special_points=tuple(special(rng, name, i, n_dofs, m, kind)
                             for i, kind in ((1, "fold"), (4, "contact_onset"))),
        status=ContinuationStatus.MAX_POINTS, message="7 points computed (max_points)",
        records={"writhe": rng.normal(size=k), "n_contact_points": rng.integers(0, 3, size=k),
                 "pair": rng.normal(size=(k, 2)), "tail_wrapped": rng.random(k) > 0.5},
        phase_modes=rng.normal(size=(1, n_dofs)), phase_state=rng.normal(size=n_dofs))


def prefix(branch: Branch, k: int) -> Branch:
    """The branch as the continuation saw it after ``k`` points."""
    return dataclasses.replace(
        branch, special_points=tuple(p for p in branch.special_points if p.index + 1 < k),
        records={n: v[:k] for n, v in branch.records.items()},
        **{n: getattr(branch, n)[:k] for n in POINT_ARRAYS})


def assert_special_equal(a: SpecialPoint, b: SpecialPoint):
    for f in dataclasses.fields(SpecialPoint):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "records":
            assert x.keys() == y.keys()
            for key in x:
                np.testing.assert_array_equal(x[key], y[key])
        elif isinstance(x, np.ndarray):
            assert x.shape == y.shape
            np.testing.assert_array_equal(x, y)
        else:
            assert x == y, f.name
            assert type(x) is type(y), f.name


def assert_branch_equal(a: Branch, b: Branch):
    for f in dataclasses.fields(Branch):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape, f.name
            assert x.dtype.kind == y.dtype.kind, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        elif f.name == "records":
            assert x.keys() == y.keys()
            for key in x:
                np.testing.assert_array_equal(x[key], y[key], err_msg=key)
        elif f.name == "special_points":
            assert len(x) == len(y)
            for p, q in zip(x, y):
                assert_special_equal(p, q)
        elif f.name == "origin":
            assert (x is None) == (y is None)
            if x is not None:
                assert_special_equal(x, y)
        else:
            assert x == y, f.name


def new_writer(path, **kw):
    kw.setdefault("settings", {"rod": {"twist_ratio": 0.5, "nodes": 4}, "list": [1, 2]})
    return ResultWriter.create(path, problem="ring_diagram",
                               attributes={"n_nodes": 4, "diameter": 0.025, "closed": True,
                                           "twist_ratio": 0.5}, study_text="[rod]\n", **kw)


def test_round_trip_whole_branches(tmp_path):
    path = tmp_path / "r.h5"
    branches = [make_branch(name="circle", origin=False, seed=1), make_branch(seed=2),
                make_branch(k=1, name="single", seed=3), make_branch(k=0, name="empty", seed=4),
                make_branch(k=2, name=".odd/name 100%", seed=5)]
    with new_writer(path) as writer:
        for b in branches:
            writer.write_branch(b, contact=b.name == "alpha")
        writer.set_summary({"points": [{"branch": "alpha", "index": 0, "x": 1.5}], "ok": True})
        writer.set_status("complete", "done")
    result = supercoil.load(path)
    assert result.branch_names == ("circle", "alpha", "single", "empty", ".odd/name 100%")
    for b in branches:
        assert_branch_equal(b, result.branch(b.name))
    assert result.status == "complete" and result.message == "done"
    assert result.settings == {"rod": {"twist_ratio": 0.5, "nodes": 4}, "list": [1, 2]}
    assert result.summary == {"points": [{"branch": "alpha", "index": 0, "x": 1.5}], "ok": True}
    assert result.points("alpha") == [{"branch": "alpha", "index": 0, "x": 1.5}]
    assert result.study_text == "[rod]\n"
    assert result.complete_branches == frozenset(b.name for b in branches)
    assert result.contact_branches == {"alpha"}
    assert result.attributes["n_nodes"] == 4 and result.diameter == 0.025 and result.closed
    assert result.provenance["supercoil_version"] == supercoil.__version__
    assert "excess_link" in result.conventions
    np.testing.assert_array_equal(result.centreline("alpha", -1),
                                  branches[1].states[-1].reshape(4, 3))


def test_appending_point_by_point_equals_the_whole_branch(tmp_path):
    branch = make_branch(k=9, seed=5)
    path = tmp_path / "r.h5"
    with new_writer(path) as writer:
        for k in range(1, len(branch) + 1):
            assert writer.append(prefix(branch, k)) == k
            partial = load(path).branch("alpha")  # readable after every point
            assert_branch_equal(prefix(branch, k), partial)
        writer.append(branch)  # same length: nothing new
    result = load(path)
    assert_branch_equal(branch, result.branch("alpha"))
    assert result.status == "running" and result.complete_branches == frozenset()
    rows = result.points("alpha")  # no summary: built from the records
    assert [r["index"] for r in rows] == list(range(9))
    np.testing.assert_array_equal([r["writhe"] for r in rows], branch.records["writhe"])
    np.testing.assert_array_equal([r["excess_link"] for r in rows], branch.parameter_values)
    assert [r["stable"] for r in rows] == list(branch.stable)


def test_branches_without_constraints_round_trip(tmp_path):
    """m = 0 (the generic continuation's toy problems): zero-width multipliers."""
    branch = make_branch(k=7, m=0, seed=6)
    path = tmp_path / "r.h5"
    with new_writer(path) as writer:
        for k in range(1, 8):
            writer.append(prefix(branch, k))
        writer.write_branch(dataclasses.replace(branch, name="whole"))
    result = load(path)
    assert_branch_equal(branch, result.branch("alpha"))
    assert result.branch("whole").multipliers.shape == (7, 0)


def test_appending_follows_a_moved_gauge(tmp_path):
    """A branch that re-picks its phase row (ContinuationOptions.regauge) is stored with
    the row its last point satisfies, so that a resume starts from it."""
    branch = make_branch(k=6, seed=7)
    moved = np.zeros_like(branch.phase_modes)
    moved[0, 7] = 1.0
    later = dataclasses.replace(branch, phase_modes=moved, phase_state=branch.states[-1])
    path = tmp_path / "r.h5"
    with new_writer(path) as writer:
        writer.append(prefix(branch, 3))
        writer.append(later)
    stored = load(path).branch("alpha")
    np.testing.assert_array_equal(stored.phase_modes, moved)
    np.testing.assert_array_equal(stored.phase_state, branch.states[-1])


def test_write_branch_replaces_a_partial_one_and_keeps_its_order(tmp_path):
    path = tmp_path / "r.h5"
    first, second = make_branch(name="circle", origin=False, seed=1), make_branch(seed=2)
    with new_writer(path) as writer:
        writer.append(prefix(first, 3))
        writer.write_branch(second)
        final = prefix(first, 5)
        writer.write_branch(final)
    with h5py.File(path, "r") as raw:
        assert sorted(raw["branches"]) == ["alpha", "circle"]
    result = load(path)
    assert result.branch_names == ("circle", "alpha")
    assert_branch_equal(final, result.branch("circle"))
    assert "circle" in result.complete_branches


def test_a_torn_journal_record_is_ignored(tmp_path):
    """A write cut short by the end of the process (its record incomplete at the end of
    the journal): the reader returns the points before it; a resumed writer drops it."""
    path = tmp_path / "r.h5"
    branch = make_branch(seed=6)
    writer = new_writer(path)
    writer.append(prefix(branch, 4))
    journal = path.with_name("r.h5.journal")
    whole = journal.read_bytes()
    writer.append(prefix(branch, 5))
    grown = journal.read_bytes()
    writer._journal.close()  # as a killed process: no final snapshot
    journal.write_bytes(grown[:len(whole) + (len(grown) - len(whole)) // 2])
    assert_branch_equal(prefix(branch, 4), load(path).branch("alpha"))
    with ResultWriter.reopen(path) as again:
        again.append(branch)
    assert_branch_equal(branch, load(path).branch("alpha"))
    assert not journal.exists()


@pytest.mark.parametrize("content, words", [
    (None, "no such result file"),
    (b"not hdf5 at all", "not a readable HDF5"),
    ("foreign", "not a supercoil result file"),
    ("version", "schema version '9.9'"),
    ("folder", "folder has no result.h5"),
])
def test_bad_files_are_one_line_errors(tmp_path, content, words):
    path = tmp_path / "x.h5"
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content == "foreign":
        with h5py.File(path, "w") as f:
            f.attrs["something"] = 1
    elif content == "version":
        new_writer(path).close()
        with h5py.File(path, "r+") as f:
            f.attrs["schema_version"] = "9.9"
    elif content == "folder":
        path.mkdir()
    with pytest.raises(ResultFileError) as info:
        load(path)
    message = str(info.value)
    assert words in message and str(path) in message and "\n" not in message


def test_damaged_file_is_reported(tmp_path):
    path = tmp_path / "r.h5"
    with new_writer(path) as writer:
        writer.append(make_branch())
    with h5py.File(path, "r+") as f:
        del f["branches/alpha/states"]
    with pytest.raises(ResultFileError, match="damaged result file") as info:
        load(path)
    assert isinstance(info.value, InputError)


def test_create_refuses_an_existing_file(tmp_path):
    path = tmp_path / "r.h5"
    path.write_text("keep me")
    with pytest.raises(FileExistsError):
        new_writer(path)
    assert path.read_text() == "keep me"


def test_unknown_branch_and_point_name_what_is_valid(tmp_path):
    path = tmp_path / "r.h5"
    with new_writer(path) as writer:
        writer.write_branch(make_branch(k=3))
    result = load(path)
    with pytest.raises(KeyError, match="stored: alpha"):
        result.branch("beta")
    with pytest.raises(IndexError, match=r"3 points \(0 .. 2\)"):
        result.centreline("alpha", 3)


def test_a_file_being_written_can_be_read(tmp_path):
    """The writer holds HDF5's file lock; another process still reads the flushed points."""
    path = tmp_path / "r.h5"
    branch = make_branch(seed=8)
    script = (f"import supercoil; r = supercoil.load({str(path)!r}); "
              "print(r.status, len(r.branch('alpha')))")
    with new_writer(path) as writer:
        writer.append(prefix(branch, 3))
        reader = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                                timeout=60, check=False)
        assert reader.stdout.split() == ["running", "3"], reader.stderr
        writer.append(branch)
        reader = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                                timeout=60, check=False)
        assert reader.stdout.split() == ["running", "7"], reader.stderr


def test_a_second_writer_is_refused_while_a_run_writes(tmp_path):
    path = tmp_path / "r.h5"
    holder = textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from test_io_store import make_branch, new_writer
        writer = new_writer({str(path)!r})
        writer.append(make_branch())
        print("ready", flush=True)
        time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", holder], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        for attempt in (lambda: ResultWriter.reopen(path),
                        lambda: new_writer(path, overwrite=True)):
            with pytest.raises(ResultFileError, match="another running process is writing it"):
                attempt()
        assert len(load(path).branch("alpha")) == 7  # still readable meanwhile
    finally:
        proc.kill()
        proc.communicate()
    ResultWriter.reopen(path).close()  # the lock went with the process


WRITER = textwrap.dedent("""
    import sys, time
    sys.path.insert(0, {tests!r})
    from test_io_store import make_branch, new_writer, prefix
    branch = make_branch(k=100000 // 100, n_dofs=300, m=100, seed=7)
    writer = new_writer({path!r})
    try:
        for k in range(1, len(branch) + 1):
            writer.append(prefix(branch, k))
            print(k, flush=True)
            # slower once the parent may signal (it does at 40): a parent descheduled on a
            # loaded host must still find the writer running, not done (960 points, 48 s)
            time.sleep(0.002 if k < 40 else 0.05)
    except KeyboardInterrupt:
        writer.set_status("interrupted", "Ctrl-C")
        writer.close()
        print("interrupted", flush=True)
""")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_killed_writer_leaves_a_readable_file(tmp_path, sig):
    """Kill a writer mid-run: every point it reported stored is in the file, exactly."""
    path = tmp_path / "r.h5"
    script = WRITER.format(tests=os.path.dirname(__file__), path=str(path))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    proc = interruptible.popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                            env=env)
    reported = 0
    deadline = time.monotonic() + 60
    while reported < 40 and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        reported = int(line)
    assert reported >= 40, "the writer did not start"
    proc.send_signal(sig)
    tail = proc.communicate(timeout=30)[0].split()
    if sig == signal.SIGINT:
        assert tail and tail[-1] == "interrupted"
    reported = max([reported] + [int(w) for w in tail if w.isdigit()])
    result = load(path)
    stored = result.branch("alpha")
    assert reported <= len(stored) <= reported + 1
    assert_branch_equal(prefix(make_branch(k=1000, n_dofs=300, m=100, seed=7), len(stored)),
                        stored)
    assert result.status == ("interrupted" if sig == signal.SIGINT else "running")


# ------------------------------------------------------------------------- damage
def assert_same_result(a, b):
    assert list(a.branches) == list(b.branches)
    for name in a.branches:
        assert_branch_equal(a.branch(name), b.branch(name))
    for key in ("status", "message", "settings", "attributes", "summary", "study_text",
                "complete_branches", "contact_branches", "provenance", "conventions"):
        assert getattr(a, key) == getattr(b, key), key


def flipped(source, target, rng) -> tuple[int, int]:
    """Copy ``source`` to ``target`` with one byte at a random place XORed with a random
    non-zero value."""
    data = bytearray(source.read_bytes())
    at = int(rng.integers(len(data)))
    data[at] ^= int(rng.integers(1, 256))
    target.write_bytes(bytes(data))
    return at, data[at]


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    """A closed result file and one left with a journal (its writer killed)."""
    folder = tmp_path_factory.mktemp("stored")
    whole = folder / "whole" / "result.h5"
    whole.parent.mkdir()
    save(whole, [make_branch(name="circle", origin=False, seed=1), make_branch(seed=2)],
         problem="ring_diagram", settings={"rod": {"nodes": 4}},
         attributes={"n_nodes": 4, "diameter": 0.025}, summary={"ok": True, "x": [1.5]})
    live = folder / "live" / "result.h5"
    live.parent.mkdir()
    branch = make_branch(k=9, seed=3)
    writer = new_writer(live)
    writer.write_branch(make_branch(name="circle", origin=False, seed=1))
    for k in range(1, len(branch) + 1):
        writer.append(prefix(branch, k))
    writer.set_summary({"ok": False})
    writer._journal.close()  # as a killed process: the journal stays
    return whole, live


def test_byte_flips_in_a_result_file_load_the_same_data_or_fail_cleanly(tmp_path, stored):
    """Every flip either loads bit-identical data or is a one-line ResultFileError naming
    the file (never altered data, never another exception)."""
    whole, _ = stored
    original = load(whole)
    target = tmp_path / "result.h5"
    rng = np.random.default_rng(20240)
    outcomes = {"same": 0, "error": 0}
    for _ in range(150):
        flipped(whole, target, rng)
        try:
            result = load(target)
        except ResultFileError as exc:
            assert str(target) in str(exc) and "\n" not in str(exc)
            outcomes["error"] += 1
            continue
        assert_same_result(result, original)
        outcomes["same"] += 1
    assert outcomes["error"] > 0  # the data and metadata are most of the file


def test_byte_flips_in_a_journal_load_the_same_data_or_fail_cleanly(tmp_path, stored):
    _, live = stored
    original = load(live)
    assert len(original.branch("alpha")) == 9 and original.status == "running"
    journal = live.with_name("result.h5.journal")
    target = tmp_path / "result.h5"
    shutil.copy(live, target)
    rng = np.random.default_rng(20241)
    errors = 0
    for _ in range(100):
        flipped(journal, tmp_path / "result.h5.journal", rng)
        try:
            result = load(target)
        except ResultFileError as exc:
            assert "result.h5" in str(exc) and "\n" not in str(exc)
            errors += 1
            continue
        assert_same_result(result, original)
    assert errors > 90  # the journal is all records: nearly every byte is checked


def test_truncated_files(tmp_path, stored):
    """A truncated result file is an error; a truncated journal is a write cut short:
    the points of its whole records, a prefix of every branch."""
    whole, live = stored
    original, running = load(whole), load(live)
    target = tmp_path / "result.h5"
    data = whole.read_bytes()
    for size in np.random.default_rng(7).integers(0, len(data), 20):
        target.write_bytes(data[:size])
        with pytest.raises(ResultFileError, match=str(target)):
            load(target)
    target.write_bytes(live.read_bytes())
    journal = live.with_name("result.h5.journal").read_bytes()
    counts = set()
    for size in sorted(np.random.default_rng(8).integers(0, len(journal), 30)):
        (tmp_path / "result.h5.journal").write_bytes(journal[:size])
        result = load(target)
        for name, b in result.branches.items():
            ref = running.branch(name)
            assert_branch_equal(prefix(ref, len(b)) if name == "alpha" else ref, b)
        counts.add(len(result.branches.get("alpha", ())))
    assert len(counts) > 3
    assert original.summary == {"ok": True, "x": [1.5]}


def test_load_reads_a_folder_and_prints_briefly(tmp_path, stored):
    whole, _ = stored
    result = supercoil.load(whole.parent)
    assert result.path == whole
    text = repr(result)
    assert len(text.splitlines()) <= 4 and "circle (7 points)" in text and "[" not in text
    text = repr(result.branch("alpha"))
    assert len(text.splitlines()) <= 3 and "7 points" in text and "array" not in text
