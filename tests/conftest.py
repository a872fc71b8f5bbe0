"""Shared test settings."""

from hypothesis import settings

# The first call of a compiled (numba) function includes its compilation, which can take a
# second; hypothesis's per-example deadline would count that as slowness of the law under test.
settings.register_profile("default", deadline=None, max_examples=60)
settings.load_profile("default")
