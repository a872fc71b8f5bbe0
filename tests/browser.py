"""The console in a real headless Chromium (Debian's /usr/bin/chromium, driven by Playwright):
fixtures (one console server, one browser and one API client per test module) and the helpers
that find viser's controls by their labels. Registered for every test module by
``tests/conftest.py``; a module that uses the ``page`` fixture is skipped when chromium is
missing.
"""

from __future__ import annotations

import io
import os
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from app.console import ConsoleSettings
from app.server import RunningServer, serve_in_thread

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
"""Chromium as the benchmarks launch it (``benchmarks/page_rates.py``, ``console_benchmark.py``,
``pilot_latency.py``): the page drawn as a person's browser draws it."""
TEST_CHROMIUM_ARGS = [
    *CHROMIUM_ARGS,
    # no multisampling of the software-drawn WebGL scene: a live page costs less of a core
    # (docs/performance.md); edges are a little more jagged, and the tests
    # compare pages drawn the same way. The benchmarks keep it: they measure a person's page.
    "--webgl-antialiasing-mode=none",
]
"""Chromium as the tests launch it."""
SCENE_DPR = 1.0 if os.environ.get("ROV_SCREENSHOTS_DIR") else 0.5
"""The pixels of a test page's 3D view per CSS pixel (viser's ``fixedDpr``): at 0.5 the scene
is drawn at a quarter of its pixels and scaled up, its labels blurred; its colours and shapes,
which the tests look at, are as at 1, and a live page takes less than half the CPU
(docs/performance.md, "The tests' ten minutes"). The docs' pictures (``ROV_SCREENSHOTS_DIR``)
are drawn sharp."""
SCREENSHOTS = Path(
    os.environ.get("ROV_SCREENSHOTS_DIR") or Path(tempfile.gettempdir()) / "rov-console-screenshots"
)
"""Where the browser tests save their screenshots, to look at: a folder of the machine's temp
directory, so a test run leaves the checkout as it was. ``ROV_SCREENSHOTS_DIR=docs/screenshots``
refreshes the pictures the docs show."""


def _playwright():
    if not CHROMIUM.exists():
        pytest.skip("Debian's chromium is missing")
    return pytest.importorskip("playwright.sync_api")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningServer]:
    settings = ConsoleSettings(
        port=0, viser_port=0, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with serve_in_thread(settings) as srv:
        yield srv


@pytest.fixture(scope="module")
def page(server: RunningServer, tmp_path_factory: pytest.TempPathFactory):
    with _playwright().sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")),
            executable_path=str(CHROMIUM),
            args=TEST_CHROMIUM_ARGS,
            headless=True,
            viewport={"width": 1400, "height": 900},
        )
        context.add_init_script(WATCH_SHADERS)
        context.add_init_script(SLOW_FRAMES)
        try:
            pg = context.new_page()
            open_console(pg, server.view_url)
            _dismiss_notifications(pg)
            yield pg
        finally:
            context.close()


@pytest.fixture(scope="module")
def api(server: RunningServer) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=server.base_url, headers=server.auth, timeout=30.0) as client:
        yield client


# ---------------------------------------------------------------------- helpers
WATCH_SHADERS = """
(() => {
  window.__glPrograms = 0;
  window.__glLastCompileMs = -1;
  for (const proto of [WebGLRenderingContext.prototype, WebGL2RenderingContext.prototype]) {
    const link = proto.linkProgram;
    const status = proto.getProgramParameter;
    proto.linkProgram = function (...args) {
      window.__glPrograms += 1;
      window.__glLastCompileMs = performance.now();
      return link.apply(this, args);
    };
    proto.getProgramParameter = function (...args) {
      const out = status.apply(this, args);
      window.__glLastCompileMs = performance.now();
      return out;
    };
  }
})()
"""
"""Counts the WebGL programs a page links and notes when it last linked or asked after one.
Chromium without a GPU compiles shaders in software, and the page's main thread waits on
each: a fresh console page answers nothing for seconds while it compiles its scene's programs,
and a click sent then times out (docs/performance.md, "The tests' ten minutes")."""
FRAME_EVERY_MS = 1000
"""The least time between two frames of a test page's 3D view (``SLOW_FRAMES``)."""
SLOW_FRAMES = """
(() => {
  const DELAY_MS = FRAME_EVERY_MS;
  const native = window.requestAnimationFrame.bind(window);
  const cancelNative = window.cancelAnimationFrame.bind(window);
  const pending = new Map();  // id -> timer (>= 0) or -(native frame id)
  let next = 1;
  window.requestAnimationFrame = (callback) => {
    const id = next++;
    const timer = setTimeout(() => {
      pending.set(id, -native((t) => { pending.delete(id); callback(t); }));
    }, DELAY_MS);
    pending.set(id, timer);
    return id;
  };
  window.cancelAnimationFrame = (id) => {
    const handle = pending.get(id);
    if (handle === undefined) return;
    pending.delete(id);
    if (handle < 0) cancelNative(-handle); else clearTimeout(handle);
  };
})()
""".replace("FRAME_EVERY_MS", str(FRAME_EVERY_MS))
"""Draws the page's 3D view at most once a second instead of whenever the scene moves. Without a
GPU, Chromium draws the console's live scene in software, at a high cost a frame, as fast
as the scene changes: one page kept most of this machine's two cores busy, starving the
other test worker and the page's own input. Playwright's own checks (an element is stable over
two frames) run in its own isolated world and keep the browser's real frames. What each frame
interval cost and bought is in docs/performance.md ("The tests' ten minutes")."""
CONSOLE_PROGRAMS = 12
"""The WebGL programs a fresh console page links for its scene: eleven at once, the twelfth
(viser's label renderer) when its first label is drawn, some seconds later."""
SHADERS_QUIET_S = 4.0
"""Seconds without a shader compile after which a page with fewer programs than
``CONSOLE_PROGRAMS`` counts as settled: its groups of programs came at most 2.5 s apart."""
PROGRAMS_QUIET_S = 0.5
"""Seconds without a compile after which a page that has linked ``CONSOLE_PROGRAMS`` programs
counts as settled: its main thread is then free to take a click."""


