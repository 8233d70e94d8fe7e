"""DNA in magnetic tweezers: σ for turns, the default nodes (n0, more where the force needs
them) and the quintic contact curve by default, and nm / pN nm / σ through the JSON and
the figures, for the command line, study files and the library.

Oracles: the unit conversions from the preset's constants (kT = 4.11 pN nm, A = 50 nm kT,
0.34 nm/bp, 10.5 bp/turn), exact to rounding; n0 and the default nodes against a
brute-force search over N and against the clamped rod's own edge length and mesh test;
the JSON's DNA keys against the nondimensional ones times the scales; bad input refused
before any file is written.
"""

import json
import math

import numpy as np
import pytest
from matplotlib.text import Text

import supercoil as sc
from supercoil import checks
from supercoil.cli.main import run
from supercoil.io.study import StudyError, parse_study
from supercoil.units.dna import DNAPreset
from supercoil.units.tweezers import (
    DNA_MAX_POINTS,
    default_nodes,
    dna_numerics,
    dna_tweezers_inputs,
    resolving_nodes,
    turns_of_span,
    tweezers_payload_in_dna_units,
)

KT, P_B, RISE, REPEAT = 4.11, 50.0, 0.34, 10.5  # pN nm, nm, nm/bp, bp/turn


# ------------------------------------------------------------------ unit conversions
@pytest.mark.parametrize("bp", [300, 3000, 10_000])
def test_sigma_turns_and_scales_exact(bp):
    preset = DNAPreset(bp, salt_mM=150)
    start, stop = turns_of_span(preset, (0.01, 0.06))
    assert start == pytest.approx(0.01 * bp / REPEAT, rel=1e-15)
    assert stop == pytest.approx(0.06 * bp / REPEAT, rel=1e-15)
    assert preset.superhelical_density_of(stop) == pytest.approx(0.06, rel=1e-15)
    length = bp * RISE
    numbers = dna_tweezers_inputs(preset, 1.0, superhelical_density=(0.0, 0.06))
    # F L^2/A with A = 50 nm * 4.11 pN nm
    assert numbers["tension"] == pytest.approx(1.0 * length**2 / (P_B * KT), rel=1e-14)
    assert numbers["turns"] == pytest.approx((0.0, 0.06 * bp / REPEAT), rel=1e-15)
    payload = {"turns_range": [0.0, 2.0], "greenhill_turns": 1.5,
               "hard_core_ply": {"spanning_turns": 4.0, "torque": 2.5},
               "points": [{"turns": 2.0, "extension": 0.25, "torque": 3.0, "tension": 7.0}]}
    out = tweezers_payload_in_dna_units(payload, preset, 1.0)
    assert out["force_scale_pN"] == pytest.approx(P_B * KT / length**2, rel=1e-14)
    assert out["torque_scale_pN_nm"] == pytest.approx(P_B * KT / length, rel=1e-14)
    assert out["superhelical_density_range"] == pytest.approx([0.0, 2.0 * REPEAT / bp])
    assert out["greenhill_superhelical_density"] == pytest.approx(1.5 * REPEAT / bp)
    assert out["ply_spanning_superhelical_density"] == pytest.approx(4.0 * REPEAT / bp)
    assert out["ply_torque_pN_nm"] == pytest.approx(2.5 * P_B * KT / length, rel=1e-14)
    p = out["points"][0]
    assert p["extension_nm"] == pytest.approx(0.25 * length, rel=1e-15)
    assert p["torque_pN_nm"] == pytest.approx(3.0 * P_B * KT / length, rel=1e-14)
    assert p["force_pN"] == pytest.approx(7.0 * P_B * KT / length**2, rel=1e-14)
    assert p["superhelical_density"] == pytest.approx(2.0 * REPEAT / bp, rel=1e-15)
    assert payload["points"][0] == {"turns": 2.0, "extension": 0.25, "torque": 3.0,
                                    "tension": 7.0}  # the input is not changed


