"""``supercoil view``: one self-contained HTML page, tested in a real headless browser.

The browser is Debian's chromium. When it is missing, the ``browser`` fixture
installs it with apt-get (CI runs as root); the browser tests are skipped
only where that is impossible (not root, no apt-get), and never under CI.
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from plot_results import write_ring_result, write_tweezers_result

from supercoil.cli.main import run
from supercoil.plotting import style

WINDOW = (1400, 640)
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "chrome")


def _find_browser() -> str | None:
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def _install_chromium() -> str:
    """Install Debian's chromium (and a font); return why not when impossible."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return "not root, so apt-get cannot install chromium"
    if shutil.which("apt-get") is None:
        return "no apt-get on this machine"
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    steps = (["apt-get", "update", "-qq"],
             ["apt-get", "install", "-y", "-qq", "--no-install-recommends", "chromium",
              "fonts-dejavu-core"])
    for cmd in steps:
        try:
            done = subprocess.run(cmd, check=False, capture_output=True, text=True,
                                  env=env, timeout=900)
        except (OSError, subprocess.TimeoutExpired) as exc:
            return f"{' '.join(cmd[:2])} failed: {exc}"
        if done.returncode != 0:
            return f"{' '.join(cmd[:2])} failed: {done.stderr.strip()[-300:]}"
    return ""


@pytest.fixture(scope="module")
def browser() -> str:
    path = _find_browser()
    why = ""
    if path is None:
        why = _install_chromium()
        path = _find_browser()
    if path is None:
        message = f"no headless chromium and it cannot be installed here: {why}"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path


def _chromium(browser: str, profile: Path, url: str, *args: str) -> subprocess.CompletedProcess:
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
           "--disable-extensions", "--hide-scrollbars", f"--user-data-dir={profile}",
           f"--window-size={WINDOW[0]},{WINDOW[1]}", "--enable-logging=stderr", "--v=0",
           *args, url]
    done = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]
    return done


def _console_lines(stderr: str) -> list[str]:
    """Every message the page wrote to the console, and uncaught exceptions."""
    return [line for line in stderr.splitlines() if "CONSOLE" in line or "Uncaught" in line]


@pytest.fixture(scope="module")
def page(tmp_path_factory) -> Path:
    folder = write_ring_result(tmp_path_factory.mktemp("viewer") / "ring")
    assert run(["view", str(folder), "--out", str(folder / "page.html")]) == 0
    return folder / "page.html"


def _payload(page: Path) -> dict:
    text = page.read_text(encoding="utf-8")
    block = re.search(r'<script id="result-data" type="application/json">(.*?)</script>',
                      text, re.DOTALL)
    return json.loads(block.group(1))


# ----------------------------------------------------------------- the file


def test_page_is_one_offline_file(page):
    text = page.read_text(encoding="utf-8")
    # nothing is fetched: no external scripts, styles, images or fonts
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)
    assert not re.search(r"url\(\s*['\"]?(https?:)?//", text)
    assert "<script src" not in text and "<link" not in text
    assert text.count("</script>") == 3  # the error hook, the data, the page


def test_page_holds_the_result_as_stored(page):
    import supercoil

    data = _payload(page)
    stored = json.loads((page.parent / "diagram.json").read_text(encoding="utf-8"))
    assert [b["name"] for b in data["branches"]] == ["circle", "loop_contact"]
    assert data["diameter"] == stored["diameter"]
    for b in data["branches"]:
        rows = [p for p in stored["points"] if p["branch"] == b["name"]]
        assert b["points"] == rows  # numbers exactly as stored
        states = supercoil.load(page.parent).branch(b["name"]).states
        assert np.max(np.abs(np.array(b["states"]) - states)) <= 0.5e-5 + 1e-12
    assert {s["kind"] for s in data["special_points"]} == {"bifurcation", "fold"}
    assert data["style"]["branch_colors"] == list(style.BRANCH_COLORS)
    # the test's click target is a point of another branch than the start
    assert data["start"]["click"]["branch"] != data["start"]["branch"]


