"""Shared test settings."""

from hypothesis import settings

# the console in headless Chromium: fixtures ``server``, ``page``, ``api`` for any test module
pytest_plugins = ["tests.browser"]

# The first call of a compiled (numba) function includes its compilation, which can take a
# second; hypothesis's per-example deadline would count that as slowness of the law under test.
# derandomize: the same examples on every run, so CI cannot turn red on a new random draw (a
# law that fails shows up on the first run that includes the change).
settings.register_profile("default", deadline=None, max_examples=60, derandomize=True)
settings.load_profile("default")
