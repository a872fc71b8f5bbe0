"""Shared test settings."""

import pytest
from hypothesis import settings

# the console in headless Chromium: fixtures ``server``, ``page``, ``api`` for any test module
pytest_plugins = ["tests.browser"]

# The first call of a compiled (numba) function includes its compilation, which can take a
# second; hypothesis's per-example deadline would count that as slowness of the law under test.
# derandomize: the same examples on every run, so CI cannot turn red on a new random draw (a
# law that fails shows up on the first run that includes the change).
settings.register_profile("default", deadline=None, max_examples=60, derandomize=True)
settings.load_profile("default")

# How the default run shares the modules between its two workers (``--dist loadfile
# --no-loadscope-reorder`` in scripts/test.sh, and ``pytest_xdist_make_scheduler`` below): a
# module goes whole to one worker, in the order below, and the console-in-Chromium modules
# listed here go together as one unit, so one worker runs them one after the other while the
# other worker runs the rest. Two Chromiums drawing software WebGL at once slow each other
# down, and a long module taken last leaves a worker idle at the end; the measurements behind
# this split are in docs/performance.md ("The tests' ten minutes").
BROWSER_MODULES = (
    "test_console_replay.py",
    "test_console_scene.py",
    "test_console_browser.py",
    "test_console_panels.py",
    "test_console_builder.py",
    "test_instructor_browser.py",
    "test_plots_page.py",
    "test_pilot_browser.py",
    "test_review_browser.py",
    "test_console_vessel_advice_browser.py",
)
LONGEST_FIRST = (
    "test_missions.py",
    "test_report.py",
    "test_plant_allocation.py",
    "test_numba_cache.py",
    "test_campaign.py",
    "test_landing_limit_mission.py",
    "test_studies.py",
    "test_readme_scripts.py",
)
"""The longest of the other modules (25-45 s each), started first so that short ones fill in
at the end; the rest keep their file order after these."""


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    first = BROWSER_MODULES + LONGEST_FIRST
    items.sort(key=lambda item: first.index(n) if (n := item.path.name) in first else len(first))


def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    """``--dist loadfile`` with the browser modules as one unit (xdist's own ``loadgroup``
    does not group under pytest 9.2: it renames the items' ``_nodeid``, which pytest no longer
    reads)."""
    if config.getvalue("dist") != "loadfile":
        return None  # xdist's own scheduler
    from xdist.scheduler import LoadScopeScheduling

    class BrowserModulesTogether(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return "browser" if path.rsplit("/", 1)[-1] in BROWSER_MODULES else path

    return BrowserModulesTogether(config, log)
