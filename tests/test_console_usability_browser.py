"""Issue 47 items 26 and 27, in a real headless Chromium: what a first user met in the page.

A typed speed applied by Enter; thruster bars that say which way each pushes; the plots above
the tabs; a replay watched without the token, at its own speed, its events named; a debrief
that opens in a tab of its own; a top-down view that keeps the tree in the picture. Pictures
go to the screenshots folder (``tests/browser.py``), to look at.
"""

from __future__ import annotations

import time

import httpx
import numpy as np

from app.server import RunningServer
from tests.browser import (
    button,
    choose,
    click,
    field,
    image,
    save,
    scene_part,
    tab,
    unlock,
    wait_for,
)


def _record(api: httpx.Client, seconds: float) -> str:
    """A recording of ``seconds`` of the live run with a gain change in it (an event)."""
    api.post("/api/recordings/start", json={"label": "usability"}).raise_for_status()
    time.sleep(seconds / 2)
    gains = api.get("/api/gains").json()
    api.put("/api/gains", json={k: gains[k] for k in ("kp", "ki", "kd")}).raise_for_status()
    time.sleep(seconds / 2)
    return str(api.post("/api/recordings/stop").json()["name"])


def test_a_replay_opens_without_the_token_at_its_own_speed(
    page, server: RunningServer, api: httpx.Client
) -> None:
    """Open replay was greyed out with no word of why until the console token was entered;
    the replay ran at the live run's speed; a typed time was written over while playing; the
    scrub bar's dots had no words."""
    name = _record(api, 6.0)
    tab(page, "Record")
    assert button(page, "Lock controls").is_visible() is False, "this page is locked"
    click(page, "Refresh list")
    choose(page, "Recording", name)
    assert button(page, "Open replay").is_enabled()
    click(page, "Open replay")
    page.get_by_text("REPLAY").first.wait_for(timeout=20_000)
    panel = next(iter(server.app.state.view._panels.values()))
    wait_for(lambda: panel.replay is not None, 10.0, "the page's replay")
    # the replay's own speed (the Run tab's presets have a "5" too, out of sight)
    page.locator("xpath=//button[normalize-space(.)='5']").filter(visible=True).first.click()
    wait_for(lambda: panel.replay.speed == 5.0, 10.0, "the replay at 5x")
    assert api.get("/api/state").json()["loop"]["speed"] == 1.0, "the live run's speed is its own"
    click(page, "Play replay")
    page.get_by_text("replay playing at x5").first.wait_for(timeout=10_000)
    start = panel.replay.status().start_s
    box = field(page, "Go to t s")
    box.fill(f"{start + 1.0:.1f}")
    time.sleep(0.3)  # viser sends an input's value at most every 50 ms
    box.press("Enter")
    wait_for(lambda: panel.replay.status().t_s < start + 2.5, 10.0, "the typed time, while playing")
    click(page, "Pause replay")
    options = _jump_options(panel)
    choose(page, "Jump to event", next(o for o in options if o.endswith(": gains")))
    t_gains = next(t for t, text in panel.replay.status().jumps if text == "gains")
    wait_for(lambda: abs(panel.replay.status().t_s - t_gains) < 0.1, 10.0, "the jump to the gains")
    page.get_by_text("Jump to event").first.scroll_into_view_if_needed()
    save(page.screenshot(), "console-replay-panel.png")
    click(page, "Close replay")
    wait_for(lambda: panel.replay is None, 10.0, "live again")


def _choose_visible(pg, label: str, option: str) -> None:
    inputs = "*[self::input[not(@type='hidden')] or self::select or self::textarea]"
    pg.locator(
        f"xpath=//label[normalize-space(.)='{label}']/ancestor::div[.//{inputs}][1]//{inputs}"
    ).filter(visible=True).first.click()
    pg.locator(f"xpath=//*[@role='option'][normalize-space(.)='{option}']").filter(
        visible=True
    ).first.click()


def _jump_options(panel) -> list[str]:
    return [str(o) for o in panel.record.jump.options]


def test_debrief_opens_in_a_tab_of_its_own(page, server: RunningServer, api) -> None:
    """The debrief link replaced the console's tab, and coming back needed the token again."""
    name = _record(api, 2.0)
    unlock(page, server.token)
    tab(page, "Scores")
    click(page, "Show my scores")
    _choose_visible(page, "Recording", name)  # the Record tab has a "Recording" too
    click(page, "Debrief")
    link = page.locator("a", has_text=f"open the debrief of {name}").first
    link.wait_for(timeout=10_000)
    assert link.get_attribute("target") == "_blank"
    assert "noopener" in (link.get_attribute("rel") or "")


def test_a_typed_speed_is_applied_by_enter(page, server: RunningServer, api) -> None:
    """Typing a speed and pressing Enter did nothing."""
    unlock(page, server.token)
    tab(page, "Run")
    box = field(page, "Speed x real time")
    box.fill("3")
    time.sleep(0.3)
    box.press("Enter")
    try:
        wait_for(lambda: api.get("/api/state").json()["loop"]["speed"] == 3.0, 10.0, "speed 3x")
    finally:
        api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()


def test_thruster_bars_are_named_signed_and_the_plots_sit_above_the_tabs(page) -> None:
    """The bars showed magnitude only, with no names; the plots sat below the builder."""
    rows = page.locator("[data-thruster]")
    wait_for(lambda: rows.count() == 4, 20.0, "a row a thruster of the full-scale ROV")
    texts = [" ".join(rows.nth(k).inner_text().split()) for k in range(4)]
    for k, text in enumerate(texts):
        assert text.startswith(f"T{k + 1}") and "%" in text, text
        assert any(sign in text for sign in ("+", "-", " 0 %")), text
    page.get_by_text("forward").first.wait_for(timeout=5000)
    plots = page.locator('iframe[title="plots"]').bounding_box()
    tabs = page.locator("xpath=//*[@role='tab'][normalize-space(.)='Mission']").bounding_box()
    assert plots is not None and tabs is not None
    assert plots["y"] < tabs["y"], "the plots above the tabs"
    page.locator("[data-thruster]").first.scroll_into_view_if_needed()
    save(page.screenshot(), "console-thrusters.png")


def test_top_down_keeps_the_tree_in_the_picture(page) -> None:
    """Top-down cut the tree off (the panel covered it)."""
    click(page, "Top-down")
    time.sleep(4.0)  # frames are a second apart in these tests
    shot = page.screenshot()
    save(shot, "console-top-down.png")
    img = scene_part(image(page))
    click(page, "Overview")
    # the tree (pale yellow) and the ROV (orange) are brighter than the seabed (about 200, 185,
    # 140): neither runs into the picture's edges, nor into the panel beyond the scene's part
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    bodies = (r > 235) & (g > 150) & (b < 190)
    bodies[-120:, :120] = False  # the axes in the corner
    ys, xs = np.nonzero(bodies)
    assert len(xs) > 5000, "the tree and the ROV are drawn"
    assert xs.max() < img.shape[1] - 5 and xs.min() > 5, (xs.min(), xs.max())
    assert ys.min() > 5 and ys.max() < img.shape[0] - 5, (ys.min(), ys.max())
