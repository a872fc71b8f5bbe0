"""Compile every kernel the product calls into numba's on-disk cache, ahead of first use.

Nothing needs it: a kernel compiles on its first call after a change of the code it
depends on (``sim.numba_cache``), and the console's first chunk and a mission's first run
wait for theirs. What it is for: the console runs it in a background process of low
priority once it serves (``start_in_background``), so that a command the session has not
used yet (the QP allocation, free mode, the grip) loads its kernels from the cache instead
of compiling for seconds inside the paced loop; and the test script runs it beside the
static checks, so that the tests' first calls load rather than compile.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from sim.plant import PlantArrays


PARTS = ("steps", "tools")
"""The two halves of the work, each a process of its own when there are two cores: the
chunk kernels with the controller's unit they link (``compile_steps``), and the plant's
step, which the chunk kernels load from the cache when they come to it, with the kernels
that tools, tests and the landing planner call from Python (``compile_tools``). They share
few kernels, and a kernel both compile is cached twice over, the same code."""


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m app.precompile", description=__doc__)
    parser.add_argument("--part", choices=PARTS, help="compile only this half, in this process")
    parser.add_argument(
        "--jobs",
        type=int,
        default=min(2, os.cpu_count() or 1),
        help="processes to share the work (1 or 2; default: 2 on two cores or more)",
    )
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    if args.part == "steps":
        compile_steps()
        return
    if args.part == "tools":
        compile_tools()
        return
    if args.jobs >= 2:
        tools = subprocess.Popen([sys.executable, "-m", "app.precompile", "--part", "tools"])
        compile_steps()
        if tools.wait() != 0:
            raise SystemExit(f"precompile: the tools' half failed (exit code {tools.returncode})")
    else:
        compile_all()
    print(f"precompile: every kernel in the cache ({time.perf_counter() - t0:.0f} s)", flush=True)


def start_in_background() -> subprocess.Popen[bytes]:
    """``python -m app.precompile`` in a process of low priority (its halves one after the
    other, so a serving console keeps a core), its output discarded."""
    return subprocess.Popen(
        [sys.executable, "-m", "app.precompile", "--jobs", "1"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        preexec_fn=lambda: os.nice(10),
    )


def compile_all() -> None:
    """Run what fills the cache: every kernel the product calls, with the argument types it
    calls them with."""
    compile_tools()
    compile_steps()


def _full_scale_arrays() -> PlantArrays:
    from control.simulation import Simulation
    from sim import params

    return Simulation(params.load("full-scale"), tree_depth_m=100.0).arrays


def compile_tools() -> None:
    """The plant's own kernels as tools, benchmarks and tests call them from Python, and the
    small kernels Python calls directly (``compile_entry_points``)."""
    from sim import plant

    arrays = _full_scale_arrays()
    m = arrays.thr_T.shape[1]
    x, n, env = np.zeros(plant.N_STATE), np.zeros(m), np.zeros(plant.N_ENV)
    env[plant.E_LREST] = 100.0  # a 100 m wire; the values do not matter, the calls only compile
    # first: the chunk kernels of the other half link it (they come to it after the
    # controller's unit, and load it from the cache)
    plant.rk4_step_into(x.copy(), x, n, env, arrays, 0.01, plant.make_work(m))
    plant.rk4_step(x, n, env, arrays, 0.01)
    plant.rhs_into(np.zeros(plant.N_STATE), x, np.zeros(6), env, arrays, plant.make_work(m))
    plant.rhs(x, n, env, arrays)
    plant.advance(x, n, env[None, :], arrays, 0.01)
    compile_entry_points(arrays)


def compile_steps() -> None:
    """The chunk kernels, as every path runs them: each feedback, allocation and reference,
    and what the console does to a running simulation."""
    from control.config import ALLOCATIONS, MODES, ControlSettings
    from control.simulation import Simulation
    from sim import params

    ps = params.load("model-scale")
    for feedback in ("perfect", "ekf"):
        for allocation in ("pinv", "priority"):
            for reference in ("first", "third"):
                settings = ControlSettings(
                    feedback=feedback, allocation=allocation, reference=reference, feedforward=True
                )
                Simulation(ps, tree_depth_m=100.0, settings=settings).step(2)
    # a request of several chunks: each writes into the request's rows (run_chunk_into)
    Simulation(ps, tree_depth_m=100.0, chunk_steps=1).step(2)
    Simulation(ps, tree_depth_m=100.0, control=False).step(2)
    Simulation(ps, tree_depth_m=100.0, control=False, chunk_steps=1).step(2)
    # what the console does to a running simulation: every mode, every allocation in each,
    # the grip, the pilot's demand, and the readings its snapshot takes (some call kernels
    # from Python with argument types of their own)
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
        for allocation in ALLOCATIONS:
            sim.set_allocation(allocation)
            sim.set_grip(False)
            sim.step(2)
            sim.set_grip(True)
            sim.step(2)


def compile_entry_points(arrays: PlantArrays) -> None:
    """The small kernels that Python calls directly (not only from inside the chunk
    kernels): the landing plan's hold (``plant.hold_needed_xyn``), the scoring's
    angle wrap, the site's wire offset, the allocation's thruster maps, and the plant's,
    observer's, controller's and reference's pieces as the unit tests and tools call them.
    Each is compiled for the argument types it is called with (``dispatcher.compile``, nothing
    run). A call with other types compiles on first use."""
    from numba import typeof, types
    from numba.core.errors import NumbaPerformanceWarning

    from control import allocation, ekf, pid, quality, refkernel
    from sim import gnc, plant, sensors, thrusters, wire

    f8, i8, b1 = types.float64, types.int64, types.boolean
    a1, a2, a3 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, ::1]
    any1 = types.float64[:]
    ro1 = types.Array(f8, 1, "C", readonly=True)
    i1, i2 = types.int64[::1], types.int64[:, ::1]
    ro_i1 = types.Array(i8, 1, "C", readonly=True)
    bools = types.boolean[::1]
    pa = typeof(arrays)
    signatures: list[tuple[Any, tuple[Any, ...]]] = [
        (gnc.ssa, (f8,)),
        (gnc.ssa, (a1,)),
        (gnc.ssa_each, (a1,)),
        (gnc.Tzyx, (f8, f8)),
        (gnc.m2c, (a2, a1)),
        (gnc.mv, (a2, a1)),
        (gnc.cross, (a1, a1)),
        (gnc.coriolis_force, (a2, a1)),
        (gnc.euler_from_rotation, (a2,)),
        (wire.horizontal_offset_c, (f8, f8, f8, f8, f8)),
        (wire.horizontal_offset_c, (f8, f8, f8, i8, f8)),
        (plant.hold_needed_xyn, (a2, f8, a1, pa)),
        (plant.attachment_velocity_n, (a1, a2, a1)),
        (plant.tree_wrench, (a1, a1, pa, a2)),
        (plant.rov_wrench, (a1, a1, a1, pa, a2)),
        (plant.coupling_wrench, (a1, pa, a2, a2)),
        (plant.contact_wrench, (a1, a1, pa, a2)),
        (plant.contact_energy, (a1, a1, pa)),
        (plant.contact_reach, (pa,)),
        (plant.post_penetration, (a1, pa)),
        (plant._post_top, (a1, a1, pa, i8)),
        (plant._post_top, (any1, any1, pa, i8)),
        (plant._corner_body, (pa, i8)),
        (sensors.sample_into, (a1, a1, a1, a1, bools, i1)),
        (sensors.sample_into, (a1, a1, a1, a1, bools, ro_i1)),
        (ekf.predict, (a1, a2, a1, f8, a2, a2, a1, a1, f8, a1, a1, a2)),
        (ekf.correct, (a1, a2, a1, i1, a1, i8)),
        (ekf.model_rhs, (a1, a1, a2, a2, a1, a1, f8, a1, a1)),
        (ekf.jacobian_phi_into, (a2, a1, f8, f8, f8, a2, a2, a1, a1, f8, a1, a1)),
        (pid.ned_to_body, (a1, f8)),
        (pid.tree_pid, (a1,) * 9 + (b1, a2, a1, a1, f8, a1, a2, a2, a1, f8)),
        (
            quality.check_sample,
            (i8, a1, f8, a1, a1, i1, a2, i2, a1, a1, a1, a1, i1, a1, i1, i1),
        ),
        (refkernel._first_kernel, (a1, a1, a1, f8)),
        (refkernel.first_order_step, (a1, a1, f8, a2)),
        (refkernel.third_order_step, (a1, a1, f8, a2)),
        (refkernel.reference_step, (i8, a1, a1, f8, a2)),
        (refkernel.reference_step_into, (a1, i8, a1, a1, f8, a2)),
        (refkernel.polls_still_away, (i8, a1, a1, f8, a2, a1, a1, i8, i8, a1)),
        (allocation._priority_forces, (a2, a3, a3, a1, a1, a1, f8)),
    ]
    # the thrusters' maps: the parameter sets' arrays are read-only, a caller's own are not
    for speed_or_thrust in (thrusters.speed_from_thrust, thrusters.thrust_from_speed):
        for first, rest in ((a1, a1), (a1, ro1), (ro1, ro1)):
            signatures.append((speed_or_thrust, (first, rest, rest, rest)))
    for into in (thrusters.speed_from_thrust_into, thrusters.thrust_from_speed_into):
        for second, rest in ((a1, a1), (a1, ro1), (ro1, ro1)):
            signatures.append((into, (a1, second, rest, rest, rest)))
    signatures.append((thrusters.speed_from_thrust_into, (a1, ro1, a1, a1, a1)))
    with warnings.catch_warnings():  # gnc.m2c's '@' on a block of M: a reference form, not
        warnings.simplefilter("ignore", NumbaPerformanceWarning)  # the step's
        for kernel, sig in signatures:
            kernel.compile(sig)


if __name__ == "__main__":
    main()
