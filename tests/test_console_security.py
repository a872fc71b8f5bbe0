"""What a hostile or careless client can do to the console: it cannot publish the console,
and what it sends through the 3D view passes the same checks as the API."""

from __future__ import annotations

import asyncio
import time

import msgspec
import pytest
import viser
import websockets

from app.console import ConsoleSettings
from app.console import commands as cmd
from app.server import serve_in_thread


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory):
    settings = ConsoleSettings(
        port=0,
        viser_port=0,
        token="security-test-token",
        recordings_dir=tmp_path_factory.mktemp("rec"),
        speed=5.0,
    )
    with serve_in_thread(settings) as running:
        yield running


async def _send_raw(port: int, messages: list[dict]) -> None:
    """A client that never entered the token, speaking viser's own wire format."""
    uri = f"ws://127.0.0.1:{port}"
    async with websockets.connect(uri, subprotocols=[f"viser-v{viser.__version__}"]) as ws:
        for message in messages:
            await ws.send(msgspec.msgpack.encode(message))
        await asyncio.sleep(1.0)


def test_no_client_can_open_a_public_share_link(served) -> None:
    view = served.app.state.view
    port = view.port
    asyncio.run(_send_raw(port, [{"type": "ShareUrlRequest"}, {"type": "ShareUrlRequest"}]))
    deadline = time.monotonic() + 5.0
    while view.share_requests_refused < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert view.share_requests_refused == 2
    assert view.server._share_tunnel is None, "no tunnel was opened"
    assert view.server.request_share_url() is None
    assert served.console.loop.health() == "ok"


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: cmd.SetCurrent(50.0, 0.0), "speed_mps must be in [0, 3] m/s, got 50"),
        (lambda: cmd.SetCurrent(1e6, 0.0), "speed_mps must be in [0, 3] m/s"),
        (lambda: cmd.SetCurrent(float("nan"), 0.0), "speed_mps must be finite"),
        (lambda: cmd.MoveVessel(1e9, 0.0, 0.5), "north_m must be in [-1000, 1000] m"),
        (lambda: cmd.MoveVessel(0.0, 0.0, 0.0), "speed_mps must be in (0, 5] m/s"),
        (lambda: cmd.SetTarget(1e300, 0.0, 0.0), "north_m must be in [-10000, 10000] m"),
        (lambda: cmd.SetTarget(0.0, 0.0, True), "heading_deg must be a number, got bool"),
        (lambda: cmd.SetGrip("yes"), "grip must be true or false, got str"),  # type: ignore[arg-type]
        (lambda: cmd.SetGrip(1), "grip must be true or false, got int"),  # type: ignore[arg-type]
        (lambda: cmd.Step(100_000), "steps must be in [1, 1000]"),
        (lambda: cmd.SetSpeed(1e9), "speed must be in [0.25, 50]"),
    ],
)
def test_commands_check_their_own_ranges_whoever_sends_them(make, words) -> None:
    """The view builds these same commands: out-of-range values never reach the loop."""
    with pytest.raises(ValueError) as err:
        make()
    assert words in str(err.value)


def test_a_big_step_request_is_spread_over_ticks_and_the_server_keeps_answering(served) -> None:
    import httpx

    base, auth = served.base_url, served.auth
    with httpx.Client(base_url=base, timeout=30.0) as client:
        assert client.post("/api/run/pause", headers=auth).status_code == 200
        t0 = client.get("/api/state").json()["t_s"]
        import threading

        answers: list[float] = []

        def step() -> None:
            r = client.post("/api/run/step", json={"steps": 1000}, headers=auth)
            answers.append(r.json()["result"]["t_s"])

        ticks0 = served.console.loop.ticks
        worker = threading.Thread(target=step)
        worker.start()
        health_answers = 0
        while worker.is_alive():
            assert client.get("/api/health").status_code == 200
            health_answers += 1
        worker.join()
        assert answers and answers[0] == pytest.approx(t0 + 10.0, abs=0.02)
        # 1000 steps at most 50 a tick: at least 20 ticks, and the server answered meanwhile
        assert served.console.loop.ticks - ticks0 >= 20
        assert health_answers >= 3
        client.post("/api/run/resume", headers=auth)
