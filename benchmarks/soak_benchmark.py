"""Soak benchmark: memory and loop timing over time under steady, partly hostile, use.

Serves the console on loopback (API only, no 3D view), runs a library mission at a chosen
speed, keeps telemetry WebSocket clients connected, and every second sends a mixed batch of
requests: state reads, valid commands, and bad requests from the corpus
(tests/corpus/bad_requests.txt). Each report interval it prints the process's resident memory,
the loop's tick jitter (median, p99), overruns, the loop's caught faults, and simulated seconds
per wall second. Bounded in time and count; loopback only. With ``--record`` the console
records the session (MCAP) from the start, as an operator pressing Record would. At the end it
prints the whole run's figures: ticks run against ticks due, overruns, lateness median and
p99, memory at the first and last report, simulated seconds per wall second, and the CPU
used by the loop's thread, the recorder's thread and the whole process (per cent of a core).

Not a unit test. Run from the repository root:

    .venv/bin/python benchmarks/soak_benchmark.py [--minutes 5] [--speed 50] [--clients 3]
        [--record]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import numpy as np
import websockets

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.console import ConsoleSettings
from app.console.loop import PacedLoop
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


def thread_cpu_s() -> dict[str, float]:
    """CPU time [s] (user + system) of this process's Python threads by name, summed over
    threads of one name (Linux /proc; empty elsewhere)."""
    out: dict[str, float] = {}
    tick = os.sysconf("SC_CLK_TCK")
    for thread in threading.enumerate():
        try:
            stat = Path(f"/proc/self/task/{thread.native_id}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        used = (int(fields[11]) + int(fields[12])) / tick
        out[thread.name] = out.get(thread.name, 0.0) + used
    return out


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
    ap.add_argument("--record", action="store_true", help="record the session (MCAP)")
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
        with httpx.Client(base_url=running.base_url, timeout=30.0) as client:
            if args.record:
                answer = client.post(
                    "/api/recordings/start", json={"label": "soak"}, headers=running.auth
                )
                answer.raise_for_status()
            ticks0, t_sim_start, wall0 = loop.ticks, loop.snapshot.t_s, time.monotonic()
            cpu0, process0 = thread_cpu_s(), time.process_time()
            t_sim0, k = t_sim_start, 0
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
            wall = time.monotonic() - wall0
            whole = whole_run(loop, ticks0, wall, loop.snapshot.t_s - t_sim_start)
            cpu = thread_cpu_s()
            for name in ("console-loop", "mcap-writer", "mcap-flush"):
                if name in cpu:
                    used = cpu[name] - cpu0.get(name, 0.0)
                    whole[f"cpu_{name.replace('-', '_')}_pct"] = round(100 * used / wall, 1)
            whole["cpu_process_pct"] = round(100 * (time.process_time() - process0) / wall, 1)
            if args.record:
                client.post("/api/recordings/stop", headers=running.auth)
        stop.set()
    if rows:
        whole |= {"rss_first_mb": rows[0]["rss_mb"], "rss_last_mb": rows[-1]["rss_mb"]}
    if args.json:
        print(json.dumps({"reports": rows, "whole": whole}, indent=2))
    else:
        print("whole run: " + "  ".join(f"{key} {v}" for key, v in whole.items()))


def whole_run(loop: PacedLoop, ticks0: int, wall_s: float, sim_s: float) -> dict:
    """The run's figures since ``ticks0``: ticks run against due (one per plant step of wall
    time), overruns, wake-up lateness median and p99 [ms], simulated per wall second."""
    ran = loop.ticks - ticks0
    late_ms = loop.lateness_s()[-ran:] * 1e3 if ran else np.zeros(1)
    return {
        "ticks_run": ran,
        "ticks_due": round(wall_s / loop.period_s),
        "overruns": loop.snapshot.stats.overruns,
        "lateness_median_ms": round(float(np.median(late_ms)), 3),
        "lateness_p99_ms": round(float(np.percentile(late_ms, 99)), 3),
        "sim_per_wall": round(sim_s / wall_s, 1),
    }


if __name__ == "__main__":
    main()
