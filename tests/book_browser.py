"""Headless Chromium through Playwright: open pages of the built book and check what a reader sees.

Playwright (the Python package) drives the *system's* Chromium through ``executable_path``; its own
browser download is never used. Every request to the network is aborted, so a result never depends
on a CDN: only the book's own files count.

For each page, :func:`check_page` reports

* whether it loaded (navigation error, ``load`` event, a non-empty title and an ``<h1>``);
* every ``<img>``: loaded and decoded by the browser (``complete`` and ``naturalWidth > 0``), and
  its source whole on disk (a ``file:`` URL) or after decoding (a ``data:`` URI);
* every internal link (``href`` to a local file, with or without ``#anchor``): the target exists
  inside the book, and the anchor is an ``id`` (or ``name``) in the target page;
* local files the page asked for that failed to load (stylesheets, scripts, fonts, images);
* uncaught JavaScript exceptions (reported, not judged here).

:func:`player_states` finds the JavaScript players (matplotlib's ``to_jshtml``) on a page, and
:func:`move_player` moves one's slider the way a reader does.
"""

from __future__ import annotations

import base64
import binascii
import os
import shutil
import struct
import time
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlsplit
from urllib.request import url2pathname
from xml.etree import ElementTree

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
WINDOW = {"width": 1280, "height": 2000}


def find_chromium() -> str | None:
    """The system's Chromium: ``$CHROME_BIN``, else the first of :data:`CHROMIUM_NAMES` on PATH."""
    for name in (os.environ.get("CHROME_BIN", ""), *CHROMIUM_NAMES):
        if name:
            found = shutil.which(name)
            if found:
                return found
    return None


