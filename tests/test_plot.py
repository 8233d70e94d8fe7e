"""``supercoil plot``: figures of a result (PNG and SVG, one style, axes with units)."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from plot_results import DIAMETER, write_ring_result, write_tweezers_result

from supercoil.cli.main import run
from supercoil.plotting import style
from supercoil.plotting.figures import KINDS, figure_of, supported_kinds
from supercoil.plotting.result_data import ResultError, load_result


@pytest.fixture
def ring(tmp_path):
    return write_ring_result(tmp_path / "ring")


def _png(path):
    from matplotlib.image import imread

    return imread(path)


def _svg_texts(path):
    """The text of an SVG saved with svg.fonttype = path: matplotlib writes each text
    element's string as a comment before its glyphs."""
    return re.findall(r"<!-- (.*?) -->", path.read_text(encoding="utf-8"))


def test_kinds_match_the_cli_copy():
    from supercoil.cli import plot

    assert plot.KINDS == KINDS


def test_plot_writes_png_and_svg_with_unit_labels(ring, tmp_path, capsys):
    out = tmp_path / "figs"
    assert run(["plot", str(ring), "--out", str(out)]) == 0
    assert "wrote diagram.png" in capsys.readouterr().out
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(f"{k}.{f}" for k in ("diagram", "contact_map", "configurations")
                           for f in ("png", "svg"))
    image = _png(out / "diagram.png")
    assert image.shape[0] > 500 and image.shape[1] > 700  # 200 dpi
    texts = _svg_texts(out / "diagram.svg")
    assert style.LABELS["writhe"] in texts and style.LABELS["excess_link"] in texts
    assert "fold" in texts and "bifurcation" in texts and "loop_contact" in texts
    assert style.LABELS["arclength"] in " ".join(_svg_texts(out / "contact_map.svg"))


