"""Observer, controller, reference models, allocation and the supervisor.

Imports ``sim`` first, which installs the core's numba cache locator (``sim.numba_cache``)
before any kernel here is compiled or loaded."""

import sim as _sim  # noqa: F401