@contextmanager
def chromium(executable: str) -> Iterator[object]:
    """A headless Playwright ``Browser`` on the system's Chromium (offline: the network is refused)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=executable,
            headless=True,
            args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
        )
        try:
            yield browser
        finally:
            browser.close()


def new_page(browser: object) -> object:
    """A page at the window size whose requests to the network are aborted (offline reader)."""
    page = browser.new_page(viewport=WINDOW)  # type: ignore[attr-defined]
    page.route("http*://**", lambda route: route.abort())
    return page


# Runs in the page after the load event: load lazy images, wait until every image has settled
# (loaded or failed, 15 s at most), then describe images, links and anchors.
PAGE_JS = r"""
async () => {
  const imgs = [...document.images];
  for (const img of imgs) { if (img.loading === 'lazy') img.loading = 'eager'; }
  const settle = img => (img.complete ? Promise.resolve() : new Promise(res => {
    img.addEventListener('load', res, {once: true});
    img.addEventListener('error', res, {once: true});
  }));
  await Promise.race([Promise.all(imgs.map(settle)), new Promise(res => setTimeout(res, 15000))]);
  const ids = new Set([...document.querySelectorAll('[id]')].map(e => e.id));
  for (const a of document.querySelectorAll('a[name]')) ids.add(a.getAttribute('name'));
  return {
    readyState: document.readyState,
    title: document.title,
    h1: [...document.querySelectorAll('h1')].map(h => h.textContent.trim()),
    images: imgs.map(i => ({src: i.getAttribute('src') || '', url: i.currentSrc || i.src,
                            complete: i.complete, naturalWidth: i.naturalWidth,
                            naturalHeight: i.naturalHeight})),
    links: [...document.querySelectorAll('a[href]')].map(a => ({href: a.getAttribute('href'),
                                                               url: a.href})),
    ids: [...ids],
  };
}
"""


class _Anchors(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for key, value in attrs:
            if value is not None and (key == "id" or (key == "name" and tag == "a")):
                self.ids.add(value)


_ANCHOR_CACHE: dict[tuple[Path, float], set[str]] = {}


def anchors_of(path: Path) -> set[str]:
    """Every ``id`` (and ``<a name>``) in the HTML file ``path`` (cached per modification time)."""
    key = (path, path.stat().st_mtime)
    if key not in _ANCHOR_CACHE:
        parser = _Anchors()
        parser.feed(path.read_text(encoding="utf-8", errors="replace"))
        _ANCHOR_CACHE[key] = parser.ids
    return _ANCHOR_CACHE[key]


def file_url_path(url: str) -> Path:
    """The local path of a ``file:`` URL (fragment and query dropped, %-escapes decoded)."""
    return Path(url2pathname(unquote(urlsplit(url).path)))


def image_bytes_problem(data: bytes, kind: str) -> str | None:
    """Why image bytes are empty or cut short (``None`` if they look whole).

    A browser shows the top of a truncated PNG or JPEG with its full ``naturalWidth``, so the bytes
    are checked too: a PNG must have valid chunk CRCs up to ``IEND``, a JPEG must end with EOI, an
    SVG must be well-formed XML. Other formats only have to be non-empty.
    """
    if not data:
        return "is empty"
    if data.startswith(b"\x89PNG\r\n\x1a\n"):
        pos = 8
        while pos + 12 <= len(data):
            (length,) = struct.unpack(">I", data[pos : pos + 4])
            kind_ = data[pos + 4 : pos + 8]
            body = data[pos + 8 : pos + 8 + length]
            crc = data[pos + 8 + length : pos + 12 + length]
            if len(body) < length or len(crc) < 4 or struct.unpack(">I", crc)[0] != zlib.crc32(kind_ + body):
                return f"is a truncated or corrupted PNG (bad {kind_.decode(errors='replace')} chunk)"
            if kind_ == b"IEND":
                return None
            pos += 12 + length
        return "is a truncated PNG (no IEND chunk)"
    if data.startswith(b"\xff\xd8"):
        return None if data.rstrip(b"\x00").endswith(b"\xff\xd9") else "is a truncated JPEG (no EOI marker)"
    if kind == "svg" or data.lstrip()[:5] in (b"<?xml", b"<svg ", b"<svg>"):
        try:
            ElementTree.fromstring(data)
        except ElementTree.ParseError as exc:
            return f"is not well-formed SVG ({exc})"
    return None


def image_source_problem(src_url: str) -> str | None:
    """Why an image's source is missing, empty or cut short (``None`` if it is fine)."""
    if src_url.startswith("data:"):
        head, _, payload = src_url.partition(",")
        try:
            if ";base64" in head:
                data = base64.b64decode(payload, validate=False)
            else:
                data = unquote(payload).encode()
        except (binascii.Error, ValueError) as exc:
            return f"data: URI does not decode ({exc})"
        why = image_bytes_problem(data, "svg" if "svg" in head else "")
        return f"data: URI {why}" if why else None
    if src_url.startswith("file:"):
        path = file_url_path(src_url)
        if not path.is_file():
            return f"file {path} does not exist"
        why = image_bytes_problem(path.read_bytes(), path.suffix.lower().lstrip("."))
        return f"file {path} {why}" if why else None
    return None  # remote images are not fetched (offline) and not judged here


def _in_root(path: Path, root: Path) -> bool:
    try:
        path.resolve().relative_to(root.resolve())
    except ValueError:
        return False
    return True



@dataclass
class PageReport:
    """What one page looked like in the browser, and what was wrong with it."""

    path: Path
    title: str = ""
    images: list[dict] = field(default_factory=list)
    links: list[dict] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    js_exceptions: list[str] = field(default_factory=list)
    seconds: float = 0.0


def check_page(browser: object, page_path: Path, root: Path, timeout_s: float = 60.0) -> PageReport:
    """Load ``page_path`` (an HTML file under the book's ``root``) and check it (module docstring)."""
    t0 = time.monotonic()
    report = PageReport(page_path)
    page = new_page(browser)
    failed: list[str] = []
    page.on("requestfailed", lambda req: failed.append(f"{req.url} ({req.failure})"))
    page.on("pageerror", lambda exc: report.js_exceptions.append(str(exc).splitlines()[0]))
    try:
        try:
            page.goto(page_path.resolve().as_uri(), wait_until="load", timeout=timeout_s * 1000)
        except Exception as exc:  # playwright's TimeoutError or a navigation error
            report.problems.append(f"navigation failed: {str(exc).splitlines()[0]}")
            return report
        info = page.evaluate(PAGE_JS)
        report.title, report.images, report.links = info["title"], info["images"], info["links"]
        if info["readyState"] != "complete":
            report.problems.append(f"document.readyState is {info['readyState']!r} after the load event")
        if not info["title"].strip() or not info["h1"]:
            report.problems.append(f"page has no title or no <h1> (title {info['title']!r})")
        _check_images(report)
        _check_links(report, page_path, root, set(info["ids"]))
        report.problems += [f"local file failed to load: {f}" for f in failed if f.startswith("file:")]
        report.problems = list(dict.fromkeys(report.problems))  # a link repeated in the page: once
    finally:
        page.close()
        report.seconds = time.monotonic() - t0
    return report