def settle(pg, timeout_s: float = 120.0) -> None:
    """Wait until the page has compiled its scene's shaders (see ``WATCH_SHADERS``), so that
    what a test does next is not held behind them: all of a console page's programs and
    ``PROGRAMS_QUIET_S`` after the last, or any other page's and ``SHADERS_QUIET_S``."""

    def quiet() -> bool:
        programs, quiet_ms = pg.evaluate(
            "[window.__glPrograms ?? -1, performance.now() - (window.__glLastCompileMs ?? 0)]"
        )
        if programs < 0:
            raise AssertionError("the page was opened without WATCH_SHADERS")
        wait_s = PROGRAMS_QUIET_S if programs >= CONSOLE_PROGRAMS else SHADERS_QUIET_S
        return programs > 0 and quiet_ms > 1000 * wait_s

    wait_for(
        quiet, timeout_s, f"the scene's shaders ({CONSOLE_PROGRAMS} or {SHADERS_QUIET_S:g} s quiet)"
    )


def open_console(pg, url: str, dpr: float = SCENE_DPR) -> None:
    """Load the console in ``pg`` and wait until its panel is there and its scene drawn (its
    3D view at ``dpr`` pixels per CSS pixel)."""
    pg.goto(f"{url}{'&' if '?' in url else '?'}fixedDpr={dpr:g}")
    pg.get_by_text("Unlock controls").wait_for(timeout=60_000)
    settle(pg)


HIDE_NOTICES = """
(() => {
  if (document.getElementById("tests-hide-notices")) return;
  const style = document.createElement("style");
  style.id = "tests-hide-notices";
  style.textContent = ".mantine-Notification-root { display: none !important; }";
  document.head.appendChild(style);
})()
"""
"""A style rule that keeps viser's notices out of the page's pictures from then on (the
console itself shows none; viser's own 'software WebGL' notice is the only one)."""


def _dismiss_notifications(pg) -> None:
    """Keep viser's notices (its 'software WebGL' notice is the only one) out of the page's
    pictures from now on, with the ``HIDE_NOTICES`` style rule. Hidden, a notice neither covers
    the scene nor takes a click, so none is closed by hand: on a loaded machine such a click
    could miss it (the notice stood over page A's scene and failed test_console_replay's
    comparison of two identical scenes in a full run), and the wait for it to appear before the
    click, a second each call, was 12 s of that test alone."""
    pg.evaluate(HIDE_NOTICES)


def field(pg, label: str):
    """The text/number input of a viser control, found by its label."""
    inputs = "*[self::input[not(@type='hidden')] or self::select or self::textarea]"
    return pg.locator(
        f"xpath=//label[normalize-space(.)='{label}']/ancestor::div[.//{inputs}][1]//{inputs}"
    ).first


def choose(pg, label: str, option: str) -> None:
    """Pick an option of a viser dropdown (a combobox with a list of options)."""
    field(pg, label).click()
    pg.locator(f"xpath=//*[@role='option'][normalize-space(.)='{option}']").filter(
        visible=True
    ).first.click()


def button(pg, name: str):
    """A button by its text (XPath: role queries are slow on viser's large page)."""
    return pg.locator(f"xpath=//button[normalize-space(.)='{name}']").first


def click(pg, name: str) -> None:
    button(pg, name).click()


def tab(pg, name: str) -> None:
    pg.locator(f"xpath=//*[@role='tab'][normalize-space(.)='{name}']").first.click()


def unlock(pg, token: str) -> None:
    """Unlock this page's controls (nothing to do when they are unlocked already)."""
    if button(pg, "Lock controls").is_visible():
        return
    # viser sends an input's value at most every 50 ms, later under load. Once in a full run
    # (2026-11-27, the first test of a module) no "controls unlocked" came within 10 s and the
    # cause was not caught; a click that overtakes the token would be answered "wrong token".
    # So try again, letting the token settle longer, as a person would, and say what each
    # try saw
    tries = []
    for settle_s in (0.2, 1.0, 3.0):
        field(pg, "Token").fill(token)
        time.sleep(settle_s)
        click(pg, "Unlock controls")
        try:
            pg.get_by_text("controls unlocked").wait_for(timeout=10_000)
            return
        except _playwright().TimeoutError:
            wrong = pg.get_by_text("wrong token").count() > 0
            tries.append(f"{settle_s} s: {'wrong token' if wrong else 'no answer'}")
    raise AssertionError(f"controls not unlocked in three tries ({'; '.join(tries)})")


def wait_for(predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll ``predicate`` every 0.1 s until it holds. Playwright's sync API takes in a page's
    events (new frames, navigations) only while one of its calls runs, so a predicate must
    make such a call (``evaluate``, ``inner_text``, ...), not only read ``page.frames``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def image(pg) -> np.ndarray:
    """The page as an RGB array."""
    return np.asarray(Image.open(io.BytesIO(pg.screenshot())).convert("RGB"), dtype=float)


def scene_part(img: np.ndarray) -> np.ndarray:
    """The 3D view without the control panel on the right."""
    return img[:, : int(0.6 * img.shape[1])]


def save(img_bytes: bytes, name: str) -> Path:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / name
    path.write_bytes(img_bytes)
    return path
