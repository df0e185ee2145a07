"""The built book in a real browser: every chapter loads, every figure shows, no internal link is broken.

The book is built here, in the quick profile, with the Makefile's flags (``-W -n --keep-going``),
into ``_build/browser-test/`` (never into ``_build/html``, which ``make book`` owns). In ``make test``
nothing is executed twice: nbval has just run every chapter in the book's mode and kept its outputs
(``--keep-executed``, ``tests/executed_book.py``), and when every chapter has a fresh execution the
book is built from them with execution off. Otherwise (this file run alone, a chapter that failed
under nbval) it executes the chapters itself with ``HUSKY_STATIC_WIDGETS=1``, as ``make book`` does;
``--all`` re-renders every page on every run, so the pages checked are never left over from an
earlier build; only notebook *executions* are reused, from jupyter-book's cache, and that cache is
wiped whenever the library, the requirements or the build config change (``library.sha256``).

Then every page of ``_toc.yml`` is opened in headless Chromium (driven by Playwright through the
system browser's executable path, offline: see ``tests/book_browser.py``) and checked: it loads,
every ``<img>`` is decoded by the browser from a whole, non-empty file, every internal link (and
anchor) resolves, and no local file it asks for fails. The JavaScript players (the book's form of
the live widgets) are scrubbed: a slider moved, the frame shown must change. Screenshots (the
planner chapter; a player before and after its slider moved) go to ``_build/screenshots/``, and
each chapter's HTML size is printed and bounded.

Without Chromium the tests skip, saying so, except under ``CI=true``, where they fail
(``.ci/run`` installs it).
"""

from __future__ import annotations

import base64
import os
import re
import shutil
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import pytest
import yaml
from book_browser import (
    CHROMIUM_NAMES,
    check_page,
    chromium,
    find_chromium,
    landing_url,
    move_player,
    new_page,
    player_states,
    png_size,
    screenshot,
)
from executed_book import build_fingerprint, fresh_executions, stage_book

REPO = Path(__file__).resolve().parents[1]
BUILD_FLAGS = ("-W", "-n", "--keep-going")  # the Makefile's `book` target
OUT = REPO / "_build" / "browser-test"  # --path-output: the HTML lands in OUT/_build/html
HTML = OUT / "_build" / "html"
STAMP = OUT / "library.sha256"
SCREENSHOTS = REPO / "_build" / "screenshots"
SOURCE_SUFFIXES = (".ipynb", ".md", ".myst", ".rst")
BUILD_TIMEOUT_S = 1500  # a cold build trains the quick models; a warm one takes seconds
PAGE_MB_LIMIT = 8.0  # a chapter page (players embed their frames) an offline reader downloads


def require_chromium() -> str:
    """The browser's path; skip (or fail under ``CI=true``) when there is none."""
    chrome = find_chromium()
    if chrome is None:
        reason = (
            f"no Chromium found (looked for $CHROME_BIN, {', '.join(CHROMIUM_NAMES)}); "
            "install it with `apt-get install chromium` to run the browser test of the book"
        )
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true: {reason}", pytrace=False)
        pytest.skip(reason)
    return chrome


# --- the table of contents -------------------------------------------------------------------
def toc_files(toc: dict) -> list[str]:
    """Every ``file`` of a jb-book ``_toc.yml`` in reading order (root first, parts and sections)."""
    files = [toc["root"]]

    def walk(entries: list | None) -> None:
        for entry in entries or []:
            if "file" in entry:
                files.append(entry["file"])
            walk(entry.get("sections"))

    walk(toc.get("chapters"))
    for part in toc.get("parts") or []:
        walk(part.get("chapters"))
    return files


def source_of(entry: str) -> Path:
    """The source file of a toc entry (``notebooks/01_environment`` -> ``.ipynb``)."""
    path = REPO / entry
    if path.suffix in SOURCE_SUFFIXES and path.is_file():
        return path
    for suffix in SOURCE_SUFFIXES:
        if path.with_name(path.name + suffix).is_file():
            return path.with_name(path.name + suffix)
    raise FileNotFoundError(f"_toc.yml names {entry!r}, which has no source file")


