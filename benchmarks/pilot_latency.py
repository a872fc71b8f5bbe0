"""Pilot latency benchmark: how long from a key press on the pilot page to the thrusters, and
to the 3D view showing the ROV move? (Issue 13's targets: 50 ms and 150 ms.)

Starts the console on loopback (free ports) with its 3D view, opens the pilot page in headless
Chromium (Debian's, as the browser tests), signs in, releases the ROV from the tree and takes
over by hand (P). Then, ``--trials`` times, it taps W or S (alternately, with Shift: full
stick) for 0.1 s and waits 2 s (the station keeping brings the ROV back meanwhile). Times are
the system clock: ``performance.timeOrigin + performance.now()`` in each document (the page
and the 3D view's frame) and ``time.time()`` in this process:

- key: the keydown event's own time stamp on the pilot page;
- thrusters: the first published state (the console's ``Snapshot``, polled every 2 ms by a
  thread in this process and stamped with ``time.time()``, the same system clock as the
  browser's epoch time) whose commanded thruster forces differ from the state before the key
  by more than 2 % of the largest thruster force; and the same seen by the page on the
  console's telemetry socket (opened in the page at 100 Hz, so up to 10 ms of sampling and
  the page's own event queue are included);
- 3D view: the viser page in the pilot page's frame gets its scene updates from a web worker;
  a wrapper of ``Worker`` (an init script in that frame) stamps every ``/rov`` position update
  when it reaches the page, and the next animation frame (the frame that draws it). Each
  update is matched to the published state it shows (its ROV position equals that state's, to
  1 micrometre; the same thread records every state's ROV position). The response is the
  first update showing a state published at or after the first one with the new thruster
  forces: the 3D view drawing the ROV as it is once the thrusters answer the key.

Not a test. Run from the repository root:

    .venv/bin/python benchmarks/pilot_latency.py [--trials 30] [--json] [--no-view]

``--no-view`` takes the 3D view out of the page once it is up: key to thrusters without the
page's renderer sharing the CPU with the view's (software, in headless Chromium) drawing.
``PILOT_LATENCY_RAW=FILE`` writes every time stamp to FILE (JSON).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.console import ConsoleSettings
from app.server import serve_in_thread
from tests import browser

TARGET_THRUSTERS_MS = 50.0
TARGET_VIEW_MS = 150.0
TAP_S = 0.1
SETTLE_S = 2.0
RAW_PATH = os.environ.get("PILOT_LATENCY_RAW", "")
"""Where to write the raw time stamps (JSON) for a closer look; empty: nowhere."""

FRAME_SCRIPT = """
(() => {
  if (window.__rovUpdates) return;
  window.__rovUpdates = [];
  const Original = window.Worker;
  if (!Original) return;
  window.Worker = class extends Original {
    constructor(...args) {
      super(...args);
      this.addEventListener("message", (event) => {
        const data = event.data;
        if (!data || data.type !== "message_batch") return;
        const now = performance.timeOrigin + performance.now();
        for (const m of data.messages) {
          if (m && m.name === "/rov" && m.position && m.position.length === 3) {
            const entry = {t: now, raf: null, p: Array.from(m.position)};
            window.__rovUpdates.push(entry);
            requestAnimationFrame(() => {
              entry.raf = performance.timeOrigin + performance.now();
            });
          }
        }
      });
    }
  };
})();
"""

PAGE_SCRIPT = """
(url) => {
  window.__keys = [];
  window.__thr = [];
  window.addEventListener("keydown", (e) => {
    if ((e.code === "KeyW" || e.code === "KeyS") && !e.repeat) {
      window.__keys.push({t: performance.timeOrigin + e.timeStamp, code: e.code});
    }
  }, true);
  const ws = new WebSocket(url);
  ws.onmessage = (msg) => {
    const s = JSON.parse(msg.data);
    window.__thr.push({t: performance.timeOrigin + performance.now(),
                       f: s.thrusters.map((x) => x.force_newton)});
  };
  return new Promise((resolve) => { ws.onopen = () => resolve(true); });
}
"""


def _wait(predicate, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise RuntimeError(f"timed out waiting for {what}")


def run(trials: int, with_view: bool = True) -> dict:
    from playwright.sync_api import sync_playwright

    settings = ConsoleSettings(
        port=0, viser_port=0, recordings_dir=Path(tempfile.mkdtemp(prefix="pilot-bench-"))
    )
    with serve_in_thread(settings) as srv, sync_playwright() as pw:
        api = httpx.Client(base_url=srv.base_url, headers=srv.auth, timeout=30.0)
        b = pw.chromium.launch(
            executable_path=str(browser.CHROMIUM), args=browser.CHROMIUM_ARGS, headless=True
        )
        context = b.new_context(viewport={"width": 1200, "height": 800})
        context.add_init_script(FRAME_SCRIPT)
        pg = context.new_page()
        pg.goto(f"{srv.base_url}/pilot")
        pg.fill("#name", "benchmark")
        pg.fill("#token", srv.token)
        pg.click("#fly")
        _wait(lambda: pg.locator("#message").text_content() == "flying as benchmark", 30, "sign-in")
        api.put("/api/control/grip", json={"grip": False}).raise_for_status()
        pg.keyboard.press("p")
        _wait(lambda: api.get("/api/state").json()["mode"] == "manual", 10, "manual mode")
        host = srv.base_url.removeprefix("http://")
        pg.evaluate(PAGE_SCRIPT, f"ws://{host}/api/telemetry?rate_hz=100")
        view = next(f for f in pg.frames if f != pg.main_frame)
        _wait(lambda: view.evaluate("window.__rovUpdates.length") > 0, 60, "the 3D view")
        if not with_view:  # diagnosis: the same without the 3D view drawing in the page
            pg.evaluate("document.getElementById('view').remove()")
        time.sleep(3.0)
        heading = math.radians(api.get("/api/state").json()["rov_eta_n"]["heading_deg"])
        f_max = float(np.max(srv.console.loop.session.sim.ps.rov.thrusters.f_max_pos))
        published: list[dict] = []
        stop = threading.Event()
        poller = threading.Thread(target=_poll, args=(srv.console, published, stop), daemon=True)
        poller.start()
        load_before = os.getloadavg()
        for i in range(trials):
            key = "w" if i % 2 == 0 else "s"
            pg.keyboard.down("Shift")
            pg.keyboard.down(key)
            time.sleep(TAP_S)
            pg.keyboard.up(key)
            pg.keyboard.up("Shift")
            time.sleep(SETTLE_S)
        load_after = os.getloadavg()
        stop.set()
        poller.join()
        keys = pg.evaluate("window.__keys")
        thr = pg.evaluate("window.__thr")
        rov = view.evaluate("window.__rovUpdates") if with_view else []
        b.close()
        api.close()
    raw = {"keys": keys, "thr": thr, "published": published, "rov": rov, "heading": heading}
    if RAW_PATH:
        Path(RAW_PATH).write_text(json.dumps(raw))
    return analyse(keys, thr, published, rov, heading, f_max) | {
        "trials": trials,
        "loadavg_before": load_before,
        "loadavg_after": load_after,
        "cpus": os.cpu_count(),
    }


def _poll(console, out: list, stop: threading.Event) -> None:
    """Every newly published state's thruster forces, stamped with the system clock [ms]."""
    last = -1
    while not stop.is_set():
        snap = console.loop.snapshot
        if snap.seq != last:
            last = snap.seq
            out.append(
                {
                    "t": time.time() * 1e3,
                    "f": list(snap.thruster_force_newton),
                    "p": list(snap.rov_eta_n[0:3]),
                }
            )
        time.sleep(0.002)