def _check_images(report: PageReport) -> None:
    for img in report.images:
        name = img["src"] if not img["src"].startswith("data:") else img["src"][:40] + "..."
        why = image_source_problem(img["url"])
        if not img["complete"] or img["naturalWidth"] <= 0 or img["naturalHeight"] <= 0:
            report.problems.append(
                f"image {name} did not load or decode (complete={img['complete']}, "
                f"naturalWidth={img['naturalWidth']})" + (f": {why}" if why else "")
            )
        elif why:
            report.problems.append(f"image {name}: {why}")


def _check_links(report: PageReport, page: Path, root: Path, own_ids: set[str]) -> None:
    for link in report.links:
        url, href = link["url"], link["href"]
        if not url.startswith("file:"):
            continue  # http(s), mailto, javascript: not internal
        base, frag = urldefrag(url)
        target = file_url_path(base)
        frag = unquote(frag)
        if target.resolve() == page.resolve():
            if frag and frag not in own_ids:
                report.problems.append(f"link {href!r}: no element with id {frag!r} on this page")
            continue
        if not _in_root(target, root):
            report.problems.append(f"link {href!r} leaves the book ({target})")
            continue
        if target.is_dir():
            target = target / "index.html"
        if not target.is_file():
            report.problems.append(f"link {href!r}: {target.relative_to(root.resolve())} does not exist")
            continue
        if frag and target.suffix == ".html" and frag not in anchors_of(target):
            report.problems.append(
                f"link {href!r}: no element with id {frag!r} in {target.relative_to(root.resolve())}"
            )


def landing_url(browser: object, start: Path, want: Path, timeout_s: float = 20.0) -> str:
    """Open ``start`` (e.g. a redirecting ``index.html``) and return the URL it settles on."""
    page = new_page(browser)
    want_url = want.resolve().as_uri()
    try:
        page.goto(start.resolve().as_uri(), wait_until="load", timeout=timeout_s * 1000)
        try:
            page.wait_for_url(lambda url: urldefrag(url)[0] == want_url, timeout=timeout_s * 1000)
        except Exception:  # playwright's TimeoutError: report where it stopped instead
            pass
        return urldefrag(page.url)[0]
    finally:
        page.close()


def screenshot(page: object, out: Path) -> tuple[int, int]:
    """Save a PNG of ``page``'s viewport to ``out`` (atomically); return its size."""
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp.png")
    page.screenshot(path=str(tmp))  # type: ignore[attr-defined]
    os.replace(tmp, out)
    return png_size(out)


# --- matplotlib's JavaScript players (Animation.to_jshtml) --------------------------------------
PLAYERS_JS = r"""
() => [...document.querySelectorAll('div.animation')].map(div => {
  const slider = div.querySelector('input[type=range]');
  const img = div.querySelector('img');
  return {id: slider ? slider.id : null, frames: slider ? Number(slider.max) + 1 : 0,
          value: slider ? Number(slider.value) : null, src: img ? img.src : '',
          width: img ? img.naturalWidth : 0};
})
"""


def player_states(page: object) -> list[dict]:
    """Every ``to_jshtml`` player on ``page``: slider id, frame count, value, shown image's source."""
    return page.evaluate(PLAYERS_JS)  # type: ignore[attr-defined]


def move_player(page: object, slider_id: str, frame: int) -> None:
    """Drag a player's slider to ``frame`` as a reader would (keyboard on the focused slider)."""
    slider = page.locator(f"#{slider_id}")  # type: ignore[attr-defined]
    slider.scroll_into_view_if_needed()
    slider.focus()
    slider.press("Home")
    for _ in range(frame):
        slider.press("ArrowRight")


def png_size(path: Path) -> tuple[int, int]:
    """``(width, height)`` of a PNG file; ``ValueError`` if it is not one."""
    head = path.read_bytes()[:24]
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{path} is not a PNG file")
    return struct.unpack(">II", head[16:24])
