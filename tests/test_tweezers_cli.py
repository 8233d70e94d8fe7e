"""``supercoil tweezers`` end to end at small N, and its bad input (one line, exit 2)."""

import json

import numpy as np
import pytest

import supercoil
from supercoil.cli.main import run
from supercoil.problems.greenhill import critical_turns
from supercoil.problems.ply import hard_core_ply

POINT_KEYS = ("turns", "extension", "torque", "writhe", "twist", "energy", "load_potential",
              "unstable_count", "zero_modes", "n_contact_points", "n_contact_intervals",
              "min_gap_over_diameter")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("tweezers") / "run"
    status = run(["tweezers", "--twist-ratio", "1.3333333333333333", "--length-over-diameter",
                  "20", "--tension", "20", "--turns", "0:1.6", "--nodes", "40", "--out",
                  str(out)])
    assert status == 0
    return out


def test_branch_json_keys_and_invariants(folder):
    data = json.loads((folder / "branch.json").read_text())
    for key in ("schema_version", "units", "conventions", "provenance", "points",
                "special_points", "branches"):
        assert key in data
    assert data["units"] == "nondimensional"
    for p in data["points"]:
        for key in POINT_KEYS:
            assert key in p, key
        assert abs(p["twist"] + p["writhe"] - p["turns"]) < 1e-9
    kinds = {(s["kind"], s["branch"]) for s in data["special_points"]}
    assert ("bifurcation", "straight") in kinds and ("contact_onset", "buckled") in kinds
    for s in data["special_points"]:
        assert {"kind", "branch", "turns", "extension"} <= set(s)
    # the located buckling against the exact clamped condition (N = 40: 0.6 % off, O(h^2))
    bif = next(s for s in data["special_points"] if s["kind"] == "bifurcation")
    exact = critical_turns(1.3333333333333333, 20.0)
    assert abs(bif["turns"] - exact) / exact < 1e-2
    assert data["greenhill_turns"] == pytest.approx(exact, rel=1e-12)
    ply = hard_core_ply(1 / 20, 20.0, 1.3333333333333333)
    assert data["hard_core_ply"]["spanning_turns"] == pytest.approx(ply.spanning_turns,
                                                                    rel=1e-12)
    assert data["hard_core_ply"]["torque"] == pytest.approx(ply.torque, rel=1e-12)
    assert not any("span the whole rod" in n for n in data["notes"])  # 1.6 < 2.06 turns
    contact = [p for p in data["points"] if p["branch"] == "buckled_contact"]
    assert min(p["min_gap_over_diameter"] for p in contact) > 1.0


def test_files_and_stored_states(folder):
    for name in ("hat_curve.png", "torque.png", "writhe.png", "configurations.png"):
        assert (folder / name).stat().st_size > 1000
    data = json.loads((folder / "branch.json").read_text())
    stored = supercoil.load(folder)
    assert stored.summary == data and stored.status == "complete" and stored.problem == "tweezers"
    assert not stored.closed and stored.n_nodes == 40
    for b in data["branches"]:
        assert b["file"] == "result.h5"
        branch = stored.branch(b["name"])
        rows = [p for p in data["points"] if p["branch"] == b["name"]]
        assert len(branch) == len(rows) == b["n_points"]
        assert np.allclose(branch.records["extension"], [p["extension"] for p in rows])


