"""What one live console page costs the machine in the tests' headless Chromium: the chromium
processes' CPU time over ``--seconds`` of a running console, in cores, with the test pages'
frame limit (``tests.browser.SLOW_FRAMES``, ``--frame-ms``), with or without WebGL
multisampling (``--multisampling``: the benchmarks' ``CHROMIUM_ARGS``; without, the tests'
``TEST_CHROMIUM_ARGS``), at a page size (``--viewport``) and a resolution of its 3D view
(``--dpr``, the tests' ``SCENE_DPR`` unless given).

    .venv/bin/python benchmarks/browser_cpu.py [--frame-ms 1000] [--multisampling] [--seconds 10]
        [--viewport 1400x900] [--dpr 0.5]

The test suite's browser modules run beside another test worker on this 2-core machine; what
a page takes from it is what this prints. Also the time of a screenshot (four, in seconds).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.console import ConsoleSettings
from app.server import serve_in_thread
from tests import browser


def chromium_cpu_s() -> float:
    """User and system CPU seconds of every chromium process now running."""
    total = 0.0
    for proc in psutil.process_iter(["name"]):
        try:
            if "chrom" in (proc.info["name"] or ""):
                times = proc.cpu_times()
                total += times.user + times.system
        except psutil.Error:
            pass  # gone meanwhile
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frame-ms", type=int, default=browser.FRAME_EVERY_MS)
    parser.add_argument("--multisampling", action="store_true")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--viewport", default="1400x900", help="the page's WIDTHxHEIGHT [px]")
    parser.add_argument(
        "--dpr", type=float, default=browser.SCENE_DPR, help="the 3D view's pixels per CSS pixel"
    )
    args = parser.parse_args()
    width, height = (int(n) for n in args.viewport.split("x"))
    from playwright.sync_api import sync_playwright

    chromium_args = browser.CHROMIUM_ARGS if args.multisampling else browser.TEST_CHROMIUM_ARGS
    frames = browser.SLOW_FRAMES.replace(
        f"DELAY_MS = {browser.FRAME_EVERY_MS};", f"DELAY_MS = {args.frame_ms};"
    )
    assert f"DELAY_MS = {args.frame_ms};" in frames, "SLOW_FRAMES no longer sets DELAY_MS"
    settings = ConsoleSettings(port=0, viser_port=0, recordings_dir=Path(tempfile.mkdtemp()))
    with serve_in_thread(settings) as srv, sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            tempfile.mkdtemp(),
            executable_path=str(browser.CHROMIUM),
            args=chromium_args,
            headless=True,
            viewport={"width": width, "height": height},
        )
        context.add_init_script(browser.WATCH_SHADERS)
        context.add_init_script(frames)
        try:
            page = context.new_page()
            browser.open_console(page, srv.view_url, args.dpr)
            browser._dismiss_notifications(page)
            cpu0, t0 = chromium_cpu_s(), time.monotonic()
            time.sleep(args.seconds)
            cores = (chromium_cpu_s() - cpu0) / (time.monotonic() - t0)
            shots = []
            for _ in range(4):
                t1 = time.monotonic()
                page.screenshot()
                shots.append(round(time.monotonic() - t1, 2))
        finally:
            context.close()
    print(
        json.dumps(
            {
                "frame_ms": args.frame_ms,
                "viewport": args.viewport,
                "dpr": args.dpr,
                "multisampling": args.multisampling,
                "chromium_cores": round(cores, 2),
                "screenshot_s": shots,
            }
        )
    )


if __name__ == "__main__":
    main()
