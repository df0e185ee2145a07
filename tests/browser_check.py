"""Open pages of a built HTML book in headless Chromium and check what a reader would see.

Standard library only: Chromium is driven over the DevTools protocol on a pipe
(``--remote-debugging-pipe``: NUL-terminated JSON on file descriptors 3 and 4), so no websocket
package is needed. Every request to the network is refused (``--host-resolver-rules``), so the
result never depends on a CDN; only the book's own files are checked.

For each page, :func:`check_page` reports

* whether it loaded (navigation error, ``load`` event, a non-empty title);
* every ``<img>``: loaded and decoded by the browser (``complete`` and ``naturalWidth > 0``), and
  its source non-empty on disk (a ``file:`` URL) or after decoding (a ``data:`` URI);
* every internal link (``href`` to a local file, with or without ``#anchor``): the target exists
  inside the book, and the anchor is an ``id`` (or ``name``) in the target page;
* local files the page asked for that failed to load (stylesheets, scripts, fonts, images);
* uncaught JavaScript exceptions (reported, not judged here).

Run it by hand on a built book::

    .venv/bin/python tests/browser_check.py _build/html [--screenshot notebooks/01_environment.html]
"""

from __future__ import annotations

import base64
import binascii
import fcntl
import json
import os
import queue
import shutil
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlsplit
from urllib.request import url2pathname
from xml.etree import ElementTree

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
CHROME_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-dev-shm-usage",  # containers often have a tiny /dev/shm
    "--host-resolver-rules=MAP * ~NOTFOUND",  # offline: only the book's own files count
    "--window-size=1280,2000",
    "--remote-debugging-pipe",
)
WINDOW = (1280, 2000)

# Runs in the page after the load event: load lazy images, wait until every image has settled
# (loaded or failed, 15 s at most), then describe images, links and anchors.
_PAGE_JS = r"""
(async () => {
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
})()
"""


def find_chromium() -> str | None:
    """Path of a Chromium-family browser: ``$CHROME_BIN``, else the first of :data:`CHROMIUM_NAMES`."""
    env = os.environ.get("CHROME_BIN")
    if env and shutil.which(env):
        return shutil.which(env)
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class BrowserError(RuntimeError):
    """Chromium failed to start, died, or answered a DevTools command with an error."""


# A tiny launcher: put our two pipe ends on fds 3 (commands in) and 4 (replies out), as
# --remote-debugging-pipe expects, then exec the browser (distribution wrappers are shell scripts
# that keep the descriptors open). Done in a child interpreter, not with a shell, because dash
# cannot redirect descriptors above 9.
_LAUNCH = (
    "import os, sys\n"
    "r, w = int(sys.argv[1]), int(sys.argv[2])\n"
    "os.dup2(r, 3); os.dup2(w, 4); os.close(r); os.close(w)\n"
    "os.execv(sys.argv[3], sys.argv[3:])\n"
)


def _high_fd(fd: int) -> int:
    """``fd`` moved to a number >= 10 (so that dup2 onto 3 and 4 can never clobber it)."""
    new = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
    os.close(fd)
    return new