def html_of(entry: str) -> Path:
    """Where the built page of a toc entry lives."""
    path = Path(entry)
    if path.suffix in SOURCE_SUFFIXES:
        path = path.with_suffix("")
    return HTML / f"{path}.html"


def draws_figures(source: Path) -> bool:
    """Whether a notebook's code plots (then its page must show at least one image)."""
    if source.suffix != ".ipynb":
        return False
    import nbformat

    nb = nbformat.read(source, as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    return any(word in code for word in ("plt.", "plotting.", "imshow", ".plot("))


def planner_entry(entries: list[str]) -> str:
    """The page to photograph: the planner chapter (``07_planner``), else the last chapter."""
    named = [e for e in entries if "07_planner" in e]
    return named[0] if named else entries[-1]


# --- the build ---------------------------------------------------------------------------------
def jupyter_book() -> str:
    exe = Path(sys.executable).parent / "jupyter-book"
    found = str(exe) if exe.is_file() else shutil.which("jupyter-book")
    if not found:
        pytest.fail("jupyter-book is not installed (run `make install`)", pytrace=False)
    return found


@pytest.fixture(scope="module")
def book() -> dict:
    """Build the quick-profile book (see the module docstring); return its pages and build time."""
    require_chromium()  # no browser, no point in building
    toc = yaml.safe_load((REPO / "_toc.yml").read_text())
    entries = toc_files(toc)
    sources = {entry: source_of(entry) for entry in entries}

    fingerprint = build_fingerprint()
    if not STAMP.is_file() or STAMP.read_text() != fingerprint:
        shutil.rmtree(OUT, ignore_errors=True)  # library changed: cached executions are stale
    OUT.mkdir(parents=True, exist_ok=True)
    STAMP.write_text(fingerprint)  # the cache holds only executions made under this fingerprint
    env = {**os.environ, "HUSKY_PROFILE": "quick", "HUSKY_STATIC_WIDGETS": "1"}  # as `make book`
    env.pop("MPLBACKEND", None)  # as in the Makefile: kernels need the inline backend
    notebooks = [s for s in sources.values() if s.suffix == ".ipynb"]
    executions = fresh_executions(notebooks)
    source_dir = stage_book(OUT / "source", executions) if executions else REPO
    print("book source:", f"nbval's runs of {len(executions)} chapters" if executions else "executed here")
    cmd = [jupyter_book(), "build", str(source_dir), "--path-output", str(OUT), "--all", *BUILD_FLAGS]
    started = time.time()
    proc = subprocess.run(
        cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S, check=False
    )
    seconds = time.time() - started
    if proc.returncode != 0:
        log = re.sub(r"\x1b\[[0-9;]*m", "", proc.stdout + proc.stderr)
        flagged = [
            line
            for line in log.splitlines()
            if re.search(r"WARNING|ERROR|Error|Traceback", line) and "IPKernelApp" not in line
        ]
        pytest.fail(
            f"`{' '.join(cmd)}` failed ({proc.returncode}):\n"
            + "\n".join(flagged[-40:])
            + "\n--- end of the build log ---\n"
            + log[-3000:],
            pytrace=False,
        )

    pages = {}
    for entry in entries:
        page = html_of(entry)
        assert page.is_file(), f"the build made no page for {entry} (expected {page})"
        # --all rewrites every page; one older than this build would be a leftover, not this book
        assert page.stat().st_mtime >= started - 1, f"{page} was not written by this build"
        assert sources[entry].stat().st_mtime <= page.stat().st_mtime + 1, (
            f"{sources[entry]} changed while the book was being built; run the test again"
        )
        pages[entry] = page
    return {"entries": entries, "pages": pages, "sources": sources, "seconds": seconds,
            "reused": executions is not None}


@pytest.fixture(scope="module")
def browser():
    chrome = require_chromium()
    with chromium(chrome) as b:
        yield b


def tiny_png() -> bytes:
    """A valid 1 x 1 grey PNG (standard library only)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(b"\x00\x80"))
        + chunk(b"IEND", b"")
    )


# --- the tests -------------------------------------------------------------------------------
def test_checker_catches_broken_pages(browser, tmp_path):
    """The checks are not vacuous: a page with a broken image, link and anchor is reported."""
    root = tmp_path / "site"
    root.mkdir()
    pixel = tiny_png()
    (root / "ok.png").write_bytes(pixel)
    (root / "empty.png").write_bytes(b"")
    (root / "cut.png").write_bytes(pixel[:-12])  # no IEND: a browser may still show it
    (root / "other.html").write_text(
        "<html><head><title>o</title></head><body><h1 id='here'>o</h1></body></html>"
    )
    (root / "page.html").write_text(
        "<html><head><title>t</title></head><body><h1 id='top'>t</h1>"
        "<img src='ok.png'><img src='data:image/png;base64," + base64.b64encode(pixel).decode() + "'>"
        "<img src='empty.png'><img src='missing.png'><img src='cut.png'>"
        "<a href='other.html'>1</a><a href='other.html#here'>2</a><a href='#top'>3</a>"
        "<a href='https://example.org/x.html'>ext</a>"
        "<a href='gone.html'>4</a><a href='other.html#nowhere'>5</a><a href='#lost'>6</a>"
        "</body></html>"
    )
    report = check_page(browser, root / "page.html", root)
    problems = "\n".join(report.problems)
    assert len(report.images) == 5 and len(report.links) == 7
    assert "empty.png did not load or decode (complete=True, naturalWidth=0): file" in problems
    assert "missing.png did not load" in problems and "missing.png (net::ERR_FILE_NOT_FOUND)" in problems
    assert "cut.png: file" in problems and "truncated PNG (no IEND chunk)" in problems
    assert "ok.png" not in problems and "data:" not in problems
    assert "'gone.html'" in problems and "'other.html#nowhere'" in problems and "'#lost'" in problems
    assert "'other.html'" not in problems and "#here" not in problems and "'#top'" not in problems
    assert "example.org" not in problems
    assert len(report.problems) == 7, problems


def test_every_chapter_renders_in_chromium(book, browser):
    """Every page of the toc loads; images decode; internal links and anchors resolve."""
    failures, lines = [], []
    for entry in book["entries"]:
        report = check_page(browser, book["pages"][entry], HTML)
        if draws_figures(book["sources"][entry]) and not report.images:
            report.problems.append("the notebook plots, but its page shows no image (figures lost?)")
        lines.append(
            f"{entry}: {len(report.images)} images, {len(report.links)} links, {report.seconds:.1f} s"
            + "".join(
                f"\n    JS exception (reported, not judged): {e}" for e in sorted(set(report.js_exceptions))
            )
        )
        failures += [f"{entry}: {p}" for p in report.problems]
    print(f"Chromium {browser.version}; book built in {book['seconds']:.1f} s\n" + "\n".join(lines))
    assert not failures, "\n".join(failures)


def unrendered_output(page_html: str) -> list[str]:
    """What an offline reader of a built page would see broken or raw.

    * a widget view (``application/vnd.jupyter.widget-view+json``): it needs the CDN's JavaScript,
      so offline it is an empty box (a progress bar left as a widget, a widget without its static
      figure);
    * a Markdown table left as text: a paragraph of ``| a | b |`` lines with a ``|---|`` rule.
    """
    found = []
    views = page_html.count("application/vnd.jupyter.widget-view+json")
    if views:
        found.append(f"{views} widget view(s), empty without the widgets' JavaScript")
    for para in re.findall(r"<p>(.*?)</p>", page_html, flags=re.S):
        text = re.sub(r"<[^>]+>", "", para)
        if text.lstrip().startswith("|") and re.search(r"\|\s*(-{3}|—)", text):
            found.append(f"a Markdown table shown as text: {text.strip()[:80]!r}")
    return found


def test_unrendered_output_is_detected():
    raw = (
        "<p>| a | b |\n|—|—|\n| 1 | 2 |</p>"
        '<script type="application/vnd.jupyter.widget-view+json">{}</script>'
    )
    assert len(unrendered_output(raw)) == 2
    assert unrendered_output("<table><tr><td>| a |</td></tr></table><p>a | b</p>") == []


def test_no_page_shows_raw_tables_or_empty_widgets(book):
    """Every displayed table is a real table and no widget is left without its static figure."""
    problems = [
        f"{entry}: {p}"
        for entry in book["entries"]
        for p in unrendered_output(book["pages"][entry].read_text())
    ]
    assert not problems, "\n".join(problems)
    tables = sum(book["pages"][e].read_text().count("<table") for e in book["entries"])
    assert tables >= 10, f"only {tables} tables in the whole book: are displayed tables rendered?"


def test_index_leads_to_the_first_page(book, browser):
    """``_build/html/index.html`` (the path `make book` prints) lands on the root page of the toc."""
    root_page = book["pages"][book["entries"][0]]
    url = landing_url(browser, HTML / "index.html", root_page)
    assert url == root_page.resolve().as_uri(), f"index.html ends on {url}, not {root_page}"


def test_screenshot_of_the_planner_chapter(book, browser):
    entry = planner_entry(book["entries"][1:] or book["entries"])
    out = SCREENSHOTS / f"{Path(entry).name}.png"
    out.unlink(missing_ok=True)
    page = new_page(browser)
    try:
        page.goto(book["pages"][entry].resolve().as_uri(), wait_until="load")
        width, height = screenshot(page, out)
    finally:
        page.close()
    assert (width, height) == (1280, 2000)
    assert png_size(out) == (1280, 2000) and out.stat().st_size > 10_000, "a blank or broken screenshot"
    print(f"screenshot of {entry}: {out}")


def test_page_sizes(book):
    """Each chapter's HTML (players included) stays light enough to open offline on a laptop."""
    sizes = {entry: book["pages"][entry].stat().st_size / 1e6 for entry in book["entries"]}
    print("\n".join(f"{entry}: {mb:.2f} MB" for entry, mb in sizes.items()))
    heavy = {e: round(mb, 2) for e, mb in sizes.items() if mb > PAGE_MB_LIMIT}
    assert not heavy, f"pages over {PAGE_MB_LIMIT} MB: {heavy}"


def test_players_scrub_offline(book, browser):
    """Every JavaScript player in the book: moving its slider changes the frame it shows.

    The pages are opened as an offline reader has them (network refused, no kernel). The first
    player of the book is photographed before and after (``_build/screenshots/player-*.png``).
    """
    found, failures, photographed = 0, [], False
    for entry in book["entries"]:
        page = new_page(browser)
        try:
            page.goto(book["pages"][entry].resolve().as_uri(), wait_until="load")
            for player in player_states(page):
                found += 1
                if player["frames"] < 2:
                    failures.append(f"{entry}: player {player['id']} has {player['frames']} frame(s)")
                    continue
                if not player["src"].startswith("data:image/png") or player["width"] <= 0:
                    failures.append(f"{entry}: player {player['id']} shows no decoded image")
                    continue
                target = min(player["frames"] - 1, 2)
                if not photographed:
                    page.locator(f"#{player['id']}").scroll_into_view_if_needed()
                    screenshot(page, SCREENSHOTS / "player-before.png")
                move_player(page, player["id"], target)
                after = next(p for p in player_states(page) if p["id"] == player["id"])
                if after["value"] != target or after["src"] == player["src"]:
                    failures.append(
                        f"{entry}: player {player['id']}: slider at {after['value']} (wanted {target}), "
                        f"frame {'unchanged' if after['src'] == player['src'] else 'changed'}"
                    )
                elif not photographed:
                    screenshot(page, SCREENSHOTS / "player-after.png")
                    photographed = True
        finally:
            page.close()
    print(f"{found} players checked; screenshots in {SCREENSHOTS}")
    assert found >= 4, f"only {found} JavaScript players in the book (expected the explorers and the map)"
    assert not failures, "\n".join(failures)
