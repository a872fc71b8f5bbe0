"""The command line as a first user meets it: help text, version, option checks."""

from __future__ import annotations

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

EXE = str(Path(sys.executable).parent / "rov-console")


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = {"COLUMNS": "120", "PATH": "/usr/bin:/bin", "TERM": "dumb"}
    return subprocess.run([EXE, *args], capture_output=True, text=True, timeout=120, env=env)


def test_help_keeps_units_in_brackets():
    out = cli("simulate", "--help").stdout
    assert "tree depth [m]" in out and "simulated time [s]" in out


def test_version_prints_the_installed_version():
    proc = cli("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"rov-console {version('rov-console')}"


def test_run_options_say_their_default_comes_from_the_mission_file():
    out = " ".join(cli("run", "--help").stdout.split())
    for option in ("--allocation", "--feedback", "--law"):
        assert option in out
    assert out.count("default: the mission file's") == 3


def test_serve_says_what_a_token_needs():
    assert "at least 16 printable characters" in " ".join(cli("serve", "--help").stdout.split())
    proc = cli("serve", "--token", "short")
    assert proc.returncode == 2
    assert "at least 16 printable characters" in proc.stderr and "Traceback" not in proc.stderr