def test_contact_lists_are_those_of_the_stored_states(folder):
    """Oracle: contact_summary of each saved state of the contact branch, recomputed
    here; branch.json's lists are made while the figures are drawn (the tubes' states
    before), and they must be the same, entry for entry."""
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.contact.report import contact_summary
    from supercoil.problems.tweezers import TweezersOptions, clamped_problem

    data = json.loads((folder / "branch.json").read_text())
    options = TweezersOptions(twist_ratio=1.3333333333333333, length_over_diameter=20,
                              tension=20, turns=(0, 1.6), n_nodes=40)
    rod, _ = clamped_problem(options)
    cp = ContactProblem(rod, ContactOptions(diameter=options.diameter,
                                            curve=options.contact_curve,
                                            formulation=options.contact_formulation))
    listed = 0
    for b in data["branches"]:
        branch = supercoil.load(folder / b["file"]).branch(b["name"])
        rows = [p for p in data["points"] if p["branch"] == b["name"]]
        for i, row in enumerate(rows):
            if b["contact"]:
                summary = contact_summary(cp, branch.states[i], branch.multipliers[i])
                expected = (summary["contact_points"], summary["contact_intervals"])
            else:
                expected = ([], [])
            # JSON keeps floats exactly: the same numbers, bit for bit
            assert [row["contact_points"], row["contact_intervals"]] == \
                json.loads(json.dumps(list(expected)))
            assert len(row["contact_points"]) == row["n_contact_points"]
            listed += len(row["contact_points"])
    assert listed > 0


@pytest.mark.parametrize("args, words", [
    (["--turns", "5:1", "--tension", "1"], "--turns"),
    (["--turns", "0:1e300", "--tension", "1"], "0 <= start < stop <= 1000"),
    (["--max-points", "1000000000", "--tension", "1"], "--max-points"),
    (["--protocol", "up-down", "--step", "1e-12", "--tension", "1"], "at most 100000"),
    (["--turns", "abc"], "--turns"),
    (["--tension", "1", "--end-distance", "0.5"], "exactly one"),
    (["--end-distance", "1.5"], "--end-distance"),
    (["--tension", "-1"], "--tension"),
    (["--length-over-diameter", "2", "--tension", "1"], "--length-over-diameter"),
    (["--protocol", "sideways", "--tension", "1"], "--protocol"),
    (["--nodes", "5", "--tension", "1"], "--nodes"),
    (["--contact-formulation", "sum", "--tension", "1"], "--contact-formulation"),
    (["--contact-curve", "bezier", "--tension", "1"], "--contact-curve"),
    (["--contact-curve", "quintic", "--contact-formulation", "pairs", "--tension", "1"],
     "quintic"),
])
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, args, words):
    base = ["tweezers", "--twist-ratio", "1", "--out", str(tmp_path / "x")]
    if "--turns" not in args:
        base += ["--turns", "0:1"]
    status = run(base + args)
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert len(err) == 1 and err[0].startswith("error:") and words in err[0]
    assert not (tmp_path / "x").exists()  # refused before any write


def test_existing_folder_needs_overwrite(folder, capsys):
    status = run(["tweezers", "--twist-ratio", "1", "--tension", "1", "--turns", "0:1",
                  "--out", str(folder)])
    assert status == 2 and "--overwrite" in capsys.readouterr().err


def test_up_down_writes_the_path(tmp_path):
    out = tmp_path / "ud"
    status = run(["tweezers", "--twist-ratio", "1.3333333333333333", "--length-over-diameter",
                  "20", "--tension", "20", "--turns", "0:1.6", "--nodes", "40", "--protocol",
                  "up-down", "--step", "0.2", "--out", str(out)])
    assert status == 0
    data = json.loads((out / "branch.json").read_text())
    path = data["path"]
    assert path[0]["direction"] == 1 and path[-1]["direction"] == -1
    assert path[0]["turns"] == 0.0 and path[-1]["turns"] == 0.0
    jumps = [s for s in data["special_points"] if s["kind"] == "jump"]
    assert jumps and all(s["branch"] == "path" and "extension" in s for s in jumps)
    stored = supercoil.load(out).extras["path"]
    assert stored["states"].shape[0] == len(path) == stored["turns"].shape[0]
    assert list(stored["turns"]) == [p["turns"] for p in path]


def test_up_down_needs_tension(tmp_path, capsys):
    status = run(["tweezers", "--twist-ratio", "1", "--end-distance", "0.5", "--turns", "0:1",
                  "--protocol", "up-down", "--out", str(tmp_path / "x")])
    assert status == 2 and "--tension" in capsys.readouterr().err