def test_same_result_same_files(ring, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert run(["plot", str(ring), "--out", str(a), "--kind", "diagram"]) == 0
    assert run(["plot", str(ring), "--out", str(b), "--kind", "diagram"]) == 0
    assert (a / "diagram.svg").read_bytes() == (b / "diagram.svg").read_bytes()
    assert np.array_equal(_png(a / "diagram.png"), _png(b / "diagram.png"))


def test_configurations_change_with_the_state(tmp_path):
    one = write_ring_result(tmp_path / "one")
    two = write_ring_result(tmp_path / "two", shift=0.0)
    moved = write_ring_result(tmp_path / "moved", shift=0.0)
    # move one node of the last contact state: only the third panel may change
    from dataclasses import replace

    from supercoil.io.store import load, save

    stored = load(moved)
    b = stored.branch("loop_contact")
    states = np.array(b.states)
    states[-1, 3 * 5:3 * 6] += 0.05
    save(moved / "result.h5", [stored.branch("circle"), replace(b, states=states)],
         problem="ring_diagram", summary=stored.summary, attributes=stored.attributes,
         overwrite=True)
    images = {}
    for name, folder in (("one", one), ("two", two), ("moved", moved)):
        out = tmp_path / f"out_{name}"
        assert run(["plot", str(folder), "--out", str(out), "--kind", "configurations",
                    "--format", "png"]) == 0
        images[name] = _png(out / "configurations.png")
    assert np.array_equal(images["one"], images["two"])
    diff = np.any(images["one"] != images["moved"], axis=2)
    assert diff.any()
    columns = np.flatnonzero(diff.any(axis=0))
    assert columns.min() > 2 * diff.shape[1] / 3 - 10  # the third panel only


def test_diagram_heavy_exactly_where_stable(ring):
    result = load_result(ring)
    fig = figure_of(result, "diagram")
    ax = fig.axes[0]
    heavy = [line for line in ax.get_lines() if line.get_linewidth() == style.STABLE_WIDTH
             and len(line.get_xdata()) > 1]
    assert len(heavy) == 2  # one per branch
    for line, branch in zip(heavy, result.branches, strict=True):
        stable = np.array([p["stable"] for p in branch.points])
        y = np.asarray(line.get_ydata(), float)
        assert np.array_equal(np.isfinite(y), stable)
        assert np.array_equal(y[stable], [p["excess_link"] for p, s in
                                          zip(branch.points, stable, strict=True) if s])


def test_contact_map_shows_the_stored_contacts(ring):
    result = load_result(ring)
    ax = figure_of(result, "contact-map").axes[0]
    dots = [line for line in ax.get_lines() if line.get_marker() == "."]
    assert len(dots) == 1
    branch = result.branch("loop_contact")
    expected = [(p["writhe"], s) for p in branch.points for c in p["contact_points"]
                for s in (c["s1"], c["s2"])]
    assert list(zip(dots[0].get_xdata(), dots[0].get_ydata(), strict=True)) == expected
    bars = ax.collections[0].get_segments()
    assert len(bars) == 2 * sum(len(p["contact_intervals"]) for p in branch.points)
    assert {tuple(np.round(seg[:, 1], 12)) for seg in bars} == {(0.2, 0.3), (0.7, 0.8)}


def test_configuration_tubes_have_the_diameter(ring):
    fig = figure_of(load_result(ring), "configurations")
    ax = fig.axes[0]
    tubes = ax.collections[0]
    width_pt = float(tubes.get_linewidths()[0])
    span = ax.get_xlim()[1] - ax.get_xlim()[0]
    fig.draw_without_rendering()
    expected = DIAMETER / span * ax.bbox.height * 72.0 / fig.dpi
    assert width_pt == pytest.approx(expected, rel=0.02)
    assert "D = 0.025 L" in fig._suptitle.get_text()


def test_hat_curve_from_a_tweezers_result(tmp_path):
    folder = write_tweezers_result(tmp_path / "tw")
    result = load_result(folder)
    assert supported_kinds(result) == ("diagram", "hat-curve")
    ax = figure_of(result, "hat-curve").axes[0]
    assert ax.get_xlabel() == style.LABELS["turns"]
    assert ax.get_ylabel() == style.LABELS["extension"]
    thin = ax.get_lines()[0]
    data = json.loads((folder / "branch.json").read_text())["points"]
    assert list(thin.get_xdata()) == [p["turns"] for p in data]
    assert list(thin.get_ydata()) == [p["extension"] for p in data]
    out = tmp_path / "figs"
    assert run(["plot", str(folder), "--kind", "hat-curve", "--out", str(out)]) == 0
    assert (out / "hat_curve.png").is_file() and (out / "hat_curve.svg").is_file()


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: ")
    return err


def test_bad_input_is_one_line_and_exit_2(ring, tmp_path, capsys):
    out = tmp_path / "figs"
    assert run(["plot", str(tmp_path / "missing"), "--out", str(out)]) == 2
    assert "no such file or folder" in _error(capsys)
    assert run(["plot", str(ring), "--out", str(out), "--kind", "pie"]) == 2
    assert "diagram, contact-map, hat-curve, configurations" in _error(capsys)
    assert run(["plot", str(ring), "--out", str(out), "--kind", "hat-curve"]) == 2
    assert "kinds it has: diagram, contact-map, configurations" in _error(capsys)
    assert run(["plot", str(ring), "--out", str(out), "--format", "jpg"]) == 2
    _error(capsys)
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "diagram.json").write_text("{not json", encoding="utf-8")
    assert run(["plot", str(bad), "--out", str(out)]) == 2
    assert f"{bad / 'diagram.json'}: not valid JSON" in _error(capsys)
    (bad / "diagram.json").write_text('{"points": []}', encoding="utf-8")
    assert run(["plot", str(bad / "diagram.json"), "--out", str(out)]) == 2
    assert "no 'points' list" in _error(capsys)
    assert not out.exists()
    (ring / "notes.txt").write_text("x", encoding="utf-8")
    with pytest.raises(ResultError, match="unknown result type"):
        load_result(ring / "notes.txt")


def test_existing_figures_are_not_overwritten(ring, tmp_path, capsys):
    out = tmp_path / "figs"
    assert run(["plot", str(ring), "--out", str(out), "--kind", "diagram"]) == 0
    before = (out / "diagram.svg").read_bytes()
    (out / "diagram.svg").write_text("mine", encoding="utf-8")
    assert run(["plot", str(ring), "--out", str(out), "--kind", "diagram"]) == 2
    assert "diagram.png exists" in _error(capsys)
    assert (out / "diagram.svg").read_text(encoding="utf-8") == "mine"
    # another kind into the same folder is fine; --overwrite replaces
    assert run(["plot", str(ring), "--out", str(out), "--kind", "contact-map"]) == 0
    assert run(["plot", str(ring), "--out", str(out), "--kind", "diagram", "--overwrite"]) == 0
    assert (out / "diagram.svg").read_bytes() == before
    (tmp_path / "file").write_text("x", encoding="utf-8")
    assert run(["plot", str(ring), "--out", str(tmp_path / "file")]) == 2
    assert "is a file" in _error(capsys)


