"""The numeric core: vehicles, wire, environment, sensors.

Importing it first installs the core's numba cache locator (``sim.numba_cache``), before
any kernel is compiled or loaded from the cache."""

from sim import numba_cache as _numba_cache

_numba_cache.install()