# ------------------------------------------------------------------------------- n0
@pytest.mark.parametrize("lod", [3.5, 10.0, 23.7, 100.0, 237.31719891377858, 1000.0])
def test_n0_is_the_fewest_nodes_with_segments_no_longer_than_d(lod):
    from supercoil.problems.tweezers import TweezersOptions
    from supercoil.problems.tweezers.problem import clamped_problem

    diameter = 1.0 / lod

    def edge(n):  # the clamped rod's edges: its ends are the first and last edges' midpoints
        return 1.0 / (n - 2)

    brute = next(n for n in range(checks.MIN_CLAMPED_NODES, 10_000) if edge(n) <= diameter)
    assert resolving_nodes(lod) == brute
    if lod <= 100:  # the model's own edge length at n0 and n0 - 1
        for n, fits in ((brute, True), (brute - 1, False)):
            if n < checks.MIN_CLAMPED_NODES:
                continue
            rod, _ = clamped_problem(TweezersOptions(twist_ratio=1.0, length_over_diameter=lod,
                                                     tension=1.0, n_nodes=n))
            assert (rod.rod.edge_length <= diameter * (1 + 1e-12)) == fits


@pytest.mark.parametrize(("salt", "force"), [(10, 0.1), (10, 0.25), (10, 1.0), (10, 4.0),
                                              (150, 1.0), (150, 4.0)])
def test_default_nodes_are_the_fewest_with_segments_within_d_and_the_resolved_core(
        salt, force):
    # brute force over N: the clamped rod's segments 1/(N - 2) no longer than D and at
    # most min(1/3, 1.25 / ln(lambda / 0.54)) of the loop's core sqrt(A/F) = 1/lambda;
    # the model's own mesh test agrees
    from supercoil.problems.tweezers.options import mesh_pins_loop, mesh_resolves_loop

    numbers = dna_tweezers_inputs(DNAPreset(3000, salt_mM=salt), force, turns=(0, 1))
    lod, tension = numbers["length_over_diameter"], numbers["tension"]
    lam = math.sqrt(tension)
    brute = next(n for n in range(checks.MIN_CLAMPED_NODES, 10_000)
                 if 1.0 / (n - 2) <= 1.0 / lod
                 and lam / (n - 2) <= min(1 / 3, 1.25 / math.log(lam / 0.54)) + 1e-12)
    assert default_nodes(lod, tension) == numbers["n_nodes"] == brute
    assert mesh_resolves_loop(tension, brute) and not mesh_pins_loop(tension, brute)
    if brute > resolving_nodes(lod):  # the force decides: one node fewer does not resolve
        assert not mesh_resolves_loop(tension, brute - 1)
    assert default_nodes(lod) == resolving_nodes(lod)  # no force: n0


def test_n0_too_many_nodes_is_refused():
    preset = DNAPreset(10_000_000, diameter_nm=10.0)  # L/D = 340,000
    n0 = resolving_nodes(preset.length_over_diameter)
    assert n0 > checks.MAX_NODES
    tension = dna_tweezers_inputs(preset, 1.0, turns=(0, 1), n_nodes=500)["tension"]
    default = default_nodes(preset.length_over_diameter, tension)
    assert default >= n0
    with pytest.raises(sc.InputError, match=rf"^n_nodes \(the default {default}: .*exceeds"):
        dna_tweezers_inputs(preset, 1.0, turns=(0, 1))
    assert dna_tweezers_inputs(preset, 1.0, turns=(0, 1), n_nodes=500)["n_nodes"] == 500


# ------------------------------------------------------------------ command line
@pytest.fixture(scope="module")
def dna_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("dna") / "run"
    status = run(["tweezers", "--dna", "--bp", "300", "--force-pN", "0.3", "--sigma",
                  "0:0.04", "--out", str(out), "--quiet"])
    assert status == 0
    return out


def test_cli_sigma_and_default_nodes(dna_run):
    data = json.loads((dna_run / "branch.json").read_text())
    preset = DNAPreset(300)
    assert data["n_nodes"] == resolving_nodes(preset.length_over_diameter) == 26
    assert data["turns_range"] == pytest.approx([0.0, 0.04 * 300 / REPEAT], rel=1e-15)
    assert data["superhelical_density_range"] == pytest.approx([0.0, 0.04], rel=1e-15)
    assert data["force_pN"] == pytest.approx(0.3) and data["salt_mM"] == 150.0
    length, torque = 300 * RISE, P_B * KT / (300 * RISE)
    assert data["length_nm"] == pytest.approx(length, rel=1e-15)
    assert data["torque_scale_pN_nm"] == pytest.approx(torque, rel=1e-14)
    for p in data["points"] + data["special_points"]:
        assert p["extension_nm"] == pytest.approx(p["extension"] * length, rel=1e-14)
        assert p["superhelical_density"] == pytest.approx(p["turns"] * REPEAT / 300, rel=1e-14)
        if "torque" in p:
            assert p["torque_pN_nm"] == pytest.approx(p["torque"] * torque, rel=1e-14)
    assert data["points"][-1]["turns"] == pytest.approx(0.04 * 300 / REPEAT, rel=1e-12)


