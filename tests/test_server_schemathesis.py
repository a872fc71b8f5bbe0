"""Property-based API test: schemathesis generates requests for every operation in
/openapi.json (with the token, so the actions are exercised too) against a live server on
loopback; none may get a 5xx, and the loop must still run afterwards."""

from __future__ import annotations

import time
from collections.abc import Iterator

import httpx
import pytest
from hypothesis import HealthCheck, given, settings

from app.console import ConsoleSettings
from app.server import RunningServer, serve_in_thread

schemathesis = pytest.importorskip("schemathesis")
EXAMPLES_PER_OPERATION = 8
"""Bounded so the whole API is covered in well under a minute."""


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningServer]:
    settings = ConsoleSettings(
        port=0, view=False, speed=5.0, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with serve_in_thread(settings) as srv:
        yield srv


def check_operation(operation, server: RunningServer, failures: list[str]) -> None:
    """Call one operation with generated requests; note every 5xx."""

    @settings(
        max_examples=EXAMPLES_PER_OPERATION,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(case=operation.as_strategy())
    def check(case) -> None:
        response = case.call(base_url=server.base_url, headers=server.auth, timeout=30)
        if response.status_code >= 500:
            failures.append(
                f"{operation.label} -> {response.status_code}: "
                f"{response.text[:200]} (body {case.body!r})"
            )

    check()


def test_no_request_gets_a_server_error(server: RunningServer) -> None:
    schema = schemathesis.openapi.from_url(f"{server.base_url}/openapi.json")
    operations = [result.ok() for result in schema.get_all_operations()]
    assert len(operations) >= 30, "every resource's operations are in the schema"
    failures: list[str] = []
    for operation in operations:
        check_operation(operation, server, failures)
    assert failures == []
    t0 = httpx.get(f"{server.base_url}/api/state").json()["t_s"]
    time.sleep(0.5)
    health = httpx.get(f"{server.base_url}/api/health").json()
    assert health["loop_running"] is True
    paused = httpx.get(f"{server.base_url}/api/run").json()["paused"]
    assert paused or health["t_s"] > t0, "the loop still runs after the fuzzing"
