"""Study files (supercoil.io.study), 'supercoil run', interrupts and --resume."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import supercoil
from supercoil.cli.main import run as cli
from supercoil.continuation import ContinuationOptions, continuation, switch_branch
from supercoil.continuation.resume import resume_branch
from supercoil.io.study import StudyError, load_study, parse_study
from supercoil.units.dna import effective_diameter_nm

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

RING_DIAGRAM = """
[rod]
twist_ratio = 0.6667
length_over_diameter = 20
nodes = 24

[problem]
kind = "ring_diagram"
modes = [2]
max_excess_link = 4.0

[continuation]
free_max_points = 40
contact_max_points = 8

[outputs]
figures = false
"""


def error(text: str, overrides=()) -> str:
    with pytest.raises(StudyError) as info:
        parse_study(text, "s.toml", overrides)
    message = str(info.value)
    assert "\n" not in message and message.startswith("s.toml: ") or message.startswith("--set")
    return message


# ------------------------------------------------------------------------ validation
def test_defaults_filled_and_values_converted():
    s = parse_study(RING_DIAGRAM).settings
    assert s["rod"] == {"twist_ratio": 0.6667, "length_over_diameter": 20.0, "nodes": 24}
    assert isinstance(s["rod"]["length_over_diameter"], float)
    assert s["problem"] == {"kind": "ring_diagram", "modes": [2], "max_excess_link": 4.0,
                            "contact": "barrier"}
    from supercoil.problems.ring_diagram import DiagramOptions

    assert s["continuation"]["free_max_step"] == DiagramOptions.free_max_step  # its default
    assert s["outputs"] == {"figures": False, "json": True}
    assert s["units"] == {"preset": "nondimensional"}


def test_diagram_options_follow_the_study():
    from supercoil.problems.ring_diagram import DiagramOptions

    opts = parse_study(RING_DIAGRAM, overrides=["continuation.contact_gauge=false"]
                       ).diagram_options()
    assert opts == DiagramOptions(0.6667, 20.0, 24, (2,), 4.0, "barrier", free_max_points=40,
                                  contact_max_points=8, contact_gauge=False)
    deeper = parse_study(RING_DIAGRAM, overrides=["continuation.branch_depth=3",
                                                  'continuation.gauge="integral"']
                         ).diagram_options()
    assert (deeper.branch_depth, deeper.gauge, deeper.secondary_max_points) == (3, "integral", 40)
    # the contact's formulation, curve and predictor and the secondary branches' count
    pairs = parse_study(RING_DIAGRAM, overrides=[
        'continuation.contact_formulation="pairs"', 'continuation.contact_curve="polygon"',
        'continuation.contact_predictor="tangent"', "continuation.secondary_max_branches=3"]
    ).diagram_options()
    assert (pairs.contact_formulation, pairs.contact_curve, pairs.contact_predictor,
            pairs.secondary_max_branches) == ("pairs", "polygon", "tangent", 3)
    default = parse_study(RING_DIAGRAM).diagram_options()
    assert (default.contact_formulation, default.contact_curve, default.contact_predictor,
            default.secondary_max_branches) == (DiagramOptions.contact_formulation,
                                                DiagramOptions.contact_curve,
                                                DiagramOptions.contact_predictor,
                                                DiagramOptions.secondary_max_branches)


@pytest.mark.parametrize("edit, words", [
    (("nodes = 24", "nodse = 24"), ["unknown key [rod] nodse", "did you mean 'nodes'",
                                     "valid keys: twist_ratio, length_over_diameter, nodes"]),
    (("[outputs]", "[output]"), ["unknown table [output]", "did you mean 'outputs'"]),
    (("nodes = 24", 'nodes = "24"'), ["[rod] nodes must be an integer", "'24'",
                                      "a string"]),
    (("nodes = 24", "nodes = 24.0"), ["[rod] nodes must be an integer", "a number"]),
    (("nodes = 24", "nodes = 3"), ["[rod] nodes", "must be a whole number from 8 to 100000",
                                   "got 3"]),
    (("modes = [2]", "modes = [1, 2]"), ["[problem] modes", ("must be distinct whole numbers "
                                         "from 2 to 12")]),
    (("length_over_diameter = 20", "length_over_diameter = 3"),
     ["[rod] length_over_diameter (L/D) must be a number above pi"]),
    (('kind = "ring_diagram"', 'kind = "ring_diagramm"'),
     ["kind = 'ring_diagramm' is not a problem kind", "did you mean 'ring_diagram'"]),
    (("max_excess_link = 4.0", "excess_link = 4.0"),
     ["[problem] excess_link does not apply to a ring_diagram problem"]),
    (("max_excess_link = 4.0", 'contact = "exact"'),
     ["[problem] contact must be one of barrier, penalty, got 'exact'"]),
    (("figures = false", "figures = 0"), ["[outputs] figures must be true or false"]),
    (("twist_ratio = 0.6667", "twist_ratio = true"), ["[rod] twist_ratio must be C/A",
                                                      "a boolean"]),
    (("twist_ratio = 0.6667", "twist_ratio = 2e6"), [("[rod] twist_ratio (C/A) must be a "
                                                     "number above 0 and up to 1e6")]),
    (("twist_ratio = 0.6667", "twist_ratio = inf"), ["[rod] twist_ratio (C/A) must be",
                                                     "got inf"]),
    (("[rod]", "rod = 3\n[rodx]"), ["rod must be a table ([rod]), got an integer"]),
    (("twist_ratio = 0.6667", ""), ["[rod] twist_ratio is missing"]),
    (("[problem]", "[problem]\nkind2 = 1"), ["unknown key [problem] kind2"]),
    (("nodes = 24", "nodes = = 24"), ["not valid TOML"]),
    (("contact_max_points = 8", "branch_depth = 4"),
     ["[continuation] branch_depth", "1 primary, 2 and secondary, 3 and tertiary",
      "from 1 to 3"]),
    (("contact_max_points = 8", 'gauge = "nodes"'), ['gauge must be "node" or "integral"']),
    (("contact_max_points = 8", 'contact_formulation = "pair"'),
     ['contact_formulation must be "integral" or "pairs"']),
    (("contact_max_points = 8", 'contact_curve = "quintic"\ncontact_formulation = "pairs"'),
     ["[continuation] contact_curve 'quintic' needs contact_formulation 'integral'"]),
    (("contact_max_points = 8", "contact_max_points = 10000000"),
     ["[continuation] contact_max_points", "from 2 to 100000"]),
])
def test_bad_keys_and_types_are_one_line_errors(edit, words):
    old, new = edit
    assert old in RING_DIAGRAM
    message = error(RING_DIAGRAM.replace(old, new, 1))
    for w in words:
        assert w in message, message


def test_missing_tables_and_kind():
    assert "missing table [problem]" in error("[rod]\ntwist_ratio = 1.0\n")
    assert "[problem] kind is missing" in error("[rod]\ntwist_ratio = 1.0\n[problem]\n")


def test_overrides():
    s = parse_study(RING_DIAGRAM, overrides=["rod.nodes=32", "problem.contact=penalty",
                                             "study.name='x y'"]).settings
    assert s["rod"]["nodes"] == 32 and s["problem"]["contact"] == "penalty"
    assert s["study"]["name"] == "x y"
    assert "give TABLE.KEY=VALUE" in error(RING_DIAGRAM, ["nodes=3"])
    assert "unknown table [rods]" in error(RING_DIAGRAM, ["rods.nodes=3"])
    assert "[rod] nodes must be an integer" in error(RING_DIAGRAM, ["rod.nodes=many"])


DNA = """
[units]
preset = "dna"
base_pairs = 600
salt_mM = 100
[rod]
nodes = 64
[problem]
kind = "ring_diagram"
modes = [2]
max_superhelical_density = 0.05
"""


def test_dna_preset_derives_the_nondimensional_numbers():
    study = parse_study(DNA)
    s = study.settings
    length_nm = 600 * 0.34
    assert s["rod"]["twist_ratio"] == pytest.approx(95 / 50, rel=1e-15)
    assert s["rod"]["length_over_diameter"] == pytest.approx(
        length_nm / effective_diameter_nm(100.0), rel=1e-15)
    assert s["problem"]["max_excess_link"] == pytest.approx(0.05 * 600 / 10.5, rel=1e-15)
    assert s["units"]["effective_diameter_nm"] == pytest.approx(effective_diameter_nm(100.0))
    assert s["units"]["salt_mM"] == 100.0 and "diameter_nm" not in s["units"]
    assert study.dna_preset().length_nm == pytest.approx(length_nm)


@pytest.mark.parametrize("edit, words", [
    (("nodes = 64", "nodes = 64\ntwist_ratio = 1.0"),
     ["[rod] twist_ratio cannot be given with units preset 'dna'"]),
    (("base_pairs = 600", ""), ["[units] base_pairs is missing"]),
    (("salt_mM = 100", "salt_mM = 100\ndiameter_nm = 4"), ["salt_mM and diameter_nm both"]),
    (("max_superhelical_density = 0.05", "max_excess_link = 3"),
     ["[problem] max_excess_link cannot be given with units preset 'dna'"]),
    (("base_pairs = 600", "base_pairs = 12"), ["[units] base_pairs", "L/D = ",
                                               "give base_pairs >= "]),
    (("base_pairs = 600", "base_pairs = 100000000"), ["[units] base_pairs", "12 to 10000000"]),
    (("salt_mM = 100", "salt_mM = 1e9"), ["[units] salt_mM", "10 to 200 mM"]),
    (("max_superhelical_density = 0.05", "max_superhelical_density = 6"),
     ["[problem] max_superhelical_density", "up to 1"]),
])
def test_dna_errors(edit, words):
    old, new = edit
    message = error(DNA.replace(old, new, 1))
    for w in words:
        assert w in message, message


TWEEZERS = """
[rod]
twist_ratio = 1.3333
length_over_diameter = 20
nodes = 40
[problem]
kind = "tweezers"
tension = 20.0
turns = [0, 1.6]
"""
DNA_RING_STUDY = """
[units]
preset = "dna"
base_pairs = 600
[rod]
nodes = 40
[problem]
kind = "ring"
superhelical_density = -0.06
"""


@pytest.mark.parametrize("study, edit, option, value", [
    (TWEEZERS, ("turns = [0, 1.6]", "turns = [0, 1e300]"), "--turns", "0:1e300"),
    (TWEEZERS, ("tension = 20.0", "tension = -1.0"), "--tension", "-1"),
    (TWEEZERS, ("nodes = 40", "nodes = 11"), "--nodes", "11"),
    (DNA_RING_STUDY, ("superhelical_density = -0.06", "superhelical_density = -6"), "--sigma",
     "-6"),
    (DNA_RING_STUDY, ("base_pairs = 600", "base_pairs = 20"), "--bp", "20"),
    (RING_DIAGRAM, ("max_excess_link = 4.0", "max_excess_link = 1e300"), "--max-excess-link",
     "1e300"),
])
def test_study_files_and_the_command_line_refuse_the_same_values(tmp_path, study, edit,
                                                                 option, value):
    """Oracle: one validation. The study's value is refused with the message of the options
    (naming the study's key), and the command line refuses the same value with the same
    message (naming its option), exit 2, writing nothing."""
    from supercoil.cli.main import run

    old, new = edit
    assert old in study
    message = error(study.replace(old, new, 1))
    kind = parse_study(study).kind
    args = {"tweezers": ["tweezers", "--twist-ratio", "4/3", "--length-over-diameter", "20",
                         "--nodes", "40", "--tension", "20", "--turns", "0:1.6"],
            "ring": ["ring", "--dna", "--bp", "600", "--sigma", "-0.06", "--nodes", "40"],
            "ring_diagram": ["diagram", "ring", "--twist-ratio", "0.6667",
                             "--length-over-diameter", "20", "--nodes", "24"]}[kind]
    args = [a for a in args]
    k = args.index(option) if option in args else None
    if k is None:
        args += [option, value]
    else:
        args[k + 1] = value
    if kind != "ring":
        args += ["--out", str(tmp_path / "out")]
    import contextlib
    import io

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = run(args)
    line = err.getvalue().strip()
    assert status == 2 and line.startswith(f"error: {option}"), (status, line)
    # the same text after the input's name (what is wrong and what is valid), the names
    # of inputs aside (an option on the command line, a key in the study)
    def text(words: str) -> str:
        return re.sub(r"--[a-z-]+|\b[a-z]+_[a-z_]+\b", "NAME", words)

    assert text(line.split(" ", 2)[2]) == text(message.split("] ", 1)[1].split(" ", 1)[1]), \
        (line, message)
    assert not (tmp_path / "out").exists()


def test_dna_keys_need_the_preset():
    text = RING_DIAGRAM.replace("[rod]", "[units]\nbase_pairs = 600\n[rod]")
    assert "[units] base_pairs cannot be given with units preset 'nondimensional'" in error(text)


def test_examples_are_valid_studies():
    names = sorted(p.name for p in EXAMPLES.glob("*.toml"))
    assert {"ring_diagram.toml", "dna_plasmid.toml"} <= set(names)
    for path in EXAMPLES.glob("*.toml"):
        if "\n[sweep]" in path.read_text(encoding="utf-8"):
            continue  # a sweep study, for supercoil sweep: tests/test_sweep.py reads it
        study = load_study(path)
        assert study.kind in ("ring_diagram", "ring", "tweezers")


def test_missing_study_file(tmp_path):
    with pytest.raises(StudyError, match="no such study file"):
        load_study(tmp_path / "none.toml")


# ------------------------------------------------------------------------------- run
def write_study(tmp_path, text=RING_DIAGRAM) -> Path:
    path = tmp_path / "study.toml"
    path.write_text(text)
    return path


def one_line_error(capsys, status, expected_status=2):
    captured = capsys.readouterr()
    assert status == expected_status, captured
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), captured.err
    return lines[0]


def test_run_bad_input_exit_2_and_nothing_touched(tmp_path, capsys):
    study = write_study(tmp_path, RING_DIAGRAM.replace("nodes = 24", "nodez = 24"))
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(tmp_path / "o")]))
    assert "nodez" in line and "did you mean 'nodes'" in line
    assert not (tmp_path / "o").exists()
    study = write_study(tmp_path)
    taken = tmp_path / "taken"
    taken.mkdir()
    (taken / "keep.txt").write_text("mine")
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(taken)]))
    assert "not empty" in line and (taken / "keep.txt").read_text() == "mine"
    assert sorted(p.name for p in taken.iterdir()) == ["keep.txt"]
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(taken), "--resume"]))
    assert "nothing to resume" in line
    (taken / "result.h5").write_bytes(b"garbage")
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(taken), "--resume"]))
    assert "--resume: " in line and "not a readable HDF5 result file" in line
    assert (taken / "result.h5").read_bytes() == b"garbage"
    line = one_line_error(capsys, cli(["run", str(tmp_path / "nope.toml"), "--out",
                                       str(tmp_path / "o")]))
    assert "no such study file" in line
    (tmp_path / "file").write_text("x")
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(tmp_path / "file")]))
    assert "is a file" in line


RING = """
[rod]
twist_ratio = 1.5
nodes = 24
[problem]
kind = "ring"
excess_link = 0.5
"""


def test_ring_study_stores_one_state(tmp_path, capsys):
    study = write_study(tmp_path, RING)
    out = tmp_path / "o"
    assert cli(["run", str(study), "--out", str(out), "--quiet"]) == 0
    result = supercoil.load(out / "result.h5")
    assert result.problem == "ring" and result.status == "complete"
    (branch,) = result.branches.values()
    assert len(branch) == 1 and branch.parameter_values[0] == 0.5
    data = json.loads((out / "ring.json").read_text())
    assert data == result.summary
    # below Michell's threshold the answer is the twisted circle: its exact energy
    assert branch.records["energy"][0] == pytest.approx(2 * math.pi**2 * (1 + 1.5 * 0.25),
                                                        rel=2e-3)
    assert data["energy"] == branch.records["energy"][0] and data["stable"]
    points = result.centreline("ring", 0)
    radii = np.linalg.norm(points - points.mean(axis=0), axis=1)
    # a regular 24-gon of perimeter L = 1: circumradius 1 / (2 n sin(pi / n))
    np.testing.assert_allclose(radii, 1 / (48 * math.sin(math.pi / 24)), rtol=1e-8)


def test_a_run_in_python_speaks_through_its_callbacks_only(tmp_path, capsys):
    """The library's run prints nothing and handles no signal: its lines go to
    ``progress``, and ``on_point`` sees every point the result file stores of the
    continued branches."""
    import signal

    from supercoil.api.study_run import run_study

    messages, points = [], []

    def on_point(branch):
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
        points.append((branch.name, len(branch)))

    outcome = run_study(parse_study(RING_DIAGRAM), tmp_path, progress=messages.append,
                        on_point=on_point)
    assert capsys.readouterr() == ("", "")
    assert messages[0].startswith("ring diagram: C/A = 0.6667")
    result = supercoil.load(tmp_path)
    assert outcome["status"] == result.status
    # every continued branch point by point (the circle, known in closed form, is not)
    assert {b for b, _ in points} == set(result.branch_names) - {"circle"}
    for name in result.branch_names[1:]:
        counts = [k for b, k in points if b == name]
        assert counts == list(range(1, len(result.branch(name)) + 1)), name


def test_an_interrupt_while_drawing_keeps_the_data_and_says_so(tmp_path, capsys,
                                                                 monkeypatch):
    from supercoil.plotting import figures

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(figures, "plot_result", interrupted)
    study = write_study(tmp_path, RING + "[outputs]\nfigures = true\n")
    out = tmp_path / "o"
    assert cli(["run", str(study), "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "interrupted while drawing the figures" in err and "supercoil plot" in err
    assert "--resume" not in err
    result = supercoil.load(out)
    assert result.status == "complete"
    assert json.loads((out / "ring.json").read_text()) == result.summary


def test_json_to_standard_output(tmp_path, capsys):
    study = write_study(tmp_path, RING)
    out = tmp_path / "o"
    assert cli(["run", str(study), "--out", str(out), "--json", "-"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((out / "ring.json").read_text())
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(tmp_path / "p"),
                                       "--json", str(tmp_path / "none" / "x.json")]))
    assert "does not exist" in line and not (tmp_path / "p").exists()


def test_overwrite_replaces_the_run_files_only(tmp_path, capsys):
    study = write_study(tmp_path, RING)
    out = tmp_path / "o"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    (out / "result.h5").write_bytes(b"old")
    assert cli(["run", str(study), "--out", str(out), "--overwrite", "--quiet"]) == 0
    assert (out / "keep.txt").read_text() == "mine"
    assert supercoil.load(out / "result.h5").status == "complete"
    line = one_line_error(capsys, cli(["run", str(study), "--out", str(out), "--overwrite",
                                       "--resume"]))
    assert "exclude each other" in line


def run_diagram(tmp_path, name, progress=None, resume=False, text=RING_DIAGRAM):
    from supercoil.api.study_run import run_study

    out = tmp_path / name
    out.mkdir(exist_ok=True)
    callbacks = {} if progress is None else {"progress": progress.message,
                                             "on_point": progress.point}
    return out, run_study(parse_study(text), out, resume=resume, **callbacks)


class InterruptAt:
    """Progress callbacks that raise KeyboardInterrupt at the ``n``-th message or point."""

    def __init__(self, n: int):
        self.n, self.seen = n, 0

    def _tick(self):
        self.seen += 1
        if self.seen == self.n:
            raise KeyboardInterrupt

    def message(self, text):
        self._tick()

    def point(self, *args):
        self._tick()


def assert_same_branches(a, b, atol=1e-10):
    assert a.branch_names == b.branch_names
    for x, y in zip(a.branches.values(), b.branches.values()):
        assert len(x) == len(y), x.name
        np.testing.assert_allclose(x.states, y.states, atol=atol, err_msg=x.name)
        np.testing.assert_allclose(x.parameter_values, y.parameter_values, atol=atol)
        np.testing.assert_array_equal(x.unstable_count, y.unstable_count)
        assert [p.kind for p in x.special_points] == [p.kind for p in y.special_points]


def test_interrupted_run_keeps_a_valid_file_and_resume_completes_it(tmp_path, capsys):
    full_dir, full = run_diagram(tmp_path, "full")
    # alpha_contact stops at contact_max_points = 8, before dLk 4: an incomplete run
    assert full["status"] == "incomplete" and "alpha_contact" in full["message"], full
    reference = supercoil.load(full_dir / "result.h5")
    assert reference.status == "incomplete"
    assert list(reference.branches) == ["circle", "alpha", "alpha_contact"]
    assert json.loads((full_dir / "diagram.json").read_text()) == reference.summary
    # interrupt while the contact branch is computed
    out, outcome = run_diagram(tmp_path, "cut", progress=InterruptAt(4))
    assert outcome["status"] == "interrupted"
    cut = supercoil.load(out / "result.h5")
    assert cut.status == "interrupted" and cut.summary is None
    for b in cut.branches.values():  # whatever was saved is a prefix of the uninterrupted run
        ref = reference.branch(b.name)
        np.testing.assert_allclose(b.states, ref.states[:len(b)], atol=1e-10)
    # saved point by point: the circle and the start of alpha_contact's run
    assert cut.branch_names[:2] == ("circle", "alpha") and len(cut.branch("alpha")) > 0
    # --resume: a settings mismatch is refused and leaves the file alone
    study = write_study(tmp_path)
    before = (out / "result.h5").read_bytes()
    other = tmp_path / "other.toml"
    other.write_text(RING_DIAGRAM.replace("max_excess_link = 4.0", "max_excess_link = 3.0"))
    line = one_line_error(capsys, cli(["run", str(other), "--out", str(out), "--resume"]))
    assert "[problem] max_excess_link = 4.0 in the file, 3.0 in the study" in line
    assert (out / "result.h5").read_bytes() == before
    assert cli(["run", str(study), "--out", str(out), "--resume", "--quiet"]) == 1
    resumed = supercoil.load(out / "result.h5")
    assert resumed.status == "incomplete"
    assert_same_branches(resumed, reference)
    assert resumed.complete_branches == set(reference.branch_names)
    # every branch ended: nothing to do, nothing touched (exit 1: still incomplete)
    before = (out / "result.h5").read_bytes()
    assert cli(["run", str(study), "--out", str(out), "--resume"]) == 1
    assert "nothing to resume" in capsys.readouterr().out
    assert (out / "result.h5").read_bytes() == before


def test_a_run_interrupted_in_the_contact_free_branch_resumes_to_the_same_result(tmp_path):
    """Interrupted while alpha (the contact-free run, stopped past its contact onset) is
    computed, then resumed: the same branches as the uninterrupted run (the resumed
    alpha stops past its onset too, and nothing of it is computed twice)."""
    full_dir, full = run_diagram(tmp_path, "full")
    assert full["status"] == "incomplete", full  # alpha_contact stops at its point limit
    reference = supercoil.load(full_dir / "result.h5")
    assert reference.branch("alpha").message.endswith("the contact onset is located")
    out, outcome = run_diagram(tmp_path, "cut", progress=InterruptAt(8))
    assert outcome["status"] == "interrupted"
    cut = supercoil.load(out / "result.h5")
    assert 0 < len(cut.branch("alpha")) < len(reference.branch("alpha"))
    assert "alpha_contact" not in cut.branch_names
    assert cli(["run", str(write_study(tmp_path)), "--out", str(out), "--resume",
                "--quiet"]) == 1
    resumed = supercoil.load(out / "result.h5")
    assert resumed.status == "incomplete"
    assert_same_branches(resumed, reference)
    assert "the contact onset is located (resumed after point" in resumed.branch("alpha").message


# -------------------------------------------------------------------- resume_branch
def ring_alpha(n_nodes=24):
    from supercoil.problems.ring_branches import circle_branch

    circle, problem = circle_branch(0.6667, n_nodes, 3.0)
    (point, *_) = circle.points_of_kind("bifurcation")
    return problem, circle, point


def test_resume_branch_reproduces_the_uninterrupted_ring_branch():
    """alpha off the circle (near-symmetry gauge row), steps growing after fast corrections:
    interrupted after k points and resumed from the stored partial branch, the points are
    the same (the next step is recovered from the last one and its replayed correction)."""
    from supercoil.problems.ring_branches import ring_records

    problem, circle, point = ring_alpha()
    opts = ContinuationOptions(initial_step=0.005, max_step=0.05, max_points=12,
                               parameter_bounds=(0.0, 3.0))
    records = ring_records(problem)
    full = switch_branch(problem, circle, point, opts, amplitude=0.005, name="alpha",
                         records=records)
    assert len(full) == 12 and full.phase_modes.shape[0] == 1
    steps = np.diff(full.arclength)
    assert steps[-1] > 2 * steps[0]  # the steps grew: the resume must know the next one
    saved = []

    def stop_after_5(branch):
        saved.append(branch)
        if len(branch) == 5:
            raise KeyboardInterrupt

    problem, circle, point = ring_alpha()
    with pytest.raises(KeyboardInterrupt):
        switch_branch(problem, circle, point, opts, amplitude=0.005, name="alpha",
                      records=records, on_point=stop_after_5)
    partial = saved[-1]
    assert len(partial) == 5
    np.testing.assert_allclose(partial.states, full.states[:5], atol=1e-12)
    problem, _, _ = ring_alpha()  # a fresh problem, as after a restart
    seen = []
    resumed = resume_branch(problem, partial, opts, records=ring_records(problem),
                            on_point=lambda b: seen.append(len(b)))
    assert seen == list(range(5, 13))
    assert len(resumed) == len(full) and resumed.status is full.status
    np.testing.assert_allclose(resumed.states, full.states, atol=1e-9)
    np.testing.assert_allclose(resumed.arclength, full.arclength, atol=1e-9)
    np.testing.assert_allclose(resumed.records["writhe"], full.records["writhe"], atol=1e-9)
    np.testing.assert_array_equal(resumed.unstable_count, full.unstable_count)
    assert resumed.parent == "circle" and resumed.origin is partial.origin
    assert "resumed after point 4" in resumed.message


@pytest.mark.parametrize("predictor", ["tangent", "quadratic"])
def test_resume_branch_events_and_full_branch(predictor):
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from test_continuation_toys import Bratu

    from supercoil.continuation import UserEvent

    opts = ContinuationOptions(parameter_bounds=(1.0, 4.0), initial_step=0.02, max_step=0.1,
                               max_points=60, predictor=predictor)
    user = UserEvent("threshold", lambda q, mu, lam: {"u_mid_minus_1": q[16] - 1.0})

    def run(**kw):
        return continuation(Bratu(32, 1.0), np.zeros(33), parameter="lam", options=opts,
                            events=[user], records=lambda q, mu, lam: {"u_mid": q[16]}, **kw)

    full = run()
    saved = []

    assert [p.kind for p in full.special_points] == ["threshold", "fold"]
    fold = full.special_points[1]
    # cut far from the events, and right after the fold was found (the point that
    # closes its interval is the last one saved)
    for cut in (20, fold.index + 2):
        def stop(branch, cut=cut):
            saved.append(branch)
            if len(branch) == cut:
                raise KeyboardInterrupt

        with pytest.raises(KeyboardInterrupt):
            run(on_point=stop)
        resumed = resume_branch(Bratu(32, 1.0), saved[-1], opts, events=[user],
                                records=lambda q, mu, lam: {"u_mid": q[16]})
        np.testing.assert_allclose(resumed.states, full.states, atol=1e-10)
        assert [(p.kind, p.index) for p in resumed.special_points] == \
            [(p.kind, p.index) for p in full.special_points], cut
        for p, q in zip(resumed.special_points, full.special_points):
            assert p.parameter == pytest.approx(q.parameter, abs=1e-9)
            assert p.arclength == pytest.approx(q.arclength, abs=1e-9)
    # a complete branch is returned as it is
    again = resume_branch(Bratu(32, 1.0), resumed, opts)
    assert len(again) == len(resumed)
    with pytest.raises(ValueError, match="no point to resume"):
        resume_branch(Bratu(32, 1.0), dataclasses.replace(
            full, **{n: getattr(full, n)[:0] for n in (
                "parameter_values", "states", "multipliers", "unstable_count", "zero_modes",
                "determinant_sign", "nearest_eigenvalue", "tangents", "arclength")},
            records={}), opts)


def test_tweezers_study():
    study = parse_study(TWEEZERS)
    opts = study.tweezers_options()
    assert opts.tension == 20.0 and opts.turns == (0.0, 1.6) and opts.n_nodes == 40
    assert opts.free_max_step == 0.1  # TweezersOptions' default
    from supercoil.problems.tweezers import TweezersOptions

    # runs as long as the library's (the pin is checked at every point)
    assert opts.segment_points == TweezersOptions.segment_points == 2000
    assert study.settings["continuation"]["max_points"] == 400
    for edit, words in [
        (("tension = 20.0", "tension = 20.0\nend_distance = 0.5"), "exactly one of tension"),
        (("tension = 20.0", ""), "exactly one of tension"),
        (("turns = [0, 1.6]", "turns = [2, 1]"),
         "[problem] turns must be (start, stop) turns with 0 <= start < stop <= 1000"),
        (("nodes = 40", "nodes = 10"), ("[rod] nodes (nodes of the clamped rod) must be a whole "
         "number from 12")),
        (("tension = 20.0", 'tension = 20.0\ncontact = "barrier"'),
         "[problem] contact does not apply to a tweezers problem"),
        (("[problem]", "[continuation]\ncontact_max_points = 3\n[problem]"),
         "[continuation] contact_max_points does not apply to a tweezers problem"),
    ]:
        assert words in error(TWEEZERS.replace(*edit, 1))


def test_dna_tweezers_study():
    text = """
[units]
preset = "dna"
base_pairs = 3000
[rod]
nodes = 60
[problem]
kind = "tweezers"
force_pN = 0.5
turns = [0, 10]
"""
    study = parse_study(text)
    preset = study.dna_preset()
    assert study.settings["problem"]["tension"] == pytest.approx(preset.force_from_pN(0.5))
    assert study.tweezers_options().length_over_diameter == pytest.approx(
        3000 * 0.34 / effective_diameter_nm(150.0))
    assert "force_pN is missing" in error(text.replace("force_pN = 0.5", ""))
    assert "[problem] tension cannot be given with units preset 'dna'" in error(
        text.replace("force_pN = 0.5", "tension = 3.0"))


# --------------------------------------------------------------------------- progress
def test_progress_plain_lines_and_quiet():
    import io

    from supercoil.cli.progress import Progress

    stream = io.StringIO()
    with Progress(live=False, every=2, stream=stream) as progress:
        progress.message("circle  up to dLk = 4")
        for k in range(1, 6):
            progress.point("alpha", "excess_link", 2.0 - 0.1 * k, 0.1 if k > 1 else None, k)
        progress.point("alpha_contact", "excess_link", 1.4, None, 1)
    lines = stream.getvalue().splitlines()
    assert lines[0] == "circle up to dLk = 4"
    # the first point of each branch and every second point
    assert [line.split(" (")[0] for line in lines[1:]] == [
        "  alpha: excess_link = 1.9, 1 points",
        "  alpha: excess_link = 1.8, step 0.1, 2 points",
        "  alpha: excess_link = 1.6, step 0.1, 4 points",
        "  alpha_contact: excess_link = 1.4, 1 points"]
    quiet = io.StringIO()
    with Progress(quiet=True, live=True, stream=quiet) as progress:
        progress.message("x")
        progress.point("alpha", "excess_link", 1.0, 0.1, 3)
        assert progress._bar is None
    assert quiet.getvalue() == ""


def test_progress_live_shows_the_latest_numbers(capsys):
    from supercoil.cli.progress import Progress

    with Progress(live=True) as progress:
        progress.message("alpha: switched")
        progress.point("alpha", "excess_link", 1.25, 0.02, 7)
        (task,) = progress._bar.tasks
        assert task.description == "alpha"
        assert task.fields["numbers"] == "excess_link = 1.25, step 0.02, 7 points"
    assert "alpha: switched" in capsys.readouterr().out


def test_interrupted_tweezers_run_keeps_its_points(tmp_path):
    """Point by point for tweezers too: an interrupt inside the buckled branch leaves the
    straight branch whole and a prefix of the buckled one (the uninterrupted run)."""
    text = TWEEZERS.replace("nodes = 40", "nodes = 24")
    full_dir, _ = run_diagram(tmp_path, "full", text=text)
    reference = supercoil.load(full_dir / "result.h5")
    assert reference.branch_names[:2] == ("straight", "buckled")
    k_straight = len(reference.branch("straight"))
    out, outcome = run_diagram(tmp_path, "cut", text=text,
                               progress=InterruptAt(k_straight + 12))
    assert outcome["status"] == "interrupted"
    cut = supercoil.load(out / "result.h5")
    assert cut.branch_names == ("straight", "buckled")
    assert 0 < len(cut.branch("buckled")) < len(reference.branch("buckled"))
    for name in cut.branch_names:
        b, ref = cut.branch(name), reference.branch(name)
        np.testing.assert_allclose(b.states, ref.states[:len(b)], atol=1e-10)
    assert len(cut.branch("straight")) == k_straight
    # --resume: straight kept, buckled continued from its last point (with an azimuth
    # pin picked there: a rotation about the axis is a gauge), to the same end state
    stored_buckled = cut.branch("buckled")
    study = tmp_path / "tweezers.toml"
    study.write_text(text)
    assert cli(["run", str(study), "--out", str(out), "--resume", "--quiet"]) in (0, 1)
    resumed = supercoil.load(out / "result.h5")
    assert resumed.branch_names == reference.branch_names
    np.testing.assert_array_equal(resumed.branch("straight").states,
                                  reference.branch("straight").states)
    b = resumed.branch("buckled")
    k = len(stored_buckled)
    np.testing.assert_allclose(b.states[:k - 1], stored_buckled.states[:k - 1], atol=1e-12)
    last = reference.branch_names[-1]
    b, ref = resumed.branch(last), reference.branch(last)
    assert b.parameter_values[-1] == ref.parameter_values[-1] == 1.6
    for key in ("extension", "writhe", "twist", "energy"):
        assert b.records[key][-1] == pytest.approx(ref.records[key][-1], abs=1e-6), key