class Browser:
    """A headless Chromium driven over the DevTools protocol on a pipe (use as a context manager)."""

    def __init__(self, executable: str, timeout: float = 60.0) -> None:
        self.executable = executable
        self.timeout = timeout
        self.profile = Path(tempfile.mkdtemp(prefix="chromium-profile-"))
        self.log_path = self.profile.parent / f"{self.profile.name}.log"
        self._next_id = 0
        self._messages: queue.Queue = queue.Queue()
        self._events: list[dict] = []
        self._lock = threading.Lock()
        cmd_r, cmd_w = os.pipe()
        out_r, out_w = os.pipe()
        cmd_r, out_w = _high_fd(cmd_r), _high_fd(out_w)
        args = [executable, *CHROME_FLAGS, f"--user-data-dir={self.profile}", "about:blank"]
        self._log = open(self.log_path, "wb")  # noqa: SIM115 - closed in close()
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-c", _LAUNCH, str(cmd_r), str(out_w), *args],
                pass_fds=(cmd_r, out_w),
                stdin=subprocess.DEVNULL,
                stdout=self._log,
                stderr=subprocess.STDOUT,
            )
        finally:
            os.close(cmd_r)
            os.close(out_w)
        self._out = os.fdopen(cmd_w, "wb", buffering=0)
        self._reader = threading.Thread(target=self._read, args=(out_r,), daemon=True)
        self._reader.start()
        try:
            self.version = self.send("Browser.getVersion", timeout=timeout)["product"]
        except BaseException:
            self.close()
            raise

    # --- protocol ---------------------------------------------------------------------------
    def _read(self, fd: int) -> None:
        buf = b""
        with os.fdopen(fd, "rb", buffering=0) as fh:
            while True:
                chunk = fh.read(1 << 16)
                if not chunk:
                    self._messages.put(None)
                    return
                buf += chunk
                *messages, buf = buf.split(b"\0")
                for raw in messages:
                    self._messages.put(json.loads(raw))

    def log_tail(self, chars: int = 3000) -> str:
        """The end of Chromium's own output (for error messages)."""
        try:
            return self.log_path.read_text(errors="replace")[-chars:]
        except OSError:
            return ""

    def _pump(self, deadline: float) -> dict:
        try:
            msg = self._messages.get(timeout=max(deadline - time.monotonic(), 0.001))
        except queue.Empty:
            raise TimeoutError from None
        if msg is None:
            raise BrowserError(f"Chromium exited (status {self.proc.poll()}):\n{self.log_tail()}")
        return msg

    def send(
        self,
        method: str,
        params: dict | None = None,
        session: str | None = None,
        timeout: float | None = None,
    ) -> dict:
        """Send one DevTools command and return its result (events seen meanwhile are kept)."""
        self._next_id += 1
        ident = self._next_id
        message = {"id": ident, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        try:
            self._out.write(json.dumps(message).encode() + b"\0")
        except BrokenPipeError:
            raise BrowserError(f"Chromium is gone (status {self.proc.poll()}):\n{self.log_tail()}") from None
        deadline = time.monotonic() + (timeout or self.timeout)
        while True:
            try:
                msg = self._pump(deadline)
            except TimeoutError:
                raise BrowserError(f"no answer to {method} within {timeout or self.timeout} s") from None
            if msg.get("id") == ident:
                if "error" in msg:
                    raise BrowserError(f"{method} failed: {msg['error']}")
                return msg.get("result", {})
            if "method" in msg:
                self._events.append(msg)

    def wait_event(
        self,
        method: str,
        session: str,
        timeout: float | None = None,
        where: Callable[[dict], bool] | None = None,
    ) -> dict | None:
        """Wait for event ``method`` of ``session`` (with ``where(params)`` true); ``None`` on timeout."""
        deadline = time.monotonic() + (timeout or self.timeout)
        seen = 0
        while True:
            for ev in self._events[seen:]:
                if (
                    ev.get("method") == method
                    and ev.get("sessionId") == session
                    and (where is None or where(ev.get("params", {})))
                ):
                    return ev
            seen = len(self._events)
            try:
                msg = self._pump(deadline)
            except TimeoutError:
                return None
            if "method" in msg:
                self._events.append(msg)

    def take_events(self, session: str) -> list[dict]:
        """Remove and return the events recorded for ``session``."""
        mine = [e for e in self._events if e.get("sessionId") == session]
        self._events = [e for e in self._events if e.get("sessionId") != session]
        return mine

    # --- lifetime -----------------------------------------------------------------------------
    def close(self) -> None:
        """Close the browser (politely, then by force) and delete its profile."""
        if self.proc.poll() is None:
            try:
                self._out.write(json.dumps({"id": 0, "method": "Browser.close"}).encode() + b"\0")
                self.proc.wait(timeout=10)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait(timeout=10)
        try:
            self._out.close()
        except OSError:
            pass
        self._log.close()
        shutil.rmtree(self.profile, ignore_errors=True)
        self.log_path.unlink(missing_ok=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# --- checks --------------------------------------------------------------------------------
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


def check_page(browser: Browser, page: Path, root: Path, timeout: float = 60.0) -> PageReport:
    """Load ``page`` (an HTML file under the book's ``root``) and check it (see the module docstring)."""
    t0 = time.monotonic()
    report = PageReport(page)
    target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    try:
        for domain in ("Page", "Network", "Runtime"):
            browser.send(f"{domain}.enable", session=session)
        browser.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": WINDOW[0], "height": WINDOW[1], "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        browser.take_events(session)  # forget about:blank; from here on, events are this page's
        nav = browser.send("Page.navigate", {"url": page.resolve().as_uri()}, session=session)
        if nav.get("errorText"):
            report.problems.append(f"navigation failed: {nav['errorText']}")
            return report
        if browser.wait_event("Page.loadEventFired", session, timeout) is None:
            report.problems.append(f"no load event within {timeout} s")
            return report
        result = browser.send(
            "Runtime.evaluate",
            {"expression": _PAGE_JS, "awaitPromise": True, "returnByValue": True},
            session=session,
            timeout=timeout,
        )
        if "exceptionDetails" in result:
            report.problems.append(f"page script failed: {result['exceptionDetails'].get('text')}")
            return report
        info = result["result"]["value"]
        report.title, report.images, report.links = info["title"], info["images"], info["links"]
        if info["readyState"] != "complete":
            report.problems.append(f"document.readyState is {info['readyState']!r} after the load event")
        if not info["title"].strip() or not info["h1"]:
            report.problems.append(f"page has no title or no <h1> (title {info['title']!r})")
        _check_images(report)
        _check_links(report, page, root, set(info["ids"]))
        _check_events(report, browser.take_events(session))
        report.problems = list(dict.fromkeys(report.problems))  # a link repeated in the page: once
    finally:
        browser.send("Target.closeTarget", {"targetId": target})
        browser.take_events(session)
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


def _check_events(report: PageReport, events: list[dict]) -> None:
    urls: dict[str, str] = {}
    for ev in events:
        params = ev.get("params", {})
        if ev["method"] == "Network.requestWillBeSent":
            urls[params["requestId"]] = params["request"]["url"]
        elif ev["method"] == "Network.loadingFailed":
            url = urls.get(params["requestId"], "?")
            if url.startswith("file:") and not params.get("canceled"):
                report.problems.append(f"local file failed to load: {url} ({params.get('errorText')})")
        elif ev["method"] == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            text = details.get("exception", {}).get("description") or details.get("text", "")
            report.js_exceptions.append(text.splitlines()[0] if text else "?")


def landing_url(browser: Browser, page: Path, want: Path, timeout: float = 20.0) -> str:
    """Open ``page`` (e.g. a redirecting ``index.html``) and return the URL it settles on.

    Waits until the main frame has navigated to ``want`` and loaded it, or ``timeout``.
    """
    target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    want_url = want.resolve().as_uri()
    try:
        browser.send("Page.enable", session=session)
        browser.take_events(session)
        browser.send("Page.navigate", {"url": page.resolve().as_uri()}, session=session)
        arrived = browser.wait_event(
            "Page.frameNavigated",
            session,
            timeout,
            where=lambda p: "parentId" not in p["frame"] and urldefrag(p["frame"]["url"])[0] == want_url,
        )
        navigated = [
            e["params"]["frame"]["url"]
            for e in browser.take_events(session)
            if e["method"] == "Page.frameNavigated" and "parentId" not in e["params"]["frame"]
        ]
        if arrived is None:
            return navigated[-1] if navigated else "about:blank"
        return urldefrag(arrived["params"]["frame"]["url"])[0]
    finally:
        browser.send("Target.closeTarget", {"targetId": target})
        browser.take_events(session)


def screenshot(browser: Browser, page: Path, out: Path, timeout: float = 60.0) -> tuple[int, int]:
    """Save a PNG of ``page`` at the window size (1280 x 2000) to ``out``; return its size."""
    target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    try:
        browser.send("Page.enable", session=session)
        browser.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": WINDOW[0], "height": WINDOW[1], "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        browser.take_events(session)
        browser.send("Page.navigate", {"url": page.resolve().as_uri()}, session=session)
        if browser.wait_event("Page.loadEventFired", session, timeout) is None:
            raise BrowserError(f"{page} did not load within {timeout} s")
        browser.send(
            "Runtime.evaluate",
            {"expression": _PAGE_JS, "awaitPromise": True, "returnByValue": True},
            session=session,
            timeout=timeout,
        )
        data = base64.b64decode(
            browser.send("Page.captureScreenshot", {"format": "png"}, session=session, timeout=timeout)[
                "data"
            ]
        )
    finally:
        browser.send("Target.closeTarget", {"targetId": target})
        browser.take_events(session)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, out)
    return png_size(out)


def png_size(path: Path) -> tuple[int, int]:
    """``(width, height)`` of a PNG file; ``ValueError`` if it is not one."""
    head = path.read_bytes()[:24]
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{path} is not a PNG file")
    return struct.unpack(">II", head[16:24])


def main(argv: list[str] | None = None) -> int:
    """Check every ``*.html`` page under a built book (by hand; the test checks the toc's pages)."""
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", type=Path, help="the built book, e.g. _build/html")
    parser.add_argument("--screenshot", help="page (relative to root) to save as _build/screenshots/*.png")
    args = parser.parse_args(argv)
    chrome = find_chromium()
    if chrome is None:
        print(f"no Chromium found (looked for $CHROME_BIN, {', '.join(CHROMIUM_NAMES)})", file=sys.stderr)
        return 2
    # the root index.html is a redirect (no content of its own): check where it leads instead
    pages = sorted(
        p for p in args.root.rglob("*.html") if "_static" not in p.parts and p != args.root / "index.html"
    )
    bad = 0
    with Browser(chrome) as browser:
        print(browser.version)
        for page in pages:
            report = check_page(browser, page, args.root)
            bad += bool(report.problems)
            status = "ok " if not report.problems else "BAD"
            print(
                f"{status} {page.relative_to(args.root)}: {len(report.images)} images, "
                f"{len(report.links)} links, {report.seconds:.1f} s"
            )
            for problem in report.problems:
                print(f"    {problem}")
            for exc in report.js_exceptions:
                print(f"    (JS exception) {exc}")
        if args.screenshot:
            out = Path("_build/screenshots") / (Path(args.screenshot).stem + ".png")
            print("screenshot", out, screenshot(browser, args.root / args.screenshot, out))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
