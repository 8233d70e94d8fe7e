"""The documentation: the site builds, its pages speak of the tool, its code runs.

Oracles: ``mkdocs build --strict`` exits 0 (no broken link, anchor or API
reference) and writes one page per entry of the nav, each carrying its own
title; no page, README or study file carries development history; the Python
of the README and of the docs' tour runs and satisfies Lk = Tw + Wr.
"""

from __future__ import annotations

import html
import importlib.util
import os
import re
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

import supercoil

ROOT = Path(__file__).resolve().parents[1]
HISTORY = re.compile(r"\bsessions?\b|\bissue [0-9]|seed 00[0-9]|\bseed (paper|problem)|DESIGN|"
                     r"\.\./shared", re.IGNORECASE)
PUBLIC_API = ("Rod", "Ring", "Barrier", "Tweezers", "equilibrium", "ring_diagram", "tweezers",
              "save", "load", "writhe", "linking_number")


def _nav_pages(nav) -> list[str]:
    """The markdown files named by mkdocs' ``nav`` (nested sections included)."""
    pages = []
    for entry in nav:
        value = next(iter(entry.values())) if isinstance(entry, dict) else entry
        if isinstance(value, list):
            pages += _nav_pages(value)
        else:
            pages.append(value)
    return pages


def _built_page(site: Path, page: str) -> Path:
    """Where mkdocs (directory URLs) writes ``page``: index.md -> index.html, x.md -> x/index.html."""
    stem = page[:-len(".md")]
    return site / "index.html" if stem == "index" else site / stem / "index.html"


def _title(markdown: Path) -> str:
    for line in markdown.read_text(encoding="utf-8").splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    raise AssertionError(f"{markdown} has no '# ' title")


@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None,
                    reason="mkdocs is not installed (pip install -e '.[docs]')")
def test_docs_build_strict_and_every_nav_page_is_written(tmp_path):
    import yaml  # installed with mkdocs

    config = ROOT / "mkdocs.yml"
    nav = yaml.safe_load(config.read_text(encoding="utf-8"))["nav"]
    pages = _nav_pages(nav)
    assert "index.md" in pages and "api.md" in pages and "references.md" in pages
    site = tmp_path / "site"
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1", PYTHONPATH=str(ROOT / "src"))
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config),
                          "-d", str(site)], capture_output=True, text=True, env=env, cwd=ROOT,
                         timeout=600, check=False)
    assert run.returncode == 0, run.stdout + run.stderr
    for page in pages:
        built = _built_page(site, page)
        assert built.is_file(), f"{page} was not written ({built})"
        text = html.unescape(re.sub(r"<[^>]+>", "", built.read_text(encoding="utf-8")))
        title = _title(ROOT / "docs" / page).replace("`", "")
        assert title in text, f"{page}: its title {title!r} is not in {built}"
    api = (_built_page(site, "api.md")).read_text(encoding="utf-8")
    assert "InputError" in api  # mkdocstrings rendered the docstrings


def _user_facing_files() -> list[Path]:
    files = [ROOT / "README.md", ROOT / "mkdocs.yml", ROOT / "benchmarks" / "README.md"]
    files += sorted((ROOT / "docs").glob("*.md"))
    files += sorted((ROOT / "benchmarks" / "results").glob("*.md"))
    files += sorted((ROOT / "examples").glob("*.toml"))
    files += sorted((ROOT / "examples").glob("*.py"))
    return files


@pytest.mark.parametrize("path", _user_facing_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_user_facing_text_has_no_development_history(path):
    hits = [f"{path.name}:{n}: {line.strip()}"
            for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
            if HISTORY.search(line)]
    assert not hits, "history words (the git log keeps history):\n" + "\n".join(hits)


def test_readme_is_short_and_keeps_the_two_command_quickstart():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150
    assert ("python3 -m venv .venv && . .venv/bin/activate && pip install -e . && supercoil demo"
            in text)
    assert ('python3 -m venv .venv && . .venv/bin/activate && pip install -e ".[test]" '
            "&& python -m pytest -q -n auto") in text
    assert "docs/img/diagram.png" in text and (ROOT / "docs" / "img" / "diagram.png").is_file()


def marked_python(path: Path, marker: str) -> str:
    """The Python code blocks of ``path`` between ``<!-- MARKER:start -->`` and
    ``<!-- MARKER:end -->``, joined in order."""
    text = path.read_text(encoding="utf-8")
    match = re.search(rf"<!-- {marker}:start -->(.*?)<!-- {marker}:end -->", text, re.DOTALL)
    assert match, f"{path.name} has no {marker} markers"
    blocks = re.findall(r"```python\n(.*?)```", match.group(1), re.DOTALL)
    assert blocks, f"{path.name}: no python block between the {marker} markers"
    return "\n".join(blocks)


@pytest.mark.parametrize("path, marker", [("README.md", "readme"), ("docs/index.md", "tour")])
def test_marked_snippets_parse(path, marker):
    compile(marked_python(ROOT / path, marker), path, "exec")


@pytest.mark.skipif(not all(hasattr(supercoil, name) for name in PUBLIC_API),
                    reason="the public API (supercoil.Rod, Ring, equilibrium, ...) is not exported")
@pytest.mark.parametrize("path, marker", [("README.md", "readme"), ("docs/index.md", "tour")])
def test_marked_snippets_run(path, marker, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the tour writes ring.h5
    script = tmp_path / f"{marker}.py"
    script.write_text(marked_python(ROOT / path, marker), encoding="utf-8")
    namespace = runpy.run_path(str(script))
    eq = namespace["eq"]
    assert abs(eq.twist + eq.writhe - 3) < 1e-8  # Lk = Tw + Wr, computed independently
    assert eq.unstable_count == 0 and abs(eq.writhe) > 0.5  # above Michell: supercoiled, stable
    assert len(namespace["alpha"]) > 0