def _first_change(key_t: float, samples: list, f_max: float) -> int | None:
    """Index of the first sample after a key press whose forces moved (None: none)."""
    t = np.array([s["t"] for s in samples])
    f = np.array([s["f"] for s in samples])
    before = np.flatnonzero(t < key_t)
    after = np.flatnonzero(t >= key_t)
    if len(before) and len(after):
        moved = after[np.max(np.abs(f[after] - f[before[-1]]), axis=1) > 0.02 * f_max]
        if len(moved):
            return int(moved[0])
    return None


def analyse(
    keys: list, thr: list, published: list, rov: list, heading_rad: float, f_max: float
) -> dict:
    """Latencies [ms] per key press (see the module's text for the criteria)."""
    t_pub = np.array([s["t"] for s in published])
    p_pub = np.array([s["p"] for s in published])
    t_page = np.array([s["t"] for s in thr])
    t_rov = np.array([u["t"] for u in rov])
    p_rov = np.array([u["p"] for u in rov])
    raf = np.array([u["raf"] if u["raf"] is not None else np.nan for u in rov])
    to_thr, to_page, to_msg, to_frame = [], [], [], []
    for k in keys:
        tk = k["t"]
        i_thr = _first_change(tk, published, f_max)
        i_page = _first_change(tk, thr, f_max)
        if i_page is not None:
            to_page.append(t_page[i_page] - tk)
        if i_thr is None:
            continue
        to_thr.append(t_pub[i_thr] - tk)
        window = np.flatnonzero((t_pub > tk - 2000.0) & (t_pub < tk + 3000.0))
        for j in np.flatnonzero((t_rov >= tk) & (t_rov < tk + 3000.0)):
            shown = window[np.max(np.abs(p_pub[window] - p_rov[j]), axis=1) < 1e-6]
            if len(shown) and shown[-1] >= i_thr:
                to_msg.append(t_rov[j] - tk)
                to_frame.append(raf[j] - tk)
                break

    def stats(values: list) -> dict:
        a = np.array(values, float)
        a = a[np.isfinite(a)]
        if not len(a):
            return {"n": 0}
        return {
            "samples_ms": [round(float(x), 1) for x in a],
            "n": int(len(a)),
            "median_ms": float(np.median(a)),
            "p95_ms": float(np.percentile(a, 95)),
            "max_ms": float(a.max()),
        }

    return {
        "key_presses": len(keys),
        "to_thrusters": stats(to_thr),
        "to_thrusters_on_page": stats(to_page),
        "to_view_update": stats(to_msg),
        "to_view_frame": stats(to_frame),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument(
        "--no-view",
        action="store_true",
        help="take the 3D view out of the page after start (key to thrusters without it)",
    )
    args = parser.parse_args()
    result = run(args.trials, with_view=not args.no_view)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(f"{result['key_presses']} key presses (W/S with Shift, {TAP_S} s taps)")
    for name, target in (
        ("to_thrusters", TARGET_THRUSTERS_MS),
        ("to_thrusters_on_page", TARGET_THRUSTERS_MS),
        ("to_view_update", TARGET_VIEW_MS),
        ("to_view_frame", TARGET_VIEW_MS),
    ):
        s = result[name]
        if not s["n"]:
            print(f"{name:20s} no responses found")
            continue
        verdict = "meets" if s["p95_ms"] <= target else "misses"
        print(
            f"{name:20s} n={s['n']:3d}  median {s['median_ms']:6.1f} ms  p95 {s['p95_ms']:6.1f} ms"
            f"  max {s['max_ms']:6.1f} ms  ({verdict} the {target:.0f} ms target at p95)"
        )
    lb, la = result["loadavg_before"], result["loadavg_after"]
    print(
        f"load average (1, 5, 15 min): before {lb[0]:.2f} {lb[1]:.2f} {lb[2]:.2f}, "
        f"after {la[0]:.2f} {la[1]:.2f} {la[2]:.2f} on {result['cpus']} CPUs"
    )


if __name__ == "__main__":
    main()
