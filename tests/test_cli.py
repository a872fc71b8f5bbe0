"""The command line as a first user meets it: help text, version, option checks."""

from __future__ import annotations

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

from tests.cli import cli, cli_process


def test_help_keeps_units_in_brackets():
    out = cli("simulate", "--help").stdout
    assert "tree depth [m]" in out and "simulated time [s]" in out


def test_version_prints_the_installed_version():
    """The installed script itself, in a process of its own."""
    proc = cli_process("--version")
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


HEAVY = ("numba", "scipy", "control", "missions.campaign", "app.recording", "dask")
"""What the simulation and the campaigns load (some 1.4 s on this machine): the command line's
help and its option checks answer without them, and a command loads them when it runs."""


def _heavy_after(*args: str) -> tuple[subprocess.CompletedProcess[str], str]:
    """``rov-console ARGS`` in a fresh interpreter (no ARGS: only the import of the command
    line): the process, and the exit code and the ``HEAVY`` modules loaded by the end, as
    the last line of its output gives them."""
    call = (
        f"try:\n    app({list(args)!r})\nexcept SystemExit as done:\n    code = done.code\n"
        if args
        else "code = 0\n"
    )
    probe = (
        f"import sys\nfrom app.cli import app\nHEAVY = {HEAVY!r}\n{call}"
        "print(code, ' '.join(m for m in HEAVY if m in sys.modules))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=120
    )
    return proc, proc.stdout.splitlines()[-1].strip() if proc.stdout else ""


def test_the_command_line_starts_without_the_simulation():
    """Defect: ``rov-console --help`` took 2.2 s, the campaign and log subcommands importing
    the campaign runner and the log reader (numba, scipy, the control core) at start-up."""
    proc, loaded = _heavy_after()
    assert loaded == "0", f"loaded at start-up: {loaded}; {proc.stderr}"


def test_version_answers_without_the_simulation():
    """Defect: ``rov-console --version`` imported the recording package, and with it the
    control core and scipy, only to read the package's version."""
    proc, loaded = _heavy_after("--version")
    assert proc.stdout.splitlines()[0] == f"rov-console {version('rov-console')}"
    assert loaded == "0", f"exit code and what was loaded: {loaded}"


def test_a_missing_log_is_reported_before_the_simulation_loads(tmp_path: Path):
    """``rov-console report`` of a file that is not there answered after loading the report's
    imports (the whole simulation, 2.6 s); it is told at once (0.6 s)."""
    missing = tmp_path / "none.mcap"
    proc, loaded = _heavy_after("report", str(missing))
    assert f"no log file {missing}" in proc.stderr
    assert loaded == "2", f"exit code and what was loaded: {loaded}"


def test_runs_per_task_states_and_checks_its_range():
    from missions import limits

    most = limits.MAX_RUNS_PER_TASK
    out = " ".join(cli("campaign", "run", "--help").stdout.split())
    assert f"at most {most}) [1<=x<={most}]" in out
    proc = cli("campaign", "run", "missing.toml", "--runs-per-task", str(most + 1))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    said = " ".join(proc.stderr.split())
    assert f"'--runs-per-task': Input should be less than or equal to {most}" in said
