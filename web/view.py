"""The console's 3D view: a viser server bound to the console's host (viser binds 0.0.0.0 by
default), its share button off, one shared scene, and panels per browser.

A publisher thread reads the newest snapshot ``FRAME_HZ`` times a second and pushes it to the
scene and the panels; the loop never waits for it, and viser coalesces what a slow browser has
not taken yet.
"""

from __future__ import annotations

import threading
import time
import traceback
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import viser

from app.console import PILOT_VIEW_PATH, allowed_hosts, origin_allowed
from web import geometry as geo
from web.panels import ClientPanel
from web.scene import SceneView
from web.uploads import VIEW_MESSAGE_MAX_BYTES, UploadGuard

if TYPE_CHECKING:
    from app.console import Console, Snapshot

FRAME_HZ = 20.0
"""Scene updates per second."""


class ConsoleView:
    """Starts with the console, stops with it."""

    def __init__(self, console: Console, host: str, port: int) -> None:
        self.console = console
        self.refused_requests = 0
        """Requests to the view's port refused for their Host or Origin header."""
        self.server = _guarded_viser_server(
            host,
            port,
            allowed_hosts(host, console.settings.allow_remote),
            lambda: {console.settings.port, self.port},
            self._count_refused,
        )
        self.share_requests_refused = 0
        _refuse_share_links(self.server, self._count_share_request)
        self.server.gui.configure_theme(
            show_share_button=False,
            control_width="large",
            dark_mode=False,
            brand_color=(20, 90, 160),
        )
        self.scene = SceneView(self.server)
        self.uploads = UploadGuard()
        self._panels: dict[int, ClientPanel] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.errors: list[str] = []
        self.viser_event_races = 0
        """Scene updates cut short by viser's message buffer racing its own event loop
        (``_viser_event_race``): each healed by drawing the scene whole on the next frame."""
        self.frame_ms: deque[tuple[float, float]] = deque(maxlen=1000)
        """Work of the latest frames [ms]: (the shared scene, all panels)."""
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        self._set_initial_camera()
        self.scene.update(console.loop.snapshot)
        self._thread = threading.Thread(target=self._publish, name="console-view", daemon=True)
        self._thread.start()

    def _count_refused(self) -> None:
        self.refused_requests += 1

    def _count_share_request(self) -> None:
        self.share_requests_refused += 1

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def clients(self) -> int:
        with self._lock:
            return len(self._panels)

    def _set_initial_camera(self) -> None:
        snap = self.console.loop.snapshot
        frame = snap.scene.frame
        pose = geo.overview_camera(
            np.array(snap.tree_eta_n),
            max(snap.scene.tree_dimensions_m),
            np.array([*frame.center_n, frame.landing_depth_m]),
        )
        cam = self.server.initial_camera
        cam.position = pose.position_n
        cam.look_at = pose.look_at_n
        cam.up = pose.up_n

    def _socket_path(self, client_id: int) -> str:
        """The path the browser opened the view's socket on ('/' for the console's page,
        ``PILOT_VIEW_PATH`` for the pilot page's view). viser keeps each client's websocket
        by its id but does not hand it on, so it is read from there."""
        live = getattr(self.server._websock_server, "_live_connections", {})
        connection = live.get(client_id)
        request = getattr(connection, "request", None)
        return str(getattr(request, "path", "/") or "/")

    def _connect(self, client: viser.ClientHandle) -> None:
        panel = ClientPanel(client, self.console, self.scene)
        if self._socket_path(client.client_id).split("?")[0] == PILOT_VIEW_PATH:
            client.gui.main_panel.minimize()  # the pilot page has its own side panel
        self.uploads.guard(client.gui, lambda: panel.operator.unlocked, panel.mission.builder.say)
        with self._lock:
            self._panels[client.client_id] = panel

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._panels.pop(client.client_id, None)
        self.uploads.forget_client(client.client_id)

    def shown_snapshot(self, client_id: int | None, live: Snapshot) -> Snapshot:
        """What browser ``client_id`` shows: its own replay when it has one open, else the live
        run (the plots page follows it)."""
        with self._lock:
            panel = self._panels.get(client_id) if client_id is not None else None
        replay = panel.replay if panel is not None else None
        return replay.snapshot(live) if replay is not None else live

    def _publish(self) -> None:
        """Frames on a fixed schedule (``FRAME_HZ``, not a fixed wait after each frame's work:
        that stretched every period by the work and, through the panels' every-n-seconds
        updates, cut the status line's 5 a second to 4 and the plots' 2 to 1.8)."""
        last = -1
        period = 1.0 / FRAME_HZ
        due = time.monotonic()
        while True:
            due += period
            now = time.monotonic()
            if due < now - period:  # fell behind by more than a frame: do not burst
                due = now
            if self._stop.wait(max(due - now, 0.0)):
                return
            snap = self.console.loop.snapshot
            if snap.seq == last:
                continue
            last = snap.seq
            start = time.perf_counter()
            try:
                self.scene.update(snap)
                scene_done = time.perf_counter()
                with self._lock:
                    panels = list(self._panels.items())
                # a browser that has gone: viser drops it from its clients before it calls
                # ``_disconnect``, and its socket's buffer is closed then (a message queued
                # on it is never sent, and viser warns)
                connected = self.server.get_clients()
                for client_id, panel in panels:
                    if client_id in connected:
                        panel.update(snap)
            except Exception as err:
                if _viser_event_race(err):
                    self.viser_event_races += 1
                    self.scene.redraw()
                    continue
                if len(self.errors) < 100:
                    self.errors.append(f"{type(err).__name__}: {err}{_where(err)}")
                continue
            end = time.perf_counter()
            self.frame_ms.append((1e3 * (scene_done - start), 1e3 * (end - scene_done)))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.server.stop()


