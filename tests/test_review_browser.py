"""Reviewing a trial in the page, in a real headless Chromium (issue 45, "Notes" and
"Compare"): a note added live is in the recording, a refused note says why, the replay lists
the note to jump to, a note added in replay goes to the side file, and a second recording is
compared with the replay (the table in the tab, its run a ghost in that browser's scene).

Its own server and browser (the module fixtures of ``tests/browser.py``).
"""

from __future__ import annotations

import time

import httpx

from app.recording.notes import read_notes
from app.server import RunningServer
from tests.browser import choose, click, field, save, tab, unlock, wait_for
from tests.test_console_replay import _open, _status

LIVE_NOTE = "silt cloud, lost the view"
REVIEW_NOTE = "winch slip here"


def _shown(pg, text: str, timeout_s: float = 10.0) -> None:
    """Wait for ``text`` to be visible on the page (the operations log, folded, holds some
    of the same words)."""
    pg.get_by_text(text).filter(visible=True).first.wait_for(timeout=1000 * timeout_s)


def _body(pg) -> str:
    return pg.locator("body").inner_text()


def _note(pg, text: str, enter: bool) -> None:
    """Type a note and send it (Enter in the box, or the button)."""
    field(pg, "Note").fill(text)
    time.sleep(0.2)  # viser sends an input's value at most every 50 ms
    if enter:
        field(pg, "Note").press("Enter")
    else:
        click(pg, "Add note")


def _recorded(api: httpx.Client, target: tuple[float, float, float], sim_s: float) -> None:
    api.put(
        "/api/control/target",
        json={"north_m": target[0], "east_m": target[1], "heading_deg": target[2]},
    ).raise_for_status()
    t0 = api.get("/api/state").json()["t_s"]
    wait_for(lambda: api.get("/api/state").json()["t_s"] > t0 + sim_s, 30.0, f"{sim_s} s run")


def _panel(server: RunningServer):
    (panel,) = server.app.state.view._panels.values()
    return panel


def test_notes_live_and_in_replay_and_compare(
    page, server: RunningServer, api: httpx.Client
) -> None:
    """Defects: the page had no way to add a note, to see a recording's notes on its replay,
    or to compare two runs."""
    recordings = server.app.state.console.settings.recordings_dir
    unlock(page, server.token)
    tab(page, "Record")
    api.put("/api/run/speed", json={"speed": 10.0}).raise_for_status()
    first = api.post("/api/recordings/start", json={"label": "noted"}).json()["name"]
    _recorded(api, (4.0, 0.0, 0.0), 15.0)
    # a bad note is refused with the validation's words, and its text stays to be corrected
    _note(page, "   ", enter=False)
    _shown(page, "text must not be empty")
    _note(page, LIVE_NOTE, enter=True)
    _shown(page, "in the recording")
    _recorded(api, (4.0, 0.0, 0.0), 15.0)
    assert api.post("/api/recordings/stop").json() == {"name": first}
    notes = read_notes(recordings / first)
    assert [(n.text, n.source) for n in notes] == [(LIVE_NOTE, "live")]
    assert notes[0].author.startswith("viewer "), notes[0].author

    second = api.post("/api/recordings/start", json={"label": "other"}).json()["name"]
    _recorded(api, (0.0, 4.0, 90.0), 30.0)
    assert api.post("/api/recordings/stop").json() == {"name": second}
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()

    # the replay lists the note in the jump list and below it; picking it goes there
    _open(page, first)
    _shown(page, LIVE_NOTE)
    page.get_by_text(LIVE_NOTE).filter(visible=True).first.scroll_into_view_if_needed()
    save(page.screenshot(), "console-notes.png")
    jump = f"{notes[0].t_s:.1f} s: note: {LIVE_NOTE} ({notes[0].author})"
    choose(page, "Jump to event", jump)
    wait_for(lambda: abs(_status(page)[1] - notes[0].t_s) < 0.2, 10.0, "the jump to the note")

    # a note in replay: at the scrub bar's time, into the side file, on the jump list at once
    _note(page, REVIEW_NOTE, enter=False)
    _shown(page, "in its side file")
    by_source = {n.source: n for n in read_notes(recordings / first)}
    assert sorted(by_source) == ["live", "review"]
    assert by_source["review"].text == REVIEW_NOTE
    assert abs(by_source["review"].t_s - notes[0].t_s) < 0.2  # the scrub bar's row
    _shown(page, REVIEW_NOTE)

    # compare with the second recording: the table in the tab, B's run as the ghost
    choose(page, "Compare with", second)
    click(page, "Compare runs")
    _shown(page, "RMS north error", 30.0)
    text = _body(page)
    assert "better" in text and second in text, text[-2000:]
    ghost = _panel(server).record.ghost
    assert ghost is not None
    assert ghost.tree_node.name == "/compare_ghost/tree"
    plot = _panel(server).record.compare_plot
    assert plot.visible and plot.image.shape[0] > 300, "both runs on one time axis"
    click(page, "Top-down")
    page.get_by_text("RMS north error").filter(visible=True).first.scroll_into_view_if_needed()
    time.sleep(2.0)  # a test page draws once a second (SLOW_FRAMES)
    save(page.screenshot(), "console-compare.png")
    click(page, "Close replay")
    wait_for(lambda: _status(page)[0] == "live", 10.0, "the page live again")
    wait_for(lambda: _panel(server).record.ghost is None, 5.0, "the ghost gone")
    assert server.app.state.view.errors == []
