"""Tests of ``supercoil ring``: the twisted ring, with self-contact, from a given curve,
and in DNA units. Every test has an oracle.

Oracles used here:

- exact values: the twisted circle has energy 2 pi^2 (1 + (C/A) dLk^2), Lk = Tw + Wr
  to 1e-9, and unstable count 0 below Michell's (A/C) sqrt(3), 2 between it and
  (A/C) sqrt(8), 4 above, with a determinant that keeps its sign (pair crossings);
- invariants of a state with contact (docs/model.md, "Contacts in the output"):
  non-negative forces, no penetration, Lk conserved, stable;
- conversions by hand of the DNA units (kT, nm, pN);
- the command line's contract: JSON keys and envelope, exit statuses (0, 1, 2).
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from cli_helpers import (
    ENVELOPE,
    RING_KEYS,
    assert_one_line,
    assert_one_line_error,
    invoke,
    json_out,
    run_main,
    tight_trefoil,
    write_curve,
)

import supercoil as sc
from supercoil import __version__
from supercoil.io.results import CONVENTIONS

# ------------------------------------------------------------------------ ring


def test_ring_below_threshold_matches_the_exact_circle(runner):
    data = json_out(
        invoke(runner, "ring", "--excess-link", "1", "--twist-ratio", "0.6667", "--json", "-")
    )
    exact = 2 * math.pi**2 * (1 + 0.6667 * 1.0**2)
    assert data["energy"] == pytest.approx(exact, rel=1e-6)
    assert data["unstable_count"] == 0
    assert data["zero_modes"] == 0
    assert data["stable"] is True
    assert data["converged"] is True
    assert data["link_error"] < 1e-9
    assert data["twist"] + data["writhe"] == pytest.approx(1.0, abs=1e-9)
    assert data["n_nodes"] == 100
    for key in RING_KEYS + ENVELOPE:
        assert key in data, key


@pytest.mark.parametrize(("excess_link", "count"), [(1.5, 0), (2.0, 2), (3.0, 4)])
def test_ring_unstable_count_rises_in_pairs(runner, excess_link, count):
    """C/A = 1: Michell's thresholds are sqrt(3) = 1.73 and sqrt(8) = 2.83; each is a
    pair crossing, so the count goes 0, 2, 4 and the determinant keeps its sign +1."""
    data = json_out(
        invoke(
            runner,
            "ring",
            "--twist-ratio",
            "1",
            "--excess-link",
            str(excess_link),
            "--nodes",
            "50",
            "--json",
            "-",
        )
    )
    assert data["unstable_count"] == count
    assert data["negative_eigenvalue_count"] == count
    assert data["determinant_sign"] == +1
    assert data["stable"] is (count == 0)
    assert data["michell_threshold_exact"] == pytest.approx(math.sqrt(3), rel=1e-15)
    assert data["converged"] is True
    assert data["link_error"] < 1e-9


def test_ring_json_envelope(runner, tmp_path):
    target = tmp_path / "ring.json"
    result = invoke(
        runner,
        "ring",
        "--twist-ratio",
        "0.5",
        "--excess-link",
        "-0.5",
        "--nodes",
        "24",
        "--json",
        target,
    )
    assert result.exit_code == 0
    assert "energy" in result.stdout  # the human table is still printed
    data = json.loads(target.read_text())
    assert data["schema_version"] == "1.0"
    assert data["units"] == "nondimensional"
    assert set(CONVENTIONS) <= set(data["conventions"])
    assert "A = 1" in data["conventions"]["units"]
    assert "right-handed" in data["conventions"]["writhe"]
    provenance = data["provenance"]
    assert provenance["supercoil_version"] == __version__
    assert provenance["n_nodes"] == 24
    assert provenance["contact_treatment"] == "none"
    assert provenance["tolerances"]["zero_modes"] > 0
    assert provenance["numpy_version"] == np.__version__
    assert data["excess_link"] == -0.5 and data["twist_ratio"] == 0.5
    assert data["energy"] == pytest.approx(2 * math.pi**2 * (1 + 0.5 * 0.25), rel=1e-12)


def _unconverged(solve):
    """``solve`` with its result marked not converged (the state is kept)."""

    def wrapped(*args, **kwargs):
        return dataclasses.replace(solve(*args, **kwargs), converged=False,
                                   status="max_iterations", message="stopped (test)")

    return wrapped


def test_ring_not_converged_exits_1_and_saves(runner, tmp_path, monkeypatch):
    """Exit status 1 when Newton does not converge; the state is still written."""
    from supercoil.problems import ring as ring_module

    monkeypatch.setattr(ring_module, "solve_ring", _unconverged(ring_module.solve_ring))
    target = tmp_path / "ring.json"
    result = invoke(
        runner,
        "ring",
        "--twist-ratio",
        "1",
        "--excess-link",
        "0.5",
        "--nodes",
        "16",
        "--json",
        target,
    )
    assert result.exit_code == 1
    assert "not converged" in result.stderr and str(target) in result.stderr
    assert json.loads(target.read_text())["converged"] is False


# ------------------------------------------------------- ring with self-contact

CONTACT_KEYS = (
    "length_over_diameter",
    "contact_treatment",
    "contacts",
    "contact_points",
    "contact_intervals",
    "n_contact_points",
    "n_contact_intervals",
    "min_gap_over_diameter",
    "writhe_error",
)


def contact_ring(excess_link: str, nodes: str, *options) -> tuple:
    """The arguments of ``supercoil ring`` at C/A = 1 and L/D = 40 with ``options``."""
    return ("ring", "--twist-ratio", "1", "--excess-link", excess_link,
            "--length-over-diameter", "40", "--nodes", nodes, *options)


def test_contact_help_states_the_library_defaults():
    """The help's treatments and tolerances are the library's (no copies of them)."""
    from supercoil.cli import ring as ring_command
    from supercoil.cli._options import exponent
    from supercoil.contact.options import DEFAULT_TREATMENT, TREATMENTS, ContactOptions

    defaults = ContactOptions(diameter=1.0)
    help_text = " ".join(ring_command.contact_help().split())
    assert help_text.count("Default:") == 1
    assert f"Default: {DEFAULT_TREATMENT}." in help_text
    for name in TREATMENTS:
        assert f"{name} = " in help_text
    for value in (defaults.barrier_activation, defaults.penetration_tolerance,
                  defaults.penalty_tolerance):
        assert exponent(value) + " D" in help_text


def assert_contact_state(data: dict, treatment: str, excess_link: float) -> None:
    """The oracles of a converged supercoiled ring (docs/model.md: "Contacts in the output",
    "Stability"; Lk = Tw + Wr)."""
    for key in RING_KEYS + CONTACT_KEYS + ENVELOPE:
        assert key in data, key
    assert data["converged"] is True, data["message"]
    assert data["contact_treatment"] == treatment
    # contact forces are never negative; each touching pair names two arc lengths
    assert data["contacts"], "no contact"
    for contact in data["contacts"] + data["contact_points"]:
        assert contact["force"] > 0, contact
        assert 0 <= contact["s1"] < 1 and 0 <= contact["s2"] < 1
    assert data["n_contact_points"] == len(data["contact_points"])
    assert data["n_contact_intervals"] == len(data["contact_intervals"])
    assert data["n_contact_points"] + data["n_contact_intervals"] >= 1
    # impenetrable (1 = touching), Lk conserved with Tw and Wr computed independently,
    # and no strand passed through another (continuous writhe == double-sum writhe)
    assert data["min_gap_over_diameter"] >= 1 - 1e-4
    assert abs(data["twist"] + data["writhe"] - excess_link) < 1e-8
    assert data["writhe_error"] < 1e-8
    assert data["unstable_count"] == 0 and data["stable"] is True
    provenance = data["provenance"]
    assert provenance["contact_treatment"] == treatment
    assert provenance["tolerances"]["penetration_over_diameter"] == (
        5e-2 if treatment == "penalty" else 1e-4
    )
    assert provenance["tolerances"]["newton_residual"] > 0


@pytest.mark.parametrize("treatment", ["barrier", "augmented", "exact"])
def test_ring_with_contact_json(runner, tmp_path, treatment):
    """Above Michell's sqrt(8) (C/A = 1, dLk = 3) the ring leaves the circle and
    supercoils: writhe > 1, at least one contact, the oracles of assert_contact_state."""
    target = tmp_path / "ring.json"
    result = invoke(runner, *contact_ring("3", "48", "--contact", treatment, "--json", target))
    data = json.loads(target.read_text())
    assert result.exit_code == 0, (result.stderr, data["message"])
    assert_contact_state(data, treatment, 3.0)
    assert data["length_over_diameter"] == 40 and data["initial_curve"] is None
    assert data["n_nodes"] == 48 and data["provenance"]["n_nodes"] == 48
    assert data["writhe"] > 1.0  # supercoiled: part of the excess link went into writhe


def test_ring_with_contact_not_converged_exits_1_and_saves(runner, tmp_path, monkeypatch):
    """Exit status 1 when the contact solve does not converge; the state is still written."""
    from supercoil.problems import ring_contact

    monkeypatch.setattr(ring_contact, "solve_supercoiled_ring",
                        _unconverged(ring_contact.solve_supercoiled_ring))
    target = tmp_path / "ring.json"
    result = invoke(runner, *contact_ring("1", "24", "--json", target))
    assert result.exit_code == 1
    assert "not converged" in result.stderr and str(target) in result.stderr
    data = json.loads(target.read_text())
    from supercoil.contact.options import DEFAULT_TREATMENT as DEFAULT_CONTACT_TREATMENT

    assert data["converged"] is False
    assert data["contact_treatment"] == DEFAULT_CONTACT_TREATMENT
    assert data["provenance"]["contact_treatment"] == DEFAULT_CONTACT_TREATMENT


def test_ring_contact_errors_of_the_numerics_are_not_bad_input(capsys, monkeypatch):
    """An InputError raised inside a solver is a failure of the numerics (exit 1, internal
    error), not bad input (exit 2); one raised while setting the problem up is bad input."""
    from supercoil.problems import ring_contact
    from supercoil.solvers.newton import NewtonOptions

    args = contact_ring("3", "24")
    monkeypatch.delenv("SUPERCOIL_DEBUG", raising=False)

    def inside_a_solver(*_args, **_kwargs):
        NewtonOptions(tolerance=-1.0)  # raises ValueError in supercoil.solvers.newton

    monkeypatch.setattr(ring_contact, "solve_supercoiled_ring", inside_a_solver)
    status, out, err = run_main(capsys, *args)
    assert_one_line(status, out, err, 1, "internal error", "InputError", "tolerance")

    def at_set_up(*_args, **_kwargs):
        from supercoil.errors import InputError

        raise InputError("the starting ring already penetrates itself (test)")

    monkeypatch.setattr(ring_contact, "solve_supercoiled_ring", at_set_up)
    status, out, err = run_main(capsys, *args)
    assert_one_line(status, out, err, 2, "penetrates itself (test)")


def test_ring_contact_table_below_michell(runner):
    """Below Michell's sqrt(3) the circle is stable and stays: the human table shows the
    contact rows with no contact, a closest approach above D and the exact circle energy."""
    result = invoke(runner, *contact_ring("1", "40", "--contact", "exact"))
    assert result.exit_code == 0, result.stderr
    rows = {}
    for line in result.stdout.splitlines():
        cells = [c.strip() for c in line.strip("\u2502 ").split("\u2502")]
        if len(cells) == 2:
            rows[cells[0]] = cells[1]
    assert "Supercoiled ring" in result.stdout
    assert rows["started from"] == "the circle"
    assert rows["branch (quasi-static path)"] == "circle, no jump"  # below the threshold
    assert rows["L/D, contact treatment"] == "40, exact"
    assert float(rows["closest approach / D"]) > 1
    assert rows["contacts"] == "0 point(s), 0 interval(s)"
    assert rows["contact points (s1, s2, force)"] == "none"
    assert rows["contact intervals"] == "none"
    assert float(rows["energy E*L/A"]) == pytest.approx(4 * math.pi**2, rel=1e-8)
    assert float(rows["writhe (turns)"]) == pytest.approx(0, abs=1e-9)


def test_ring_initial_trefoil_keeps_its_knot(runner, tmp_path, monkeypatch):
    """A trefoil relaxed with exact contact stays a tight trefoil: |writhe| > 2 (about 3.05
    here; it would fall towards 0 if the knot were undone), Lk conserved, impenetrable,
    non-negative forces, stable; the curve file's size does not matter (scaled to L = 1).

    N = 48: a mesh on which the exact treatment converges to a stable state for this
    trefoil at L/D = 40 (on some other meshes the contact solver stops short at its line
    search or iteration limit, which the command reports as exit 1 with the state saved)."""
    monkeypatch.chdir(tmp_path)  # a short relative path, shown whole in the table
    write_curve(tmp_path / "trefoil.txt", 7.5 * tight_trefoil(), "trefoil")
    curve = "trefoil.txt"
    target = tmp_path / "trefoil.json"
    result = invoke(runner, *contact_ring("0", "48", "--contact", "exact", "--initial", curve,
                                          "--json", target))
    data = json.loads(target.read_text())
    assert result.exit_code == 0, (result.stderr, data["message"])
    assert_contact_state(data, "exact", 0.0)
    assert abs(data["writhe"]) > 2
    assert data["writhe"] < 0  # this parametrisation is a left-handed trefoil
    assert data["initial_curve"] == curve
    # the table (printed with --json PATH too) names the start and shows the contacts
    text = result.stdout
    assert "started from" in text and "trefoil.txt" in text
    for row in (
        "L/D, contact treatment",
        "closest approach / D",
        "contact points",
        "contact intervals",
    ):
        assert row in text, row
    assert f"{data['n_contact_points']} point(s)" in text
    assert "exact circle energy" not in text  # a reference that belongs to the circle


# ------------------------------------------------------------- ring --dna (units)

DNA_KEYS = (
    "base_pairs",
    "superhelical_density",
    "relaxed_link",
    "length_nm",
    "diameter_nm",
    "salt_mM",
    "temperature_K",
    "kT_pN_nm",
    "energy_kT",
    "energy_circle_exact_kT",
    "michell_threshold_superhelical_density",
    "min_gap_nm",
)


def test_ring_dna_plasmid_json_and_table(runner, tmp_path):
    """A 1000 bp plasmid at sigma = -0.04 in 100 mM salt. Oracles by hand: L = 340 nm,
    C/A = 95/50, dLk = -0.04 * 1000/10.5, D = 5 nm (a table point), L/D = 68; every
    suffixed key is its nondimensional value times A/L (in kT), A/L^2 (pN) or D (nm),
    with A = 50 nm * 4.11 pN nm; Lk = Tw + Wr; the units are the preset's name."""
    target = tmp_path / "plasmid.json"
    result = invoke(runner, "ring", "--dna", "--bp", "1000", "--sigma", "-0.04",
                    "--salt-mM", "100", "--nodes", "48", "--json", target)
    data = json.loads(target.read_text())
    assert result.exit_code == 0, (result.stderr, data["message"])
    for key in (*ENVELOPE, *RING_KEYS, *CONTACT_KEYS, *DNA_KEYS):
        assert key in data, key
    assert data["units"] == "dna"
    a_pN_nm2, length_nm = 50 * 4.11, 1000 * 0.34
    assert data["twist_ratio"] == pytest.approx(1.9, rel=1e-15)
    assert data["excess_link"] == pytest.approx(-0.04 * 1000 / 10.5, rel=1e-14)
    assert data["superhelical_density"] == -0.04
    assert data["relaxed_link"] == pytest.approx(1000 / 10.5, rel=1e-15)
    assert data["length_over_diameter"] == pytest.approx(68.0, rel=1e-14)
    assert data["length_nm"] == pytest.approx(length_nm, rel=1e-15)
    assert data["diameter_nm"] == 5.0 and data["salt_mM"] == 100.0
    assert data["temperature_K"] == 298.0 and data["kT_pN_nm"] == 4.11
    assert data["energy_kT"] == pytest.approx(data["energy"] * a_pN_nm2 / length_nm / 4.11,
                                              rel=1e-14)
    assert data["energy_circle_exact_kT"] == pytest.approx(
        data["energy_circle_exact"] * 50 / length_nm, rel=1e-14)
    assert data["michell_threshold_superhelical_density"] == pytest.approx(
        data["michell_threshold_exact"] / (1000 / 10.5), rel=1e-14)
    assert data["min_gap_nm"] == pytest.approx(data["min_gap_over_diameter"] * 5.0, rel=1e-14)
    # a supercoiled plasmid touches itself, at points or along intervals
    assert data["contact_points"] or data["contact_intervals"], data["message"]
    for key in ("contacts", "contact_points"):
        for contact in data[key]:
            assert contact["force_pN"] == pytest.approx(
                contact["force"] * a_pN_nm2 / length_nm**2, rel=1e-14)
    for interval in data["contact_intervals"]:
        assert interval["force_per_length_pN_per_nm"] == pytest.approx(
            interval["force_per_length"] * a_pN_nm2 / length_nm**3, rel=1e-14)
    assert data["converged"] and data["stable"]
    assert abs(data["twist"] + data["writhe"] - data["excess_link"]) < 1e-9
    assert data["writhe"] < -1.0  # underwound: negative supercoils
    assert "athermal" in data["conventions"] and "units_preset" in data["conventions"]
    record = data["provenance"]["units_preset"]
    assert record["name"] == "dna" and record["base_pairs"] == 1000
    assert record["bending_persistence_nm"] == 50.0 and record["twist_persistence_nm"] == 95.0
    assert record["rise_nm_per_bp"] == 0.34 and record["helical_repeat_bp"] == 10.5
    assert record["kT_reference_pN_nm"] == 4.11 and record["diameter_nm"] == 5.0
    text = " ".join(result.stdout.replace("\u2502", " ").split())  # cells rejoined
    assert "DNA supercoiled ring, 1000 bp" in text
    for row in ("energy (kT)", "superhelical density sigma", "contact forces (pN)",
                "closest approach (nm)", "L = 340 nm", "D = 5 nm (100 mM salt)",
                "Athermal model (zero temperature)"):
        assert row in text, row