def test_tweezers_page_has_the_hat_curve(tmp_path):
    folder = write_tweezers_result(tmp_path / "tw")
    assert run(["view", str(folder)]) == 0
    data = _payload(folder / "viewer.html")
    assert (data["axes"]["x"], data["axes"]["y"]) == ("turns", "extension")
    assert data["branches"][0]["states"] is None
    assert [p["turns"] for p in data["branches"][0]["points"]] == list(np.linspace(-6, 6, 13))


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: ")
    return err


def test_bad_input_is_one_line_and_exit_2(page, tmp_path, capsys):
    folder = page.parent
    before = page.read_bytes()
    assert run(["view", str(folder), "--out", str(page)]) == 2
    assert "file exists" in _error(capsys)
    assert page.read_bytes() == before
    assert run(["view", str(folder), "--out", str(tmp_path / "page.png")]) == 2
    assert "ending in .html" in _error(capsys)
    assert run(["view", str(tmp_path / "nothing"), "--out", str(tmp_path / "a.html")]) == 2
    assert "no such file or folder" in _error(capsys)
    assert run(["view", str(folder), "--out", str(tmp_path / "no" / "a.html")]) == 2
    assert "does not exist" in _error(capsys)
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "diagram.json").write_text('{"points": [{"branch": "x", "excess_link": 1}]}',
                                         encoding="utf-8")
    assert run(["view", str(broken)]) == 2
    assert "point 0 lacks writhe" in _error(capsys)
    assert not (broken / "viewer.html").exists()
    assert run(["view", str(folder), "--out", str(page), "--overwrite"]) == 0


# -------------------------------------------------------------- the browser


def _dom(browser, tmp_path, url):
    done = _chromium(browser, tmp_path / "profile", url, "--dump-dom")
    return done.stdout, done.stderr


def _pre(dom: str, name: str) -> str:
    match = re.search(rf'<pre id="{name}">(.*?)</pre>', dom, re.DOTALL)
    assert match, f"no #{name} in the page"
    return html.unescape(match.group(1))


def test_moving_along_the_branch_in_a_browser(browser, page, tmp_path):
    """The page's own autotest moves the slider to three points, clicks the diagram
    and drags the tube, recording after each what the table shows and a hash of
    each canvas."""
    data = _payload(page)
    dom, stderr = _dom(browser, tmp_path, page.as_uri() + "#autotest")
    assert _pre(dom, "errors") == ""
    assert _console_lines(stderr) == []
    steps = json.loads(_pre(dom, "autotest"))["steps"]
    assert [s["what"] for s in steps][:4] == ["start", "slider 0", "slider 4", "slider 8"]
    start = data["start"]
    assert (steps[0]["branch"], steps[0]["index"]) == ("loop_contact", start["index"])
    for s in steps:  # the table shows the selected point's number
        assert s["shown"] == s["expected"]
        branch = next(b for b in data["branches"] if b["name"] == s["branch"])
        assert float(s["shown"]) == pytest.approx(branch["points"][s["index"]]["excess_link"],
                                                  abs=6e-6)
    slider = steps[1:4]
    assert [s["index"] for s in slider] == [0, 4, 8]
    assert len({s["tube"] for s in slider}) == 3  # each state draws another tube
    assert len({s["diagram"] for s in slider}) == 3  # and moves the marker
    click = steps[4]
    target = start["click"]
    assert (click["branch"], click["index"]) == (data["branches"][target["branch"]]["name"],
                                                 target["index"])
    drag = steps[5]
    assert drag["tube"] != click["tube"]  # the tube turned
    assert (drag["diagram"], drag["shown"]) == (click["diagram"], click["shown"])


def _screenshot(browser, tmp_path, url, name):
    from matplotlib.image import imread

    path = tmp_path / f"{name}.png"
    done = _chromium(browser, tmp_path / f"profile-{name}", url, f"--screenshot={path}")
    assert _console_lines(done.stderr) == []
    return imread(path)[:, :, :3] * 255.0


