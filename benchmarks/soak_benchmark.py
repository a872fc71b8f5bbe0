"""Soak benchmark: memory and loop timing over time under steady, partly hostile, use.

Serves the console on loopback (API only, no 3D view), runs a library mission at a chosen
speed, keeps telemetry WebSocket clients connected, and every second sends a mixed batch of
requests: state reads, valid commands, and bad requests from the corpus
(tests/corpus/bad_requests.txt). Each report interval it prints the process's resident memory,
the loop's tick jitter (median, p99), overruns, the loop's caught faults, and simulated seconds
per wall second. Bounded in time and count; loopback only.

Not a unit test. Run from the repository root:

    .venv/bin/python benchmarks/soak_benchmark.py [--minutes 5] [--speed 50] [--clients 3]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import resource
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import websockets

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.console import ConsoleSettings
from app.server import serve_in_thread
from tests.test_corpus import CASES, body_bytes

TOKEN = "soak-benchmark-token-01"


def rss_mb() -> float:
    """Resident memory now [MB] (Linux /proc; falls back to the peak)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def telemetry_clients(url: str, n: int, stop: threading.Event, counts: list[int]) -> None:
    async def one(k: int) -> None:
        async with websockets.connect(url) as ws:
            while not stop.is_set():
                await ws.recv()
                counts[k] += 1

    async def all_of_them() -> None:
        await asyncio.gather(*(one(k) for k in range(n)), return_exceptions=True)

    asyncio.run(all_of_them())


def request_mix(client: httpx.Client, auth: dict[str, str], k: int) -> None:
    """One second's traffic: reads, a harmless command, and two bad requests."""
    client.get("/api/state")
    client.get("/api/health")
    client.put("/api/run/speed", json={"speed": 50.0}, headers=auth)
    for case in (CASES[k % len(CASES)], CASES[(k + 7) % len(CASES)]):
        if case.auth == "wrong" or any(w in case.path for w in ("abort", "reset", "start")):
            continue  # keep the soak from locking itself out or ending its own mission
        headers = auth if case.auth == "token" else {}
        content = body_bytes(case.body)
        if content is not None:
            headers = {**headers, "content-type": "application/json"}
        client.request(case.method, case.path, content=content, headers=headers)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--minutes", type=float, default=5.0)
    ap.add_argument("--speed", type=float, default=50.0)
    ap.add_argument("--clients", type=int, default=3)
    ap.add_argument("--report-s", type=float, default=30.0)
    ap.add_argument("--mission", default="sea-trial-appendix-c")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    settings = ConsoleSettings(
        port=0,
        view=False,
        token=TOKEN,
        speed=args.speed,
        mission=args.mission,
        recordings_dir=Path(tempfile.mkdtemp()),
    )
    rows = []
    with serve_in_thread(settings) as running:
        loop = running.console.loop
        stop = threading.Event()
        counts = [0] * args.clients
        ws_url = running.base_url.replace("http", "ws") + "/api/telemetry?rate_hz=20"
        watchers = threading.Thread(
            target=telemetry_clients, args=(ws_url, args.clients, stop, counts), daemon=True
        )
        watchers.start()
        start = time.monotonic()
        end = start + 60.0 * args.minutes
        next_report = start + args.report_s
        t_sim0, k = loop.snapshot.t_s, 0
        with httpx.Client(base_url=running.base_url, timeout=30.0) as client:
            while time.monotonic() < end:
                request_mix(client, running.auth, k)
                k += 1
                time.sleep(max(0.0, start + k - time.monotonic()))
                if time.monotonic() >= next_report:
                    late = loop.lateness_s()[-int(args.report_s * 100) :] * 1e3
                    snap = loop.snapshot
                    row = {
                        "wall_s": round(time.monotonic() - start, 1),
                        "rss_mb": round(rss_mb(), 1),
                        "jitter_median_ms": round(float(sorted(late)[len(late) // 2]), 3),
                        "jitter_p99_ms": round(float(snap.stats.jitter_p99_ms), 3),
                        "overruns": snap.stats.overruns,
                        "faults": loop.faults,
                        "sim_per_wall": round((snap.t_s - t_sim0) / args.report_s, 1),
                        "telemetry_msgs": sum(counts),
                        "mission": snap.mission.state,
                    }
                    t_sim0 = snap.t_s
                    rows.append(row)
                    if not args.json:
                        print("  ".join(f"{key} {v}" for key, v in row.items()), flush=True)
                    next_report += args.report_s
        stop.set()
    if args.json:
        print(json.dumps(rows, indent=2))
    elif len(rows) >= 2:
        print(
            f"memory growth from the first to the last report: "
            f"{rows[-1]['rss_mb'] - rows[0]['rss_mb']:+.1f} MB"
        )


if __name__ == "__main__":
    main()
