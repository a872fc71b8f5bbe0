"""What the console's page receives and draws, measured in headless Chromium.

The page promises a status line refreshed 5 times a second (``web.panels.STATUS_EVERY_S``) and
plots that get new rows at most twice a second (``app.api.plots.PERIOD_S``, from the plots
page's own socket, /api/plots, embedded in the page's "Plots" folder). This opens the console in
Debian's chromium, counts in the page itself how often the status text changes (a
MutationObserver) and how many plot messages the plots page took, and how many bytes each
websocket delivers a second (viser's and the plots socket apart), for ``--seconds`` of a running
console at ``--speed``.

    .venv/bin/python benchmarks/page_rates.py --warmup 125 --seconds 20 --speed 1

Prints one JSON object: rates per second, against what the page promises, the 1-minute load
average at the end, and the view publisher's work per frame (median and 95th percentile).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.api import plots
from app.console import ConsoleSettings
from app.server import serve_in_thread
from tests.browser import CHROMIUM, CHROMIUM_ARGS, _dismiss_notifications
from web import panels

WATCH = """() => {
  window.__rates = {status: 0, plots: 0, bytes: 0, frames: 0};
  const frame = () => { window.__rates.frames++; requestAnimationFrame(frame); };
  requestAnimationFrame(frame);
  const status = Array.from(document.querySelectorAll('p, div'))
    .find(e => e.children.length < 6 && /t = .* s, (running|paused)/.test(e.textContent));
  new MutationObserver(() => window.__rates.status++)
    .observe(status, {subtree: true, childList: true, characterData: true});
}"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--warmup", type=float, default=2.0, help="seconds of running before measuring")
    ap.add_argument("--paused", action="store_true", help="measure with the run paused")
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    settings = ConsoleSettings(port=0, viser_port=0, recordings_dir=Path("/tmp/page-rates"))
    with serve_in_thread(settings) as srv, sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=str(CHROMIUM), args=CHROMIUM_ARGS, headless=True
        )
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        received = {"bytes": 0, "plot_bytes": 0, "plot_messages": 0}

        def watch(ws: Any) -> None:
            def count(payload: str | bytes) -> None:
                if "/api/plots" in ws.url:
                    received["plot_bytes"] += len(payload)
                    received["plot_messages"] += 1
                else:
                    received["bytes"] += len(payload)

            ws.on("framereceived", count)

        page.on("websocket", watch)
        page.goto(srv.view_url)
        page.get_by_text("Unlock controls").wait_for(timeout=60_000)
        _dismiss_notifications(page)
        srv.console.loop.speed = args.speed
        time.sleep(args.warmup)
        if args.paused:
            httpx.post(f"{srv.base_url}/api/run/pause", headers=srv.auth).raise_for_status()
            time.sleep(1.0)
        panels_ = list(srv.app.state.view._panels.values())
        page.evaluate(WATCH)
        received.update(bytes=0, plot_bytes=0, plot_messages=0)
        sent0 = dict(panels_[0].updates_sent)
        time.sleep(args.seconds)
        counts = page.evaluate("() => window.__rates")
        sent = {k: panels_[0].updates_sent[k] - sent0[k] for k in sent0}
        frames = np.array(list(srv.app.state.view.frame_ms)) if srv.app.state.view else None
        browser.close()
    out = {
        "seconds": args.seconds,
        "speed": args.speed,
        "paused": args.paused,
        "warmup_s": args.warmup,
        "status_sent_per_s": round(sent["status"] / args.seconds, 2),
        "status_per_s": round(counts["status"] / args.seconds, 2),
        "status_promised_per_s": 1.0 / panels.STATUS_EVERY_S,
        "plot_messages_per_s": round(received["plot_messages"] / args.seconds, 2),
        "plots_promised_at_most_per_s": 1.0 / plots.PERIOD_S,
        # the plots' data: all on the plots socket (viser's carries none of it any more)
        "plot_socket_B_per_s": round(received["plot_bytes"] / args.seconds, 1),
        "viser_websocket_kB_per_s": round(received["bytes"] / args.seconds / 1e3, 1),
        # the page handles what viser sends once per animation frame: several updates of the
        # status line between two frames are drawn once
        "page_frames_per_s": round(counts["frames"] / args.seconds, 2),
        "load_average_1min": round(os.getloadavg()[0], 2),
    }
    if frames is not None and len(frames):
        # the view's publisher: work per frame (shared scene, all panels) [ms]
        for k, part in enumerate(("scene", "panels")):
            out[f"publisher_{part}_ms_median"] = round(float(np.median(frames[:, k])), 2)
            out[f"publisher_{part}_ms_p95"] = round(float(np.percentile(frames[:, k], 95)), 2)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