def test_contact_curve_defaults_to_the_quintic_with_dna(dna_run, tmp_path):
    # DNA runs resolve the ply at segments of D, where the cubic B-spline's contact
    # ripples (tests/test_contact_integral.py): their default curve is DNA_CONTACT_CURVE,
    # on the command line, in study files and in the library; a given curve is kept.
    # loop_sliding, not given, is applied where the mesh lets the loop slide, DNA or not
    data = json.loads((dna_run / "branch.json").read_text())
    assert data["contact_curve"] == "quintic"
    assert data["loop_sliding"] is None and data["loop_sliding_applied"] is True
    assert data["loop_sliding_in_contact"] is True
    assert sc.load(dna_run).settings["contact_curve"] == "quintic"
    assert sc.load(dna_run).settings["loop_sliding"] is None  # a resume must match it
    # and the points per branch default to DNA_MAX_POINTS (2000 without --dna)
    assert sc.load(dna_run).settings["max_points"] == DNA_MAX_POINTS
    dna = parse_study(STUDY).tweezers_options()
    assert dna.contact_curve == "quintic" and dna.loop_sliding is None and dna.loop_slides
    plain = '[rod]\ntwist_ratio = 1.5\n[problem]\nkind = "tweezers"\ntension = 10\n'
    assert parse_study(plain).tweezers_options().contact_curve == "spline"
    assert parse_study(plain).tweezers_options().loop_slides
    out = tmp_path / "cubic"
    assert run(["tweezers", "--dna", "--bp", "300", "--force-pN", "0.3", "--sigma",
                "0:0.002", "--contact-curve", "spline", "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "branch.json").read_text())["contact_curve"] == "spline"
    assert sc.load(out).settings["max_points"] == DNA_MAX_POINTS
    given = tmp_path / "given"
    assert run(["tweezers", "--dna", "--bp", "300", "--force-pN", "0.3", "--sigma",
                "0:0.002", "--max-points", "30", "--out", str(given), "--quiet"]) == 0
    assert sc.load(given).settings["max_points"] == 30
    assert json.loads((out / "branch.json").read_text())["loop_sliding_applied"] is True


@pytest.mark.parametrize("given,dna,expected", [(["--no-loop-sliding"], True, False),
                                                ([], False, None),
                                                (["--loop-sliding"], False, True)])
def test_the_command_line_keeps_a_given_loop_sliding(given, dna, expected, tmp_path):
    """``--loop-sliding/--no-loop-sliding``: a given choice is kept, with or without
    --dna (the run's settings and branch.json say which); without it (None) it is
    applied where the mesh lets the loop slide, here on both meshes."""
    out = tmp_path / "run"
    problem = (["--dna", "--bp", "300", "--force-pN", "0.3", "--sigma", "0:0.002"] if dna
               else ["--twist-ratio", "1.5", "--length-over-diameter", "40", "--tension",
                     "100", "--turns", "0:0.2", "--nodes", "40"])
    assert run(["tweezers", *problem, *given, "--out", str(out), "--quiet"]) == 0
    data = json.loads((out / "branch.json").read_text())
    assert data["loop_sliding"] is expected
    assert data["loop_sliding_applied"] is (expected is not False)
    assert data["loop_sliding_in_contact"] is (expected is not False)
    assert sc.load(out).settings["loop_sliding"] is expected


@pytest.mark.parametrize("force,salt", [(1.0, 150), (4.0, 150), (1.0, 10)])
def test_loop_sliding_applies_with_dna_where_the_mesh_lets_the_loop_slide(force, salt):
    """The default nodes' segments h = L/(N - 2) are at most a third of the loop's core
    sqrt(A/F) (h sqrt(F/A) <= 1/3, computed here from the preset's own L, D and A), so
    loop_sliding applies; where n0's segments are longer (given as [rod] nodes), the
    mesh pins the loop and loop_sliding applies on the contact-free branches only."""
    preset = DNAPreset(3000, salt_mM=salt)
    text = STUDY.replace("salt_mM = 150", f"salt_mM = {salt}").replace(
        "force_pN = 1.0", f"force_pN = {force}")
    n0 = resolving_nodes(preset.length_over_diameter)
    for given in (None, n0):
        options = parse_study(text + ("" if given is None else f"nodes = {given}\n")
                              ).tweezers_options()
        nodes = options.n_nodes
        assert nodes == (given or default_nodes(preset.length_over_diameter,
                                                options.tension))
        core = 3000 * RISE / (nodes - 2) * math.sqrt(force / (P_B * KT))
        assert options.core_segments == pytest.approx(core, rel=1e-12)
        assert options.loop_sliding is None and options.loop_slides
        assert options.loop_slides_in_contact is (core <= 0.5)
        assert given is not None or core <= 1 / 3 + 1e-12
    assert dna_numerics({}) == {"contact_curve": "quintic", "max_points": DNA_MAX_POINTS}
    assert dna_numerics({"contact_curve": "spline", "max_points": 7}) == {
        "contact_curve": "spline", "max_points": 7}


def _texts(fig) -> list[str]:
    return [t.get_text() for t in fig.findobj(Text)]


def test_figures_speak_dna_units(dna_run):
    from supercoil.plotting.figures import figure_of
    from supercoil.plotting.result_data import load_result
    from supercoil.plotting.tweezers import draw_job, figure_jobs

    data = json.loads((dna_run / "branch.json").read_text())
    built = {}
    for path, builder, kwargs in figure_jobs(data, [], dna_run / "figures"):
        assert builder == "diagram"
        from supercoil.plotting.figures import diagram_figure

        kwargs = dict(kwargs)
        built[path.name] = diagram_figure(kwargs.pop("branches"), kwargs.pop("special_points"),
                                          **kwargs)
    hat = built["hat_curve.png"]
    ax = hat.axes[0]
    assert ax.get_xlabel() == r"end rotation $n$ (turns)"
    assert ax.get_ylabel() == r"extension $z$ (nm)"
    texts = _texts(hat)
    assert r"superhelical density $\sigma$" in texts and r"extension $z/L$" in texts
    title = ax.get_title()
    for words in ("300 bp", "102 nm", "F = 0.3 pN", "150 mM salt", "D = 4.3 nm"):
        assert words in title
    assert sum("Athermal" in t for t in texts) == 1  # the caveat, once
    torque = built["torque.png"].axes[0]
    assert torque.get_ylabel() == r"torque $M$ (pN nm)"
    plateau = [line for line in torque.get_lines()
               if np.ptp(line.get_ydata()) == 0 and len(line.get_ydata()) == 2]
    assert [line.get_ydata()[0] for line in plateau] == pytest.approx(
        [data["ply_torque_pN_nm"]], rel=1e-12)  # the hard-core ply's, in pN nm
    assert r"superhelical density $\sigma$" in _texts(built["torque.png"])
    assert not any("Athermal" in t for t in _texts(built["writhe.png"]))
    # the same from the stored result (supercoil plot, supercoil run)
    result = load_result(dna_run)
    assert result.dna is not None and "F = 0.3 pN" in result.title
    stored = figure_of(result, "hat-curve")
    assert stored.axes[0].get_ylabel() == r"extension $z$ (nm)"
    assert r"superhelical density $\sigma$" in _texts(stored)
    line = stored.axes[0].get_lines()[0]
    assert max(line.get_ydata()) == pytest.approx(300 * RISE, rel=1e-9)  # straight: z = L
    assert draw_job(figure_jobs(data, [], dna_run)[0]).stat().st_size > 1000


@pytest.mark.parametrize("args, words", [
    (["--sigma", "0:0.04", "--twist-ratio", "1", "--tension", "1"], "--sigma needs --dna"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--sigma", "0:0.04", "--turns", "0:1"],
     "both --turns and --sigma"),
    (["--dna", "--bp", "300", "--force-pN", "1"], "neither of --turns and --sigma"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--sigma", "0.05:0.01"],
     "--sigma must be (start, stop) with 0 <= start < stop <= 1"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--sigma", "0:2"], "--sigma must be"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--sigma", "0.01"], "--sigma '0.01'"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--sigma", "0:0.04", "--nodes", "5"],
     "--nodes (nodes of the clamped rod) must be a whole number from 12"),
    (["--twist-ratio", "1", "--tension", "1"], "--turns START:STOP is missing"),
])
def test_cli_bad_combinations_exit_2_before_writing(tmp_path, capsys, args, words):
    out = tmp_path / "x"
    status = run(["tweezers", "--out", str(out)] + args)
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and words in err[0], err
    assert not out.exists()


def test_help_states_the_nodes_default(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "1000")  # one line per option
    assert run(["tweezers", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "n0 = ceil(L/D) + 2" in text and "--sigma" in text


# ------------------------------------------------------------------------ studies
STUDY = """
[units]
preset = "dna"
base_pairs = 3000
salt_mM = 150
[problem]
kind = "tweezers"
force_pN = 1.0
superhelical_density = [0, 0.06]
[rod]
"""


def _error(text: str) -> str:
    with pytest.raises(StudyError) as info:
        parse_study(text)
    return str(info.value)


def test_study_sigma_and_n0():
    s = parse_study(STUDY).settings
    preset = DNAPreset(3000, salt_mM=150)
    assert s["problem"]["turns"] == pytest.approx([0.0, 0.06 * 3000 / REPEAT], rel=1e-15)
    # at 1 pN the loop's core needs more nodes than n0 = 240 (segments of D)
    tension = dna_tweezers_inputs(preset, 1.0, turns=(0, 1))["tension"]
    assert resolving_nodes(preset.length_over_diameter) == 240
    assert s["rod"]["nodes"] == default_nodes(preset.length_over_diameter, tension) == 280
    assert parse_study(STUDY + "nodes = 300").settings["rod"]["nodes"] == 300
    turns = parse_study(STUDY.replace("superhelical_density = [0, 0.06]", "turns = [0, 3]"))
    assert turns.settings["problem"]["turns"] == [0.0, 3.0]
    assert "[problem] superhelical_density and turns both" in _error(
        STUDY.replace("force_pN = 1.0", "force_pN = 1.0\nturns = [0, 1]"))
    assert "[problem] superhelical_density must be (start, stop)" in _error(
        STUDY.replace("[0, 0.06]", "[0.06, 0]"))
    assert "[rod] nodes (nodes of the clamped rod) must be" in _error(STUDY + "nodes = 3")
    plain = ('[rod]\ntwist_ratio = 1.5\n[problem]\nkind = "tweezers"\ntension = 10\n')
    assert parse_study(plain).settings["rod"]["nodes"] == 100
    assert parse_study(plain).settings["problem"]["turns"] == [0.0, 5.0]
    assert "cannot be given with units preset 'nondimensional'" in _error(
        plain + "superhelical_density = [0, 0.06]\n")


# ------------------------------------------------------------------------ library
def test_library_from_dna_and_sigma(tmp_path):
    preset = DNAPreset(300)
    problem = sc.Tweezers.from_dna(preset, 0.3)
    assert problem.rod.nodes == 26 and problem.force_pN == pytest.approx(0.3, rel=1e-14)
    assert problem.rod.twist_ratio == pytest.approx(95 / 50)
    assert problem.contact.length_over_diameter == preset.length_over_diameter
    with pytest.raises(sc.InputError, match="superhelical_density and turns both"):
        sc.tweezers(problem, turns=(0, 1), superhelical_density=(0, 0.04))
    with pytest.raises(sc.InputError, match="superhelical_density needs a problem in DNA"):
        sc.tweezers(sc.Tweezers(sc.Rod(1.0, 30), tension=1.0), superhelical_density=(0, 0.1))
    with pytest.raises(sc.InputError, match="^dna: "):
        sc.Tweezers(sc.Rod(1.0, 30), tension=1.0, dna=preset)
    with pytest.raises(sc.InputError, match="^nodes "):
        sc.Tweezers.from_dna(preset, 0.3, nodes=3)
    diagram = sc.tweezers(problem, superhelical_density=(0, 0.02), max_points=40)
    assert diagram.settings.turns == pytest.approx((0.0, 0.02 * 300 / REPEAT), rel=1e-15)
    assert diagram.settings.contact_curve == "quintic"  # DNA_CONTACT_CURVE
    assert diagram.settings.loop_slides  # the default, where it applies
    given = sc.tweezers(problem, superhelical_density=(0, 0.002), max_points=5,
                        contact_curve="spline", loop_sliding=False).settings
    assert given.contact_curve == "spline" and not given.loop_sliding
    assert (diagram.settings.max_points, given.max_points) == (40, 5)
    assert sc.tweezers(problem, superhelical_density=(0, 0.002)
                       ).settings.max_points == DNA_MAX_POINTS
    saved = sc.load(sc.save(diagram, tmp_path / "r.h5"))
    assert saved.units == "dna"
    point = saved.summary["points"][-1]
    assert point["extension_nm"] == pytest.approx(point["extension"] * 300 * RISE, rel=1e-14)
    assert math.isclose(saved.summary["force_pN"], 0.3, rel_tol=1e-14)