def test_ring_dna_folder_exports_in_nm(runner, tmp_path):
    """``ring --dna --out``: the result file carries the DNA scales, so its state exports
    in nm (the stored centreline times L = 300 * 0.34 nm) and as PDB beads."""
    out = tmp_path / "plasmid"
    result = invoke(runner, "ring", "--dna", "--bp", "300", "--sigma", "-0.02",
                    "--salt-mM", "100", "--nodes", "24", "--out", out, "--quiet")
    assert result.exit_code == 0, result.stderr
    assert invoke(runner, "export", out, "--out", tmp_path / "s.xyz", "--quiet").exit_code == 0
    assert invoke(runner, "export", out, "--out", tmp_path / "s.pdb", "--quiet").exit_code == 0
    nm = np.loadtxt(tmp_path / "s.xyz", skiprows=2, usecols=(1, 2, 3))
    branch = sc.load(out).branches["ring"]
    stored = branch.states[0].reshape(-1, 3)
    np.testing.assert_allclose(nm, stored * 300 * 0.34, rtol=0, atol=1e-9)
    # one converged state at the requested dLk: complete, not cut by a point limit
    assert branch.status.name == "PARAMETER_BOUND" and branch.status.complete
    assert branch.parameter_values[0] == pytest.approx(-0.02 * 300 / 10.5, abs=1e-12)