def test_a_contact_free_child_branch_ends_before_its_contact_onset(ring):
    """'supercoil diagram ring' stops a contact-free child branch one step past the
    contact onset; that last state overlaps itself, so it is not shown (as the
    command's own figure does)."""
    path = ring / "diagram.json"
    data = json.loads(path.read_text(encoding="utf-8"))
    data["branches"][1]["contact"] = False
    path.write_text(json.dumps(data), encoding="utf-8")
    result = load_result(path)
    stored = [p for p in data["points"] if p["branch"] == "loop_contact"]
    assert list(result.branch("loop_contact").points) == stored[:-1]
    assert result.branch("loop_contact").states().shape == (len(stored) - 1, 24, 3)
    assert len(result.branch("circle").points) == 7  # no parent: all points


def _store(ring, path, *, summary: bool, extra: dict | None = None):
    from supercoil.io.store import ResultWriter, load

    data = json.loads((ring / "diagram.json").read_text(encoding="utf-8"))
    attributes = {k: data[k] for k in ("twist_ratio", "length_over_diameter", "diameter",
                                       "n_nodes")}
    with ResultWriter.create(path, problem="ring_diagram", settings={},
                             attributes={**attributes, "closed": True, **(extra or {})}) \
            as writer:
        for entry in data["branches"]:
            writer.write_branch(load(ring).branch(entry["name"]), contact=entry["contact"])
        if summary:
            writer.set_summary(data)
        writer.set_status("complete" if summary else "interrupted")
    return path


def test_a_result_file_reads_like_its_folder(ring, tmp_path):
    folder = load_result(ring)
    stored = load_result(_store(ring, tmp_path / "result.h5", summary=True))
    assert (stored.kind, stored.title, stored.diameter) == (folder.kind, folder.title,
                                                              folder.diameter)
    for a, b in zip(folder.branches, stored.branches, strict=True):
        assert (a.name, a.parent, a.contact) == (b.name, b.parent, b.contact)
        assert list(a.points) == list(b.points)
        assert np.array_equal(a.states(), b.states())
    assert supported_kinds(stored) == ("diagram", "contact-map", "configurations")
    # a folder holding a result file reads the file
    (ring / "result.h5").write_bytes((tmp_path / "result.h5").read_bytes())
    assert load_result(ring).path == ring / "result.h5"


def test_an_interrupted_result_file_draws_from_its_records(ring, tmp_path):
    """Without the finished run's summary the points come from the stored records
    (no contact lists: no contact map)."""
    result = load_result(_store(ring, tmp_path / "partial.h5", summary=False))
    circle = result.branch("circle")
    assert [p["excess_link"] for p in circle.points] == list(np.linspace(0.0, 3.0, 7))
    assert [p["stable"] for p in circle.points] == [True] * 4 + [False] * 3
    assert supported_kinds(result) == ("diagram", "configurations")
    fig = figure_of(result, "diagram")
    assert fig.axes[0].get_xlabel() == style.LABELS["writhe"]


def test_a_damaged_result_file_is_one_line(tmp_path, capsys):
    bad = tmp_path / "result.h5"
    bad.write_bytes(b"not hdf5 at all")
    with pytest.raises(ResultError, match="result.h5"):
        load_result(bad)
    assert run(["plot", str(bad), "--out", str(tmp_path / "figs")]) == 2
    assert str(bad) in _error(capsys)


def test_tweezers_configurations_are_open_tubes(tmp_path):
    result = load_result(write_tweezers_result(tmp_path / "tw", with_states=True))
    assert supported_kinds(result) == ("diagram", "hat-curve", "configurations")
    ax = figure_of(result, "configurations").axes[0]
    segments = ax.collections[0].get_segments()
    assert len(segments) == 2 * (24 - 1)  # an open rod: n - 1 segments (each + stripe)
    starts = np.array([seg[0] for seg in segments[0::2]])
    xlim, ylim = ax.get_xlim(), ax.get_ylim()  # the box is centred on the picture
    assert (starts[:, 0].min() + starts[:, 0].max()) / 2 == pytest.approx(
        (xlim[0] + xlim[1]) / 2, abs=0.05 * (xlim[1] - xlim[0]))
    assert ylim[0] < starts[:, 1].min() and starts[:, 1].max() < ylim[1]


def test_without_the_result_file_no_configurations(ring, tmp_path, capsys):
    (ring / "result.h5").unlink()
    assert supported_kinds(load_result(ring)) == ("diagram", "contact-map")
    out = tmp_path / "figs"
    assert run(["plot", str(ring), "--out", str(out), "--kind", "configurations"]) == 2
    assert "kinds it has: diagram, contact-map" in _error(capsys)
    assert not out.exists()


