"""A chapter in JupyterLab, driven through its UI in headless Chromium: the live widget responds.

What a student does in class, automated: JupyterLab is started on a free localhost port (the
venv's kernel, the quick profile) over a *copy* of chapter 1 (JupyterLab autosaves, and the
committed notebook must stay without outputs); Playwright opens it, runs every cell from the
**Run** menu, moves the world explorer's slider (its value typed into the slider's readout, as a
keyboard user does), and checks the way ipywidgets' own UI tests check widgets: the figure's image
changes, and it is still *one* figure (redrawn in place, not a second one below).

Skips without Chromium, except under ``CI=true`` (``.ci/run`` installs it). Screenshots before and
after the slider moved go to ``_build/screenshots/jupyterlab-*.png``.
"""

from __future__ import annotations

import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.request import urlopen

import pytest
from book_browser import chromium, find_chromium, screenshot

REPO = Path(__file__).resolve().parents[1]
CHAPTER = "01_environment.ipynb"
SCREENSHOTS = REPO / "_build" / "screenshots"
START_TIMEOUT_S = 90
RUN_TIMEOUT_S = 300  # every cell of chapter 1 in the quick profile, through the UI


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory):
    """A JupyterLab server over a copy of chapter 1; yields ``(url of the notebook, log path)``."""
    chrome = find_chromium()
    if chrome is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI=true: no Chromium for the JupyterLab test", pytrace=False)
        pytest.skip("no Chromium (apt-get install chromium) for the JupyterLab test")
    root = tmp_path_factory.mktemp("lab")
    shutil.copy(REPO / "notebooks" / CHAPTER, root / CHAPTER)
    port, token = free_port(), secrets.token_hex(16)
    log = root / "lab.log"
    # JupyterLab 4 renders only the cells near the viewport ("windowing"): Run All scrolls to the
    # end and the explorer's cell leaves the DOM. A user setting keeps every cell rendered. The
    # kernel starts without asking (as `make install` configures for students).
    settings = root / ".lab-settings" / "@jupyterlab" / "notebook-extension"
    settings.mkdir(parents=True)
    (settings / "tracker.jupyterlab-settings").write_text(
        '{"windowingMode": "none", "autoStartDefaultKernel": true}'
    )
    news = root / ".lab-settings" / "@jupyterlab" / "apputils-extension"
    news.mkdir(parents=True)
    (news / "notification.jupyterlab-settings").write_text('{"fetchNews": "false"}')
    env = {**os.environ, "HUSKY_PROFILE": "quick"}
    env.pop("MPLBACKEND", None)  # the kernel needs the inline backend
    for name in ("HUSKY_STATIC_WIDGETS", "CI"):  # either makes widgets static; live is what is tested
        env.pop(name, None)
    cmd = [
        sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={port}", "--ip=127.0.0.1",
        f"--ServerApp.token={token}", f"--ServerApp.root_dir={root}", "--ServerApp.open_browser=False",
        f"--LabApp.user_settings_dir={root / '.lab-settings'}",
        f"--LabApp.workspaces_dir={root / '.lab-workspaces'}", "--LabApp.news_url=",
        "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
    ]
    if hasattr(os, "getuid") and os.getuid() == 0:
        cmd.append("--allow-root")
    with open(log, "w") as out:
        proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=out, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            try:
                with urlopen(f"{base}/api/status?token={token}", timeout=2) as resp:
                    if resp.status == 200:
                        break
            except OSError:
                pass
            if proc.poll() is not None or time.monotonic() > deadline:
                pytest.fail(f"JupyterLab did not start:\n{log.read_text()[-3000:]}", pytrace=False)
            time.sleep(0.5)
        yield {"chrome": chrome, "url": f"{base}/lab/tree/{CHAPTER}?token={token}", "log": log}
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()