def _box(mask):
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return cols.min(), rows.min(), cols.max(), rows.max()


def test_screenshots_show_the_selected_state(browser, page, tmp_path):
    dom, _ = _dom(browser, tmp_path, page.as_uri())
    tube = [int(v) for v in re.search(r'data-tube-rect="([\d,]+)"', dom).group(1).split(",")]
    diagram = [int(v) for v in
               re.search(r'data-diagram-rect="([\d,]+)"', dom).group(1).split(",")]
    assert diagram[2] <= tube[0]  # side by side: the diagram left, the tube right
    touching = _screenshot(browser, tmp_path, page.as_uri() + "#branch=loop_contact&point=0",
                           "touching")
    circle = _screenshot(browser, tmp_path, page.as_uri() + "#branch=circle&point=0", "circle")
    assert touching.shape == circle.shape == (WINDOW[1], WINDOW[0], 3)
    r, g, b = touching[..., 0], touching[..., 1], touching[..., 2]
    red = (r > 80) & (r > 4 * np.maximum(g, b))  # the contact colour, shaded
    assert red.sum() > 30
    x0, y0, x1, y1 = _box(red)
    assert tube[0] <= x0 and x1 <= tube[2] and tube[1] <= y0 and y1 <= tube[3]
    r, g, b = circle[..., 0], circle[..., 1], circle[..., 2]
    assert not ((r > 80) & (r > 4 * np.maximum(g, b))).any()  # a circle has no contacts
    # the circle's tube: bluish pixels inside the tube canvas, centred in it
    blue = (b > r + 40) & (b > 100)
    inside = np.zeros_like(blue)
    inside[tube[1]:tube[3], tube[0]:tube[2]] = True
    x0, y0, x1, y1 = _box(blue & inside)
    centre = ((tube[0] + tube[2]) / 2, (tube[1] + tube[3]) / 2)
    assert abs((x0 + x1) / 2 - centre[0]) < 30 and abs((y0 + y1) / 2 - centre[1]) < 40
    changed = np.any(np.abs(touching - circle) > 10, axis=2)
    assert changed[tube[1]:tube[3], tube[0]:tube[2]].mean() > 0.02  # another tube
    assert changed[diagram[1]:diagram[3], diagram[0]:diagram[2]].any()  # marker moved


def test_tweezers_page_shows_the_open_rod(tmp_path):
    import supercoil

    folder = write_tweezers_result(tmp_path / "tw", with_states=True)
    assert run(["view", str(folder)]) == 0
    data = _payload(folder / "viewer.html")
    assert data["closed"] is False and data["diameter"] == 0.025
    (branch,) = data["branches"]
    stored = supercoil.load(folder).branch("plectoneme").states
    assert np.max(np.abs(np.array(branch["states"]) - stored)) <= 0.5e-5 + 1e-12


def test_drawn_line_is_stable_up_to_the_located_bifurcation(tmp_path):
    """The page's line (not the selectable points) holds the located special point twice,
    stable before it and unstable after, as the PNG figures do."""
    folder = write_ring_result(tmp_path / "ring")
    stored = json.loads((folder / "diagram.json").read_text(encoding="utf-8"))
    stored["special_points"][0].update(excess_link=1.8, index=3, count_before=0,
                                       count_after=2)
    (folder / "diagram.json").write_text(json.dumps(stored), encoding="utf-8")
    assert run(["view", str(folder / "diagram.json"), "--out", str(tmp_path / "page.html")]) == 0
    circle = _payload(tmp_path / "page.html")["branches"][0]
    line = circle["line"]
    assert len(circle["points"]) == 7 and len(line["y"]) == 9
    stable_y = [y for y, s in zip(line["y"], line["stable"], strict=True) if s]
    assert max(stable_y) == 1.8  # the last stable sample is at 1.5
    i = line["y"].index(1.8)
    assert line["stable"][i] and not line["stable"][i + 1] and line["y"][i + 1] == 1.8