def test_a_damaged_result_file_in_a_folder_is_one_line(ring, tmp_path, capsys):
    data = bytearray((ring / "result.h5").read_bytes())
    (ring / "result.h5").write_bytes(bytes(data[:len(data) // 2]))
    assert run(["plot", str(ring), "--out", str(tmp_path / "figs")]) == 2
    assert "result.h5: cannot read the result file" in _error(capsys)
    assert run(["view", str(ring)]) == 2
    assert "result.h5: cannot read the result file" in _error(capsys)
    assert run(["plot", str(ring / "diagram.json"), "--out", str(tmp_path / "figs")]) == 2
    assert "result.h5: cannot read the result file" in _error(capsys)
    assert not (ring / "viewer.html").exists() and not (tmp_path / "figs").exists()


def test_a_dna_result_says_so_in_its_title(ring, tmp_path):
    result = load_result(_store(ring, tmp_path / "dna.h5", summary=True,
                                extra={"base_pairs": 600, "salt_mM": 150.0}))
    assert result.title == "DNA ring of 600 bp in 150 mM salt, C/A = 0.6667, L/D = 40, N = 24"


def test_house_style_png_fast_encoding_keeps_the_pixels(tmp_path):
    """style.save writes PNGs at zlib level 1: decoded, the same pixels as the default
    level (and not the same bytes, so the option reached the encoder)."""
    from supercoil.plotting.figures import diagram_figure
    from supercoil.plotting.style import save, styled

    x = np.linspace(0.0, 3.0, 40)
    with styled():
        fig = diagram_figure([{"name": "alpha", "writhe": x, "excess_link": 1 + x**2,
                               "stable": x < 2.0}], [], title="ring", x="writhe",
                             y="excess_link")
        fig.savefig(tmp_path / "default.png", format="png", metadata={})
    save(fig, tmp_path / "fast.png")
    assert (tmp_path / "fast.png").read_bytes() != (tmp_path / "default.png").read_bytes()
    np.testing.assert_array_equal(_png(tmp_path / "fast.png"), _png(tmp_path / "default.png"))


def test_special_points_on_one_segment_enter_the_line_in_arclength_order():
    """Two bifurcations between two samples (a straight rod stepping by a turn): each
    enters twice, both in order along the segment, so the polyline goes forward."""
    from supercoil.plotting.figures import through_special_points

    row = {"name": "straight", "turns": [0.0, 1.0, 2.0, 3.0],
           "extension": [1.0, 1.0, 1.0, 1.0], "stable": [True, True, False, False]}
    specials = [  # listed out of order on purpose
        {"branch": "straight", "index": 1, "arclength": 1.7, "turns": 1.7, "extension": 1.0,
         "count_before": 2, "count_after": 4},
        {"branch": "straight", "index": 1, "arclength": 1.2, "turns": 1.2, "extension": 1.0,
         "count_before": 0, "count_after": 2},
        {"branch": "other", "index": 1, "arclength": 1.5, "turns": 1.5, "extension": 1.0,
         "count_before": 0, "count_after": 2},
    ]
    out = through_special_points(row, specials, ("turns", "extension"))
    assert out["turns"].tolist() == [0.0, 1.0, 1.2, 1.2, 1.7, 1.7, 2.0, 3.0]
    assert out["stable"].tolist() == [True, True, True, False, False, False, False, False]


def test_tweezers_lines_are_stable_up_to_the_located_buckling():
    """The hat curve's straight rod is heavy up to its located bifurcation (count 0
    before it), not only up to its last stable sample."""
    from supercoil.plotting.tweezers import figure_jobs

    points = [{"branch": "straight", "turns": t, "extension": 1.0, "torque": 0.0,
               "writhe": 0.0, "stable": s} for t, s in ((0.0, True), (1.6, True), (2.5, False))]
    payload = {"branches": [{"name": "straight"}], "points": points, "twist_ratio": 1.0,
               "n_nodes": 10, "special_points": [{
                   "kind": "bifurcation", "branch": "straight", "index": 1, "arclength": 2.2,
                   "turns": 2.2, "extension": 1.0, "torque": 0.0, "writhe": 0.0,
                   "count_before": 0, "count_after": 2}]}
    for _path, _builder, kwargs in figure_jobs(payload, [], "unused"):
        (line,) = kwargs["branches"]
        stable_turns = np.asarray(line["turns"])[np.asarray(line["stable"])]
        assert stable_turns.max() == 2.2


def test_the_torque_figure_draws_the_hard_core_plys_plateau():
    """With ``hard_core_ply`` in the payload the torque's figure (only) gains a line at
    the ply's torque from the turns whose straight twist carries it to those at which
    the ply spans the rod (:func:`~supercoil.problems.ply.hard_core_ply`)."""
    from supercoil.plotting.tweezers import figure_jobs
    from supercoil.problems.ply import hard_core_ply

    ply = hard_core_ply(0.01, 6400.0, 1.5)
    points = [{"branch": "straight", "turns": t, "extension": 1.0, "torque": 3 * np.pi * t,
               "writhe": 0.0, "stable": True} for t in (0.0, 30.0)]
    payload = {"branches": [{"name": "straight"}], "points": points, "twist_ratio": 1.5,
               "n_nodes": 102, "special_points": [], "hard_core_ply": ply.summary()}
    jobs = {path.name: kwargs for path, _builder, kwargs in figure_jobs(payload, [], "unused")}
    (line,) = [b for b in jobs["torque.png"]["branches"] if b["name"] == "hard-core ply"]
    assert line["turns"] == [ply.twist_turns, ply.spanning_turns]
    payload["turns_range"] = [0.0, 20.0]  # the run ends before the ply spans the rod
    (short,) = [b for b in figure_jobs(payload, [], "unused")[1][2]["branches"]
                if b["name"] == "hard-core ply"]
    assert short["turns"] == [ply.twist_turns, 20.0]
    assert line["torque"] == [ply.torque, ply.torque]
    # the straight rod's torque 2 pi (C/A) turns meets the plateau where the line starts
    assert 3 * np.pi * line["turns"][0] == pytest.approx(ply.torque, rel=1e-12)
    for name in ("hat_curve.png", "writhe.png"):
        assert [b["name"] for b in jobs[name]["branches"]] == ["straight"]


@pytest.mark.parametrize("made_at", [100, 150])  # 150: as draw_job makes the figures
@pytest.mark.parametrize("scale, names", [
    (1.0, ("straight", "buckled")),
    (1e5, ("a branch with a long name, and another clause", "b")),  # wide labels
    (-3e-4, ("straight", "buckled_contact")),  # negative ticks, an offset text
])
def test_diagram_layout_keeps_every_text_inside_and_the_legend_beside(scale, names, made_at):
    """The diagram's own layout (``figures._fit_beside_legend``): made at ``made_at`` dpi
    and drawn at the saving resolution, every tick label, axis label, the title and the
    legend lie inside the figure, and the legend lies right of everything the axes draw."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from supercoil.plotting.figures import diagram_figure

    turns = np.linspace(0.0, 5.0, 40)
    branches = [{"name": name, "turns": turns, "torque": scale * (k + 1) * turns**2,
                 "stable": turns < 2.5} for k, name in enumerate(names)]
    specials = [{"kind": "fold", "turns": 2.0, "torque": 4.0 * scale}]
    with matplotlib.rc_context({"figure.dpi": made_at}):
        fig = diagram_figure(branches, specials, title="clamped rod, a title of some length",
                             x="turns", y="torque")
    assert fig.dpi == made_at
    fig.set_dpi(150)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    ax = fig.axes[0]
    figure_box = fig.bbox
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    # the tick labels drawn: those of ticks within the view limits
    texts = [t for t in ax.get_xticklabels() if x0 <= t.get_position()[0] <= x1]
    texts += [t for t in ax.get_yticklabels() if y0 <= t.get_position()[1] <= y1]
    assert len(texts) >= 4
    texts += [ax.xaxis.label, ax.yaxis.label, ax.title, ax.yaxis.get_offset_text()]
    for text in texts:
        if not text.get_visible() or not text.get_text():
            continue
        box = text.get_window_extent(renderer)
        assert box.x0 >= figure_box.x0 - 0.5 and box.x1 <= figure_box.x1 + 0.5, text
        assert box.y0 >= figure_box.y0 - 0.5 and box.y1 <= figure_box.y1 + 0.5, text
    legend = fig.legends[0].get_window_extent(renderer)
    assert figure_box.x0 <= legend.x0 and legend.x1 <= figure_box.x1 + 0.5
    assert legend.y0 >= figure_box.y0 and legend.y1 <= figure_box.y1 + 0.5
    assert legend.x0 >= ax.get_tightbbox(renderer).x1  # beside the axes, not over them
