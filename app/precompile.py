"""Compile the numeric core once, into numba's on-disk cache, at set-up time.

Every later process loads the compiled code instead of compiling it again (a first run would
otherwise spend half a minute compiling). It also makes runs bit-for-bit repeatable: code
compiled fresh in a process and the same code loaded from the cache can differ in the last
bits (about 1e-9 relative after a long run), so set-up puts the cache in place before any run.
"""

from __future__ import annotations

import time


def main() -> None:
    from control.config import ALLOCATIONS, MODES, ControlSettings
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
    # what the console does to a running simulation: every mode, every allocation in each,
    # the grip, the pilot's demand, and the readings its snapshot takes. Some of these call
    # kernels from Python with their own argument types; compiled here, they are loaded from
    # the cache later instead of compiling for seconds inside the console's loop (where a
    # command then waited 10 s and got a 503)
    for name in ("model-scale", "full-scale"):
        sim = Simulation(params.load(name), tree_depth_m=100.0)
        sim.step(2)
        for mode in MODES:
            sim.set_mode(mode)
            for allocation in ALLOCATIONS:
                sim.set_allocation(allocation)
                sim.step(2)
                sim.set_pilot_demand(0.2, -0.1, 0.1, 0.05)
                sim.step(2)
                sim.present_row()
                sim.wire_tension_newton()
        sim.set_mode("tree")
        sim.set_grip(False)
        sim.step(2)
        sim.set_grip(True)
        sim.step(2)
    print(f"precompile: numeric core compiled in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