def _refuse_share_links(server: viser.ViserServer, on_request: Callable[[], None]) -> None:
    """Never open a public share tunnel, whatever a client asks. Hiding viser's share button
    is not enough: any client (one that never entered the token, or a web page the operator
    has open) can still send the request message, and viser would open the tunnel. Its two
    handlers are taken off, a refusing one counts the attempts, and the method itself is
    replaced, so no other path reaches it."""
    from viser import _messages  # viser's own message types (no public handle for these)

    incoming = server._websock_server._incoming_handlers
    for message in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
        incoming.pop(message, None)
    server._websock_server.register_handler(
        _messages.ShareUrlRequest, lambda client_id, message: on_request()
    )

    def refused(verbose: bool = True) -> None:
        on_request()
        return None

    server.request_share_url = refused  # type: ignore[method-assign]


_SERVE_LOCK = threading.Lock()


def _guarded_viser_server(
    host: str,
    port: int,
    hosts: list[str],
    page_ports: Callable[[], set[int]],
    on_refused: Callable[[], None],
) -> viser.ViserServer:
    """A viser server whose port answers only requests that name this server in their Host
    header and, from a browser, come from one of the console's pages (Origin: one of our names
    and one of ``page_ports``, the view's own and the API's): the same checks as the HTTP API
    (DNS rebinding; another web page the operator has open). viser has no option for it, so
    its websockets server is started with a request check in front of viser's own, and with a
    smaller largest message (``VIEW_MESSAGE_MAX_BYTES``, viser's is 50 MB)."""
    import websockets.asyncio.server as ws_server

    original = ws_server.serve

    def serve(handler: Any, *args: Any, **kwargs: Any) -> Any:
        inner = kwargs.get("process_request")

        def check(connection: Any, request: Any) -> Any:
            name = _host_name(request.headers.get("Host", ""))
            if "*" not in hosts and name not in hosts and f"[{name}]" not in hosts:
                on_refused()
                return connection.respond(400, "Invalid host header\n")
            if not origin_allowed(request.headers.get("Origin"), hosts, page_ports()):
                on_refused()
                return connection.respond(403, "Origin not allowed\n")
            return inner(connection, request) if inner is not None else None

        kwargs["process_request"] = check
        kwargs["max_size"] = VIEW_MESSAGE_MAX_BYTES
        return original(handler, *args, **kwargs)

    with _SERVE_LOCK:  # the server binds inside the constructor: patched only meanwhile
        ws_server.serve = serve  # type: ignore[misc,assignment]
        try:
            return viser.ViserServer(host=host, port=port, label="ROV console", verbose=False)
        finally:
            ws_server.serve = original  # type: ignore[misc]


def _host_name(header: str) -> str:
    """The name in a Host header, without the port ('[::1]:8080' -> '::1')."""
    if header.startswith("["):
        return header[1 : header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


def _where(err: BaseException) -> str:
    """Where an error was raised: the innermost frame, and the innermost of this repository's
    own when that is another (one line each, for whoever reads ``errors``)."""
    frames = traceback.extract_tb(err.__traceback__)
    if not frames:
        return ""
    last = frames[-1]
    ours = [
        f for f in frames if "site-packages" not in f.filename and "/lib/python" not in f.filename
    ]
    text = f" (at {last.filename}:{last.lineno} in {last.name}"
    if ours and ours[-1] is not last:
        text += f"; from {ours[-1].filename}:{ours[-1].lineno} in {ours[-1].name}"
    return text + ")"


def _viser_event_race(err: BaseException) -> bool:
    """Whether ``err`` is viser's thread race in a scene update: viser 1.1.1's message buffer
    (``AsyncMessageBuffer.push``) calls its ``asyncio.Event``'s ``set()`` directly in the thread
    that sends a message (the publisher's, here), and ``set()`` walks the event's waiters while
    viser's event loop thread may be adding one: "RuntimeError: deque mutated during iteration"
    raised in asyncio's locks (seen in full test runs, named by ``_where``:
    ``asyncio/locks.py in set; from web/scene.py in update``). The message being
    pushed is already in the buffer then and goes out; the rest of that update does not, so the
    scene is drawn whole again on the next frame (``SceneView.redraw``). A race in a panel's
    update is not this: it stays an error."""
    if not isinstance(err, RuntimeError) or "mutated during iteration" not in str(err):
        return False
    files = [f.filename.replace("\\", "/") for f in traceback.extract_tb(err.__traceback__)]
    return (
        bool(files)
        and files[-1].endswith("asyncio/locks.py")
        and any(f.endswith("viser/infra/_async_message_buffer.py") for f in files)
        and any(f.endswith("web/scene.py") for f in files)
    )
