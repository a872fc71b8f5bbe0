"""Compile the numeric core once, into numba's on-disk cache, at set-up time.

Every later process loads the compiled code instead of compiling it again (a first run would
otherwise spend half a minute compiling). It also makes runs bit-for-bit repeatable: code
compiled fresh in a process and the same code loaded from the cache can differ in the last
bits (about 1e-9 relative after a long run), so set-up puts the cache in place before any run.
"""

from __future__ import annotations

import time


def main() -> None:
    from control.config import ControlSettings
    from control.simulation import Simulation
    from sim import params

    t0 = time.perf_counter()
    ps = params.load("model-scale")
    for feedback in ("perfect", "ekf"):
        for allocation in ("pinv", "priority"):
            for reference in ("first", "third"):
                settings = ControlSettings(
                    feedback=feedback, allocation=allocation, reference=reference, feedforward=True
                )
                Simulation(ps, tree_depth_m=100.0, settings=settings).step(2)
    Simulation(ps, tree_depth_m=100.0, control=False).step(2)
    print(f"precompile: numeric core compiled in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
