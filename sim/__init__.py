"""The numeric core: vehicles, wire, environment, sensors.

Importing it first chooses numba's cache folder for this version of the sources
(``sim.numba_cache``), before any kernel is compiled or loaded from a cache."""

from sim import numba_cache as _numba_cache

_numba_cache.configure()
