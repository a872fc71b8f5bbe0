"""``rov-console`` as the tests call it.

``cli`` runs a command in the test's own process, through typer's test runner: what most tests
check (the parsing of the arguments, what the command prints and writes, its exit code) is the
same there, and the numeric core's kernels, loaded once per test worker, are not loaded again
for each call, as a command in a process of its own must, with its imports, before it starts
(what that costs: docs/performance.md, "The tests' ten minutes"). An exception the command
does not turn into an exit code fails the test with its traceback, where a process would have
shown a bare exit code 1.

``cli_process`` runs the installed script in a process of its own, for what only a process
shows: the entry point itself, a signal, a kill, a file left behind by a process that died.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from app.cli import app

EXE = str(Path(sys.executable).parent / "rov-console")
"""The installed ``rov-console`` script of the test run's environment."""
ENV = {"COLUMNS": "120", "TERM": "dumb"}
"""A terminal of fixed width, so that help and tables wrap the same on every machine."""


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    """``rov-console ARGS`` in this process: its exit code, standard output and error."""
    result = CliRunner().invoke(app, list(args), env=ENV, catch_exceptions=False)
    return subprocess.CompletedProcess(
        ["rov-console", *args], result.exit_code, result.stdout, result.stderr
    )


def cli_process(*args: str) -> subprocess.CompletedProcess[str]:
    """``rov-console ARGS`` as a process of its own."""
    env = {**ENV, "PATH": "/usr/bin:/bin"}
    return subprocess.run([EXE, *args], capture_output=True, text=True, timeout=300, env=env)