def test_ring_dna_help_names_the_options_and_the_caveat(runner):
    result = invoke(runner, "ring", "--help")
    text = " ".join(result.stdout.split())
    for word in ("--dna", "--bp", "--sigma", "--salt-mM", "--diameter-nm", "--temperature-K",
                 "--twist-persistence-nm", "athermal", "kT"):
        assert word in text, word


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--dna", "--bp", "1000", "--sigma", "-0.04", "--twist-ratio", "1"],
         ["--twist-ratio", "cannot be combined with --dna"]),
        (["--dna", "--bp", "1000", "--sigma", "-0.04", "--excess-link", "-3"],
         ["--excess-link", "cannot be combined with --dna"]),
        (["--dna", "--bp", "1000", "--sigma", "-0.04", "--length-over-diameter", "60"],
         ["--length-over-diameter", "cannot be combined with --dna"]),
        (["--dna", "--bp", "1000"], ["--dna needs --sigma"]),
        (["--dna", "--sigma", "-0.04"], ["--dna needs --bp"]),
        (["--dna"], ["--dna needs --bp", "--sigma"]),
        (["--bp", "1000", "--sigma", "-0.04"], ["--bp, --sigma need --dna"]),
        (["--twist-ratio", "1", "--excess-link", "1", "--salt-mM", "100"],
         ["--salt-mM needs --dna"]),
        (["--twist-ratio", "1", "--excess-link", "1", "--temperature-K", "300"],
         ["--temperature-K needs --dna"]),
        (["--excess-link", "1"], ["Missing option", "'--twist-ratio'", "--dna"]),
        (["--twist-ratio", "1"], ["Missing option", "'--excess-link'"]),
        (["--dna", "--bp", "0", "--sigma", "0"], ["--bp", "from 12 to 10000000", "got 0"]),
        (["--dna", "--bp", "1000", "--sigma", "nan"], ["--sigma", "finite"]),
        (["--dna", "--bp", "1000", "--sigma", "0", "--salt-mM", "5"],
         ["--salt-mM", "outside the tabulated range 10-200 mM"]),
        (["--dna", "--bp", "1000", "--sigma", "0", "--salt-mM", "1000"],
         ["--salt-mM", "outside the tabulated range"]),
        (["--dna", "--bp", "1000", "--sigma", "0", "--temperature-K", "0"],
         ["--temperature-K", "above 0"]),
        (["--dna", "--bp", "1000", "--sigma", "0", "--salt-mM", "100", "--diameter-nm", "4"],
         ["--salt-mM and --diameter-nm"]),
        (["--dna", "--bp", "1000", "--sigma", "0", "--diameter-nm", "-4"],
         ["--diameter-nm", "above 0"]),
        (["--dna", "--bp", "20", "--sigma", "0"], ["--bp = 20", "L/D > pi", "--bp >= 40"]),
        (["--dna", "--bp", "1000", "--sigma", "1e9"], ["--sigma", "from -1 to 1"]),
        (["--dna", "--bp", "1000", "--sigma", "-6"], ["--sigma", "from -1 to 1", "got -6"]),
    ],
)
def test_ring_dna_bad_input_is_one_line_and_exit_2(runner, capsys, args, words):
    """Mixed, missing or invalid DNA options: one ``error:`` line, exit 2, nothing solved,
    both through typer's runner and through the console script's entry point."""
    assert_one_line_error(invoke(runner, "ring", *args), *words)
    status, out, err = run_main(capsys, "ring", *args)
    assert_one_line(status, out, err, 2, *words)
    assert out == ""


def test_twist_ratio_may_be_written_as_a_fraction(runner):
    # Papers quote C/A = 2/3: the fraction and its decimal give the same ring.
    as_fraction = json_out(invoke(runner, "ring", "--twist-ratio", "2/3", "--excess-link",
                                  "0.5", "--nodes", "24", "--json", "-"))
    as_decimal = json_out(invoke(runner, "ring", "--twist-ratio", repr(2 / 3), "--excess-link",
                                 "0.5", "--nodes", "24", "--json", "-"))
    assert as_fraction["twist_ratio"] == 2 / 3
    assert as_fraction["energy"] == as_decimal["energy"]


@pytest.mark.parametrize("bad, words", [("2/0", ("divides by zero",)),
                                        ("2/x", ("fraction like 2/3",)),
                                        ("1/2/3", ("fraction like 2/3",))])
def test_a_malformed_twist_ratio_is_a_one_line_error(capsys, bad, words):
    status, out, err = run_main(capsys, "ring", "--twist-ratio", bad, "--excess-link", "0.5")
    assert_one_line(status, out, err, 2, "--twist-ratio", *words)