def test_dna_units(tmp_path, capsys):
    from supercoil.units.dna import DNAPreset
    from supercoil.units.tweezers import tweezers_parameters

    out = tmp_path / "dna"
    status = run(["tweezers", "--dna", "--bp", "300", "--force-pN", "0.3", "--turns", "0:1.2",
                  "--nodes", "30", "--out", str(out)])
    assert status == 0
    assert "Athermal" in capsys.readouterr().err
    data = json.loads((out / "branch.json").read_text())
    preset = DNAPreset(300)
    assert data["units"] == "dna" and "athermal" in data["conventions"]
    assert data["provenance"]["units_preset"]["base_pairs"] == 300
    numbers = tweezers_parameters(preset, 0.3)
    # F L^2/A = F / (A / L^2): 0.3 pN on 102 nm with A = 50 nm x 4.11 pN nm
    assert data["force"] == pytest.approx(0.3 * 102.0**2 / (50 * 4.11), rel=1e-12)
    assert numbers["tension"] == pytest.approx(data["force"], rel=1e-12)
    for p in data["points"]:
        assert p["extension_nm"] == pytest.approx(p["extension"] * 102.0, rel=1e-12)
        assert p["torque_pN_nm"] == pytest.approx(p["torque"] * 50 * 4.11 / 102.0, rel=1e-12)
        assert p["force_pN"] == pytest.approx(0.3, rel=1e-12)
        assert p["superhelical_density"] == pytest.approx(p["turns"] * 10.5 / 300, rel=1e-12)
        assert p["energy_kT"] == pytest.approx(p["energy"] * 50 / 102.0, rel=1e-12)


@pytest.mark.parametrize("args, words", [
    (["--dna", "--bp", "300"], "--force-pN"),
    (["--dna", "--bp", "300", "--force-pN", "1", "--tension", "3"], "--tension"),
    (["--dna", "--bp", "300", "--force-pN", "-1"], "--force-pN"),
    (["--bp", "300", "--twist-ratio", "1", "--tension", "1"], "--dna"),
    (["--tension", "1"], "--twist-ratio"),
])
def test_dna_bad_input(tmp_path, capsys, args, words):
    status = run(["tweezers", "--turns", "0:1", "--out", str(tmp_path / "x")] + args)
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and words in err[0]


def test_force_ramp_cli_writes_force_extension(tmp_path):
    out = tmp_path / "ramp"
    status = run(["tweezers", "--twist-ratio", "1.3333333333333333", "--length-over-diameter",
                  "20", "--tension", "20", "--turns", "0:1.6", "--nodes", "30", "--protocol",
                  "force-ramp", "--step", "0.2", "--force-range", "10:30", "--force-step", "5",
                  "--out", str(out)])
    assert status == 0
    data = json.loads((out / "branch.json").read_text())
    assert {p["ramp"] for p in data["path"]} == {"turns", "tension"}
    assert (out / "force_extension.png").stat().st_size > 1000


def test_force_range_needs_force_ramp(tmp_path, capsys):
    status = run(["tweezers", "--twist-ratio", "1", "--tension", "1", "--turns", "0:1",
                  "--force-range", "0:2", "--out", str(tmp_path / "x")])
    assert status == 2 and "force-ramp" in capsys.readouterr().err


def test_displacement_control_cli(tmp_path):
    out = tmp_path / "disp"
    status = run(["tweezers", "--twist-ratio", "1.3333333333333333", "--end-distance", "0.7",
                  "--turns", "0:0.6", "--nodes", "24", "--out", str(out)])
    assert status == 0
    data = json.loads((out / "branch.json").read_text())
    assert data["control"] == "displacement" and data["branches"][0]["name"] == "clamped"
    for p in data["points"]:
        assert p["extension"] == pytest.approx(0.7, abs=1e-9) and p["load_potential"] == 0.0
    assert data["points"][0]["tension"] < 0  # the clamped buckle is compressed at 0 turns
    assert (out / "tension.png").exists() and not (out / "hat_curve.png").exists()
