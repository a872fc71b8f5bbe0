"""What a first user waits for: a fresh clone of this repository, timed as they would use it.

    .venv/bin/python benchmarks/fresh_clone.py [--what start,run,test,edit] [--json]

Each measurement clones the repository's committed HEAD into a new folder (nothing of this
checkout's ``.venv`` or ``.numba-cache`` comes along) and times, from the clone:

- ``start``: ``./scripts/start.sh`` (set-up included) until ``/api/health`` answers with the
  simulation stepping (its simulated time moving);
- ``run``: ``./scripts/setup.sh`` then ``rov-console run full-docking-current-0.3``, the first
  docking with its compile, and the same run again (loaded from the cache);
- ``test``: ``./scripts/test.sh`` whole (set-up, static checks, the default test run);
- ``edit``: what a developer waits for after an edit of the core: set-up, the docking run
  once (the cache filled), then after an edit of a comment, of the wire's force in
  ``sim/plant.py`` and of the tree controller in ``control/pid.py`` (each a formula made to
  give the same numbers, ``* 1.0``), the same run again, and after the plant's edit
  undone, ``rov-console serve`` until it steps.

pip's download cache is kept off (``PIP_NO_CACHE_DIR``), so the packages come from the
registry as on a new machine; Debian's chromium and the JavaScript test packages are whatever
this machine has (``test`` installs them if missing). Prints each figure as it is measured and,
with ``--json``, one JSON object at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import machine

ROOT = Path(__file__).resolve().parents[1]
MISSION = "full-docking-current-0.3"


def clone(into: Path) -> Path:
    repo = into / "rov-console"
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(repo)], check=True)
    return repo


def fresh_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    env["PIP_NO_CACHE_DIR"] = "1"
    return env


def _stepping(port: int) -> bool:
    """The console answers /api/health and its simulated time moves."""
    times = []
    for _ in range(2):
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/health", timeout=2) as r:
                body = json.load(r)
        except OSError:
            return False
        times.append(float(body.get("t_s", 0.0)))
        time.sleep(0.3)
    return times[1] > times[0]


def time_start(repo: Path, timeout_s: float = 900.0) -> dict:
    from app.server import free_port

    port, viser = free_port(), free_port()
    log = repo / "start.log"
    t0 = time.perf_counter()
    with log.open("w") as out:
        proc = subprocess.Popen(
            ["./scripts/start.sh", "--port", str(port), "--viser-port", str(viser)],
            cwd=repo,
            env=fresh_env(),
            stdout=out,
            stderr=subprocess.STDOUT,
        )
        try:
            while time.perf_counter() - t0 < timeout_s:
                if proc.poll() is not None:
                    raise RuntimeError(f"start.sh ended ({proc.returncode}):\n{log.read_text()}")
                if _stepping(port):
                    break
                time.sleep(0.5)
            else:
                raise RuntimeError(f"no stepping console in {timeout_s:.0f} s")
            serving_s = time.perf_counter() - t0
        finally:
            proc.terminate()
            proc.wait(timeout=30)
    return {"serving_s": serving_s, "printed": log.read_text().splitlines()[:12]}


def _timed(cmd: list[str], repo: Path) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=repo, env=fresh_env(), check=True, capture_output=True)
    return time.perf_counter() - t0


def time_run(repo: Path) -> dict:
    setup_s = _timed(["./scripts/setup.sh"], repo)
    run = [".venv/bin/rov-console", "run", MISSION]
    return {
        "setup_s": setup_s,
        "first_run_s": _timed(run, repo),
        "second_run_s": _timed(run, repo),
    }


EDITS = {
    "comment": (
        "sim/plant.py",
        "    if env[E_WEXT] > 0.0:\n",
        "    # a comment\n    if env[E_WEXT] > 0.0:\n",
    ),
    "plant": (
        "sim/plant.py",
        "    d = np.sqrt(dx * dx + dy * dy + dz * dz)\n",
        "    d = np.sqrt(dx * dx + dy * dy + dz * dz) * 1.0\n",
    ),
    "pid": ("control/pid.py", "    i_b[2] = i_n[2]\n", "    i_b[2] = i_n[2] * 1.0\n"),
}
"""The edits ``edit`` makes: (file, old text, new text), each once in its file."""


def _edit(repo: Path, name: str, undo: bool = False) -> None:
    file, old, new = EDITS[name]
    if undo:
        old, new = new, old
    path = repo / file
    text = path.read_text()
    if text.count(old) != 1:
        raise RuntimeError(f"{file}: the edit {name!r} expects {old!r} once")
    path.write_text(text.replace(old, new))


def time_edit(repo: Path) -> dict:
    res = time_run(repo)
    run = [".venv/bin/rov-console", "run", MISSION]
    for name in EDITS:
        _edit(repo, name)
        res[f"after_{name}_edit_s"] = _timed(run, repo)
    _edit(repo, "plant", undo=True)
    res["serve_after_plant_edit_s"] = time_start(repo)["serving_s"]
    return res


def time_test(repo: Path) -> dict:
    """The whole test script, timed whether it passes or not (its exit status kept)."""
    t0 = time.perf_counter()
    done = subprocess.run(["./scripts/test.sh"], cwd=repo, env=fresh_env(), capture_output=True)
    return {"test_s": time.perf_counter() - t0, "exit_status": done.returncode}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--what", default="start,run", help="start, run, test, edit (comma-separated)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object at the end")
    args = parser.parse_args()
    wanted = [w.strip() for w in args.what.split(",") if w.strip()]
    steps = {"start": time_start, "run": time_run, "test": time_test, "edit": time_edit}
    unknown = sorted(set(wanted) - set(steps))
    if unknown:
        parser.error(f"--what takes {', '.join(steps)}; got {', '.join(unknown)}")
    res: dict = {
        "commit": subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        ).stdout.strip(),
        "machine": machine.describe(),
        "load_average_before": list(os.getloadavg()),
    }
    for what in wanted:
        folder = Path(tempfile.mkdtemp(prefix=f"fresh-{what}-"))
        try:
            res[what] = steps[what](clone(folder))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        figures = ", ".join(f"{k} {v:.1f}" for k, v in res[what].items() if isinstance(v, float))
        print(f"{what}: {figures}", flush=True)
    if args.json:
        print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
