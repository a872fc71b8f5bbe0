"""Tell the person at the terminal what a first run is waiting for.

numba compiles a kernel of the numeric core the first time it is called after a change of
the code it depends on, and keeps it in its cache (``sim.numba_cache``); a fresh clone's
first console or first mission waits for that, some tens of seconds, once. The core tells
each compile to the ``sim.compile`` logger; ``report_compiles`` shows those records on
standard error: on a terminal one line that it rewrites (the kernel being compiled, how many
so far, the time), elsewhere a first line and one per kernel that Python itself called and
that took a second or more. A run that loads everything from the cache prints nothing.
"""

from __future__ import annotations

import logging
import sys
import time
from typing import TextIO

PREFIX = "compiling the numeric core (first use after a change)"
SHOWN_S = 1.0
"""Off a terminal, the kernels whose compile took at least this long get a line [s]."""
LOGGER = "sim.compile"
"""The core's logger of compiles (``sim.numba_cache.COMPILE_LOG``)."""


class CompileReport(logging.Handler):
    """Shows the records of ``LOGGER`` on ``out`` (None: whatever ``sys.stderr`` is when it
    writes). A report that cannot be written is dropped: the compile goes on."""

    def __init__(self, out: TextIO | None = None) -> None:
        super().__init__(logging.DEBUG)
        self._out = out
        self.kernels = 0
        self.first = 0.0
        self.total_s = 0.0

    @property
    def out(self) -> TextIO:
        return self._out if self._out is not None else sys.stderr

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self._show(record, self.out.isatty())
        except (ValueError, OSError):  # the stream is closed or gone (a test's capture)
            pass

    def _show(self, record: logging.LogRecord, live: bool) -> None:
        kernel, depth, phase = (record.__dict__[k] for k in ("kernel", "depth", "phase"))
        if phase == "start":
            if kernel.startswith("numba."):  # numba's own pieces: not worth a word
                return
            self.kernels += 1
            if self.kernels == 1:
                self.first = time.perf_counter()
            if live:
                spent = time.perf_counter() - self.first
                self._write(f"\r\033[K{PREFIX}: {self.kernels} kernels, {spent:.0f} s ({kernel})")
            elif self.kernels == 1:
                self._write(f"{PREFIX} ...\n")
        elif depth == 1:
            took = record.__dict__["took_s"]
            self.total_s += took
            if live:
                self._write(f"\r\033[K{PREFIX}: {self.kernels} kernels in {self.total_s:.0f} s\n")
            elif took >= SHOWN_S:
                self._write(f"  {kernel} in {took:.0f} s\n")

    def _write(self, text: str) -> None:
        self.out.write(text)
        self.out.flush()


_REPORT: CompileReport | None = None


def report_compiles(out: TextIO | None = None) -> CompileReport:
    """Show the core's compiles on ``out`` (standard error) from now on (once per process:
    a second call returns the same handler)."""
    global _REPORT
    if _REPORT is None:
        _REPORT = CompileReport(out)
        log = logging.getLogger(LOGGER)
        log.setLevel(logging.DEBUG)
        log.propagate = False
        log.addHandler(_REPORT)
    return _REPORT
