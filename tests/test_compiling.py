"""The command line says what a first run is waiting for (app.compiling, sim.numba_cache).

Defect: a fresh clone's first console or mission compiled the numeric core for minutes
behind a terminal that printed one line, or nothing."""

from __future__ import annotations

import io
import logging

from numba import njit

import sim  # noqa: F401  (installs the compile events)
from app import compiling
from app.compiling import LOGGER, PREFIX, CompileReport


def _listening(out: io.StringIO) -> CompileReport:
    handler = CompileReport(out)
    log = logging.getLogger(LOGGER)
    log.setLevel(logging.DEBUG)
    log.addHandler(handler)
    return handler


def test_a_compile_is_reported_and_a_second_call_is_not(monkeypatch) -> None:
    monkeypatch.setattr(compiling, "SHOWN_S", 1e9)  # no line per kernel, however slow
    out = io.StringIO()
    handler = _listening(out)
    try:

        @njit(cache=False)
        def twice(x: float) -> float:
            return 2.0 * x

        assert twice(1.5) == 3.0
        first = out.getvalue()
        assert twice(2.5) == 5.0  # compiled already: nothing more to say
    finally:
        logging.getLogger(LOGGER).removeHandler(handler)
    assert first == f"{PREFIX} ...\n"
    assert out.getvalue() == first
    assert handler.kernels == 1


def test_a_closed_stream_never_stops_a_compile() -> None:
    out = io.StringIO()
    out.close()
    handler = _listening(out)
    try:

        @njit(cache=False)
        def thrice(x: float) -> float:
            return 3.0 * x

        assert thrice(2.0) == 6.0
    finally:
        logging.getLogger(LOGGER).removeHandler(handler)
