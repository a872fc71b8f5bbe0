"""The live feed for Foxglove (``serve --foxglove-port``): the Foxglove SDK's server sends the
channels a recording has, with the same schemas, and every message it sends is valid against
its channel's schema; it offers no way to publish or change anything."""

from __future__ import annotations

import asyncio
import json
import re
import struct
import threading
import time

import jsonschema_rs
import numpy as np
import pytest
import websockets

from app.foxglove_live import LiveFeed
from app.recording.stream import SessionStream
from app.server import free_port
from control.columns import N_LOG
from sim import params

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]


LATE_NS: list[int] = []
"""How far each message's log time was behind the wall clock when it arrived [ns] (the
last ``_listen``'s)."""


async def _listen(port: int, seconds: float) -> tuple[dict, dict, dict[int, list[bytes]]]:
    """Connect as Foxglove does, subscribe to every channel, and gather for ``seconds``:
    (serverInfo, channels by id, payloads by channel id); ``LATE_NS`` the log times' lag."""
    LATE_NS.clear()
    url = f"ws://127.0.0.1:{port}"
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS) as ws:
        info: dict = {}
        channels: dict[int, dict] = {}
        got: dict[int, list[bytes]] = {}
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                msg = await asyncio.wait_for(ws.recv(), 0.2)
            except TimeoutError:
                continue
            if isinstance(msg, str):
                m = json.loads(msg)
                if m["op"] == "serverInfo":
                    info = m
                elif m["op"] == "advertise":
                    channels.update({c["id"]: c for c in m["channels"]})
                    subs = [{"id": c["id"], "channelId": c["id"]} for c in m["channels"]]
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
            elif msg[0] == 1:  # message data: opcode, subscription id, log time, payload
                sub, log_time_ns = struct.unpack_from("<IQ", msg, 1)
                got.setdefault(sub, []).append(bytes(msg[13:]))
                LATE_NS.append(time.time_ns() - log_time_ns)
        return info, channels, got


def _rows(t0_s: float, n: int) -> np.ndarray:
    rows = np.zeros((n, N_LOG))
    rows[:, 0] = t0_s + 0.01 * np.arange(1, n + 1)
    return rows


def test_a_viewer_gets_the_recordings_channels_and_valid_messages() -> None:
    ps = params.load("model-scale")
    feed = LiveFeed(ps, 4, 1_700_000_000_000_000_000, free_port())

    def hand_over() -> None:
        time.sleep(0.8)  # the viewer connects and subscribes first
        for k in range(20):  # 20 s of simulation in 0.5 s ticks
            feed.rows(_rows(0.5 * k, 50), np.array([1.0, 1.0, 0.0]), 100.0, None)
            time.sleep(0.05)
        feed.event(5.0, "note", "silt cloud, lost the view", {"who": "pilot"})

    threading.Thread(target=hand_over, daemon=True).start()
    try:
        info, channels, got = asyncio.run(_listen(feed.port, 3.5))
    finally:
        feed.close()
    recorded = [spec.topic for spec in SessionStream(ps, 4, 20.0, 5.0, 0).channels()]
    assert sorted(c["topic"] for c in channels.values()) == sorted(recorded)
    assert not {"clientPublish", "parameters", "services"} & set(info.get("capabilities", []))
    by_topic = {channels[cid]["topic"]: (channels[cid], payloads) for cid, payloads in got.items()}
    for topic, (channel, payloads) in by_topic.items():
        validator = jsonschema_rs.validator_for(json.loads(channel["schema"]))
        invalid = [p for p in payloads if not validator.is_valid(json.loads(p))]
        assert not invalid, f"{topic}: {invalid[0][:200]!r}"
    # 20 s of simulation handed over in about 1 s of wall time (20x): the recording's rates
    # (20 Hz, 5 Hz of simulated time) thinned to at most 20 hand-overs a wall second, each of
    # 0.5 s of simulation (10 rows at 20 Hz)
    tf, scene = len(by_topic["/tf"][1]), len(by_topic["/scene"][1])
    assert 10 <= tf <= 11 * (1 + 2.0 * 20) and tf < 400
    assert 0 < scene < tf
    (event,) = by_topic["/events"][1]
    assert json.loads(event)["text"] == "silt cloud, lost the view"


def test_nothing_is_encoded_while_nobody_watches() -> None:
    ps = params.load("model-scale")
    feed = LiveFeed(ps, 4, 0, free_port())
    sent: list[object] = []
    feed._stream.row_messages = lambda batch: sent.append(batch) or iter(())  # type: ignore[method-assign]
    try:
        feed.rows(_rows(0.0, 100), np.zeros(3), 100.0, None)
        time.sleep(0.5)
    finally:
        feed.close()
    assert sent == [] and feed.dropped == 0


def test_serve_sends_the_running_session_and_its_events(tmp_path) -> None:
    """``serve --foxglove-port``: the console's own run reaches a Foxglove client, and a
    command's event (a pause through the API) arrives on /events as it is applied."""
    import httpx

    from app.console import ConsoleSettings
    from app.server import serve_in_thread

    port = free_port()
    settings = ConsoleSettings(
        port=0, view=False, recordings_dir=tmp_path, speed=5.0, foxglove_port=port
    )
    with serve_in_thread(settings) as srv:
        assert srv.console.loop.session.live is not None

        def pause_later() -> None:
            time.sleep(1.0)
            httpx.post(
                f"{srv.base_url}/api/run/pause",
                headers={"Authorization": f"Bearer {srv.token}"},
                timeout=10.0,
            )

        threading.Thread(target=pause_later, daemon=True).start()
        _, channels, got = asyncio.run(_listen(port, 4.0))
    topics = {channels[cid]["topic"]: payloads for cid, payloads in got.items()}
    poses = [json.loads(p) for p in topics["/tree/state"]]
    assert len(poses) >= 5, "the live run's rows arrive"
    validator = jsonschema_rs.validator_for(
        json.loads(next(c for c in channels.values() if c["topic"] == "/tf")["schema"])
    )
    assert all(validator.is_valid(json.loads(p)) for p in topics["/tf"])
    texts = [json.loads(p)["text"] for p in topics.get("/events", [])]
    assert any("pause" in t.lower() for t in texts), texts
    # at 5x, log times are the wall clock when the rows were simulated: none in the future
    # (start plus simulated time ran 4 s ahead for every second of wall time), none old
    assert 0 <= min(LATE_NS) and max(LATE_NS) < 5e9, (min(LATE_NS), max(LATE_NS))


@pytest.mark.parametrize(
    "port, words",
    [(0, "foxglove_port must be in [1, 65535], got 0"), (8000, "must differ from port")],
)
def test_a_bad_foxglove_port_is_refused_with_its_range(port: int, words: str) -> None:
    from app.console import ConsoleSettings

    with pytest.raises(ValueError, match=re.escape(words)):
        ConsoleSettings(port=8000, view=False, foxglove_port=port)
