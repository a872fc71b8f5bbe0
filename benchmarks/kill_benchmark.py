"""What a killed console loses of its recording, and who can read what is left.

Starts ``rov-console serve`` (API only) at a chosen speed with a library mission, starts a
recording through the API as an operator would, lets it run a random 8-15 s of wall time,
reads the run's simulated time, and kills the process with SIGKILL. Then, for each kill:

- the simulated and wall time lost: the run's time at the kill (the last ``/api/state`` read
  plus the wall time since, times the speed) less the last row in the file;
- who reads the killed file: the product's reader (``load_session``), mcap's stock Python
  reader (``make_reader``, through the file's index), and Foxglove's own TypeScript reader
  (``@mcap/core``, through ``tests/js/read_mcap.mjs``, which falls back to reading front to
  back when the index is missing, as Foxglove Studio does);
- the same two stock readers on what ``rov-console log recover`` makes of it.

Not a unit test. Run from the repository root (node and ``tests/js``'s packages for the
Foxglove reader: ``npm ci --prefix tests/js``):

    .venv/bin/python benchmarks/kill_benchmark.py [--kills 3] [--speed 20] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.recording import load_session
from app.server import free_port
from benchmarks import machine

ROOT = Path(__file__).resolve().parents[1]
TOKEN = "kill-benchmark-token-01"
MISSION = "full-docking-current-0.3"


def _stock_reader(path: Path) -> str:
    """What mcap's Python reader makes of ``path``: 'N messages' or the error's first line."""
    from mcap.reader import make_reader

    try:
        with path.open("rb") as f:
            n = sum(1 for _ in make_reader(f).iter_messages())
        return f"{n} messages"
    except Exception as err:
        return f"error: {type(err).__name__}: {str(err).splitlines()[0][:80]}"


def _foxglove_reader(path: Path) -> str:
    """What Foxglove's @mcap/core makes of ``path`` (tests/js/read_mcap.mjs)."""
    script = ROOT / "tests" / "js" / "read_mcap.mjs"
    if shutil.which("node") is None or not (ROOT / "tests" / "js" / "node_modules").is_dir():
        return "not run (node or tests/js/node_modules missing)"
    done = subprocess.run(
        ["node", str(script), str(path)], capture_output=True, text=True, timeout=120
    )
    try:
        out = json.loads(done.stdout)
    except ValueError:
        return f"error: {done.stderr.strip()[:80]}"
    n = sum(out.get("counts", {}).values())
    how = out.get("reader", "?")
    return f"{n} messages ({how})" + (f", {out['error'][:60]}" if out.get("error") else "")


def _wait_stepping(base: str, timeout_s: float = 300.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{base}/api/health", timeout=2.0).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.5)
    raise RuntimeError("the console did not start")


def one_kill(folder: Path, speed: float, rng: random.Random) -> dict:
    port, rec = free_port(), folder / "recordings"
    proc = subprocess.Popen(
        [
            str(ROOT / ".venv" / "bin" / "rov-console"),
            "serve",
            "--port",
            str(port),
            "--viser-port",
            str(free_port()),
            "--token",
            TOKEN,
            "--speed",
            f"{speed:g}",
            "--mission",
            MISSION,
            "--recordings",
            str(rec),
        ],
        cwd=folder,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    base = f"http://127.0.0.1:{port}"
    auth = {"Authorization": f"Bearer {TOKEN}"}
    try:
        _wait_stepping(base)
        name = httpx.post(
            f"{base}/api/recordings/start", json={"label": "killed"}, headers=auth, timeout=10
        ).json()["name"]
        time.sleep(rng.uniform(8.0, 15.0))
        t_read = time.monotonic()
        state = httpx.get(f"{base}/api/state", timeout=5).json()
        t_kill = time.monotonic()
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait(30)
    sim_at_kill = float(state["t_s"]) + (t_kill - t_read) * speed
    path = rec / name
    data = load_session(path)
    last = float(data.t_s[-1]) if len(data.t_s) else float("nan")
    lost = sim_at_kill - last
    recovered = folder / "recovered.mcap"
    done = subprocess.run(
        [str(ROOT / ".venv" / "bin" / "rov-console"), "log", "recover", str(path), str(recovered)],
        capture_output=True,
        text=True,
    )
    return {
        "speed": speed,
        "recorded_s": last,
        "simulated_lost_s": lost,
        "wall_lost_s": lost / speed,
        "product_reader": f"{len(data.t_s)} rows, {sum(data.message_counts.values())} messages",
        "mcap_reader": _stock_reader(path),
        "foxglove_reader": _foxglove_reader(path),
        "recover": "ok" if done.returncode == 0 else done.stderr.strip()[:80],
        "recovered_mcap_reader": _stock_reader(recovered) if recovered.exists() else "-",
        "recovered_foxglove_reader": (_foxglove_reader(recovered) if recovered.exists() else "-"),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kills", type=int, default=3)
    ap.add_argument("--speed", type=float, default=20.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    results = []
    load = os.getloadavg()
    for k in range(args.kills):
        folder = Path(tempfile.mkdtemp(prefix="kill-"))
        try:
            results.append(one_kill(folder, args.speed, rng))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        r = results[-1]
        if not args.json:
            print(
                f"kill {k + 1}: {r['recorded_s']:.1f} s recorded, lost {r['simulated_lost_s']:.2f}"
                f" s simulated ({r['wall_lost_s']:.2f} s wall); product: {r['product_reader']};"
                f" mcap: {r['mcap_reader']}; foxglove: {r['foxglove_reader']}; recovered:"
                f" mcap {r['recovered_mcap_reader']}, foxglove {r['recovered_foxglove_reader']}",
                flush=True,
            )
    if args.json:
        print(
            json.dumps(
                {"machine": machine.describe(), "load_average_before": list(load), "kills": results}
            )
        )
    else:
        print(f"{machine.text(machine.describe())}, load average before: {load}")


if __name__ == "__main__":
    main()