RUN_DONE_JS = """
() => {
  const prompts = [...document.querySelectorAll('.jp-CodeCell .jp-InputPrompt')].map(p => p.textContent);
  return prompts.length > 0 && !prompts.some(t => t.includes('*'))
    && /\\[\\d+\\]/.test(prompts[prompts.length - 1]);
}
"""
KERNEL_READY_JS = """
() => [...document.querySelectorAll('.jp-StatusBar-TextItem')]
        .some(e => /\\| Idle$/.test(e.textContent.trim()) && !e.textContent.includes('No Kernel'))
"""
# the first code cell ran or is running (its prompt was empty in the committed notebook)
RUN_STARTED_JS = """
() => { const p = document.querySelector('.jp-CodeCell .jp-InputPrompt');
        return p !== null && /\\[(\\*|\\d+)\\]/.test(p.textContent); }
"""
OUTPUT_IMAGES_JS = """
() => [...document.querySelectorAll('.jp-OutputArea-output .widget-output img, .widget-output img')]
        .map(img => img.src)
"""


def test_world_explorer_responds_in_jupyterlab(lab):
    with chromium(lab["chrome"]) as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.route("http*://**", lambda r: r.abort() if "127.0.0.1" not in r.request.url else r.continue_())
        page.goto(lab["url"], wait_until="load", timeout=START_TIMEOUT_S * 1000)
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=START_TIMEOUT_S * 1000)
        page.wait_for_timeout(1500)
        if page.locator(".jp-Dialog").count():  # "Select Kernel" on JupyterLab without the setting
            page.locator(".jp-Dialog .jp-mod-accept").click()
        # the status bar names the kernel and says Idle. (The toolbar's execution indicator says
        # "idle" already while the status bar reads "No Kernel | Initializing": cells run then are
        # dropped, which is how this test once waited five minutes for nothing.)
        page.wait_for_function(KERNEL_READY_JS, timeout=START_TIMEOUT_S * 1000)
        try:  # Run > Run All Cells, through the menu bar as a student would
            for attempt in range(2):  # a student who sees nothing start clicks again
                page.locator(".lm-MenuBar-item", has_text="Run").first.click()
                page.locator(".lm-Menu-item[data-command='runmenu:run-all']").click()
                try:
                    page.wait_for_function(RUN_STARTED_JS, timeout=START_TIMEOUT_S * 1000)
                    break
                except Exception:
                    if attempt == 1:
                        raise
            # every cell has run: the last code cell has a number, none shows [*]
            page.wait_for_function(RUN_DONE_JS, timeout=RUN_TIMEOUT_S * 1000)
            # back to the top, where the explorer is (a windowed notebook renders only what is near)
            page.evaluate(
                "() => document.querySelectorAll('.jp-WindowedPanel-outer').forEach(e => e.scrollTop = 0)"
            )
            page.wait_for_function(
                f"() => document.querySelector('.widget-slider') && ({OUTPUT_IMAGES_JS})().length > 0",
                timeout=30_000,
            )
        except Exception:
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(SCREENSHOTS / "jupyterlab-failed.png"))
            outputs = page.evaluate(
                "() => [...document.querySelectorAll('.jp-OutputArea-output')].map(e => e.textContent)"
            )
            pytest.fail(
                "no live widget with a figure after Run All; outputs:\n"
                + "\n".join(o[:300] for o in outputs)
                + f"\nserver log:\n{lab['log'].read_text()[-2000:]}",
                pytrace=False,
            )
        slider = page.locator(".widget-slider").first
        before = page.evaluate(OUTPUT_IMAGES_JS)
        assert len(before) == 1, f"the explorer shows {len(before)} figures, expected one"
        slider.scroll_into_view_if_needed()
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        screenshot(page, SCREENSHOTS / "jupyterlab-before.png")

        readout = slider.locator(".widget-readout")
        readout.click()
        page.keyboard.press("Control+A")
        page.keyboard.type("7")
        t0 = time.monotonic()
        page.keyboard.press("Enter")
        page.wait_for_function(
            f"(old) => {{ const now = ({OUTPUT_IMAGES_JS})(); return now.length === 1 && now[0] !== old; }}",
            arg=before[0],
            timeout=60_000,
        )
        seconds = time.monotonic() - t0
        after = page.evaluate(OUTPUT_IMAGES_JS)
        slider.scroll_into_view_if_needed()
        screenshot(page, SCREENSHOTS / "jupyterlab-after.png")
        value = readout.inner_text().strip()
        print(f"world seed 0 -> {value}: new figure after {seconds:.2f} s; screenshots in {SCREENSHOTS}")
        assert value == "7"
        assert len(after) == 1 and after[0] != before[0], "the figure did not change in place"
        page.close()
